//! Rendering: the plan, the passes of a frame, and writing images.

pub mod deform;
mod frame;
mod passes;
mod readback;
mod targets;
mod upload;
pub mod world_light;
/// The GPU records (`crate::records`), under their old name.
pub use crate::records as gpu;
pub use crate::records::{Shading, MAX_SIZE};
pub use passes::environment;
mod output;
pub mod plan;
pub mod shadow;
pub mod tiles;

pub use crate::parse::{parse_finite, parse_vec3};
pub use deform::SkinPush;
pub use frame::{Frame, FrameStats, PassTiming, Renderer};
pub use output::{
    check_outputs, commit_all, display_note, stage_exr, stage_png, stage_png_with_text, temp_name,
    write_exr, write_file, write_frame, write_png, OutputPath, Staged, NAME_MAX, PATH_MAX,
};
pub use plan::{EnvPlan, FabricFeatures, Pass, Plan, ShadowPlan, WeavePlan};
pub use readback::{f16_to_f32, GBufferReadback};
pub use targets::{
    check_target_memory, host_available_bytes, readback_bytes_per_pixel, TARGET_BYTES_PER_PIXEL,
};
pub use upload::GpuScene;

use crate::Error;

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
    /// The environment's visibility: the occlusion pass's times the material's occlusion
    /// texture (white: open; the pass runs for this view whenever `--occlusion` is not none).
    Occlusion = 9,
}

impl DebugView {
    pub const ALL: [DebugView; 9] = [
        DebugView::None,
        DebugView::Albedo,
        DebugView::Normals,
        DebugView::Tangents,
        DebugView::RoughnessMetallic,
        DebugView::Coverage,
        DebugView::ThreadDir,
        DebugView::Depth,
        DebugView::Occlusion,
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
            DebugView::Occlusion => "occlusion",
        }
    }

    pub fn parse(text: &str) -> crate::Result<DebugView> {
        DebugView::ALL
            .iter()
            .copied()
            .find(|v| v.name() == text)
            .ok_or_else(|| {
                Error::input(format!(
                    "unknown debug view '{text}': choose one of {}",
                    DebugView::ALL
                        .iter()
                        .map(|v| v.name())
                        .collect::<Vec<_>>()
                        .join(", ")
                ))
            })
    }
}

/// The effects the plan can skip, forced on (`RenderOptions::force`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Force {
    /// Compile every light type's code in (LIGHT_TYPES = 7), not only the scene's.
    pub light_types: bool,
    /// Render a shadow map for every light that asks, even when nothing casts or receives, and
    /// compile shadow sampling in even when there is no map.
    pub shadows: bool,
    /// Evaluate every light at every pixel: no per-pixel range culling.
    pub no_range_culling: bool,
    /// Compile the vertex-colour code in (gbuffer VERTEX_COLORS = 1) with no mesh that has
    /// COLOR_0: every vertex reads white.
    pub vertex_colors: bool,
    /// Compile the KHR_materials_unlit path in (lighting UNLIT = 1) with no unlit material.
    pub unlit: bool,
    /// Compile the alphaMode MASK discard in (gbuffer ALPHA_MASK = 1) with no MASK material.
    pub alpha_mask: bool,
    /// Draw the transparent pass's opaque double-sided draws back faces first, as its blended
    /// ones are, instead of front faces first (whose depth rejects the back faces they hide).
    pub back_faces_first: bool,
    /// Fetch the weave's summed-area table texel by texel (WEAVE_SOURCE 3, what a device that
    /// cannot filter RGBA32F runs) even where the device can filter it.
    pub sat_fetch: bool,
    /// Compile the fabric-sheet code in (forward FABRIC_SHEETS = 1: light through the weave)
    /// with no sheet in the scene.
    pub fabric_sheets: bool,
    /// One G-buffer and one lighting pipeline with every kind of material's code (fabric and
    /// glTF, background), every texture slot sampled and every glTF extension's lighting compiled
    /// in, instead of a pipeline per kind with only what the scene has.
    pub material_kinds: bool,
    /// Compile the pooling of the fabric lobes' samples in (the lobe sums draw, lighting POOL =
    /// 1) where no woven pixel is shaded at fis: it must change nothing there.
    pub pool: bool,
    /// Run the G-buffer's depth pre-pass where the plan does not (fewer than
    /// `PREPASS_PIXELS_PER_TRIANGLE` pixels per opaque triangle): it must change no pixel.
    pub depth_prepass: bool,
    /// Skip the G-buffer's depth pre-pass where the plan runs it: every hidden fragment of an
    /// opaque draw is shaded (a bench comparison).
    pub no_depth_prepass: bool,
    /// Run FXAA's edge search over every pixel in one draw, instead of only on the 4 x 4 blocks
    /// that a first draw found an edge in (over the stencil): it must change no pixel.
    pub fxaa_everywhere: bool,
    /// Run the occlusion pass's estimates and blur over every pixel, empty ones included (where
    /// each writes "open, no surface"), instead of drawing them against the depth where a surface
    /// is: it must change no pixel.
    pub occlusion_everywhere: bool,
    /// Keep the occlusion pass's bounce beside the world light where the plan leaves the
    /// occluders' light to the world light alone (`OcclusionPlan::world_bounce()`): to measure
    /// what leaving it out changes.
    pub screen_bounce: bool,
    /// Keep the tonemap pass where nothing reads the HDR image and the plan has the lighting
    /// pass apply the tone curve itself (`Plan::tone_in_lighting`): to measure what the fold
    /// changes.
    pub tonemap_pass: bool,
}

impl Force {
    pub const NONE: Force = Force {
        light_types: false,
        shadows: false,
        no_range_culling: false,
        vertex_colors: false,
        unlit: false,
        alpha_mask: false,
        back_faces_first: false,
        sat_fetch: false,
        fabric_sheets: false,
        material_kinds: false,
        pool: false,
        depth_prepass: false,
        no_depth_prepass: false,
        fxaa_everywhere: false,
        occlusion_everywhere: false,
        screen_bounce: false,
        tonemap_pass: false,
    };
    pub const ALL: Force = Force {
        light_types: true,
        shadows: true,
        no_range_culling: true,
        vertex_colors: true,
        unlit: true,
        alpha_mask: true,
        back_faces_first: true,
        // Not a feature compiled in: the table's other reading, with the same values.
        sat_fetch: false,
        fabric_sheets: true,
        material_kinds: true,
        pool: true,
        // The costly reading: every hidden fragment shaded where the plan pre-passes depth.
        depth_prepass: false,
        no_depth_prepass: true,
        fxaa_everywhere: true,
        occlusion_everywhere: true,
        // Not code compiled in for nothing: a second estimate of the occluders' light, which
        // the world light's own takes the greater of (not the same image bit for bit).
        screen_bounce: false,
        // Not code compiled in for nothing: the same curve a pass later, from the HDR target's
        // half floats (not the same image bit for bit).
        tonemap_pass: false,
    };
}

/// How the fabric's weave is turned into reflectance over a pixel (model page §4).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Accuracy {
    /// One texel of the level-0 weave texture, no mips; one lobe (the thread on top).
    Nearest,
    /// Filtered coverages; one lobe with coverage-averaged exponents (cheap and wrong far away).
    FilteredParams,
    /// Filtered coverages; the two-lobe mixture of §3 (the default).
    #[default]
    Mixture,
    /// The analytic weave at N x N points of the pixel's footprint, two lobes each: converges to
    /// the ground truth as N grows.
    Supersampled(u32),
}

impl Accuracy {
    /// The largest N of `supersampled:N`.
    pub const MAX_SAMPLES: u32 = 64;

    pub fn name(self) -> String {
        match self {
            Accuracy::Nearest => "nearest".into(),
            Accuracy::FilteredParams => "filtered-params".into(),
            Accuracy::Mixture => "mixture".into(),
            Accuracy::Supersampled(n) => format!("supersampled:{n}"),
        }
    }

    pub fn parse(text: &str) -> crate::Result<Accuracy> {
        let bad = || {
            Error::input(format!(
                "unknown accuracy '{text}': choose nearest, filtered-params, mixture or supersampled:N (N from 1 to {})",
                Accuracy::MAX_SAMPLES
            ))
        };
        match text {
            "nearest" => Ok(Accuracy::Nearest),
            "filtered-params" => Ok(Accuracy::FilteredParams),
            "mixture" => Ok(Accuracy::Mixture),
            _ => {
                let n = text.strip_prefix("supersampled:").ok_or_else(bad)?;
                let n: u32 = n.parse().map_err(|_| bad())?;
                if (1..=Accuracy::MAX_SAMPLES).contains(&n) {
                    Ok(Accuracy::Supersampled(n))
                } else {
                    Err(bad())
                }
            }
        }
    }

    /// The specialization constant value (`ACCURACY` in gbuffer.frag and lighting.frag).
    pub fn code(self) -> u32 {
        match self {
            Accuracy::Nearest => 0,
            Accuracy::FilteredParams => 1,
            Accuracy::Mixture => 2,
            Accuracy::Supersampled(_) => 3,
        }
    }

    pub fn samples(self) -> u32 {
        match self {
            Accuracy::Supersampled(n) => n,
            _ => 1,
        }
    }
}

/// Where the G-buffer pass gets the weave coverage from (model page §4, precision axis).
/// How the G-buffer pass filters the weave over a pixel's footprint (the parallelogram spanned by
/// the UV derivatives).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Footprint {
    /// The footprint's axis-aligned bounding box: exact for a footprint aligned with the weave,
    /// blurred by the box's excess area where it is oblique.
    Box,
    /// An oblique footprint near or below a few cells is cut into pieces, N along its longer
    /// edge (more, up to [`Footprint::MAX_PIECES`], where it is more than N times longer than
    /// wide) and proportionally fewer along the shorter, each filtered by its own bounding box
    /// (texture probes or exact boxes): the excess shrinks N-fold.
    Parallelogram(u32),
}

impl Default for Footprint {
    fn default() -> Self {
        Footprint::Parallelogram(Footprint::DEFAULT_PIECES)
    }
}

impl Footprint {
    pub const DEFAULT_PIECES: u32 = 2;
    pub const MAX_PIECES: u32 = crate::reference::weave::single::WEAVE_MAX_PIECES;

    /// The most pieces per side (the G-buffer pass's FOOTPRINT_PIECES; 0: the box).
    pub fn pieces(self) -> u32 {
        match self {
            Footprint::Box => 0,
            Footprint::Parallelogram(n) => n.clamp(1, Footprint::MAX_PIECES),
        }
    }

    pub fn name(self) -> String {
        match self {
            Footprint::Box => "box".into(),
            Footprint::Parallelogram(n) => format!("parallelogram:{n}"),
        }
    }

    /// `box`, `parallelogram` (2 x 2 pieces) or `parallelogram:N`, N in 1..=4.
    pub fn parse(text: &str) -> crate::Result<Footprint> {
        let bad = || {
            Error::input(format!(
                "unknown footprint '{text}': choose box, parallelogram or parallelogram:N with N from 1 to {}",
                Footprint::MAX_PIECES
            ))
        };
        match text {
            "box" => Ok(Footprint::Box),
            "parallelogram" => Ok(Footprint::default()),
            _ => {
                let n: u32 = text
                    .strip_prefix("parallelogram:")
                    .and_then(|n| n.parse().ok())
                    .ok_or_else(bad)?;
                if (1..=Footprint::MAX_PIECES).contains(&n) {
                    Ok(Footprint::Parallelogram(n))
                } else {
                    Err(bad())
                }
            }
        }
    }
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum WeavePrecision {
    /// The weave texture in RGBA8 UNORM.
    Rgba8,
    /// The weave texture in RGBA16F.
    Rgba16f,
    /// No texture: the exact coverage of the pixel's footprint box, evaluated in the shader.
    Analytic,
    /// The weave's summed-area table (RGBA32F, [`crate::fabric::WeaveSat`]): each
    /// footprint box's mean coverage exactly, at the texture's resolution, in four corner
    /// look-ups, where the mip chain's trilinear probe blurs a footprint of about a cell (the
    /// default: 56 against 40 dB at one pixel per cell square-on, `weft bench --footprint`).
    #[default]
    Sat,
}

impl WeavePrecision {
    pub const ALL: [WeavePrecision; 4] = [
        WeavePrecision::Rgba8,
        WeavePrecision::Rgba16f,
        WeavePrecision::Analytic,
        WeavePrecision::Sat,
    ];

    pub fn name(self) -> &'static str {
        match self {
            WeavePrecision::Rgba8 => "rgba8",
            WeavePrecision::Rgba16f => "rgba16f",
            WeavePrecision::Analytic => "analytic",
            WeavePrecision::Sat => "sat",
        }
    }

    pub fn parse(text: &str) -> crate::Result<WeavePrecision> {
        WeavePrecision::ALL
            .iter()
            .copied()
            .find(|p| p.name() == text)
            .ok_or_else(|| {
                Error::input(format!(
                    "unknown weave precision '{text}': choose rgba8, rgba16f, analytic or sat"
                ))
            })
    }
}

/// The tone curves of the tonemap pass (defined beside their CPU twins).
pub use crate::reference::shading::ToneCurve;

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
    /// The tone curve (`--tonemap`; Khronos PBR Neutral by default).
    pub tonemap: ToneCurve,
    pub debug_view: DebugView,
    pub accuracy: Accuracy,
    pub weave_precision: WeavePrecision,
    /// Shade fabric pixels with the metallic-roughness BRDF instead (for measuring what the
    /// fabric model costs on the same G-buffer).
    pub fabric_as_pbr: bool,
    /// How fabric materials are shaded (the fabric model unless comparing).
    pub shading: Shading,
    /// Effects to force on whatever the scene needs (to check, and to measure, that what the plan
    /// skips changes nothing).
    pub force: Force,
    /// Environment lighting (None: lamps and the fixed hemispherical ambient only). The CLI
    /// lights every scene with one (the built-in studio unless `--env`); the library's default is
    /// none, so lamp-only tests mean what they say.
    pub environment: Option<crate::env::EnvLighting>,
    /// Read the linear HDR target back into `Frame::hdr` (on by default; `weft render` turns it
    /// off unless `--exr` is given, since the PNG needs only the 8-bit target).
    pub read_hdr: bool,
    /// Sub-pixel offset of the projection in pixels (x right, y down), each within [-1/2, 1/2]:
    /// the image is sampled at pixel centre + jitter. Frames at stratified jitters, averaged,
    /// integrate the pixel (`weft::bench::pixel_truth`, the bench's ground truth).
    pub jitter: [f32; 2],
    /// How the weave is filtered over a pixel's footprint (the parallelogram by default).
    pub footprint: Footprint,
    /// Edge anti-aliasing after tone mapping: none (the library's default, so images are the
    /// shading alone) or FXAA (`weft render` and `weft view`'s default).
    pub antialias: Antialias,
    /// Screen-space occlusion of the environment's light (`--occlusion`): none (the library's
    /// default, so images are the shading alone) or GTAO (`weft render` and `weft view`'s
    /// default). Planned only when an environment lights the scene.
    pub occlusion: Occlusion,
    /// How the frame's passes reach the queue: one submission (the normal path), or one per
    /// pass with its own timestamps (`weft render --timings`, `weft bench`: each pass's time its
    /// own, with nothing overlapping it).
    pub submission: Submission,
}

/// How a frame is submitted ([`RenderOptions::submission`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Submission {
    /// One submission: every pass, with a timestamp between each two, and the readback copies.
    #[default]
    Frame,
    /// One submission per pass, each between two timestamps, waited for before the next; the
    /// readback its own.
    PerPass,
}

impl Submission {
    pub fn by_name(name: &str) -> Option<Submission> {
        match name {
            "frame" => Some(Submission::Frame),
            "pass" => Some(Submission::PerPass),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Submission::Frame => "frame",
            Submission::PerPass => "pass",
        }
    }
}

/// Screen-space occlusion of the environment (`--occlusion`; the occlusion pass,
/// render/passes/occlusion.rs).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Occlusion {
    /// The environment lights every point as if nothing stood around it (the material's
    /// occlusion texture alone darkens it).
    #[default]
    None,
    /// Ground-truth ambient occlusion from the depth buffer (glsl/occlusion.frag) out to
    /// `radius` world units; None: 0.3 of the diagonal of what casts shadows (of the whole
    /// scene when nothing casts). The light bounced between occluders is given back by a fit
    /// from the surface's own albedo (Jimenez et al. 2016); with `bounce` (`gtao`), also the
    /// occluders' own light where the screen shows more of it than the fit gives (one bounce of
    /// the environment's diffuse light off what hides it); `gtao-nobounce`: the fit alone. With
    /// `world` (`gtao`, with the bounce), also what each vertex sees of the whole scene, baked
    /// by rays where the scene is static ([`world_light`]): the occluders and their light that
    /// the screen does not show; `gtao-screen`: the screen's alone.
    Gtao {
        radius: Option<f32>,
        bounce: bool,
        world: bool,
    },
}

impl Occlusion {
    /// The radius of `Gtao { radius: None }`, as a fraction of the scene's diagonal.
    pub const RADIUS_OF_DIAGONAL: f32 = 0.3;

    /// The default of `weft render` and `weft view`: GTAO with the occluders' bounce and the
    /// world light, at the scene's radius.
    pub const DEFAULT: Occlusion = Occlusion::Gtao {
        radius: None,
        bounce: true,
        world: true,
    };

    /// `none`, `gtao`, `gtao:R` (R > 0, world units), `gtao-screen[:R]` or `gtao-nobounce[:R]`.
    pub fn parse(text: &str) -> crate::Result<Occlusion> {
        let bad = || {
            Error::input(format!(
                "unknown occlusion '{text}': choose none, gtao (radius 0.3 of the scene's size, with the occluders' bounced light and the world light baked per vertex), gtao:R (R world units, R > 0, e.g. gtao:0.5), gtao-screen / gtao-screen:R (what the screen shows alone, no world light), or gtao-nobounce / gtao-nobounce:R (without the bounce)"
            ))
        };
        if text == "none" {
            return Ok(Occlusion::None);
        }
        let (rest, bounce, world) = if let Some(rest) = text.strip_prefix("gtao-nobounce") {
            (rest, false, false)
        } else if let Some(rest) = text.strip_prefix("gtao-screen") {
            (rest, true, false)
        } else {
            (text.strip_prefix("gtao").ok_or_else(bad)?, true, true)
        };
        if rest.is_empty() {
            return Ok(Occlusion::Gtao {
                radius: None,
                bounce,
                world,
            });
        }
        let r: f32 = rest
            .strip_prefix(':')
            .ok_or_else(bad)?
            .parse()
            .map_err(|_| bad())?;
        if r.is_finite() && r > 0.0 {
            Ok(Occlusion::Gtao {
                radius: Some(r),
                bounce,
                world,
            })
        } else {
            Err(bad())
        }
    }

    pub fn name(self) -> String {
        match self {
            Occlusion::None => "none".into(),
            Occlusion::Gtao {
                radius,
                bounce,
                world,
            } => {
                let method = match (bounce, world) {
                    (false, _) => "gtao-nobounce",
                    (true, false) => "gtao-screen",
                    (true, true) => "gtao",
                };
                match radius {
                    None => method.into(),
                    Some(r) => format!("{method}:{r}"),
                }
            }
        }
    }
}

/// Anti-aliasing of the image (`--aa`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Antialias {
    /// Geometry edges as the rasterizer leaves them: one-pixel staircases.
    #[default]
    None,
    /// A post pass (glsl/fxaa.frag): blends across luma edges along their direction.
    Fxaa,
    /// `ssN`: N x N frames at the centres of an N x N grid of sub-pixel offsets, each without
    /// FXAA, averaged: the tone-mapped images in linear display light (as a multisampled target
    /// is resolved), the HDR in linear radiance. Costs N² frames; integrates everything a pixel
    /// covers (edges, wires thinner than a pixel, texture and weave detail), so it is for still
    /// renders (N from 2 to [`Antialias::MAX_SUPERSAMPLE`]).
    Supersample(u32),
}

impl Antialias {
    /// The largest N of `ssN` (64 frames).
    pub const MAX_SUPERSAMPLE: u32 = 8;

    pub fn by_name(name: &str) -> Option<Antialias> {
        match name {
            "none" => Some(Antialias::None),
            "fxaa" => Some(Antialias::Fxaa),
            _ => name
                .strip_prefix("ss")
                .and_then(|n| n.parse::<u32>().ok())
                .filter(|n| (2..=Self::MAX_SUPERSAMPLE).contains(n))
                .map(Antialias::Supersample),
        }
    }

    pub fn name(self) -> String {
        match self {
            Antialias::None => "none".into(),
            Antialias::Fxaa => "fxaa".into(),
            Antialias::Supersample(n) => format!("ss{n}"),
        }
    }

    /// Frames per image side (1 unless supersampled).
    pub fn frames_per_side(self) -> u32 {
        match self {
            Antialias::Supersample(n) => n.clamp(1, Self::MAX_SUPERSAMPLE),
            _ => 1,
        }
    }
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            width: 1280,
            height: 720,
            camera: None,
            camera_override: None,
            exposure: 0.0,
            tonemap: ToneCurve::PbrNeutral,
            debug_view: DebugView::None,
            accuracy: Accuracy::Mixture,
            weave_precision: WeavePrecision::Sat,
            fabric_as_pbr: false,
            shading: Shading::Fabric,
            force: Force::NONE,
            environment: None,
            read_hdr: true,
            jitter: [0.0, 0.0],
            footprint: Footprint::default(),
            antialias: Antialias::None,
            occlusion: Occlusion::None,
            submission: Submission::Frame,
        }
    }
}

impl RenderOptions {
    /// Frames per image side: N for `--aa ssN` (debug views show the G-buffer of one frame), else 1.
    pub fn supersample(&self) -> u32 {
        if self.debug_view == DebugView::None {
            self.antialias.frames_per_side()
        } else {
            1
        }
    }

    pub fn validate(&self) -> crate::Result<()> {
        if self.width == 0 || self.height == 0 || self.width > MAX_SIZE || self.height > MAX_SIZE {
            return Err(Error::input(format!(
                "output size {}x{} is out of range: each side must be between 1 and {MAX_SIZE} (e.g. --size 1920x1080)",
                self.width, self.height
            )));
        }
        if let Antialias::Supersample(n) = self.antialias {
            if !(2..=Antialias::MAX_SUPERSAMPLE).contains(&n) {
                return Err(Error::input(format!(
                    "ss{n} is out of range: N must be between 2 and {}",
                    Antialias::MAX_SUPERSAMPLE
                )));
            }
            if self.jitter != [0.0, 0.0] {
                return Err(Error::input(format!(
                    "ss{n} places its own sub-pixel offsets; a jitter {:?} as well is a contradiction (use one or the other)",
                    self.jitter
                )));
            }
        }
        if let Accuracy::Supersampled(n) = self.accuracy {
            if !(1..=Accuracy::MAX_SAMPLES).contains(&n) {
                return Err(Error::input(format!(
                    "supersampled:{n} is out of range: N must be between 1 and {}",
                    Accuracy::MAX_SAMPLES
                )));
            }
        }
        if let Some(e) = &self.environment {
            e.validate()?;
        }
        if let Occlusion::Gtao {
            radius: Some(r), ..
        } = self.occlusion
        {
            if !(r.is_finite() && r > 0.0) {
                return Err(Error::input(format!(
                    "occlusion radius {r} is out of range: it must be a finite number of world units above 0 (e.g. --occlusion gtao:0.5)"
                )));
            }
        }
        if let Footprint::Parallelogram(n) = self.footprint {
            if !(1..=Footprint::MAX_PIECES).contains(&n) {
                return Err(Error::input(format!(
                    "parallelogram:{n} is out of range: N must be between 1 and {}",
                    Footprint::MAX_PIECES
                )));
            }
        }
        if !self.jitter.iter().all(|j| j.is_finite() && j.abs() <= 0.5) {
            return Err(Error::input(format!(
                "sub-pixel jitter {:?} is out of range: each offset must be within [-0.5, 0.5] pixels",
                self.jitter
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn accuracy_names_round_trip() {
        for a in [
            Accuracy::Nearest,
            Accuracy::FilteredParams,
            Accuracy::Mixture,
            Accuracy::Supersampled(8),
        ] {
            assert_eq!(Accuracy::parse(&a.name()).unwrap(), a);
        }
        for bad in [
            "supersampled:0",
            "supersampled:65",
            "supersampled:x",
            "fast",
            "",
        ] {
            assert!(Accuracy::parse(bad).is_err(), "{bad}");
        }
        for p in WeavePrecision::ALL {
            assert_eq!(WeavePrecision::parse(p.name()).unwrap(), p);
        }
        for s in Shading::ALL {
            assert_eq!(Shading::parse(s.name()).unwrap(), s);
        }
        assert!(Shading::parse("flat").is_err());
    }
}

/// Parses `WxH`, e.g. `1920x1080`.
pub fn parse_size(text: &str) -> crate::Result<(u32, u32)> {
    let bad = || {
        Error::input(format!(
            "size '{text}' is not WIDTHxHEIGHT (e.g. 1920x1080)"
        ))
    };
    let (w, h) = text.split_once(['x', 'X']).ok_or_else(bad)?;
    let w: u32 = w.trim().parse().map_err(|_| bad())?;
    let h: u32 = h.trim().parse().map_err(|_| bad())?;
    Ok((w, h))
}
