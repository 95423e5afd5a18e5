//! weft's cache on disk (issue 29 item 4): what a later run reuses instead of recomputing, so a
//! cold start comes close to a warm frame: the driver's compiled pipelines (a `VkPipelineCache`,
//! src/vk/context.rs) and preprocessed environments (render::passes::environment).
//!
//! One directory: `$WEFT_CACHE_DIR`, else `$XDG_CACHE_HOME/weft`, else `$HOME/.cache/weft`;
//! `WEFT_CACHE_DIR=off` (or empty) turns the cache off. Each entry is one file, named by its kind
//! and a hash of its key, holding a checked record: a magic, the kind, the whole key, the
//! payload's length and SHA-256, then the payload. A file that is short, corrupt, of another
//! kind, or made for another key (another device, driver, environment or weft) is not used, and
//! the next write replaces it. Writes go to a temporary file renamed into place, so two runs at
//! once never read half a file. The cache never fails a render: a directory that cannot be read
//! or written means no cache, said once on stderr when `WEFT_CACHE_VERBOSE` is set.
//!
//! The cache is bounded, as Mesa's shader cache is: after each write, while weft's entries hold
//! more than `WEFT_CACHE_MAX_SIZE` (default 1 GiB) together, the least recently used go (a read
//! marks its entry used). Only weft's own files are ever removed (`KIND-HEX.bin`, and temporaries
//! a killed run left behind), so the directory may be shared. `weft cache` shows what it holds;
//! `weft cache --clear` empties it.

use std::path::{Path, PathBuf};
use std::time::{Duration, SystemTime};

use sha2::{Digest, Sha256};

const MAGIC: &[u8; 8] = b"WEFTCAC1";

/// The largest payload read back (a pipeline cache or an environment is a few MiB).
pub const MAX_PAYLOAD: u64 = 1 << 30;

/// The cache directory, or None when the cache is off or there is no home to put it in.
pub fn dir() -> Option<PathBuf> {
    match std::env::var_os("WEFT_CACHE_DIR") {
        Some(d) if d.is_empty() || d == "off" => None,
        Some(d) => Some(PathBuf::from(d)),
        None => std::env::var_os("XDG_CACHE_HOME")
            .filter(|d| !d.is_empty())
            .map(PathBuf::from)
            .or_else(|| {
                std::env::var_os("HOME")
                    .filter(|d| !d.is_empty())
                    .map(|h| PathBuf::from(h).join(".cache"))
            })
            .map(|d| d.join("weft")),
    }
}

/// What the cache keeps when `WEFT_CACHE_MAX_SIZE` does not say (Mesa's shader cache's default).
pub const DEFAULT_MAX_SIZE: u64 = 1 << 30;

/// A temporary older than this is a killed run's, not a write in progress.
const STALE_TEMPORARY: Duration = Duration::from_secs(3600);

/// The most bytes weft's entries may hold together: `WEFT_CACHE_MAX_SIZE`, else
/// [`DEFAULT_MAX_SIZE`]. A value that is not a size is said once on stderr and the default kept
/// (the cache never fails a render).
pub fn max_size() -> u64 {
    let Some(value) = std::env::var_os("WEFT_CACHE_MAX_SIZE") else {
        return DEFAULT_MAX_SIZE;
    };
    let text = value.to_string_lossy();
    parse_size(&text).unwrap_or_else(|| {
        static SAID: std::sync::Once = std::sync::Once::new();
        SAID.call_once(|| {
            eprintln!(
                "weft: WEFT_CACHE_MAX_SIZE={text:?} is not a size; give bytes, or a number with K, \
                 M or G (e.g. 512M, 2G). The cache keeps its default, 1G."
            )
        });
        DEFAULT_MAX_SIZE
    })
}

/// A size as Mesa's `MESA_SHADER_CACHE_MAX_SIZE` takes it: bytes, or a whole number with a K, M
/// or G suffix (powers of 1024; a trailing B or iB allowed). None for anything else.
pub fn parse_size(text: &str) -> Option<u64> {
    let t = text.trim().to_ascii_uppercase();
    let t = t
        .strip_suffix("IB")
        .or_else(|| t.strip_suffix('B'))
        .unwrap_or(&t);
    let (digits, shift) = match t.as_bytes().last()? {
        b'K' => (&t[..t.len() - 1], 10),
        b'M' => (&t[..t.len() - 1], 20),
        b'G' => (&t[..t.len() - 1], 30),
        _ => (t, 0),
    };
    let digits = digits.trim();
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    digits.parse::<u64>().ok()?.checked_mul(1 << shift)
}

/// One of weft's entries in a cache directory.
#[derive(Debug, Clone)]
pub struct Entry {
    pub path: PathBuf,
    /// What it holds: `environment`, `pipelines`, `spirv`, `world-light`.
    pub kind: String,
    pub bytes: u64,
    /// When it was last written or read.
    pub used: SystemTime,
}

/// The kind of a file named as weft names its entries (`KIND-` sixteen hex digits `.bin`).
fn entry_kind(name: &str) -> Option<&str> {
    let stem = name.strip_suffix(".bin")?;
    let (kind, hex) = stem.rsplit_once('-')?;
    let ours = !kind.is_empty()
        && kind
            .bytes()
            .all(|b| b.is_ascii_lowercase() || b == b'_' || b == b'-')
        && hex.len() == 16
        && hex
            .bytes()
            .all(|b| b.is_ascii_hexdigit() && !b.is_ascii_uppercase());
    ours.then_some(kind)
}

/// Whether a file is a temporary of weft's writes (`KIND-HEX.tmpPID`).
fn is_temporary(name: &str) -> bool {
    name.rsplit_once(".tmp").is_some_and(|(stem, pid)| {
        !pid.is_empty()
            && pid.bytes().all(|b| b.is_ascii_digit())
            && entry_kind(&format!("{stem}.bin")).is_some()
    })
}

/// The temporaries of weft's writes in `dir` (a run's in progress, or a killed run's).
fn temporaries_in(dir: &Path) -> Vec<PathBuf> {
    std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .filter(|e| e.file_name().to_str().is_some_and(is_temporary))
        .map(|e| e.path())
        .collect()
}

/// weft's entries in `dir`, least recently used first (nothing when it cannot be read).
pub fn entries_in(dir: &Path) -> Vec<Entry> {
    let mut found: Vec<Entry> = std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .filter_map(|e| {
            let name = e.file_name().into_string().ok()?;
            let kind = entry_kind(&name)?.to_string();
            let meta = e.metadata().ok().filter(|m| m.is_file())?;
            Some(Entry {
                path: e.path(),
                kind,
                bytes: meta.len(),
                used: meta.modified().unwrap_or(SystemTime::UNIX_EPOCH),
            })
        })
        .collect();
    found.sort_by(|a, b| a.used.cmp(&b.used).then_with(|| a.path.cmp(&b.path)));
    found
}

/// Removes the least recently used of weft's entries in `dir` until they hold at most `max`
/// bytes together, never `keep` (the entry just written), and the temporaries of runs killed
/// over an hour ago. Files that are not weft's are never touched. Returns the entries removed.
pub fn trim_in(dir: &Path, max: u64, keep: Option<&Path>) -> Vec<Entry> {
    let now = SystemTime::now();
    for tmp in temporaries_in(dir) {
        let stale = std::fs::metadata(&tmp)
            .and_then(|m| m.modified())
            .is_ok_and(|t| now.duration_since(t).is_ok_and(|age| age > STALE_TEMPORARY));
        if stale {
            let _ = std::fs::remove_file(tmp);
        }
    }
    let entries = entries_in(dir);
    let mut total: u64 = entries.iter().map(|e| e.bytes).sum();
    let mut removed = Vec::new();
    for e in entries {
        if total <= max {
            break;
        }
        if keep == Some(e.path.as_path()) {
            continue;
        }
        // Another run may have removed it first: then its bytes are gone all the same.
        let _ = std::fs::remove_file(&e.path);
        total -= e.bytes;
        removed.push(e);
    }
    if !removed.is_empty() {
        note(format_args!(
            "{} least recently used entries removed to keep {} under {max} bytes",
            removed.len(),
            dir.display()
        ));
    }
    removed
}

/// Removes every one of weft's entries and temporaries in `dir` (nothing else); returns the
/// entries removed.
pub fn clear_in(dir: &Path) -> Vec<Entry> {
    for tmp in temporaries_in(dir) {
        let _ = std::fs::remove_file(tmp);
    }
    entries_in(dir)
        .into_iter()
        .filter(|e| std::fs::remove_file(&e.path).is_ok())
        .collect()
}

/// The file of entry (`kind`, `key`) in `dir`.
pub fn path_in(dir: &Path, kind: &str, key: &[u8]) -> PathBuf {
    let hash = Sha256::digest(key);
    let hex: String = hash[..8].iter().map(|b| format!("{b:02x}")).collect();
    dir.join(format!("{kind}-{hex}.bin"))
}

fn note(what: std::fmt::Arguments) {
    if std::env::var_os("WEFT_CACHE_VERBOSE").is_some() {
        eprintln!("weft cache: {what}");
    }
}

/// The payload of entry (`kind`, `key`), if the cache holds a sound one.
pub fn read(kind: &str, key: &[u8]) -> Option<Vec<u8>> {
    read_in(&dir()?, kind, key)
}

/// [`read`] from `dir`.
pub fn read_in(dir: &Path, kind: &str, key: &[u8]) -> Option<Vec<u8>> {
    let path = path_in(dir, kind, key);
    let bytes = std::fs::read(&path).ok()?;
    match decode(&bytes, kind, key) {
        Ok(payload) => {
            // Used now: the last to go when the cache is trimmed (a read-only cache stays as it is).
            let _ = std::fs::File::options()
                .append(true)
                .open(&path)
                .and_then(|f| f.set_modified(SystemTime::now()));
            Some(payload.to_vec())
        }
        Err(why) => {
            note(format_args!("{} not used: {why}", path.display()));
            None
        }
    }
}

/// Stores `payload` as entry (`kind`, `key`); false (and nothing changed) when it cannot.
pub fn write(kind: &str, key: &[u8], payload: &[u8]) -> bool {
    dir().is_some_and(|d| write_in(&d, kind, key, payload))
}

/// [`write`] into `dir`, its entries then trimmed to [`max_size`].
pub fn write_in(dir: &Path, kind: &str, key: &[u8], payload: &[u8]) -> bool {
    write_limited_in(dir, kind, key, payload, max_size())
}

/// [`write_in`] with the cache's size limit `max`: an entry larger than the whole cache is not
/// written; after a write the least recently used others go until the entries fit.
pub fn write_limited_in(dir: &Path, kind: &str, key: &[u8], payload: &[u8], max: u64) -> bool {
    let path = path_in(dir, kind, key);
    let record = encode(kind, key, payload);
    if record.len() as u64 > max {
        note(format_args!(
            "{} not written: {} bytes, over the cache's limit of {max} (WEFT_CACHE_MAX_SIZE)",
            path.display(),
            record.len()
        ));
        return false;
    }
    let tmp = path.with_extension(format!("tmp{}", std::process::id()));
    let result = std::fs::create_dir_all(dir)
        .and_then(|_| std::fs::write(&tmp, record))
        .and_then(|_| std::fs::rename(&tmp, &path));
    if let Err(e) = &result {
        let _ = std::fs::remove_file(&tmp);
        note(format_args!("cannot write {}: {e}", path.display()));
        return false;
    }
    trim_in(dir, max, Some(&path));
    true
}

/// The record of (`kind`, `key`, `payload`).
pub fn encode(kind: &str, key: &[u8], payload: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(64 + kind.len() + key.len() + payload.len());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&(kind.len() as u32).to_le_bytes());
    out.extend_from_slice(kind.as_bytes());
    out.extend_from_slice(&(key.len() as u32).to_le_bytes());
    out.extend_from_slice(key);
    out.extend_from_slice(&(payload.len() as u64).to_le_bytes());
    out.extend_from_slice(&Sha256::digest(payload));
    out.extend_from_slice(payload);
    out
}

/// The payload of a record, if it is whole, of `kind` and for `key`; else why not.
pub fn decode<'a>(bytes: &'a [u8], kind: &str, key: &[u8]) -> Result<&'a [u8], &'static str> {
    let mut rest = bytes;
    let mut take = |n: usize| -> Result<&'a [u8], &'static str> {
        if rest.len() < n {
            return Err("the file ends early");
        }
        let (head, tail) = rest.split_at(n);
        rest = tail;
        Ok(head)
    };
    if take(8)? != MAGIC {
        return Err("not a weft cache file");
    }
    let len = |b: &[u8]| u32::from_le_bytes(b.try_into().expect("4 bytes")) as usize;
    let n = len(take(4)?);
    if take(n)? != kind.as_bytes() {
        return Err("another kind of entry");
    }
    let n = len(take(4)?);
    if take(n)? != key {
        return Err("made for another key (device, driver, input or weft)");
    }
    let size = u64::from_le_bytes(take(8)?.try_into().expect("8 bytes"));
    if size > MAX_PAYLOAD {
        return Err("a payload larger than any weft writes");
    }
    let sum = take(32)?;
    let payload = take(size as usize)?;
    if !rest.is_empty() {
        return Err("bytes after the payload");
    }
    if Sha256::digest(payload).as_slice() != sum {
        return Err("the payload does not match its checksum");
    }
    Ok(payload)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_record_reads_back_and_every_damage_is_refused() {
        let good = encode("pipelines", b"device 1", b"payload bytes");
        assert_eq!(
            decode(&good, "pipelines", b"device 1"),
            Ok(&b"payload bytes"[..])
        );
        assert!(decode(&good, "environment", b"device 1").is_err());
        assert!(decode(&good, "pipelines", b"device 2").is_err());
        // Every truncation, and every single flipped bit, is refused (never a panic).
        for n in 0..good.len() {
            assert!(
                decode(&good[..n], "pipelines", b"device 1").is_err(),
                "cut at {n}"
            );
        }
        for i in 0..good.len() {
            for bit in 0..8 {
                let mut bad = good.clone();
                bad[i] ^= 1 << bit;
                assert!(
                    decode(&bad, "pipelines", b"device 1").is_err(),
                    "byte {i} bit {bit}"
                );
            }
        }
        let mut long = good.clone();
        long.push(0);
        assert!(decode(&long, "pipelines", b"device 1").is_err());
    }

    #[test]
    fn writes_replace_whole_files_in_the_directory_given() {
        let dir = std::env::temp_dir().join(format!("weft-cache-test-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        assert_eq!(read_in(&dir, "k", b"key"), None);
        assert!(write_in(&dir, "k", b"key", b"one"));
        assert_eq!(read_in(&dir, "k", b"key").as_deref(), Some(&b"one"[..]));
        assert!(write_in(&dir, "k", b"key", b"two, longer"));
        assert_eq!(
            read_in(&dir, "k", b"key").as_deref(),
            Some(&b"two, longer"[..])
        );
        // A file garbled on disk is not used.
        std::fs::write(path_in(&dir, "k", b"key"), b"WEFTCAC1 garbage").unwrap();
        assert_eq!(read_in(&dir, "k", b"key"), None);
        // Only the entry's own file is there (no temporary left behind).
        let names: Vec<_> = std::fs::read_dir(&dir).unwrap().flatten().collect();
        assert_eq!(names.len(), 1);
        // A directory that cannot be made (a file in the way) is no cache, not an error.
        let blocked = dir.join("file");
        std::fs::write(&blocked, b"x").unwrap();
        assert!(!write_in(&blocked.join("sub"), "k", b"key", b"one"));
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn sizes_read_as_mesa_reads_them() {
        assert_eq!(parse_size("1048576"), Some(1 << 20));
        assert_eq!(parse_size("512M"), Some(512 << 20));
        assert_eq!(parse_size(" 2g "), Some(2 << 30));
        assert_eq!(parse_size("64K"), Some(64 << 10));
        assert_eq!(parse_size("3GiB"), Some(3 << 30));
        assert_eq!(parse_size("10MB"), Some(10 << 20));
        assert_eq!(parse_size("0"), Some(0));
        for bad in [
            "",
            "M",
            "-1G",
            "1.5G",
            "12T",
            "lots",
            "1 G B",
            "99999999999999999999G",
        ] {
            assert_eq!(parse_size(bad), None, "{bad:?}");
        }
    }

    #[test]
    fn the_least_recently_used_go_first_and_only_weft_files_are_touched() {
        let dir = tempfile::tempdir().expect("a temporary directory");
        let dir = dir.path();
        let t0 = SystemTime::now() - Duration::from_secs(10_000);
        let age = |path: &Path, seconds: u64| {
            std::fs::File::options()
                .append(true)
                .open(path)
                .unwrap()
                .set_modified(t0 + Duration::from_secs(seconds))
                .unwrap();
        };
        let payload = vec![7u8; 1000];
        let unlimited = u64::MAX;
        for (i, key) in [b"a", b"b", b"c"].iter().enumerate() {
            assert!(write_limited_in(
                dir,
                "environment",
                *key,
                &payload,
                unlimited
            ));
            age(&path_in(dir, "environment", *key), 100 * i as u64);
        }
        let record = entries_in(dir)[0].bytes;
        assert_eq!(entries_in(dir).len(), 3);
        // Files that are not weft's entries, and a temporary of a run killed long ago and one
        // being written now.
        std::fs::write(dir.join("notes.txt"), b"the user's").unwrap();
        std::fs::write(dir.join("environment-0123.bin"), b"not ours: short hash").unwrap();
        let old_tmp = path_in(dir, "spirv", b"x").with_extension("tmp41");
        let new_tmp = path_in(dir, "spirv", b"y").with_extension("tmp42");
        std::fs::write(&old_tmp, b"half").unwrap();
        std::fs::write(&new_tmp, b"half").unwrap();
        age(&old_tmp, 0);

        // Reading "a" makes it the most recently used: "b" is now the oldest.
        assert!(read_in(dir, "environment", b"a").is_some());
        // A fourth entry with room for three: "b" goes, the one just written stays.
        assert!(write_limited_in(
            dir,
            "environment",
            b"d",
            &payload,
            3 * record
        ));
        let kept = |k: &[u8]| path_in(dir, "environment", k).exists();
        assert!(kept(b"a") && !kept(b"b") && kept(b"c") && kept(b"d"));
        assert!(!old_tmp.exists() && new_tmp.exists());
        assert!(dir.join("notes.txt").exists() && dir.join("environment-0123.bin").exists());
        // Room for one: only the entry just written is left.
        assert!(write_limited_in(dir, "pipelines", b"e", &payload, record));
        assert_eq!(entries_in(dir).len(), 1);
        assert!(path_in(dir, "pipelines", b"e").exists());
        // An entry larger than the whole cache is not written, and nothing is removed for it.
        assert!(!write_limited_in(
            dir,
            "environment",
            b"f",
            &payload,
            record - 1
        ));
        assert!(!path_in(dir, "environment", b"f").exists());
        assert_eq!(entries_in(dir).len(), 1);
        // Clearing removes weft's entries and temporaries, nothing else.
        assert_eq!(clear_in(dir).len(), 1);
        assert!(entries_in(dir).is_empty() && !new_tmp.exists());
        let left: Vec<_> = std::fs::read_dir(dir).unwrap().flatten().collect();
        assert_eq!(left.len(), 2, "{left:?}");
    }
}
