//! What the panel edits, as plain functions: the panel calls these, and so do the tests
//! (tests/view.rs changes a fabric parameter through [`set_fabric`] and [`apply`]).

use std::path::{Path, PathBuf};

use crate::assets::{self, Applied, MaterialRef, Overrides, Request, Source};
use crate::env::LightsMode;
use crate::fabric::FabricParams;
use crate::render::plan::weave_key;
use crate::render::{GpuScene, Renderer};
use crate::scene::{LoadOptions, Scene};
use crate::Error;

use super::SceneSource;

/// Loads a scene for the viewer (a file dropped on the window, another variant) and stages it as
/// `weft render` does (`env::stage`: the default key light and ground when it has no lights).
/// An error names the file and leaves the caller's current scene as it is.
pub fn load(
    source: &SceneSource,
    options: LoadOptions,
    lights: LightsMode,
    env_rotation: f32,
    own_env: bool,
) -> crate::Result<Scene> {
    if let SceneSource::File(path) = source {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        if !matches!(ext.as_deref(), Some("gltf") | Some("glb")) {
            return Err(Error::input(format!(
                "{} is not a .gltf or .glb file: drop a glTF scene on the window",
                path.display()
            )));
        }
    }
    let spec = crate::spec::SceneSpec {
        scene: match source {
            SceneSource::File(path) => Some(path.clone()),
            SceneSource::Builtin => None,
        },
        variant: options.variant,
        gltf_scene: options.scene,
        ..Default::default()
    };
    let (mut scene, _) = spec.load_unstaged()?;
    crate::env::stage(&mut scene, lights, env_rotation, own_env);
    Ok(scene)
}

/// What an edit of a material needs on the GPU.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MaterialUpdate {
    /// Nothing changed.
    None,
    /// Only the material records (colours, exponents, specular): rewritten in place, no texture
    /// or geometry touched.
    Records,
    /// The weave changed (pattern, gap, shadow width or strength) or its repeat (the pitch: the
    /// weave UVs of the vertices are offset by whole repeats), or the cloth became or stopped
    /// being a single sheet (which pass draws it), so the scene is uploaded again, which rebuilds
    /// the weave textures.
    Weave,
}

/// The materials of `scene` that are fabric, by index, with their names.
pub fn fabric_materials(scene: &Scene) -> Vec<(usize, String)> {
    scene
        .materials
        .iter()
        .enumerate()
        .filter(|(_, m)| m.fabric.is_some())
        .map(|(i, m)| {
            let name = if m.name.is_empty() {
                format!("material {i}")
            } else {
                m.name.clone()
            };
            (i, name)
        })
        .collect()
}

/// Gives material `material` of `scene` the fabric parameters `params` (sanitized, as the
/// renderer would use them) and says what the GPU scene then needs.
pub fn set_fabric(
    scene: &mut Scene,
    material: usize,
    params: &FabricParams,
) -> crate::Result<MaterialUpdate> {
    let count = scene.materials.len();
    let m = scene.materials.get_mut(material).ok_or_else(|| {
        Error::input(format!(
            "material {material} does not exist: the scene has {count} material(s)"
        ))
    })?;
    let old = m.fabric.as_ref().ok_or_else(|| {
        Error::input(format!(
            "material {material} ('{}') is not a fabric material",
            m.name
        ))
    })?;
    let new = params.sanitized();
    let update = if *old == new {
        MaterialUpdate::None
    } else if weave_key(old) == weave_key(&new)
        && old.repeat_uv() == new.repeat_uv()
        // A sheet is drawn by the transparent pass, any other cloth by the G-buffer pass: which
        // pass draws it is decided at upload.
        && old.transmission.is_some() == new.transmission.is_some()
    {
        MaterialUpdate::Records
    } else {
        MaterialUpdate::Weave
    };
    m.fabric = Some(new);
    Ok(update)
}

/// Brings the uploaded `gpu` scene up to date with `scene` after an edit.
pub fn apply(
    renderer: &Renderer,
    scene: &Scene,
    gpu: &mut GpuScene,
    update: MaterialUpdate,
) -> crate::Result<()> {
    match update {
        MaterialUpdate::None => Ok(()),
        MaterialUpdate::Records => renderer.update_material_records(scene, gpu),
        MaterialUpdate::Weave => {
            *gpu = renderer.upload(scene)?;
            Ok(())
        }
    }
}

// ---- Authoring: weave any material and save the file `weft fabric` would write ----

/// Every material of `scene` its file gave it (not those the loader or staging added:
/// [`Scene::file_materials`]), by index, with a name for the panel.
pub fn file_materials(scene: &Scene) -> Vec<(usize, String)> {
    scene
        .materials
        .iter()
        .enumerate()
        .take(scene.file_materials)
        .map(|(i, m)| {
            let name = if m.name.is_empty() {
                format!("material {i}")
            } else {
                format!("{i}: {}", m.name)
            };
            (i, name)
        })
        .collect()
}

/// The file behind `source` ([`assets::scene_bytes`]).
fn source_bytes(source: &SceneSource) -> crate::Result<(Vec<u8>, String, Option<PathBuf>)> {
    assets::scene_bytes(match source {
        SceneSource::File(path) => Some(path.as_path()),
        SceneSource::Builtin => None,
    })
}

/// What `weft fabric --material INDEX --preset PRESET [--draft FILE]` asks, for the panel's
/// "weave": the preset at its own pitch (the mesh's UV density converts it), the draft's weave
/// and thread colours over it. Returns the request and the draft's warnings.
pub fn weave_request(
    material: usize,
    preset: &str,
    draft: Option<&Path>,
) -> crate::Result<(Request, Vec<String>)> {
    let mut overrides = Overrides::default();
    let mut warnings = Vec::new();
    if let Some(path) = draft {
        let d = crate::fabric::draft::Draft::load(path)?;
        warnings = overrides.apply_draft(&d);
    }
    Ok((
        Request {
            materials: vec![MaterialRef::parse(&material.to_string())],
            source: Source::parse(preset)?,
            overrides,
        },
        warnings,
    ))
}

/// The request that writes `params` on material `material` exactly (the panel's live edits),
/// measured on `scene`'s meshes. It keeps the source of the material's earlier request in
/// `requests` (a preset: its fallback is written again for the new parameters; from-sheen: the
/// sheen stays, its colour texture still the threads'); a fabric the file already had is
/// written as tuned with the rest of the material untouched ([`Source::Exact`]).
pub fn exact_request(
    scene: &Scene,
    requests: &[Request],
    material: usize,
    params: &FabricParams,
) -> crate::Result<Request> {
    let density = assets::uv_density(scene, material, &format!("material {material}"))?;
    let me = MaterialRef::Index(material);
    let source = requests
        .iter()
        .find(|r| r.materials.contains(&me))
        .map_or(Source::Exact, |r| r.source.clone());
    Ok(Request {
        materials: vec![me],
        source,
        overrides: Overrides::exact(params, &density),
    })
}

/// Puts `request` in `requests` in place of any earlier one for the same materials.
pub fn replace_request(requests: &mut Vec<Request>, request: Request) {
    let same = |r: &Request| {
        r.materials.iter().any(|m| {
            request
                .materials
                .iter()
                .any(|n| format!("{m}") == format!("{n}"))
        })
    };
    requests.retain(|r| !same(r));
    requests.push(request);
}

/// Loads `source` (with `options`' variant and scene) with `requests` applied by `weft fabric`'s own transform,
/// staged as [`load`] stages it; and what was applied.
pub fn load_woven(
    source: &SceneSource,
    options: LoadOptions,
    requests: &[Request],
    lights: LightsMode,
    env_rotation: f32,
    own_env: bool,
) -> crate::Result<(Scene, Vec<Applied>)> {
    let (bytes, name, dir) = source_bytes(source)?;
    let (out, applied) = assets::transform(&bytes, &name, dir.as_deref(), requests)?;
    let mut scene = crate::scene::load_slice_with(&out, &name, dir.as_deref(), &options)?;
    crate::env::stage(&mut scene, lights, env_rotation, own_env);
    Ok((scene, applied))
}

/// Writes the file `weft fabric` would write for `requests`: beside the source as
/// `NAME-fabric.glb` (or `.gltf`, whose external files then resolve as the source's do), or for
/// the built-in scene `default-fabric.glb` in the working directory. Returns the path and what
/// was applied. Refuses to overwrite the source.
pub fn save_woven(
    source: &SceneSource,
    requests: &[Request],
) -> crate::Result<(PathBuf, Vec<Applied>)> {
    if requests.is_empty() {
        return Err(Error::input(
            "nothing to save: weave a material or change a fabric in the panel first",
        ));
    }
    let (bytes, name, dir) = source_bytes(source)?;
    let (out, applied) = assets::transform(&bytes, &name, dir.as_deref(), requests)?;
    let path = match source {
        SceneSource::File(p) => {
            let stem = p.file_stem().and_then(|s| s.to_str()).unwrap_or("scene");
            let ext = p.extension().and_then(|e| e.to_str()).unwrap_or("glb");
            p.with_file_name(format!("{stem}-fabric.{ext}"))
        }
        SceneSource::Builtin => PathBuf::from("default-fabric.glb"),
    };
    if let SceneSource::File(p) = source {
        if path == *p {
            return Err(Error::input(format!(
                "will not overwrite the source {}",
                p.display()
            )));
        }
    }
    std::fs::write(&path, out).map_err(|e| {
        Error::input(format!(
            "could not write {}: {e}; check the directory is writable",
            path.display()
        ))
    })?;
    Ok((path, applied))
}

/// The material drawn at pixel (`x`, `y`) of a frame `width` pixels wide, from its read-back
/// G-buffer (ctrl+click in the viewer); None where no surface is (the background) or the pixel
/// is outside. Surfaces drawn by the transparent pass (blended, transmissive, fabric sheets) are
/// not in the G-buffer: a click there picks what is behind them.
pub fn material_at(
    g: &crate::render::GBufferReadback,
    width: u32,
    x: u32,
    y: u32,
    scene: &Scene,
) -> Option<usize> {
    if x >= width {
        return None;
    }
    let i = (y as usize) * (width as usize) + x as usize;
    // Reversed Z: the cleared depth is 0.
    if !(*g.depth.get(i)? > 0.0) {
        return None;
    }
    let m = g.surface.get(4 * i + 1)?.round();
    (m >= 0.0 && (m as usize) < scene.materials.len()).then_some(m as usize)
}
