//! A module's SPIR-V specialised before a CPU driver sees it (issue 29 item 4, the cold start).
//!
//! Lavapipe translates a module's whole SPIR-V to NIR and inlines it before its specialization
//! constants remove anything, so making a pipeline takes time in proportion to the module's size,
//! not to the code the pipeline runs (docs/performance.md, "A module per kind of pixel"): the
//! fabric G-buffer's gbuffer.frag is 175 KB with every weave precision, accuracy level and
//! footprint compiled in, of which the default scene's pipeline keeps about 17 KB. On a CPU device
//! weft therefore hands the driver the module with the pipeline's constants already applied:
//! SPIRV-Tools' optimizer (`spirv-opt`, the Debian package `spirv-tools` that tools/setup
//! installs) sets each constant's value and freezes it, folds the constant expressions, propagates
//! constants and removes the branches and code they rule out
//! (`--freeze-spec-const --fold-spec-const-op-composite --ccp --eliminate-dead-branches
//! --eliminate-dead-code-aggressive`); nothing else is changed (no float arithmetic is
//! re-associated: the images are the same bit for bit, tests/plan.rs). The result is kept in
//! weft's cache on disk (crate::cache, kind `spirv`, keyed by the module's SHA-256, the constants
//! and the optimizer's version) and for the process, so a later run pays nothing for it.
//!
//! Never a failure: without `spirv-opt` on `PATH` (or with `WEFT_SPIRV_OPT=off`), when it exits
//! with an error, or when what it writes is not a SPIR-V module, the driver gets the module as it
//! was (said on stderr when `WEFT_CACHE_VERBOSE` is set). `WEFT_SPIRV_OPT=/path/to/spirv-opt`
//! names another optimizer. A GPU's driver is left its module: it specialises before it
//! translates, and keeps its own cache.

use std::collections::HashMap;
use std::io::{Read, Write};
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, OnceLock};

use sha2::{Digest, Sha256};

/// Modules smaller than this are handed over as they are: their translation takes a few
/// milliseconds, about what starting the optimizer costs.
pub const MIN_BYTES: usize = 16 * 1024;

/// The optimizer's passes, in order.
pub const PASSES: &[&str] = &[
    "--freeze-spec-const",
    "--fold-spec-const-op-composite",
    "--ccp",
    "--eliminate-dead-branches",
    "--eliminate-dead-code-aggressive",
];

/// How long one run of the optimizer may take (gbuffer.frag, the largest module the renderer
/// makes pipelines of, takes 30 ms alone).
const TIMEOUT: std::time::Duration = std::time::Duration::from_secs(30);

/// The cache's kind for a specialised module.
const CACHE_KIND: &str = "spirv";

/// How many modules this process handed to the driver specialised, and how many of those came
/// from weft's cache on disk ([`counts`]).
static MADE: AtomicU64 = AtomicU64::new(0);
static REUSED: AtomicU64 = AtomicU64::new(0);

/// (modules handed to the driver specialised, of which taken from weft's cache on disk).
pub fn counts() -> (u64, u64) {
    (MADE.load(Ordering::Relaxed), REUSED.load(Ordering::Relaxed))
}

struct Optimizer {
    path: PathBuf,
    /// Its `--version` line: part of each cached module's key.
    version: String,
}

fn note(what: std::fmt::Arguments) {
    if std::env::var_os("WEFT_CACHE_VERBOSE").is_some() {
        eprintln!("weft spirv: {what}");
    }
}

/// The optimizer, found once per process: `$WEFT_SPIRV_OPT`, else `spirv-opt` on `PATH`.
fn optimizer() -> Option<&'static Optimizer> {
    static FOUND: OnceLock<Option<Optimizer>> = OnceLock::new();
    FOUND
        .get_or_init(|| {
            let path = match std::env::var_os("WEFT_SPIRV_OPT") {
                Some(p) if p.is_empty() || p == "off" => return None,
                Some(p) => PathBuf::from(p),
                None => std::env::var_os("PATH").and_then(|paths| {
                    std::env::split_paths(&paths)
                        .map(|d| d.join("spirv-opt"))
                        .find(|p| p.is_file())
                })?,
            };
            let out = Command::new(&path)
                .arg("--version")
                .stdin(Stdio::null())
                .stderr(Stdio::null())
                .output()
                .ok()
                .filter(|o| o.status.success());
            let Some(out) = out else {
                note(format_args!(
                    "{} does not run: modules go to the driver as they are",
                    path.display()
                ));
                return None;
            };
            let version = String::from_utf8_lossy(&out.stdout)
                .lines()
                .next()
                .unwrap_or("")
                .trim()
                .to_string();
            Some(Optimizer { path, version })
        })
        .as_ref()
}

/// Whether `bytes` look like a SPIR-V module (whole words, the magic number, a header).
fn is_spirv(bytes: &[u8]) -> bool {
    bytes.len() >= 20 && bytes.len().is_multiple_of(4) && bytes[..4] == 0x0723_0203u32.to_le_bytes()
}

/// The cache key of `spirv` specialised for `constants` by `tool`.
fn key(tool: &Optimizer, spirv: &[u8], constants: &[(u32, u32)]) -> Vec<u8> {
    let mut key = Vec::with_capacity(64 + tool.version.len() + constants.len() * 8);
    key.extend_from_slice(&Sha256::digest(spirv));
    for (id, value) in constants {
        key.extend_from_slice(&id.to_le_bytes());
        key.extend_from_slice(&value.to_le_bytes());
    }
    key.extend_from_slice(tool.version.as_bytes());
    for pass in PASSES {
        key.extend_from_slice(pass.as_bytes());
    }
    key
}

/// `spirv` (a module's SPIR-V, little-endian words) with `constants` (id, value) applied and the
/// code they rule out removed, or None where the module should go to the driver as it is: too
/// small to gain, no constants, no optimizer, or the optimizer failed. `name` is for messages.
pub fn specialize(name: &str, spirv: &[u8], constants: &[(u32, u32)]) -> Option<Arc<Vec<u8>>> {
    if spirv.len() < MIN_BYTES || constants.is_empty() {
        return None;
    }
    let tool = optimizer()?;
    let key = key(tool, spirv, constants);
    // The process's own: a pipeline made again (another frame size, a test) asks again. Each
    // entry says whether it came from the cache on disk, for [`counts`].
    type Memo = HashMap<Vec<u8>, Option<(Arc<Vec<u8>>, bool)>>;
    static MEMO: OnceLock<Mutex<Memo>> = OnceLock::new();
    let memo = MEMO.get_or_init(Default::default);
    let known = memo
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .get(&key)
        .cloned();
    let entry = match known {
        Some(entry) => entry,
        None => {
            let entry = match crate::cache::read(CACHE_KIND, &key).filter(|b| is_spirv(b)) {
                Some(bytes) => Some((Arc::new(bytes), true)),
                None => run(tool, name, spirv, constants).map(|bytes| {
                    crate::cache::write(CACHE_KIND, &key, &bytes);
                    (Arc::new(bytes), false)
                }),
            };
            memo.lock()
                .unwrap_or_else(|e| e.into_inner())
                .insert(key, entry.clone());
            entry
        }
    };
    let (bytes, from_disk) = entry?;
    MADE.fetch_add(1, Ordering::Relaxed);
    if from_disk {
        REUSED.fetch_add(1, Ordering::Relaxed);
    }
    Some(bytes)
}

/// One run of the optimizer: the module on its standard input, the result on its output.
fn run(tool: &Optimizer, name: &str, spirv: &[u8], constants: &[(u32, u32)]) -> Option<Vec<u8>> {
    let values: Vec<String> = constants
        .iter()
        .map(|(id, value)| format!("{id}:{value}"))
        .collect();
    let child = Command::new(&tool.path)
        .arg(format!(
            "--set-spec-const-default-value={}",
            values.join(" ")
        ))
        .args(PASSES)
        // Its input is weft's own module, which spirv-val checks when it is built (tools/test).
        .arg("--skip-validation")
        .args(["-", "-o", "-"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn();
    let mut child = match child {
        Ok(c) => c,
        Err(e) => {
            note(format_args!(
                "{}: cannot start {}: {e}",
                name,
                tool.path.display()
            ));
            return None;
        }
    };
    // Fed and read by threads of their own, so that neither pipe can stall the optimizer, while
    // this one waits for it: a run that has not ended after TIMEOUT is killed (a module as it
    // is is always there to fall back on).
    let mut stdin = child.stdin.take()?;
    let mut stdout = child.stdout.take()?;
    let mut stderr = child.stderr.take()?;
    let input = spirv.to_vec();
    let writer = std::thread::spawn(move || stdin.write_all(&input));
    let reader = std::thread::spawn(move || {
        let mut out = Vec::new();
        stdout.read_to_end(&mut out).map(|_| out)
    });
    let errors = std::thread::spawn(move || {
        let mut err = String::new();
        let _ = stderr.read_to_string(&mut err);
        err
    });
    let start = std::time::Instant::now();
    let status = loop {
        match child.try_wait() {
            Ok(Some(status)) => break Some(status),
            Ok(None) if start.elapsed() < TIMEOUT => {
                std::thread::sleep(std::time::Duration::from_millis(2))
            }
            _ => {
                let _ = child.kill();
                let _ = child.wait();
                break None;
            }
        }
    };
    let wrote = writer.join().map(|r| r.is_ok()).unwrap_or(false);
    let out = reader.join().ok().and_then(Result::ok);
    let err = errors.join().unwrap_or_default();
    match (status, out) {
        (Some(status), Some(out)) if status.success() && wrote && is_spirv(&out) => Some(out),
        (Some(status), _) => {
            note(format_args!(
                "{name}: {} gave no module ({status}): {}",
                tool.path.display(),
                err.trim()
            ));
            None
        }
        (None, _) => {
            note(format_args!(
                "{name}: {} ran past {} s and was stopped",
                tool.path.display(),
                TIMEOUT.as_secs()
            ));
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_whole_spirv_modules_are_taken() {
        let mut header = 0x0723_0203u32.to_le_bytes().to_vec();
        header.resize(20, 0);
        assert!(is_spirv(&header));
        assert!(!is_spirv(&header[..19]));
        assert!(!is_spirv(&[0u8; 20]));
        assert!(!is_spirv(b"error: line 0: Invalid SPIR-V magic number.\n"));
    }

    #[test]
    fn a_module_the_optimizer_refuses_goes_as_it_is() {
        // Not SPIR-V, and a SPIR-V header followed by nothing sound: spirv-opt fails (or is not
        // there), and the caller keeps its module.
        let garbage = vec![0x5au8; MIN_BYTES];
        assert!(specialize("garbage", &garbage, &[(0, 1)]).is_none());
        let mut cut = 0x0723_0203u32.to_le_bytes().to_vec();
        cut.resize(MIN_BYTES, 0xff);
        assert!(specialize("cut", &cut, &[(0, 1)]).is_none());
    }

    #[test]
    fn small_modules_and_no_constants_go_as_they_are() {
        let small = vec![0u8; 64];
        assert!(specialize("small", &small, &[(0, 1)]).is_none());
        let big = vec![0u8; MIN_BYTES];
        assert!(specialize("unspecialised", &big, &[]).is_none());
    }
}
