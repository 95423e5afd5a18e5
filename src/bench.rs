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

pub mod ibl_bench;
pub mod load;
pub mod plan_bench;
pub mod plot;
pub mod submission;
pub mod temporal;

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
const WEAVE_SCENE_GLB: &[u8] = include_bytes!("../assets/scenes/closeup.glb");

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

/// `weft bench --footprint`: per view, the default and the analytic weave with each footprint
/// filter (the bounding box, 2 x 2 and 3 x 3 parallelogram pieces), frames of one view
/// round-robin in one run, against the pixel-integrating ground truth of `truth_samples`². Returns
/// the table; writes `footprint.csv` into `out`.
pub fn footprint_bench(
    ctx: Context,
    views: &[View],
    (width, height): (u32, u32),
    truth_samples: u32,
    frames: u32,
    out: &Path,
) -> crate::Result<String> {
    use crate::render::Footprint;
    use std::fmt::Write;
    let mut renderer = Renderer::new(ctx)?;
    let footprints = [
        Footprint::Box,
        Footprint::Parallelogram(1),
        Footprint::Parallelogram(2),
        Footprint::Parallelogram(3),
    ];
    let precisions = [
        WeavePrecision::Rgba16f,
        WeavePrecision::Sat,
        WeavePrecision::Analytic,
    ];
    let mut table = String::new();
    let mut csv = String::from("view,precision,footprint,gbuffer_ms,lighting_ms,total_ms,psnr_db,flip_mean,cost_vs_box,truth_psnr_db\n");
    let _ = writeln!(
        table,
        "footprint filters at {width}x{height}, mixture, against {truth_samples}x{truth_samples} jittered point samples per pixel (errors over the fabric pixels)"
    );
    let _ = writeln!(
        table,
        "{:<10} {:<9} {:<16} {:>10} {:>11} {:>9} {:>8} {:>9} {:>8}",
        "view",
        "precision",
        "footprint",
        "gbuffer ms",
        "lighting ms",
        "total ms",
        "PSNR dB",
        "FLIP",
        "vs box"
    );
    for &view in views {
        let scene = view.scene().load()?;
        let gpu = renderer.upload(&scene)?;
        let base = RenderOptions {
            width,
            height,
            camera_override: Some(view.camera(&scene)?),
            ..crate::bench::timed_options()
        };
        let truth = pixel_truth(&mut renderer, &scene, &gpu, &base, truth_samples, || {})?;
        let mask = truth.fabric_everywhere();
        let jobs: Vec<_> = precisions
            .iter()
            .flat_map(|&p| footprints.iter().map(move |&f| (p, f)))
            .map(|(p, f)| {
                (
                    &scene,
                    &gpu,
                    RenderOptions {
                        weave_precision: p,
                        footprint: f,
                        ..base.clone()
                    },
                )
            })
            .collect();
        let measured = measure(&mut renderer, &jobs, 1, frames, |_| {})?;
        let truth_psnr = truth.noise_psnr(&mask);
        let mut box_ms = 0.0;
        for ((_, _, o), (frame, times)) in jobs.iter().zip(&measured) {
            if o.footprint == Footprint::Box {
                box_ms = times.total_ms();
            }
            let psnr = psnr_hdr_masked(&truth.frame, frame, &mask);
            let flip = flip_mean_masked(&truth.frame, frame, &mask);
            let ratio = times.total_ms() / box_ms.max(1e-9);
            let _ = writeln!(
                table,
                "{:<10} {:<9} {:<16} {:>10} {:>11} {:>9} {:>8.2} {:>9.5} {:>7.2}x",
                view.name(),
                o.weave_precision.name(),
                o.footprint.name(),
                fmt_ms(times.gbuffer_ms),
                fmt_ms(times.lighting_ms),
                fmt_ms(times.total_ms()),
                psnr,
                flip,
                ratio
            );
            let _ = writeln!(
                csv,
                "{},{},{},{:.4},{:.4},{:.4},{:.3},{:.6},{:.4},{}",
                view.name(),
                o.weave_precision.name(),
                o.footprint.name(),
                times.gbuffer_ms,
                times.lighting_ms,
                times.total_ms(),
                psnr,
                flip,
                ratio,
                truth_psnr.map(|p| format!("{p:.3}")).unwrap_or_default()
            );
        }
        let _ = writeln!(
            table,
            "{:<10} the ground truth's own PSNR: {}",
            "",
            truth_psnr
                .map(|p| format!("~{p:.1} dB"))
                .unwrap_or_else(|| "unknown".into())
        );
    }
    create_out_dir(out)?;
    write_text(&out.join("footprint.csv"), &csv)?;
    let _ = writeln!(table, "vs box: total time against the box footprint of the same view and precision (same run, frames round-robin)");
    Ok(table)
}

/// A pixel-integrating ground truth ([`pixel_truth`]).
pub struct Truth {
    /// The mean of the sample frames' linear HDR and its tone-mapped sRGB image.
    pub frame: Frame,
    /// Per pixel, how many of the samples hit a fabric material.
    pub fabric_samples: Vec<u32>,
    pub samples: u32,
    /// Summed over the sample frames.
    pub times: PassTimes,
    /// The linear HDR means of the two halves of the strata (a checkerboard over the n x n grid),
    /// RGB: their difference estimates the truth's own sampling noise ([`Truth::noise_psnr`]).
    pub halves: [Vec<f64>; 2],
}

impl Truth {
    /// Pixels covered by fabric at every sample: away from silhouettes, which the ground truth
    /// antialiases and no accuracy level does (the levels differ in the weave, not in the edges).
    pub fn fabric_everywhere(&self) -> Vec<bool> {
        let all = self.samples * self.samples;
        self.fabric_samples.iter().map(|&c| c == all).collect()
    }

    /// The PSNR (dB, as [`psnr_hdr_masked`]) of the truth against the exact pixel integral,
    /// estimated from its two halves over `mask`: they are independent estimates with half the
    /// samples each, so their difference has 4x the variance of the truth's error and the truth's
    /// PSNR is theirs + 6.02 dB. None when n = 1 (no second half) or the halves are equal.
    pub fn noise_psnr(&self, mask: &[bool]) -> Option<f64> {
        if self.samples < 2 {
            return None;
        }
        let (mut sum, mut n, mut peak) = (0.0f64, 0usize, 0.0f64);
        for (i, _) in mask.iter().enumerate().filter(|(_, m)| **m) {
            for c in 0..3 {
                let d = self.halves[0][3 * i + c] - self.halves[1][3 * i + c];
                sum += d * d;
                peak = peak.max(self.frame.hdr[4 * i + c] as f64);
            }
            n += 3;
        }
        if n == 0 || sum == 0.0 {
            return None;
        }
        Some(psnr_db(peak, sum / n as f64) + 10.0 * 4f64.log10())
    }
}

/// The ground truth of the accuracy sweep: `n`² frames of `options` sampled at stratified,
/// jittered sub-pixel offsets (one offset per frame, in its own cell of an n x n grid over the
/// pixel), each with the weave evaluated exactly at the sample point (accuracy `nearest`, weave
/// precision `analytic`: no footprint, no texture, at a point the one-lobe level is the two-lobe
/// mixture), their linear HDR averaged: a box pixel filter over whatever the projection makes
/// the footprint. It shares no footprint approximation with the levels it judges. The sRGB image
/// is the mean tone-mapped on the CPU (`reference::shading::tonemap`, tonemap.frag's twin).
/// `done` is called after each frame.
pub fn pixel_truth(
    renderer: &mut Renderer,
    scene: &Scene,
    gpu: &GpuScene,
    options: &RenderOptions,
    n: u32,
    mut done: impl FnMut(),
) -> crate::Result<Truth> {
    use crate::reference::shading::display_rgba8;
    let n = n.max(1);
    let (w, h) = (options.width as usize, options.height as usize);
    let mut sum = vec![0.0f64; w * h * 3];
    let mut halves = [vec![0.0f64; w * h * 3], vec![0.0f64; w * h * 3]];
    let mut counts = [0u32; 2];
    let mut fabric_samples = vec![0u32; w * h];
    let (mut gbuffer, mut lighting) = (0.0, 0.0);
    let mut last = None;
    // A fixed sequence (splitmix64): the truth is deterministic.
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut unit = move || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    };
    for j in 0..n {
        for i in 0..n {
            let jitter = [
                (i as f32 + unit()) / n as f32 - 0.5,
                (j as f32 + unit()) / n as f32 - 0.5,
            ];
            let o = RenderOptions {
                accuracy: Accuracy::Nearest,
                weave_precision: WeavePrecision::Analytic,
                read_hdr: true,
                jitter,
                ..options.clone()
            };
            let frame = renderer.render_frame(scene, gpu, &o)?;
            gbuffer += pass_ms(&frame, "gbuffer");
            lighting += pass_ms(&frame, "lighting");
            let half = ((i + j) % 2) as usize;
            counts[half] += 1;
            for ((acc, hacc), px) in sum
                .chunks_exact_mut(3)
                .zip(halves[half].chunks_exact_mut(3))
                .zip(frame.hdr.chunks_exact(4))
            {
                for c in 0..3 {
                    acc[c] += px[c] as f64;
                    hacc[c] += px[c] as f64;
                }
            }
            let (fabric, _) = fabric_mask(renderer, scene)?;
            for (count, f) in fabric_samples.iter_mut().zip(fabric) {
                *count += f as u32;
            }
            last = Some(frame);
            done();
        }
    }
    for (h, &c) in halves.iter_mut().zip(&counts) {
        let s = 1.0 / c.max(1) as f64;
        h.iter_mut().for_each(|v| *v *= s);
    }
    let mut frame = last.expect("n >= 1 frames");
    let scale = 1.0 / (n * n) as f64;
    frame.hdr = sum
        .chunks_exact(3)
        .flat_map(|c| {
            [
                (c[0] * scale) as f32,
                (c[1] * scale) as f32,
                (c[2] * scale) as f32,
                1.0,
            ]
        })
        .collect();
    frame.ldr = frame
        .hdr
        .chunks_exact(4)
        .flat_map(|c| display_rgba8([c[0], c[1], c[2]], options.exposure.exp2()))
        .collect();
    Ok(Truth {
        frame,
        fabric_samples,
        halves,
        samples: n,
        times: PassTimes {
            gbuffer_ms: gbuffer,
            lighting_ms: lighting,
            frames: n * n,
        },
    })
}

/// Renders each job `warmup` times (thrown away: lavapipe compiles a pipeline at its first
/// submit), then `frames` rounds of one frame per job, so that a change in the machine's load
/// falls on every job alike. Returns per job its last frame and the median GPU time of each pass;
/// `done(i)` is called when job `i` is measured.
fn measure(
    renderer: &mut Renderer,
    jobs: &[(&Scene, &GpuScene, RenderOptions)],
    warmup: u32,
    frames: u32,
    mut done: impl FnMut(usize),
) -> crate::Result<Vec<(Frame, PassTimes)>> {
    for _ in 0..warmup {
        for (scene, gpu, options) in jobs {
            renderer.render_frame(scene, gpu, options)?;
        }
    }
    let frames = frames.max(1);
    let mut gbuffer = vec![Vec::new(); jobs.len()];
    let mut lighting = vec![Vec::new(); jobs.len()];
    let mut last: Vec<Option<Frame>> = jobs.iter().map(|_| None).collect();
    for round in 0..frames {
        for (i, (scene, gpu, options)) in jobs.iter().enumerate() {
            let frame = renderer.render_frame(scene, gpu, options)?;
            gbuffer[i].push(pass_ms(&frame, "gbuffer"));
            lighting[i].push(pass_ms(&frame, "lighting"));
            last[i] = Some(frame);
            if round + 1 == frames {
                done(i);
            }
        }
    }
    Ok(last
        .into_iter()
        .zip(gbuffer.into_iter().zip(lighting))
        .map(|(frame, (g, l))| {
            let times = PassTimes {
                gbuffer_ms: median(g),
                lighting_ms: median(l),
                frames,
            };
            (frame.expect("at least one frame per job"), times)
        })
        .collect())
}

/// Marks the rows that no other row of the same view beats in both time and error.
fn mark_pareto_front(rows: &mut [AccuracyRow]) {
    let flags: Vec<bool> = rows
        .iter()
        .map(|r| {
            !rows.iter().any(|o| {
                o.view == r.view
                    && o.times.total_ms() <= r.times.total_ms()
                    && o.flip_mean <= r.flip_mean
                    && (o.times.total_ms() < r.times.total_ms() || o.flip_mean < r.flip_mean)
            })
        })
        .collect();
    for (r, f) in rows.iter_mut().zip(flags) {
        r.pareto = f;
    }
}

/// The options every bench measurement starts from: the defaults, with each pass submitted alone
/// between two timestamps (`Submission::PerPass`), since the tables report passes and lavapipe's
/// timestamps between render passes in one submission read short.
pub(crate) fn timed_options() -> RenderOptions {
    RenderOptions {
        submission: crate::render::Submission::PerPass,
        ..Default::default()
    }
}

/// The GPU time of a pass (its wall time where the device has no timestamps), 0 if it did not run.
pub(crate) fn pass_ms(frame: &Frame, name: &str) -> f64 {
    frame
        .timings
        .iter()
        .find(|t| t.name == name)
        .map(|t| t.gpu_ms.or(t.wall_ms).unwrap_or(0.0))
        .unwrap_or(0.0)
}

pub fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Least-squares line through (x, y): (slope, intercept).
pub fn fit_line(points: &[(f64, f64)]) -> Option<(f64, f64)> {
    if points.len() < 2 {
        return None;
    }
    let n = points.len() as f64;
    let mx = points.iter().map(|p| p.0).sum::<f64>() / n;
    let my = points.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = points.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    if sxx <= 0.0 {
        return None;
    }
    let slope = sxy / sxx;
    Some((slope, my - slope * mx))
}

/// A frame's sRGB image as packed RGB bytes (what FLIP takes).
pub(crate) fn rgb8(frame: &Frame) -> Vec<u8> {
    frame
        .ldr
        .chunks_exact(4)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect()
}

/// The per-pixel FLIP error (Andersson et al. 2020) of the packed sRGB image `test` against
/// `reference`, both `w` x `h`.
pub(crate) fn flip_map_rgb(w: u32, h: u32, reference: &[u8], test: &[u8]) -> Vec<f32> {
    let a = nv_flip::FlipImageRgb8::with_data(w, h, reference);
    let b = nv_flip::FlipImageRgb8::with_data(w, h, test);
    nv_flip::flip(a, b, nv_flip::DEFAULT_PIXELS_PER_DEGREE).to_vec()
}

/// The FLIP error map of `test`'s sRGB image against `reference`'s.
fn flip_map(reference: &Frame, test: &Frame) -> Vec<f32> {
    flip_map_rgb(
        reference.width,
        reference.height,
        &rgb8(reference),
        &rgb8(test),
    )
}

/// Mean FLIP error of `test`'s sRGB image against `reference`'s.
pub fn flip_mean(reference: &Frame, test: &Frame) -> f64 {
    let map = flip_map(reference, test);
    map.iter().map(|&v| v as f64).sum::<f64>() / map.len().max(1) as f64
}

/// Root-mean-square difference of the linear HDR RGB (alpha ignored).
pub fn rmse_hdr(reference: &Frame, test: &Frame) -> f64 {
    let mut sum = 0.0f64;
    let mut n = 0usize;
    for (a, b) in reference.hdr.chunks_exact(4).zip(test.hdr.chunks_exact(4)) {
        for c in 0..3 {
            let d = a[c] as f64 - b[c] as f64;
            sum += d * d;
        }
        n += 3;
    }
    if n == 0 {
        0.0
    } else {
        (sum / n as f64).sqrt()
    }
}

/// Mean FLIP error of `test`'s sRGB image against `reference`'s over the pixels of `mask` (the
/// error map is computed on the whole images: FLIP looks at neighbourhoods).
pub fn flip_mean_masked(reference: &Frame, test: &Frame, mask: &[bool]) -> f64 {
    let values = flip_map(reference, test);
    let (mut sum, mut count) = (0.0f64, 0usize);
    for (v, _) in values.iter().zip(mask).filter(|(_, m)| **m) {
        sum += *v as f64;
        count += 1;
    }
    if count == 0 {
        0.0
    } else {
        sum / count as f64
    }
}

/// Sum of squared linear HDR RGB differences over `mask`, the channel count, and the reference's
/// largest channel value there.
fn masked_sse(reference: &[f32], test: &[f32], mask: &[bool]) -> (f64, usize, f64) {
    let (mut sum, mut n, mut peak) = (0.0f64, 0usize, 0.0f64);
    for ((a, b), _) in reference
        .chunks_exact(4)
        .zip(test.chunks_exact(4))
        .zip(mask)
        .filter(|(_, m)| **m)
    {
        for c in 0..3 {
            let d = a[c] as f64 - b[c] as f64;
            sum += d * d;
            peak = peak.max(a[c] as f64);
        }
        n += 3;
    }
    (sum, n, peak)
}

/// RMSE of the linear HDR RGB over the pixels of `mask`.
pub fn rmse_hdr_masked(reference: &Frame, test: &Frame, mask: &[bool]) -> f64 {
    let (sum, n, _) = masked_sse(&reference.hdr, &test.hdr, mask);
    if n == 0 {
        0.0
    } else {
        (sum / n as f64).sqrt()
    }
}

/// PSNR (dB) of the linear HDR RGB over the pixels of `mask`: 10·log10(peak² / MSE), the peak
/// being the reference's largest channel value over the mask; infinite for identical images.
pub fn psnr_hdr_masked(reference: &Frame, test: &Frame, mask: &[bool]) -> f64 {
    psnr_linear(&reference.hdr, &test.hdr, mask)
}

/// [`psnr_hdr_masked`] of linear RGBA images given as slices (e.g. a CPU reference's).
pub fn psnr_linear(reference: &[f32], test: &[f32], mask: &[bool]) -> f64 {
    let (sum, n, peak) = masked_sse(reference, test, mask);
    if n == 0 || sum == 0.0 {
        return f64::INFINITY;
    }
    psnr_db(peak, sum / n as f64)
}

/// 10·log10(peak² / mse).
fn psnr_db(peak: f64, mse: f64) -> f64 {
    10.0 * (peak * peak / mse).log10()
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

impl BenchReport {
    /// The ratio of the first PBR row that has one (the mid view when run by default).
    pub fn pbr_ratio(&self) -> Option<f64> {
        self.pbr.first().map(|r| r.ratio())
    }

    /// (slope ms per megapixel, intercept ms) of G-buffer + lighting time over resolution.
    pub fn ms_per_megapixel(&self) -> Option<(f64, f64)> {
        fit_line(
            &self
                .resolutions
                .iter()
                .map(|r| (r.megapixels(), r.times.total_ms()))
                .collect::<Vec<_>>(),
        )
    }

    /// (slope ms per light, intercept ms) of the lighting pass over the number of point lights.
    pub fn ms_per_light(&self) -> Option<(f64, f64)> {
        fit_line(
            &self
                .lights
                .iter()
                .map(|r| (r.lights as f64, r.times.lighting_ms))
                .collect::<Vec<_>>(),
        )
    }

    /// The whole report as text: machine, the accuracy table, the growth tables, the ratio.
    pub fn table(&self) -> String {
        use std::fmt::Write;
        let m = &self.machine;
        let mut t = String::new();
        let load = |l: Option<f64>| l.map(|l| format!("{l:.2}")).unwrap_or_else(|| "?".into());
        let _ = writeln!(
            t,
            "device   {} — {} (Vulkan {})",
            m.device, m.driver, m.api_version
        );
        let _ = writeln!(
            t,
            "cpu      {} x {} — load average {} at start, {} at end",
            m.cores,
            m.cpu,
            load(m.load_start),
            load(m.load_end)
        );
        let _ = writeln!(
            t,
            "times    GPU timestamps, one pass per submit, median of warm frames; validation {}",
            if m.validation { "ON (slower)" } else { "off" }
        );
        let _ = writeln!(t);
        let (w, h) = self.size;
        let _ = writeln!(
            t,
            "accuracy at {w}x{h} against the pixel-integrating ground truth, errors over the fabric pixels:"
        );
        for g in &self.ground_truth {
            let _ = writeln!(
                t,
                "  {:<10} ground truth {n}x{n} jittered point samples per pixel: gbuffer {} ms + lighting {} ms (sum of {} frames), fabric fills {:.0}% of the image, its own PSNR {}",
                g.view.name(),
                fmt_ms(g.times.gbuffer_ms),
                fmt_ms(g.times.lighting_ms),
                g.times.frames,
                g.fabric_fraction * 100.0,
                g.noise_psnr.map(|p| format!("~{p:.1} dB")).unwrap_or_else(|| "unknown".into()),
                n = g.samples,
            );
        }
        let _ = writeln!(
            t,
            "{:<10} {:<16} {:<9} {:>10} {:>11} {:>9} {:>10} {:>10} {:>8} {:>6}",
            "view",
            "level",
            "precision",
            "gbuffer ms",
            "lighting ms",
            "total ms",
            "FLIP mean",
            "HDR RMSE",
            "PSNR dB",
            "front"
        );
        for r in &self.accuracy {
            let _ = writeln!(
                t,
                "{:<10} {:<16} {:<9} {:>10} {:>11} {:>9} {:>10.5} {:>10.5} {:>8.2} {:>6}",
                r.view.name(),
                r.level.name(),
                r.precision.name(),
                fmt_ms(r.times.gbuffer_ms),
                fmt_ms(r.times.lighting_ms),
                fmt_ms(r.times.total_ms()),
                r.flip_mean,
                r.rmse,
                r.psnr,
                if r.pareto { "*" } else { "" }
            );
        }
        let _ = writeln!(t, "front: * = on the view's Pareto front (no other variant of the view is both faster and closer)");
        if !self.resolutions.is_empty() {
            let _ = writeln!(t);
            let _ = writeln!(
                t,
                "growth over resolution (mid view, mixture, rgba16f, the scene's 3 lights):"
            );
            let _ = writeln!(
                t,
                "{:<10} {:>6} {:>10} {:>11} {:>9} {:>8}",
                "size", "MP", "gbuffer ms", "lighting ms", "total ms", "ms/MP"
            );
            for r in &self.resolutions {
                let _ = writeln!(
                    t,
                    "{:<10} {:>6.2} {:>10} {:>11} {:>9} {:>8.1}",
                    format!("{}x{}", r.width, r.height),
                    r.megapixels(),
                    fmt_ms(r.times.gbuffer_ms),
                    fmt_ms(r.times.lighting_ms),
                    fmt_ms(r.times.total_ms()),
                    r.times.total_ms() / r.megapixels()
                );
            }
            if let Some((slope, intercept)) = self.ms_per_megapixel() {
                let _ = writeln!(t, "fit: {slope:.1} ms per megapixel + {intercept:.1} ms");
            }
        }
        if !self.lights.is_empty() {
            let _ = writeln!(t);
            let (lw, lh) = (self.lights[0].width, self.lights[0].height);
            let _ = writeln!(
                t,
                "growth over point lights (mid view, mixture, rgba16f, {lw}x{lh}):"
            );
            let _ = writeln!(
                t,
                "{:<7} {:>10} {:>11} {:>12}",
                "lights", "gbuffer ms", "lighting ms", "lighting/N"
            );
            for r in &self.lights {
                let _ = writeln!(
                    t,
                    "{:<7} {:>10} {:>11} {:>12}",
                    r.lights,
                    fmt_ms(r.times.gbuffer_ms),
                    fmt_ms(r.times.lighting_ms),
                    fmt_ms(r.times.lighting_ms / r.lights as f64)
                );
            }
            if let Some((slope, intercept)) = self.ms_per_light() {
                let _ = writeln!(
                    t,
                    "fit: {slope:.2} ms per light + {intercept:.1} ms (lighting pass)"
                );
            }
        }
        if !self.pbr.is_empty() {
            let _ = writeln!(t);
            let _ = writeln!(t, "fabric lighting pass against metallic-roughness on the same G-buffer (mixture, rgba16f):");
            for r in &self.pbr {
                let head = format!(
                    "{:<9} {}x{} fabric {:.0}% of the image: fabric lighting {} ms",
                    r.view.name(),
                    r.width,
                    r.height,
                    r.fabric_fraction * 100.0,
                    fmt_ms(r.fabric.lighting_ms)
                );
                let _ = writeln!(
                    t,
                    "{head}, as metallic-roughness {} ms: ratio {:.2}x (target: within 1.5x); \
                     about {:.1}x per fabric pixel",
                    fmt_ms(r.pbr.lighting_ms),
                    r.ratio(),
                    r.ratio_per_fabric_pixel()
                );
            }
        }
        let _ = writeln!(t);
        let _ = writeln!(
            t,
            "run took {:.0} s; wrote {} and {}",
            self.seconds,
            self.csv.display(),
            self.png.display()
        );
        t
    }

    /// One row per measurement; `section` says which table it belongs to.
    pub fn csv_text(&self) -> String {
        let mut t = CSV_COLUMNS.join(",");
        t.push('\n');
        let (w, h) = self.size;
        let base = |section: &str,
                    view: View,
                    level: String,
                    precision: WeavePrecision,
                    size: (u32, u32),
                    lights: usize| {
            let mut r = CsvRow::default();
            r.set("section", section);
            r.set("view", view.name());
            r.set("level", level);
            r.set("precision", precision.name());
            r.set("width", size.0);
            r.set("height", size.1);
            r.set("lights", lights);
            r
        };
        let times = |r: &mut CsvRow, p: &PassTimes| {
            r.set("frames", p.frames);
            r.set("gbuffer_ms", format!("{:.4}", p.gbuffer_ms));
            r.set("lighting_ms", format!("{:.4}", p.lighting_ms));
            r.set("total_ms", format!("{:.4}", p.total_ms()));
        };
        let scene_lights = 3; // the default scene's key, fill and rim lights
        for g in &self.ground_truth {
            let mut r = base(
                "ground-truth",
                g.view,
                format!("pixel:{}", g.samples),
                WeavePrecision::Analytic,
                (w, h),
                scene_lights,
            );
            times(&mut r, &g.times);
            r.set("fabric_fraction", format!("{:.4}", g.fabric_fraction));
            if let Some(p) = g.noise_psnr {
                r.set("psnr_db", format!("{p:.3}"));
            }
            r.push(&mut t);
        }
        for a in &self.accuracy {
            let mut r = base(
                "accuracy",
                a.view,
                a.level.name(),
                a.precision,
                (w, h),
                scene_lights,
            );
            times(&mut r, &a.times);
            r.set("flip_mean", format!("{:.6}", a.flip_mean));
            r.set("rmse_hdr", format!("{:.6}", a.rmse));
            r.set("psnr_db", format!("{:.3}", a.psnr));
            r.set("pareto", a.pareto as u8);
            r.push(&mut t);
        }
        let default = (Accuracy::Mixture, WeavePrecision::default());
        for g in &self.resolutions {
            let mut r = base(
                "resolution",
                View::Mid,
                default.0.name(),
                default.1,
                (g.width, g.height),
                scene_lights,
            );
            times(&mut r, &g.times);
            r.set(
                "ms_per_mp",
                format!("{:.4}", g.times.total_ms() / g.megapixels()),
            );
            r.push(&mut t);
        }
        for g in &self.lights {
            let mut r = base(
                "lights",
                View::Mid,
                default.0.name(),
                default.1,
                (g.width, g.height),
                g.lights as usize,
            );
            times(&mut r, &g.times);
            r.set(
                "ms_per_light",
                format!("{:.4}", g.times.lighting_ms / g.lights as f64),
            );
            r.push(&mut t);
        }
        for p in &self.pbr {
            for (section, pt) in [
                ("pbr-fabric", &p.fabric),
                ("pbr-metallic-roughness", &p.pbr),
            ] {
                let mut r = base(
                    section,
                    p.view,
                    default.0.name(),
                    default.1,
                    (p.width, p.height),
                    scene_lights,
                );
                times(&mut r, pt);
                r.set("fabric_fraction", format!("{:.4}", p.fabric_fraction));
                r.set("ratio", format!("{:.4}", p.ratio()));
                r.set(
                    "ratio_per_fabric_pixel",
                    format!("{:.4}", p.ratio_per_fabric_pixel()),
                );
                r.push(&mut t);
            }
        }
        if let Some((slope, intercept)) = self.ms_per_megapixel() {
            let mut r = base(
                "fit-resolution",
                View::Mid,
                default.0.name(),
                default.1,
                (0, 0),
                scene_lights,
            );
            r.set("width", "");
            r.set("height", "");
            r.set("ms_per_mp", format!("{slope:.4}"));
            r.set("total_ms", format!("{intercept:.4}"));
            r.push(&mut t);
        }
        if let Some((slope, intercept)) = self.ms_per_light() {
            let (lw, lh) = self
                .lights
                .first()
                .map(|l| (l.width, l.height))
                .unwrap_or((0, 0));
            let mut r = base(
                "fit-lights",
                View::Mid,
                default.0.name(),
                default.1,
                (lw, lh),
                0,
            );
            r.set("lights", "");
            r.set("ms_per_light", format!("{slope:.4}"));
            r.set("lighting_ms", format!("{intercept:.4}"));
            r.push(&mut t);
        }
        t
    }
}

/// The columns of bench.csv. In the `fit-*` rows, `ms_per_mp` / `ms_per_light` is the fitted slope
/// and `total_ms` / `lighting_ms` the intercept.
pub const CSV_COLUMNS: [&str; 20] = [
    "section",
    "view",
    "level",
    "precision",
    "width",
    "height",
    "lights",
    "frames",
    "gbuffer_ms",
    "lighting_ms",
    "total_ms",
    "flip_mean",
    "rmse_hdr",
    "psnr_db",
    "ms_per_mp",
    "ms_per_light",
    "fabric_fraction",
    "ratio",
    "ratio_per_fabric_pixel",
    "pareto",
];

/// One CSV line, filled by column name; unset columns stay empty.
#[derive(Default)]
struct CsvRow(Vec<(usize, String)>);

impl CsvRow {
    fn set(&mut self, column: &str, value: impl ToString) {
        let i = CSV_COLUMNS
            .iter()
            .position(|c| *c == column)
            .expect("a column of CSV_COLUMNS");
        self.0.retain(|(j, _)| *j != i);
        self.0.push((i, value.to_string()));
    }

    fn push(&self, out: &mut String) {
        let mut fields = vec![String::new(); CSV_COLUMNS.len()];
        for (i, v) in &self.0 {
            fields[*i] = v.clone();
        }
        out.push_str(&fields.join(","));
        out.push('\n');
    }
}
