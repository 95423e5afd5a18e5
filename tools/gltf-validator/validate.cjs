#!/usr/bin/env node
// Runs the Khronos glTF Validator (the npm package gltf-validator, installed by tools/setup into
// target/gltf-validator) on one .gltf/.glb, external files resolved beside it. Prints the report's
// issue counts and messages, and the whole report as JSON on the last line; exit 0 when it has
// no errors, 1 when it has, 2 when it could not run.
// Usage: node tools/gltf-validator/validate.cjs FILE
const fs = require("fs");
const path = require("path");
const root = path.resolve(__dirname, "..", "..");
const where = process.env.WEFT_GLTF_VALIDATOR || path.join(root, "target", "gltf-validator", "node_modules", "gltf-validator");
let validator;
try {
  validator = require(where);
} catch (e) {
  console.error(`gltf-validator is not installed at ${where}: run tools/setup (${e.message})`);
  process.exit(2);
}
const file = process.argv[2];
if (!file) {
  console.error("usage: validate.cjs FILE.gltf|FILE.glb");
  process.exit(2);
}
const full = path.resolve(file);
let bytes;
try {
  bytes = fs.readFileSync(full);
} catch (e) {
  console.error(`cannot read ${file}: ${e.message}`);
  process.exit(2);
}
validator
  .validateBytes(new Uint8Array(bytes), {
    uri: path.basename(full),
    maxIssues: 1000,
    externalResourceFunction: (uri) =>
      new Promise((resolve, reject) => {
        fs.readFile(path.resolve(path.dirname(full), decodeURIComponent(uri)), (err, data) =>
          err ? reject(err.toString()) : resolve(new Uint8Array(data)));
      }),
  })
  .then((report) => {
    const i = report.issues;
    console.log(`${file}: ${i.numErrors} error(s), ${i.numWarnings} warning(s), ${i.numInfos} info(s), ${i.numHints} hint(s) (validator ${report.validatorVersion})`);
    for (const m of i.messages) {
      console.log(`  [${["error", "warning", "info", "hint"][m.severity]}] ${m.code} ${m.pointer || ""}: ${m.message}`);
    }
    console.log(JSON.stringify(report));
    process.exit(i.numErrors === 0 ? 0 : 1);
  })
  .catch((e) => {
    console.error(`validator failed: ${e}`);
    process.exit(2);
  });
