//! `weft bench`: what accuracy costs in time (project issue 6).
//!
//! The default scene is seen by four cameras (close-up, mid, far, grazing). For each camera and
//! each accuracy level x weave precision, the G-buffer and lighting passes are timed (GPU
//! timestamps, one pass per submit, median of warm frames: lavapipe JIT-compiles a pipeline at its
//! first submit) and the image is compared with a ground truth, `supersampled:N` with the analytic
//! weave (FLIP mean on the sRGB images, RMSE on the linear HDR ones, both over the whole image).
//! Then the cost growth of the default level over resolution and number of point lights, and the
//! fabric lighting pass against the metallic-roughness one on the same G-buffer.
//!
//! Output: a table ([`BenchReport::table`]), `bench.csv` and `bench.png` (error against time, drawn
//! by [`plot`] with an embedded bitmap font: no font files, no plotting crate).
//!
//! Frames of the configurations being compared (the variants of one view, the light counts, fabric
//! against metallic-roughness) are rendered round-robin, so that a change in the machine's load
//! falls on all of them alike. Everything rendered is deterministic (fixed cameras, lights placed
//! on a fixed spiral); only the times vary from run to run.

mod accuracy;
mod footprint;
pub mod ibl_bench;
pub mod load;
pub mod plan_bench;
pub mod plot;
mod report;
pub mod submission;
pub mod temporal;

pub use crate::metrics::{
    fit_line, flip_mean, flip_mean_masked, median, psnr_hdr_masked, psnr_linear, rmse_hdr,
    rmse_hdr_masked,
};
pub(crate) use crate::metrics::{flip_map_rgb, psnr_db, rgb8};
pub(crate) use accuracy::*;
pub use accuracy::{pixel_truth, Truth};
pub use footprint::footprint_bench;
pub use report::CSV_COLUMNS;

use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::Vec3;

use crate::render::{Accuracy, Frame, GpuScene, RenderOptions, Renderer, WeavePrecision};
use crate::scene::{Camera, Light, LightKind, Scene};
use crate::vk::Context;
use crate::Error;

/// A camera on the default scene, chosen for what it shows of the weave.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum View {
    /// Threads resolved: a few pixels per thread.
    CloseUp,
    /// The scene's own camera.
    Mid,
    /// The weave far below a pixel: many repeats per pixel.
    Far,
    /// A low eye looking across the cloth: long, thin footprints.
    Grazing,
    /// The two-colour plain weave of `assets/scenes/closeup.glb` (red warp, gold weft), seen at
    /// 50° from its normal with the camera rolled 30°, so footprints are oblique parallelograms:
    /// a cell is about 10 pixels at 360 rows (magnified).
    Cells10,
    /// The same at a tenth of the pitch: a cell is about one pixel.
    Cells1,
    /// The fine weave seen square-on (along its normal, no roll) from 20 cm: a cell is about one
    /// pixel at 360 rows, its rows and columns along the pixel grid (a garment filling a 1080p
    /// frame at a 0.5 mm pitch).
    Cells1Square,
    /// The same from 13.3 cm: about 1.5 pixels per cell, square-on.
    Cells15Square,
    /// The fine weave at 80° from its normal, unrolled: cells about one pixel across and a
    /// sixth of a pixel deep (grazing footprints).
    CellsGrazing,
}

impl View {
    pub const ALL: [View; 9] = [
        View::CloseUp,
        View::Mid,
        View::Far,
        View::Grazing,
        View::Cells10,
        View::Cells1,
        View::Cells1Square,
        View::Cells15Square,
        View::CellsGrazing,
    ];

    pub fn name(self) -> &'static str {
        match self {
            View::CloseUp => "close-up",
            View::Mid => "mid",
            View::Far => "far",
            View::Grazing => "grazing",
            View::Cells10 => "cells-10px",
            View::Cells1 => "cells-1px",
            View::Cells1Square => "cells-1px-square",
            View::Cells15Square => "cells-1.5px-square",
            View::CellsGrazing => "cells-grazing",
        }
    }

    pub fn parse(text: &str) -> crate::Result<View> {
        View::ALL
            .iter()
            .copied()
            .find(|v| v.name() == text)
            .ok_or_else(|| {
                Error::input(format!(
                    "unknown bench view '{text}': choose close-up, mid, far, grazing, cells-10px, cells-1px, cells-1px-square, cells-1.5px-square or cells-grazing"
                ))
            })
    }

    /// Which of the bench's scenes this view looks at.
    pub fn scene(self) -> BenchScene {
        match self {
            View::Cells10 => BenchScene::Weave,
            View::Cells1 | View::Cells1Square | View::Cells15Square | View::CellsGrazing => {
                BenchScene::FineWeave
            }
            _ => BenchScene::Default,
        }
    }

    /// [`View::camera`] for an image of `rows` rows instead of the bench's 360: the weave views'
    /// fields of view narrowed (or widened) so that a cell spans the pixels it spans in the
    /// bench; the other views unchanged.
    pub fn camera_for_rows(self, scene: &Scene, rows: u32) -> crate::Result<Camera> {
        let mut c = self.camera(scene)?;
        if self.scene() != BenchScene::Default {
            let t = (0.5 * c.yfov).tan() * rows as f32 / 360.0;
            c.yfov = 2.0 * t.atan();
        }
        Ok(c)
    }

    /// The camera of this view on its scene ([`View::scene`]). The default scene: the cloth is
    /// draped over a ball of radius 0.5 at the origin, top at y = 1.015, hem at |x|, |z| <= 1.2.
    /// The weave scenes: a 28 x 22 cm patch bent along x (radius 1 m) around the origin, a cell
    /// 4 mm (0.4 mm in the fine one); the eye 20 cm from (0, 0, -0.05) at 50° from the normal,
    /// 40° field of view: a cell spans 0.004 / (0.2 · 2 tan 20°) · 360 ≈ 10 rows.
    pub fn camera(self, scene: &Scene) -> crate::Result<Camera> {
        let at = |eye: [f32; 3], target: [f32; 3], fov_deg: f32| {
            scene.look_at_camera(Vec3::from(eye), Vec3::from(target), fov_deg.to_radians())
        };
        match self {
            View::CloseUp => at([0.15, 1.12, 0.45], [0.0, 1.0, 0.1], 30.0),
            View::Mid => scene.camera(None),
            View::Far => at([0.0, 6.0, 14.0], [0.0, 0.4, 0.0], 20.0),
            View::Grazing => at([1.9, 0.16, 1.9], [-0.2, 0.25, -0.2], 32.0),
            View::Cells10 | View::Cells1 => {
                let elevation = 50f32.to_radians();
                let target = Vec3::new(0.0, 0.0, -0.05);
                let eye = target + 0.2 * Vec3::new(0.0, elevation.cos(), elevation.sin());
                let mut c = scene.look_at_camera(eye, target, 40f32.to_radians())?;
                c.view = glam::Mat4::from_rotation_z(30f32.to_radians()) * c.view;
                Ok(c)
            }
            View::Cells1Square | View::Cells15Square | View::CellsGrazing => {
                // The patch's normal at the target is +y (it bends along x about the origin).
                let target = Vec3::new(0.0, 0.0, -0.05);
                let (distance, from_normal) = match self {
                    View::Cells1Square => (0.2, 0.0f32),
                    View::Cells15Square => (0.2 / 1.5, 0.0),
                    _ => (0.2 * 80f32.to_radians().cos(), 80.0),
                };
                let a = from_normal.to_radians();
                let eye = target + distance * Vec3::new(0.0, a.cos(), a.sin());
                scene.look_at_camera(eye, target, 40f32.to_radians())
            }
        }
    }
}

/// The scenes the bench views look at.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BenchScene {
    /// The built-in default scene.
    Default,
    /// `assets/scenes/closeup.glb`: a two-colour plain weave (warp and weft of different colours).
    Weave,
    /// The same with the weave's repeat and gap a tenth as large.
    FineWeave,
}

/// The close-up scene of the regression cases, built into the binary for the bench.
const WEAVE_SCENE_GLB: &[u8] = include_bytes!("../../assets/scenes/closeup.glb");

impl BenchScene {
    pub fn load(self) -> crate::Result<Scene> {
        let mut scene = match self {
            BenchScene::Default => return Ok(crate::scene::default_scene()),
            _ => crate::scene::load_slice(WEAVE_SCENE_GLB, "assets/scenes/closeup.glb", None)?,
        };
        if self == BenchScene::FineWeave {
            for f in scene.materials.iter_mut().filter_map(|m| m.fabric.as_mut()) {
                f.repeat *= 0.1;
                f.gap *= 0.1;
            }
        }
        Ok(scene)
    }
}

/// What a bench run renders and how often.
#[derive(Clone, Debug)]
pub struct BenchConfig {
    /// Cameras of the accuracy sweep.
    pub views: Vec<View>,
    /// (level, precision) pairs of the accuracy sweep, in the order they are reported.
    pub variants: Vec<(Accuracy, WeavePrecision)>,
    /// The ground truth every variant is compared with integrates each pixel: the mean of
    /// `truth_samples`² frames at stratified jittered sub-pixel offsets, each with the weave
    /// evaluated exactly at the sample point ([`pixel_truth`]).
    pub truth_samples: u32,
    /// Image size of the accuracy sweep.
    pub size: (u32, u32),
    /// Frames timed per configuration (the median is reported).
    pub frames: u32,
    /// Frames rendered and discarded before timing (lavapipe compiles pipelines at first submit).
    pub warmup: u32,
    /// Frames timed for images above 2 megapixels (they take seconds each on lavapipe).
    pub large_frames: u32,
    /// Sizes of the resolution sweep (mid view, the default level and precision).
    pub resolutions: Vec<(u32, u32)>,
    /// Point-light counts of the light sweep; they replace the scene's own lights.
    pub light_counts: Vec<u32>,
    /// Image size of the light sweep.
    pub lights_size: (u32, u32),
    /// Size and views at which the fabric lighting pass is compared with the metallic-roughness
    /// one on the same G-buffer; None skips it.
    pub pbr_size: Option<(u32, u32)>,
    pub pbr_views: Vec<View>,
    /// Where bench.csv and bench.png go (created if missing).
    pub out: PathBuf,
    /// Draw a progress bar on stderr (only when stderr is a terminal).
    pub progress: bool,
}

/// The levels of the accuracy sweep, cheapest first.
pub const LEVELS: [Accuracy; 6] = [
    Accuracy::Nearest,
    Accuracy::FilteredParams,
    Accuracy::Mixture,
    Accuracy::Supersampled(2),
    Accuracy::Supersampled(4),
    Accuracy::Supersampled(8),
];

/// The accuracy sweep of the full run: nearest, filtered-params and mixture with each weave
/// precision; the supersampled levels with the analytic weave only, since they evaluate the weave
/// analytically at their sample points whatever the precision (the G-buffer then holds the
/// footprint, not coverages).
pub fn default_variants() -> Vec<(Accuracy, WeavePrecision)> {
    let mut v = cross_product(&LEVELS[..3], &WeavePrecision::ALL);
    v.extend(LEVELS[3..].iter().map(|&l| (l, WeavePrecision::Analytic)));
    v
}

/// Every level at every precision.
pub fn cross_product(
    levels: &[Accuracy],
    precisions: &[WeavePrecision],
) -> Vec<(Accuracy, WeavePrecision)> {
    levels
        .iter()
        .flat_map(|&l| precisions.iter().map(move |&p| (l, p)))
        .collect()
}

impl Default for BenchConfig {
    /// The full run: every view, level and precision at 640x360, growth to 3840x2160, 1..64
    /// lights, the fabric/PBR ratio at 1920x1080. A few minutes on lavapipe with 2 cores.
    fn default() -> Self {
        BenchConfig {
            views: View::ALL.to_vec(),
            variants: default_variants(),
            // 16 x 16 point samples per pixel: the estimate's own error is measured by the run
            // against 8 x 8 (docs/performance.md).
            truth_samples: 16,
            size: (640, 360),
            frames: 5,
            warmup: 1,
            large_frames: 2,
            resolutions: vec![(640, 360), (1280, 720), (1920, 1080), (3840, 2160)],
            light_counts: vec![1, 4, 16, 64],
            lights_size: (640, 360),
            pbr_size: Some((1920, 1080)),
            pbr_views: vec![View::Mid, View::CloseUp],
            out: PathBuf::from("target/bench"),
            progress: true,
        }
    }
}

impl BenchConfig {
    /// About 30 seconds on lavapipe: every view at 320x180, the texture-filtered levels at the
    /// default precision, mixture also with the analytic weave, supersampled:2 and :4, growth to
    /// 1280x720 and 16 lights.
    pub fn quick() -> Self {
        let mut variants = cross_product(&LEVELS[..3], &[WeavePrecision::default()]);
        variants.push((Accuracy::Mixture, WeavePrecision::Analytic));
        variants.extend(
            [Accuracy::Supersampled(2), Accuracy::Supersampled(4)]
                .map(|l| (l, WeavePrecision::Analytic)),
        );
        BenchConfig {
            views: View::ALL.to_vec(),
            variants,
            truth_samples: 6,
            size: (320, 180),
            frames: 3,
            warmup: 1,
            large_frames: 1,
            resolutions: vec![(320, 180), (640, 360), (1280, 720)],
            light_counts: vec![1, 4, 16],
            lights_size: (320, 180),
            pbr_size: Some((640, 360)),
            pbr_views: vec![View::Mid],
            ..BenchConfig::default()
        }
    }

    /// How many renders the run makes (for the progress bar).
    fn jobs(&self) -> u64 {
        let sweep = self.views.len() * (self.truth_samples.pow(2) as usize + self.variants.len());
        let pbr = if self.pbr_size.is_some() {
            self.pbr_views.len() * 2
        } else {
            0
        };
        (sweep + self.resolutions.len() + self.light_counts.len() + pbr) as u64
    }

    fn check(&self) -> crate::Result<()> {
        if self.frames == 0 || self.large_frames == 0 {
            return Err(Error::input("bench: --frames must be at least 1"));
        }
        if self.views.is_empty() || self.variants.is_empty() {
            return Err(Error::input(
                "bench: the accuracy sweep needs at least one view and one level",
            ));
        }
        if self.light_counts.contains(&0) {
            return Err(Error::input("bench: every light count must be at least 1"));
        }
        if !(1..=MAX_TRUTH_SAMPLES).contains(&self.truth_samples) {
            return Err(Error::input(format!(
                "bench: the ground truth's samples per pixel side must be between 1 and {MAX_TRUTH_SAMPLES}, not {}",
                self.truth_samples
            )));
        }
        Ok(())
    }
}

/// The most samples per pixel side of the ground truth (64² frames).
pub const MAX_TRUTH_SAMPLES: u32 = 64;

/// GPU times of the two passes the bench is about, medians over the timed frames.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PassTimes {
    pub gbuffer_ms: f64,
    pub lighting_ms: f64,
    /// How many frames the medians are over.
    pub frames: u32,
}

impl PassTimes {
    pub fn total_ms(&self) -> f64 {
        self.gbuffer_ms + self.lighting_ms
    }
}

/// One view rendered as the ground truth.
#[derive(Clone, Debug)]
pub struct GroundTruthRow {
    pub view: View,
    /// Samples per pixel side (`samples`² jittered frames).
    pub samples: u32,
    /// Summed over the frames (the first one cold: it includes JIT compilation).
    pub times: PassTimes,
    /// Share of the image covered by fabric at every sample (the pixels the errors are over).
    pub fabric_fraction: f64,
    /// The truth's own PSNR against the exact pixel integral, estimated ([`Truth::noise_psnr`]):
    /// a level's PSNR is meaningful up to about this.
    pub noise_psnr: Option<f64>,
}

/// One (view, level, precision) of the accuracy sweep.
#[derive(Clone, Debug)]
pub struct AccuracyRow {
    pub view: View,
    pub level: Accuracy,
    pub precision: WeavePrecision,
    pub times: PassTimes,
    /// Mean FLIP error of the sRGB image against the ground truth's, over the fabric pixels.
    pub flip_mean: f64,
    /// RMSE of the linear HDR RGB against the ground truth's, over the fabric pixels.
    pub rmse: f64,
    /// PSNR (dB) of the linear HDR RGB over the fabric pixels, the peak being the ground truth's
    /// brightest fabric channel value.
    pub psnr: f64,
    /// On the view's Pareto front: no other variant of the same view is both faster and closer to
    /// the ground truth.
    pub pareto: bool,
}

#[derive(Clone, Debug)]
pub struct ResolutionRow {
    pub width: u32,
    pub height: u32,
    pub times: PassTimes,
}

impl ResolutionRow {
    pub fn megapixels(&self) -> f64 {
        self.width as f64 * self.height as f64 / 1e6
    }
}

#[derive(Clone, Debug)]
pub struct LightsRow {
    pub lights: u32,
    pub width: u32,
    pub height: u32,
    pub times: PassTimes,
}

/// The fabric lighting pass against the metallic-roughness one on the same G-buffer.
#[derive(Clone, Debug)]
pub struct PbrRow {
    pub view: View,
    pub width: u32,
    pub height: u32,
    pub fabric: PassTimes,
    /// The same frame with `fabric_as_pbr`.
    pub pbr: PassTimes,
    pub fabric_fraction: f64,
    /// Share of the image covered by any surface (the rest is background).
    pub covered_fraction: f64,
}

impl PbrRow {
    /// Fabric lighting ms / metallic-roughness lighting ms.
    pub fn ratio(&self) -> f64 {
        self.fabric.lighting_ms / self.pbr.lighting_ms
    }

    /// The ratio per fabric pixel it implies, if every non-fabric pixel costs the same in both
    /// frames, background pixels (which skip lighting) cost nothing, and a fabric pixel shaded
    /// as metallic-roughness costs what the average covered pixel does.
    pub fn ratio_per_fabric_pixel(&self) -> f64 {
        1.0 + (self.ratio() - 1.0) * self.covered_fraction / self.fabric_fraction.max(1e-6)
    }
}

/// Where and under what load the bench ran.
#[derive(Clone, Debug, Default)]
pub struct Machine {
    pub device: String,
    pub driver: String,
    pub api_version: String,
    pub cpu: String,
    pub cores: usize,
    /// 1-minute load average at the start and the end of the run (Linux only).
    pub load_start: Option<f64>,
    pub load_end: Option<f64>,
    pub validation: bool,
}

impl Machine {
    fn probe(ctx: &Context) -> Machine {
        let info = ctx.info();
        let cpu = std::fs::read_to_string("/proc/cpuinfo")
            .ok()
            .and_then(|c| {
                c.lines()
                    .find(|l| l.starts_with("model name"))
                    .map(|l| l.split(':').nth(1).unwrap_or("").trim().to_string())
            })
            .unwrap_or_else(|| "unknown".into());
        Machine {
            device: format!("{} ({})", info.name, info.device_type),
            driver: format!("{} {}", info.driver_name, info.driver_info),
            api_version: info.api_version.clone(),
            cpu,
            cores: std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(1),
            load_start: load_average(),
            load_end: None,
            validation: ctx.validating(),
        }
    }
}

fn load_average() -> Option<f64> {
    std::fs::read_to_string("/proc/loadavg")
        .ok()?
        .split_whitespace()
        .next()?
        .parse()
        .ok()
}

/// Everything a bench run measured.
#[derive(Clone, Debug)]
pub struct BenchReport {
    pub machine: Machine,
    pub size: (u32, u32),
    pub ground_truth: Vec<GroundTruthRow>,
    pub accuracy: Vec<AccuracyRow>,
    pub resolutions: Vec<ResolutionRow>,
    pub lights: Vec<LightsRow>,
    pub pbr: Vec<PbrRow>,
    pub seconds: f64,
    pub csv: PathBuf,
    pub png: PathBuf,
}

/// Runs the bench and writes `bench.csv` and `bench.png` into `config.out`.
pub fn run(ctx: Context, config: &BenchConfig) -> crate::Result<BenchReport> {
    config.check()?;
    let start = Instant::now();
    let mut machine = Machine::probe(&ctx);
    let mut renderer = Renderer::new(ctx)?;
    let scene = crate::scene::default_scene();
    let progress = Progress::new(config.jobs(), config.progress);
    let gpu = renderer.upload(&scene)?;
    let (width, height) = config.size;

    // The accuracy sweep, view by view: the ground truth, then every variant against it.
    // The ground truths' images go there as they are made.
    create_out_dir(&config.out)?;
    let mut scenes: Vec<(BenchScene, Scene, GpuScene)> = Vec::new();
    for kind in config.views.iter().map(|v| v.scene()) {
        if !scenes.iter().any(|s| s.0 == kind) {
            let s = kind.load()?;
            let g = renderer.upload(&s)?;
            scenes.push((kind, s, g));
        }
    }
    let mut ground_truth = Vec::new();
    let mut accuracy = Vec::new();
    for &view in &config.views {
        let (_, vscene, vgpu) = scenes
            .iter()
            .find(|s| s.0 == view.scene())
            .expect("every view's scene is loaded above");
        let at = |accuracy: Accuracy, precision: WeavePrecision| {
            Ok::<_, Error>(RenderOptions {
                width,
                height,
                camera_override: Some(view.camera(vscene)?),
                accuracy,
                weave_precision: precision,
                ..crate::bench::timed_options()
            })
        };
        let n = config.truth_samples;
        progress.start(format!(
            "{} ground truth ({n}x{n} samples per pixel)",
            view.name()
        ));
        let truth = pixel_truth(
            &mut renderer,
            vscene,
            vgpu,
            &at(Accuracy::Mixture, WeavePrecision::default())?,
            n,
            || progress.done(),
        )?;
        let mask = truth.fabric_everywhere();
        let f = &truth.frame;
        crate::render::write_png(
            &config.out.join(format!("truth-{}.png", view.name())),
            f.width,
            f.height,
            &f.ldr,
        )?;
        ground_truth.push(GroundTruthRow {
            view,
            samples: n,
            times: truth.times,
            fabric_fraction: mask.iter().filter(|m| **m).count() as f64 / mask.len().max(1) as f64,
            noise_psnr: truth.noise_psnr(&mask),
        });

        let jobs = config
            .variants
            .iter()
            .map(|&(level, precision)| Ok((vscene, vgpu, at(level, precision)?)))
            .collect::<crate::Result<Vec<_>>>()?;
        progress.start(format!("{}: {} variants", view.name(), jobs.len()));
        let measured = measure(&mut renderer, &jobs, config.warmup, config.frames, |_| {
            progress.done()
        })?;
        for (&(level, precision), (frame, times)) in config.variants.iter().zip(measured) {
            if (level, precision) == (Accuracy::Mixture, WeavePrecision::default()) {
                crate::render::write_png(
                    &config.out.join(format!("default-{}.png", view.name())),
                    frame.width,
                    frame.height,
                    &frame.ldr,
                )?;
            }
            accuracy.push(AccuracyRow {
                view,
                level,
                precision,
                times,
                flip_mean: flip_mean_masked(&truth.frame, &frame, &mask),
                rmse: rmse_hdr_masked(&truth.frame, &frame, &mask),
                psnr: psnr_hdr_masked(&truth.frame, &frame, &mask),
                pareto: false,
            });
        }
    }
    drop(scenes);
    let at =
        |view: View, accuracy: Accuracy, precision: WeavePrecision, (width, height): (u32, u32)| {
            Ok::<_, Error>(RenderOptions {
                width,
                height,
                camera_override: Some(view.camera(&scene)?),
                accuracy,
                weave_precision: precision,
                ..crate::bench::timed_options()
            })
        };
    mark_pareto_front(&mut accuracy);

    // Growth over resolution: the mid view at the default level and precision. Not interleaved:
    // the renderer keeps the targets of one size only.
    let mut resolutions = Vec::new();
    for &(w, h) in &config.resolutions {
        progress.start(format!("resolution {w}x{h}"));
        let options = RenderOptions {
            width: w,
            height: h,
            ..crate::bench::timed_options()
        };
        let frames = if w as u64 * h as u64 > 2_000_000 {
            config.large_frames
        } else {
            config.frames
        };
        let job = [(&scene, &gpu, options)];
        let (_, times) = measure(&mut renderer, &job, config.warmup, frames, |_| {})?.remove(0);
        resolutions.push(ResolutionRow {
            width: w,
            height: h,
            times,
        });
        progress.done();
    }

    // Growth over lights: N point lights instead of the scene's three.
    let (lw, lh) = config.lights_size;
    let lit: Vec<Scene> = config
        .light_counts
        .iter()
        .map(|&n| with_point_lights(&scene, n))
        .collect();
    let lit_gpu = lit
        .iter()
        .map(|s| renderer.upload(s))
        .collect::<crate::Result<Vec<_>>>()?;
    let options = RenderOptions {
        width: lw,
        height: lh,
        ..crate::bench::timed_options()
    };
    let jobs: Vec<_> = lit
        .iter()
        .zip(&lit_gpu)
        .map(|(s, g)| (s, g, options.clone()))
        .collect();
    progress.start(format!("{} light counts", jobs.len()));
    let measured = measure(&mut renderer, &jobs, config.warmup, config.frames, |_| {
        progress.done()
    })?;
    let lights = config
        .light_counts
        .iter()
        .zip(measured)
        .map(|(&n, (_, times))| LightsRow {
            lights: n,
            width: lw,
            height: lh,
            times,
        })
        .collect();
    drop(jobs);
    drop(lit_gpu);

    // The fabric BRDF against metallic-roughness on the same G-buffer, frames interleaved.
    let mut pbr = Vec::new();
    if let Some(size) = config.pbr_size {
        let frames = if size.0 as u64 * size.1 as u64 > 2_000_000 {
            config.large_frames
        } else {
            config.frames
        };
        for &view in &config.pbr_views {
            let fabric = at(view, Accuracy::Mixture, WeavePrecision::default(), size)?;
            let as_pbr = RenderOptions {
                fabric_as_pbr: true,
                ..fabric.clone()
            };
            progress.start(format!(
                "{} {}x{}: fabric against metallic-roughness",
                view.name(),
                size.0,
                size.1
            ));
            let jobs = [(&scene, &gpu, fabric), (&scene, &gpu, as_pbr)];
            let mut m = measure(&mut renderer, &jobs, config.warmup, frames, |_| {
                progress.done()
            })?;
            // The last frame rendered was the metallic-roughness one: same G-buffer.
            let (fabric_fraction, covered_fraction) = coverage_fractions(&renderer, &scene)?;
            let (_, pbr_times) = m.remove(1);
            let (_, fabric_times) = m.remove(0);
            pbr.push(PbrRow {
                view,
                width: size.0,
                height: size.1,
                fabric: fabric_times,
                pbr: pbr_times,
                fabric_fraction,
                covered_fraction,
            });
        }
    }
    progress.finish();
    machine.load_end = load_average();

    let mut report = BenchReport {
        machine,
        size: (width, height),
        ground_truth,
        accuracy,
        resolutions,
        lights,
        pbr,
        seconds: start.elapsed().as_secs_f64(),
        csv: config.out.join("bench.csv"),
        png: config.out.join("bench.png"),
    };
    write_text(&report.csv, &report.csv_text())?;
    let (pw, ph, pixels) = plot::plot(&report);
    crate::render::write_png(&report.png, pw, ph, &pixels)?;
    report.seconds = start.elapsed().as_secs_f64();
    Ok(report)
}

/// Shares of the last frame's pixels covered by fabric and by any surface.
fn coverage_fractions(renderer: &Renderer, scene: &Scene) -> crate::Result<(f64, f64)> {
    let (fabric, covered) = fabric_mask(renderer, scene)?;
    let pixels = fabric.len().max(1) as f64;
    let count = |m: &[bool]| m.iter().filter(|x| **x).count() as f64;
    Ok((count(&fabric) / pixels, count(&covered) / pixels))
}

/// Per pixel of the last frame (from its G-buffer): whether a fabric material covers it, and
/// whether any surface does.
pub(crate) fn fabric_mask(
    renderer: &Renderer,
    scene: &Scene,
) -> crate::Result<(Vec<bool>, Vec<bool>)> {
    let g = renderer.read_gbuffer()?;
    let covered: Vec<bool> = g.depth.iter().map(|d| *d > 0.0).collect();
    let fabric = covered
        .iter()
        .zip(g.surface.chunks_exact(4))
        .map(|(c, s)| {
            *c && scene
                .materials
                .get(s[1].round().max(0.0) as usize)
                .is_some_and(|m| m.fabric.is_some())
        })
        .collect();
    Ok((fabric, covered))
}

/// Creates the bench's output directory (and its parents) if missing.
pub(crate) fn create_out_dir(dir: &Path) -> crate::Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| Error::Io {
        context: format!("creating the bench output directory '{}'", dir.display()),
        source: e,
    })
}

/// The scene with its lights replaced by `n` point lights of finite range on a spiral around the
/// cloth (golden-angle steps, rising from 0.8 to 2.4 above the floor, 1.8 from the axis); the total
/// intensity stays the same whatever `n`, so the images stay comparable.
pub fn with_point_lights(scene: &Scene, n: u32) -> Scene {
    let mut lit = scene.clone();
    lit.lights = (0..n)
        .map(|i| {
            let t = (i as f32 + 0.5) / n as f32;
            let phi = i as f32 * 2.399_963; // the golden angle
            Light {
                name: format!("bench point light {i}"),
                kind: LightKind::Point,
                color: [1.0, 0.93, 0.85],
                intensity: 24.0 / n as f32,
                range: Some(6.0),
                position: Vec3::new(1.8 * phi.cos(), 0.8 + 1.6 * t, 1.8 * phi.sin()),
                direction: Vec3::NEG_Y,
                shadow: None,
            }
        })
        .collect();
    lit
}

/// The scene with its lights replaced by `n` point lights of range `range` spread evenly over
/// the scene's footprint (a Fibonacci lattice over the bounds in x and z, 0.3 above the top of
/// the geometry's lower half): local lamps, each reaching only the part of the scene under it.
pub fn with_local_point_lights(scene: &Scene, n: u32, range: f32) -> Scene {
    let mut lit = scene.clone();
    let b = scene.bounds().unwrap_or(crate::scene::Bounds {
        min: Vec3::splat(-1.0),
        max: Vec3::splat(1.0),
    });
    let size = b.max - b.min;
    let y = b.min.y + 0.5 * size.y + 0.3;
    lit.lights = (0..n)
        .map(|i| {
            let u = (i as f32 + 0.5) / n as f32;
            let v = (i as f32 * 0.618_034).fract();
            Light {
                name: format!("local point light {i}"),
                kind: LightKind::Point,
                color: [1.0, 0.9, 0.8],
                intensity: 1.5,
                range: Some(range),
                position: Vec3::new(b.min.x + u * size.x, y, b.min.z + v * size.z),
                direction: Vec3::NEG_Y,
                shadow: None,
            }
        })
        .collect();
    lit
}

fn write_text(path: &Path, text: &str) -> crate::Result<()> {
    crate::render::write_file(path, text.as_bytes())
}

/// A progress bar on stderr, drawn only when asked and stderr is a terminal.
struct Progress(indicatif::ProgressBar);

impl Progress {
    fn new(jobs: u64, visible: bool) -> Progress {
        let bar = if visible {
            indicatif::ProgressBar::new(jobs)
        } else {
            indicatif::ProgressBar::hidden()
        };
        if let Ok(style) = indicatif::ProgressStyle::with_template(
            "{elapsed_precise} [{bar:30.cyan/blue}] {pos}/{len} (eta {eta}) {msg}",
        ) {
            bar.set_style(style.progress_chars("=> "));
        }
        Progress(bar)
    }
    fn start(&self, what: String) {
        self.0.set_message(what);
    }
    fn done(&self) {
        self.0.inc(1);
    }
    fn finish(&self) {
        self.0.finish_and_clear();
    }
}

fn fmt_ms(ms: f64) -> String {
    if ms >= 100.0 {
        format!("{ms:.0}")
    } else if ms >= 10.0 {
        format!("{ms:.1}")
    } else {
        format!("{ms:.2}")
    }
}
