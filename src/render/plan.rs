//! The plan: what a frame needs, computed from the scene and the render options before any GPU
//! work. The frame runs exactly the passes listed here; `weft plan` prints it and tests assert on
//! it. (Filament's variant filtering is the model: features no material uses are not compiled in.)

use std::fmt;

use crate::scene::{LightKind, Scene};

use super::{DebugView, RenderOptions};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pass {
    /// Raster pass writing the G-buffer targets and depth.
    GBuffer,
    /// Fullscreen pass: lights x materials from the G-buffer into the HDR target.
    Lighting,
    /// Exposure, tone curve and sRGB encoding into the 8-bit target.
    Tonemap,
}

impl Pass {
    pub fn name(self) -> &'static str {
        match self {
            Pass::GBuffer => "gbuffer",
            Pass::Lighting => "lighting",
            Pass::Tonemap => "tonemap",
        }
    }
}

/// How many lights of each kind the scene has.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LightCounts {
    pub directional: usize,
    pub point: usize,
    pub spot: usize,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    pub width: u32,
    pub height: u32,
    pub passes: Vec<Pass>,
    pub draws: usize,
    pub triangles: usize,
    pub lights: LightCounts,
    /// Materials that use the fabric model (the rest use glTF metallic-roughness).
    pub fabric_materials: usize,
    pub textures: usize,
    pub debug_view: DebugView,
}

impl Plan {
    pub fn new(scene: &Scene, options: &RenderOptions) -> Plan {
        let mut lights = LightCounts::default();
        for l in &scene.lights {
            match l.kind {
                LightKind::Directional => lights.directional += 1,
                LightKind::Point => lights.point += 1,
                LightKind::Spot { .. } => lights.spot += 1,
            }
        }
        let triangles = scene
            .draws
            .iter()
            .map(|d| scene.meshes[d.mesh].indices.len() / 3)
            .sum();
        Plan {
            width: options.width,
            height: options.height,
            passes: vec![Pass::GBuffer, Pass::Lighting, Pass::Tonemap],
            draws: scene.draws.len(),
            triangles,
            lights,
            fabric_materials: scene
                .materials
                .iter()
                .filter(|m| m.fabric.is_some())
                .count(),
            textures: scene.textures.len(),
            debug_view: options.debug_view,
        }
    }

    pub fn runs(&self, pass: Pass) -> bool {
        self.passes.contains(&pass)
    }
}

impl fmt::Display for Plan {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "output      {}x{}", self.width, self.height)?;
        writeln!(
            f,
            "passes      {}",
            self.passes
                .iter()
                .map(|p| p.name())
                .collect::<Vec<_>>()
                .join(" -> ")
        )?;
        writeln!(
            f,
            "draws       {} ({} triangles)",
            self.draws, self.triangles
        )?;
        writeln!(
            f,
            "lights      {} directional, {} point, {} spot",
            self.lights.directional, self.lights.point, self.lights.spot
        )?;
        writeln!(f, "materials   {} fabric", self.fabric_materials)?;
        writeln!(f, "textures    {}", self.textures)?;
        write!(f, "debug view  {}", self.debug_view.name())
    }
}
