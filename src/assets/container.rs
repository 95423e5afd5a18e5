//! The glTF container (`.gltf` JSON or `.glb` with its BIN chunk) and the external files it
//! names.

use std::fmt;
use std::path::{Component, Path, PathBuf};

use serde_json::Value;

use crate::{Error, Result};

/// A glTF file split into its JSON and, for `.glb`, its BIN chunk (kept as bytes).
#[derive(Clone, Debug)]
pub struct Container {
    pub json: Value,
    pub bin: Option<Vec<u8>>,
    pub glb: bool,
}

impl Container {
    /// Splits a `.gltf` or `.glb` file. The loader has accepted the bytes first
    /// ([`transform`]), so only what it does not check is reported here.
    pub fn split(bytes: &[u8], source: &str) -> Result<Container> {
        let broken = |why: String| Error::input(format!("'{source}': {why}"));
        if bytes.starts_with(b"glTF") {
            // gltf::Glb subtracts the header size from the declared length unchecked.
            let declared = bytes
                .get(8..12)
                .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
            if declared.is_none_or(|l| l < 12) {
                return Err(broken("the .glb header is broken".into()));
            }
            let glb = gltf::Glb::from_slice(bytes)
                .map_err(|e| broken(format!("the .glb container is broken ({e})")))?;
            let json = serde_json::from_slice(&glb.json)
                .map_err(|e| broken(format!("the JSON chunk does not parse ({e})")))?;
            Ok(Container {
                json,
                bin: glb.bin.map(|b| b.into_owned()),
                glb: true,
            })
        } else {
            let text = bytes
                .strip_prefix(b"\xEF\xBB\xBF".as_slice())
                .unwrap_or(bytes);
            let json = serde_json::from_slice(text)
                .map_err(|e| broken(format!("the JSON does not parse ({e})")))?;
            Ok(Container {
                json,
                bin: None,
                glb: false,
            })
        }
    }

    /// The file's bytes: pretty JSON for `.gltf`; for `.glb` compact JSON and the BIN chunk as it
    /// was (gltf::Glb pads the JSON chunk with spaces as the specification asks).
    pub fn to_bytes(&self) -> Result<Vec<u8>> {
        let internal = |e: &dyn fmt::Display| Error::input(format!("cannot write the glTF: {e}"));
        if !self.glb {
            let mut text = serde_json::to_vec_pretty(&self.json).map_err(|e| internal(&e))?;
            text.push(b'\n');
            return Ok(text);
        }
        let json = serde_json::to_vec(&self.json).map_err(|e| internal(&e))?;
        gltf::Glb {
            header: gltf::binary::Header {
                magic: *b"glTF",
                version: 2,
                length: 0, // to_writer computes it
            },
            json: json.into(),
            bin: self.bin.as_deref().map(Into::into),
        }
        .to_vec()
        .map_err(|e| internal(&e))
    }
}

/// The relative file URIs (buffers and images) of a `.gltf`, percent-decoded; data: URIs and
/// the BIN chunk are not files.
pub fn external_files(doc: &Value) -> Vec<String> {
    let mut out = Vec::new();
    for list in ["buffers", "images"] {
        for item in doc
            .get(list)
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
        {
            if let Some(uri) = item.get("uri").and_then(Value::as_str) {
                if uri.starts_with("data:") {
                    continue;
                }
                let decoded = urlencoding::decode_binary(uri.as_bytes());
                let path = String::from_utf8_lossy(&decoded).into_owned();
                if !out.contains(&path) {
                    out.push(path);
                }
            }
        }
    }
    out
}

/// Copies the external files of a `.gltf` from `from` to `to` (the output's folder), so that the
/// copy's unchanged URIs resolve. Files already there with the same bytes are left; different
/// ones are an error (nothing is overwritten). URIs that leave the folder (`..`, absolute) are
/// an error unless `from` and `to` are the same folder. Returns the files copied.
pub fn copy_external_files(doc: &Value, from: &Path, to: &Path) -> Result<Vec<PathBuf>> {
    let same = match (from.canonicalize(), to.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    };
    let mut copied = Vec::new();
    if same {
        return Ok(copied);
    }
    for rel in external_files(doc) {
        let p = Path::new(&rel);
        let inside = !rel.contains(':')
            && p.components()
                .all(|c| matches!(c, Component::Normal(_) | Component::CurDir));
        if !inside {
            return Err(Error::input(format!(
                "the file refers to '{rel}', outside its own folder; write the output into the input's folder (-o {}/NAME.gltf) so that the reference still resolves",
                from.display()
            )));
        }
        let p: PathBuf = p
            .components()
            .filter(|c| !matches!(c, Component::CurDir))
            .collect();
        let src = from.join(&p);
        let dst = to.join(&p);
        let bytes = std::fs::read(&src).map_err(|e| {
            Error::input(format!(
                "cannot read '{}' (referenced by the file): {e}",
                src.display()
            ))
        })?;
        if let Ok(existing) = std::fs::read(&dst) {
            if existing == bytes {
                continue;
            }
            return Err(Error::input(format!(
                "'{}' exists and differs from the input's '{}'; the copy's reference to '{rel}' would resolve to the wrong file: choose another output folder",
                dst.display(),
                src.display()
            )));
        }
        if let Some(parent) = dst.parent() {
            std::fs::create_dir_all(parent)
                .map_err(|e| Error::input(format!("cannot create '{}': {e}", parent.display())))?;
        }
        std::fs::write(&dst, &bytes)
            .map_err(|e| Error::input(format!("cannot write '{}': {e}", dst.display())))?;
        copied.push(dst);
    }
    Ok(copied)
}
