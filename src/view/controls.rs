//! What the panel edits, as plain functions: the panel calls these, and so do the tests
//! (tests/view.rs changes a fabric parameter through [`set_fabric`] and [`apply`]).

use crate::fabric::FabricParams;
use crate::render::plan::weave_key;
use crate::render::{GpuScene, Renderer};
use crate::scene::Scene;
use crate::Error;

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
