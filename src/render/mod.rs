//! Rendering: the plan, the passes of a frame, and writing images.

mod frame;
pub mod gpu;
mod output;
pub mod plan;

pub use frame::{f16_to_f32, Frame, FrameStats, GBufferReadback, GpuScene, PassTiming, Renderer};
pub use output::{write_exr, write_png};
pub use plan::{Pass, Plan};

use crate::Error;

/// The largest output the renderer accepts on either side, before asking the device.
pub const MAX_SIZE: u32 = 16384;

/// What the G-buffer debug views show instead of the lit image.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[repr(u32)]
pub enum DebugView {
    #[default]
    None = 0,
    Albedo = 1,
    Normals = 2,
    Tangents = 3,
    RoughnessMetallic = 4,
    Coverage = 5,
    ThreadDir = 6,
    Depth = 7,
}

impl DebugView {
    pub const ALL: [DebugView; 8] = [
        DebugView::None,
        DebugView::Albedo,
        DebugView::Normals,
        DebugView::Tangents,
        DebugView::RoughnessMetallic,
        DebugView::Coverage,
        DebugView::ThreadDir,
        DebugView::Depth,
    ];

    pub fn name(self) -> &'static str {
        match self {
            DebugView::None => "none",
            DebugView::Albedo => "albedo",
            DebugView::Normals => "normals",
            DebugView::Tangents => "tangents",
            DebugView::RoughnessMetallic => "roughness-metallic",
            DebugView::Coverage => "coverage",
            DebugView::ThreadDir => "thread-dir",
            DebugView::Depth => "depth",
        }
    }

    pub fn parse(text: &str) -> crate::Result<DebugView> {
        DebugView::ALL.iter().copied().find(|v| v.name() == text).ok_or_else(|| {
            Error::input(format!(
                "unknown debug view '{text}': choose one of {}",
                DebugView::ALL.iter().map(|v| v.name()).collect::<Vec<_>>().join(", ")
            ))
        })
    }
}

#[derive(Clone, Debug)]
pub struct RenderOptions {
    pub width: u32,
    pub height: u32,
    /// Index of the scene's camera; None = the first camera, or automatic framing.
    pub camera: Option<usize>,
    /// A camera given directly (e.g. by --eye/--target); overrides `camera`.
    pub camera_override: Option<crate::scene::Camera>,
    /// Exposure in EV: the HDR radiance is scaled by 2^exposure before tone mapping.
    pub exposure: f32,
    pub debug_view: DebugView,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            width: 1280,
            height: 720,
            camera: None,
            camera_override: None,
            exposure: 0.0,
            debug_view: DebugView::None,
        }
    }
}

impl RenderOptions {
    pub fn validate(&self) -> crate::Result<()> {
        if self.width == 0 || self.height == 0 || self.width > MAX_SIZE || self.height > MAX_SIZE {
            return Err(Error::input(format!(
                "output size {}x{} is out of range: each side must be between 1 and {MAX_SIZE} (e.g. --size 1920x1080)",
                self.width, self.height
            )));
        }
        if !self.exposure.is_finite() || self.exposure.abs() > 64.0 {
            return Err(Error::input(format!(
                "exposure {} EV is out of range: use a finite value between -64 and 64",
                self.exposure
            )));
        }
        Ok(())
    }
}

/// Parses `X,Y,Z`, e.g. `0,1.5,3.5`.
pub fn parse_vec3(what: &str, text: &str) -> crate::Result<glam::Vec3> {
    let bad = || Error::input(format!("{what} '{text}' is not three comma-separated numbers X,Y,Z (e.g. 0,1.5,3.5)"));
    let parts: Vec<f32> = text.split(',').map(|p| p.trim().parse::<f32>()).collect::<Result<_, _>>().map_err(|_| bad())?;
    match parts[..] {
        [x, y, z] if x.is_finite() && y.is_finite() && z.is_finite() => Ok(glam::Vec3::new(x, y, z)),
        _ => Err(bad()),
    }
}

/// Parses `WxH`, e.g. `1920x1080`.
pub fn parse_size(text: &str) -> crate::Result<(u32, u32)> {
    let bad = || Error::input(format!("size '{text}' is not WIDTHxHEIGHT (e.g. 1920x1080)"));
    let (w, h) = text.split_once(['x', 'X']).ok_or_else(bad)?;
    let w: u32 = w.trim().parse().map_err(|_| bad())?;
    let h: u32 = h.trim().parse().map_err(|_| bad())?;
    Ok((w, h))
}
