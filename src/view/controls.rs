//! What the panel edits, as plain functions: the panel calls these, and so do the tests
//! (tests/view.rs changes a fabric parameter through [`set_fabric`] and [`apply`]).

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
    variant: Option<String>,
    lights: LightsMode,
    env_rotation: f32,
    own_env: bool,
) -> crate::Result<Scene> {
    let load = LoadOptions {
        variant: variant.clone(),
    };
    let mut scene = match source {
        SceneSource::File(path) => {
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
            crate::scene::load_with(path, &load)?
        }
        SceneSource::Builtin if variant.is_none() => crate::scene::default_scene(),
        SceneSource::Builtin => crate::scene::load_slice_with(
            crate::scene::DEFAULT_SCENE_GLB,
            "built-in default scene",
            None,
            &load,
        )?,
    };
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
    /// weave UVs of the vertices are offset by whole repeats), so the scene is uploaded again,
    /// which rebuilds the weave textures.
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
    } else if weave_key(old) == weave_key(&new) && old.repeat_uv() == new.repeat_uv() {
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
