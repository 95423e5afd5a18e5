//! The library's modules form layers (src/lib.rs): a module uses only the modules below it. This
//! reads every `crate::<module>` path in src/ (comments left out) and fails on any use of a higher
//! module that is not in `KNOWN_UPWARD` below, and on any entry of `KNOWN_UPWARD` that is gone,
//! so the list only shrinks (issue 24: "no import loops between modules").

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Bottom to top.
const LAYERS: &[&str] = &[
    "error",
    "color",
    "parse",
    "cache",
    "reflect",
    "vk",
    "fabric",
    "scene",
    "records",
    "reference",
    "env",
    "render",
    "metrics",
    "assets",
    "spec",
    "package",
    "batch",
    "bench",
    "compare",
    "fidelity",
    "sheet",
    "view",
];

/// Uses of a higher layer that remain, each with why it is still there.
const KNOWN_UPWARD: &[(&str, &str, &str)] = &[];

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("read src/") {
        let path = entry.expect("a directory entry").path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The top-level modules each top-level module names through `crate::`.
fn uses() -> BTreeMap<String, BTreeSet<String>> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for file in files {
        let rel = file.strip_prefix(&src).expect("under src/");
        let top = rel
            .components()
            .next()
            .and_then(|c| c.as_os_str().to_str())
            .expect("a file name")
            .trim_end_matches(".rs")
            .to_string();
        if top == "main" || top == "lib" {
            continue;
        }
        let text = std::fs::read_to_string(&file).expect("read a source file");
        for line in text.lines() {
            let code = line.split("//").next().unwrap_or("");
            // `crate::x::...` and the members of `crate::{x::..., y, ...}`.
            let mut rest = code;
            while let Some(at) = rest.find("crate::") {
                rest = &rest[at + "crate::".len()..];
                let names: Vec<&str> = match rest.strip_prefix('{') {
                    Some(group) => group
                        .split(['}', ','])
                        .map(|p| p.trim().split("::").next().unwrap_or(""))
                        .collect(),
                    None => vec![rest
                        .split(|c: char| !c.is_alphanumeric() && c != '_')
                        .next()
                        .unwrap_or("")],
                };
                for name in names {
                    if LAYERS.contains(&name) && name != top {
                        graph
                            .entry(top.clone())
                            .or_default()
                            .insert(name.to_string());
                    }
                }
            }
        }
    }
    graph
}

#[test]
fn modules_use_only_lower_layers_but_the_known_exceptions() {
    let graph = uses();
    let layer = |m: &str| LAYERS.iter().position(|l| *l == m);
    let mut upward = BTreeSet::new();
    for (from, tos) in &graph {
        let Some(lf) = layer(from) else {
            panic!("src/{from} is not in LAYERS: place it in tests/module_layers.rs");
        };
        for to in tos {
            if layer(to).is_some_and(|lt| lt > lf) {
                upward.insert((from.clone(), to.clone()));
            }
        }
    }
    let known: BTreeSet<(String, String)> = KNOWN_UPWARD
        .iter()
        .map(|(a, b, _)| (a.to_string(), b.to_string()))
        .collect();
    let new: Vec<_> = upward.difference(&known).collect();
    assert!(
        new.is_empty(),
        "modules that now use a higher layer (src/lib.rs): {new:?}; move what they need down"
    );
    let gone: Vec<_> = known.difference(&upward).collect();
    assert!(
        gone.is_empty(),
        "KNOWN_UPWARD lists uses that are gone (take them off the list): {gone:?}"
    );
    // The reader sees real uses (a guard against a parser that finds nothing).
    assert!(graph["render"].contains("vk") && graph["render"].contains("scene"));
}
