//! Writing the package to a directory, and removing what an earlier package left there.

use std::path::{Path, PathBuf};

use super::{manifest, Manifest, INCLUDES, MANIFEST_FILE};
use crate::vk::shaders;
use crate::Error;

/// Writes the package into `dir` (created if missing): every module as `<name>.spv`,
/// `manifest.json`, `include/*.glsl` and `README.md`. Files an earlier package in `dir` listed
/// and this one does not are removed; nothing else in `dir` is touched.
pub fn write_package(dir: &Path) -> crate::Result<Manifest> {
    let manifest = manifest()?;
    std::fs::create_dir_all(dir.join("include"))
        .map_err(io(format!("creating {}", dir.join("include").display())))?;
    remove_stale_files(dir, &manifest)?;
    for shader in shaders::ALL {
        write(&dir.join(format!("{}.spv", shader.name)), shader.spirv)?;
    }
    for (name, text) in INCLUDES {
        write(&dir.join("include").join(name), text.as_bytes())?;
    }
    write(&dir.join(MANIFEST_FILE), manifest.to_json().as_bytes())?;
    write(&dir.join("README.md"), manifest.readme().as_bytes())?;
    Ok(manifest)
}

fn io(context: String) -> impl FnOnce(std::io::Error) -> Error {
    move |source| Error::Io { context, source }
}

fn write(path: &Path, bytes: &[u8]) -> crate::Result<()> {
    crate::render::write_file(path, bytes)
}

/// Removes the files that the manifest already in `dir` lists and `new` does not (a module
/// renamed or deleted since), so the package never carries a stale module.
fn remove_stale_files(dir: &Path, new: &Manifest) -> crate::Result<()> {
    let Ok(old) = std::fs::read_to_string(dir.join(MANIFEST_FILE)) else {
        return Ok(());
    };
    let Ok(old) = serde_json::from_str::<serde_json::Value>(&old) else {
        return Ok(());
    };
    let listed = |v: &serde_json::Value, key: &str| -> Vec<String> {
        v[key]
            .as_array()
            .into_iter()
            .flatten()
            .filter_map(|e| e["file"].as_str().map(String::from))
            .collect()
    };
    let keep: Vec<&str> = new
        .modules
        .iter()
        .map(|m| m.file.as_str())
        .chain(new.includes.iter().map(|f| f.file.as_str()))
        .collect();
    for file in listed(&old, "modules")
        .into_iter()
        .chain(listed(&old, "includes"))
    {
        // Only plain relative paths inside the package (the old manifest is data, not trusted).
        let path = PathBuf::from(&file);
        let inside = path
            .components()
            .all(|c| matches!(c, std::path::Component::Normal(_)));
        if inside && !keep.contains(&file.as_str()) {
            let p = dir.join(&path);
            if p.is_file() {
                std::fs::remove_file(&p).map_err(io(format!("removing stale {}", p.display())))?;
            }
        }
    }
    Ok(())
}
