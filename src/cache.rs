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

use std::path::{Path, PathBuf};

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
        Ok(payload) => Some(payload.to_vec()),
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

/// [`write`] into `dir`.
pub fn write_in(dir: &Path, kind: &str, key: &[u8], payload: &[u8]) -> bool {
    let path = path_in(dir, kind, key);
    let tmp = path.with_extension(format!("tmp{}", std::process::id()));
    let result = std::fs::create_dir_all(dir)
        .and_then(|_| std::fs::write(&tmp, encode(kind, key, payload)))
        .and_then(|_| std::fs::rename(&tmp, &path));
    if let Err(e) = &result {
        let _ = std::fs::remove_file(&tmp);
        note(format_args!("cannot write {}: {e}", path.display()));
    }
    result.is_ok()
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
}
