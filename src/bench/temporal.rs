//! `weft bench --temporal`: how much each accuracy level flickers when the camera moves slowly,
//! against the supersampled ground truth's sequence (issue 18).
//!
//! For the bench's mid and far views (where the weave is at or far below a pixel), the camera
//! turns about the vertical axis through the scene's centre by a small angle per frame
//! ([`crate::batch::sequence::CameraMotion`], as `weft render --orbit`). Each level renders the
//! same `frames` frames; every pair of consecutive frames is compared on the pixels that are
//! fabric in both (from the G-buffer's material index), with two measures:
//!
//! - **flicker** = Σ |Y(t+1) − Y(t)| / Σ (G(t) + G(t+1)) / 2: the mean absolute change of linear
//!   luminance from one frame to the next, relative to the ground truth's mean luminance G on
//!   the same pixels (one denominator for every level, so the figures add up; see below);
//! - the mean FLIP between the two consecutive sRGB frames on the same pixels (what a viewer
//!   sees change).
//!
//! Both are averaged over the pairs. The ground truth's own flicker is the change the motion
//! really makes (shading moving over the cloth, the weave's residual aliasing at its sample
//! count); a level's **ratio** flicker / ground-truth flicker says how much it adds.
//!
//! What bounds a level's flicker: per pixel, |L(t+1) − L(t)| ≤ |G(t+1) − G(t)| + |L(t) − G(t)| +
//! |L(t+1) − G(t+1)| (the triangle inequality), so, summed with the same denominator,
//! flicker(L) ≤ flicker(G) + 2 · error(L), where error(L) is the level's mean relative
//! luminance error against the ground truth in a still frame (the `error` column: the mean of
//! the two frames' errors of each pair, averaged). A level that is accurate in each frame cannot
//! flicker much more than the ground truth, whatever the motion; the `bound` column is that sum.

use std::path::PathBuf;

use super::plot::{text_width, Canvas, LogAxis};
use super::View;
use crate::batch::sequence::CameraMotion;
use crate::render::{Accuracy, Frame, RenderOptions, Renderer, WeavePrecision};
use crate::scene::Scene;
use crate::Error;

/// What a temporal bench renders.
#[derive(Clone, Debug)]
pub struct TemporalConfig {
    pub views: Vec<View>,
    /// The levels compared with the ground truth, in the order they are reported.
    pub variants: Vec<(Accuracy, WeavePrecision)>,
    /// The reference sequence (with the analytic weave).
    pub ground_truth: Accuracy,
    pub size: (u32, u32),
    /// Frames of each sequence (frames - 1 consecutive pairs).
    pub frames: u32,
    /// Degrees the camera turns between frames.
    pub degrees_per_frame: f32,
    /// Where temporal.csv and bench-temporal.png go.
    pub out: PathBuf,
}

impl Default for TemporalConfig {
    /// Mid and far at 640x360 (the size of `weft bench`'s accuracy sweep, so the footprints are
    /// its), 9 frames turning 0.1 degree each (a turntable of 3 degrees a second at 30 fps:
    /// a fraction of a pixel a frame, docs/performance.md), every level and supersampled:16, ground truth
    /// supersampled:32. About 1.5 minutes on lavapipe with 2 cores.
    fn default() -> Self {
        let mut variants = super::cross_product(&super::LEVELS[..3], &[WeavePrecision::default()]);
        variants.push((Accuracy::Mixture, WeavePrecision::Analytic));
        variants.extend(
            super::LEVELS[3..]
                .iter()
                .chain(&[Accuracy::Supersampled(16)])
                .map(|&l| (l, WeavePrecision::Analytic)),
        );
        TemporalConfig {
            views: vec![View::Mid, View::Far],
            variants,
            ground_truth: Accuracy::Supersampled(32),
            size: (640, 360),
            frames: 9,
            degrees_per_frame: 0.1,
            out: PathBuf::from("target/bench"),
        }
    }
}

impl TemporalConfig {
    /// About 10 seconds: 160x90, 5 frames, levels up to supersampled:8, ground truth
    /// supersampled:16.
    pub fn quick() -> Self {
        let mut variants = TemporalConfig::default().variants;
        variants.retain(|v| v.0 != Accuracy::Supersampled(16));
        TemporalConfig {
            variants,
            size: (160, 90),
            frames: 5,
            ground_truth: Accuracy::Supersampled(16),
            ..TemporalConfig::default()
        }
    }

    /// Refuses a configuration that cannot run (before any device is opened).
    pub fn check(&self) -> crate::Result<()> {
        if self.frames < 2 {
            return Err(Error::input(
                "bench --temporal: --frames must be at least 2 (one pair of consecutive frames)",
            ));
        }
        if !(self.degrees_per_frame.is_finite() && self.degrees_per_frame.abs() <= 90.0) {
            return Err(Error::input(format!(
                "bench --temporal: --temporal-step {} is out of range: give degrees per frame, at most 90",
                self.degrees_per_frame
            )));
        }
        if self.views.is_empty() || self.variants.is_empty() {
            return Err(Error::input(
                "bench --temporal needs at least one view and one level",
            ));
        }
        RenderOptions {
            width: self.size.0,
            height: self.size.1,
            accuracy: self.ground_truth,
            ..crate::bench::timed_options()
        }
        .validate()
    }
}

/// One (view, level) of the temporal bench.
#[derive(Clone, Debug)]
pub struct TemporalRow {
    pub view: View,
    /// None: the ground truth itself.
    pub level: Option<(Accuracy, WeavePrecision)>,
    /// Mean relative |ΔY| of consecutive frames on fabric pixels.
    pub flicker: f64,
    /// Mean FLIP between consecutive frames on fabric pixels.
    pub flip: f64,
    /// Mean relative |Y − G| against the ground truth's frame (0 for the ground truth).
    pub error: f64,
    /// flicker / the ground truth's flicker.
    pub ratio: f64,
    /// FLIP / the ground truth's FLIP.
    pub flip_ratio: f64,
}

impl TemporalRow {
    /// The triangle-inequality bound on `flicker`: ground-truth flicker + 2 error.
    pub fn bound(&self, truth_flicker: f64) -> f64 {
        truth_flicker + 2.0 * self.error
    }

    pub fn label(&self, truth: Accuracy) -> String {
        match self.level {
            None => format!("{} (ground truth)", truth.name()),
            Some((l, p)) => format!("{} {}", l.name(), p.name()),
        }
    }
}

#[derive(Clone, Debug)]
pub struct TemporalReport {
    pub config: TemporalConfig,
    pub rows: Vec<TemporalRow>,
    /// Share of the image that is fabric in every frame, per view.
    pub fabric_fraction: Vec<(View, f64)>,
    pub device: String,
    pub seconds: f64,
}

/// A level's name on the plot: N, FP, MIX, SSn.
fn short_label(level: Accuracy) -> String {
    match level {
        Accuracy::Nearest => "N".into(),
        Accuracy::FilteredParams => "FP".into(),
        Accuracy::Mixture => "MIX".into(),
        Accuracy::Supersampled(n) => format!("SS{n}"),
    }
}

/// A sequence reduced to what the measures need: per frame, linear luminance and sRGB RGB.
struct Sequence {
    luminance: Vec<Vec<f32>>,
    rgb: Vec<Vec<u8>>,
}

fn luminance(frame: &Frame) -> Vec<f32> {
    frame
        .hdr
        .chunks_exact(4)
        .map(|p| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2])
        .collect()
}

/// Renders `frames` frames of `view` turning by `degrees_per_frame`; with `mask`, also returns
/// per frame which pixels are fabric.
fn render_sequence(
    renderer: &mut Renderer,
    scene: &Scene,
    gpu: &crate::render::GpuScene,
    config: &TemporalConfig,
    view: View,
    (accuracy, precision): (Accuracy, WeavePrecision),
    mask: Option<&mut Vec<Vec<bool>>>,
) -> crate::Result<Sequence> {
    let base = view.camera(scene)?;
    // t counts frames: the orbit's speed is then degrees per frame.
    let motion = CameraMotion::centered(scene, config.degrees_per_frame, 0.0)?;
    let mut seq = Sequence {
        luminance: Vec::new(),
        rgb: Vec::new(),
    };
    let mut masks = Vec::new();
    for k in 0..config.frames {
        let options = RenderOptions {
            width: config.size.0,
            height: config.size.1,
            camera_override: Some(motion.camera_at(&base, k as f32)?),
            accuracy,
            weave_precision: precision,
            ..crate::bench::timed_options()
        };
        let frame = renderer.render_frame(scene, gpu, &options)?;
        if mask.is_some() {
            masks.push(super::fabric_mask(renderer, scene)?.0);
        }
        seq.luminance.push(luminance(&frame));
        seq.rgb.push(super::rgb8(&frame));
    }
    if let Some(m) = mask {
        *m = masks;
    }
    Ok(seq)
}

/// (flicker, FLIP, error) of `seq` against the ground truth `truth` on the pair masks.
fn measure(
    (w, h): (u32, u32),
    seq: &Sequence,
    truth: &Sequence,
    masks: &[Vec<bool>],
) -> (f64, f64, f64) {
    let pairs = seq.luminance.len() - 1;
    let (mut flicker, mut flip, mut error) = (0.0, 0.0, 0.0);
    for k in 0..pairs {
        let both: Vec<bool> = masks[k]
            .iter()
            .zip(&masks[k + 1])
            .map(|(a, b)| *a && *b)
            .collect();
        let (y0, y1) = (&seq.luminance[k], &seq.luminance[k + 1]);
        let (g0, g1) = (&truth.luminance[k], &truth.luminance[k + 1]);
        let (mut change, mut err, mut denom, mut n) = (0.0f64, 0.0f64, 0.0f64, 0usize);
        for i in (0..both.len()).filter(|&i| both[i]) {
            change += f64::from((y1[i] - y0[i]).abs());
            err += 0.5 * f64::from((y0[i] - g0[i]).abs() + (y1[i] - g1[i]).abs());
            denom += 0.5 * f64::from(g0[i] + g1[i]);
            n += 1;
        }
        let denom = denom.max(1e-12);
        flicker += change / denom;
        error += err / denom;
        let map = super::flip_map_rgb(w, h, &seq.rgb[k], &seq.rgb[k + 1]);
        let sum: f64 = (0..both.len())
            .filter(|&i| both[i])
            .map(|i| f64::from(map[i]))
            .sum();
        flip += sum / n.max(1) as f64;
    }
    let p = pairs as f64;
    (flicker / p, flip / p, error / p)
}

/// Runs the temporal bench on the default scene; writes `temporal.csv` and `bench-temporal.png`
/// into `config.out`.
pub fn run(renderer: &mut Renderer, config: &TemporalConfig) -> crate::Result<TemporalReport> {
    config.check()?;
    let start = std::time::Instant::now();
    let scene = crate::scene::default_scene();
    let gpu = renderer.upload(&scene)?;
    let mut rows = Vec::new();
    let mut fabric_fraction = Vec::new();
    for &view in &config.views {
        let mut masks = Vec::new();
        let truth = render_sequence(
            renderer,
            &scene,
            &gpu,
            config,
            view,
            (config.ground_truth, WeavePrecision::Analytic),
            Some(&mut masks),
        )?;
        let always = (0..masks[0].len())
            .filter(|&i| masks.iter().all(|m| m[i]))
            .count();
        fabric_fraction.push((view, always as f64 / masks[0].len().max(1) as f64));
        let (tf, tflip, _) = measure(config.size, &truth, &truth, &masks);
        rows.push(TemporalRow {
            view,
            level: None,
            flicker: tf,
            flip: tflip,
            error: 0.0,
            ratio: 1.0,
            flip_ratio: 1.0,
        });
        for &variant in &config.variants {
            let seq = render_sequence(renderer, &scene, &gpu, config, view, variant, None)?;
            let (flicker, flip, error) = measure(config.size, &seq, &truth, &masks);
            rows.push(TemporalRow {
                view,
                level: Some(variant),
                flicker,
                flip,
                error,
                ratio: flicker / tf.max(1e-12),
                flip_ratio: flip / tflip.max(1e-12),
            });
        }
    }
    let info = renderer.context().info();
    let report = TemporalReport {
        config: config.clone(),
        rows,
        fabric_fraction,
        device: format!("{} ({}, {})", info.name, info.driver_name, info.driver_info),
        seconds: start.elapsed().as_secs_f64(),
    };
    super::create_out_dir(&config.out)?;
    crate::render::write_file(&config.out.join("temporal.csv"), report.csv().as_bytes())?;
    let (w, h, rgba) = report.plot();
    crate::render::write_png(&config.out.join("bench-temporal.png"), w, h, &rgba)?;
    Ok(report)
}

impl TemporalReport {
    fn truth_flicker(&self, view: View) -> f64 {
        self.rows
            .iter()
            .find(|r| r.view == view && r.level.is_none())
            .map(|r| r.flicker)
            .unwrap_or(0.0)
    }

    pub fn table(&self) -> String {
        use std::fmt::Write;
        let c = &self.config;
        let mut t = String::new();
        let _ = writeln!(t, "device   {}", self.device);
        let _ = writeln!(
            t,
            "temporal stability at {}x{}: {} frames, the camera turning {} degree(s) a frame about the scene's centre; ground truth {} (analytic weave)",
            c.size.0,
            c.size.1,
            c.frames,
            c.degrees_per_frame,
            c.ground_truth.name()
        );
        for (view, f) in &self.fabric_fraction {
            let _ = writeln!(
                t,
                "  {:<4} fabric in every frame: {:.1}% of the image (the pixels measured)",
                view.name(),
                f * 100.0
            );
        }
        let _ = writeln!(
            t,
            "{:<5} {:<36} {:>9} {:>7} {:>9} {:>7} {:>9} {:>9}",
            "view", "level", "flicker", "ratio", "FLIP", "ratio", "error", "bound"
        );
        for r in &self.rows {
            let tf = self.truth_flicker(r.view);
            let _ = writeln!(
                t,
                "{:<5} {:<36} {:>9.5} {:>6.2}x {:>9.5} {:>6.2}x {:>9.5} {:>9.5}",
                r.view.name(),
                r.label(c.ground_truth),
                r.flicker,
                r.ratio,
                r.flip,
                r.flip_ratio,
                r.error,
                r.bound(tf)
            );
        }
        let _ = writeln!(
            t,
            "flicker: mean |Y(t+1) - Y(t)| / mean ground-truth Y on fabric pixels; ratio: against the ground truth's; FLIP: mean FLIP of consecutive frames on the same pixels"
        );
        let _ = writeln!(
            t,
            "error: mean |Y - G| / mean G in each frame; bound: ground-truth flicker + 2 error (no level can flicker more)"
        );
        let _ = writeln!(t, "run took {:.0} s", self.seconds);
        t
    }

    pub fn csv(&self) -> String {
        let mut t = String::from(
            "view,level,precision,width,height,frames,degrees_per_frame,flicker,ratio,flip,flip_ratio,error,bound\n",
        );
        let c = &self.config;
        for r in &self.rows {
            let (level, precision) = match r.level {
                None => (c.ground_truth.name(), "analytic".to_string()),
                Some((l, p)) => (l.name(), p.name().to_string()),
            };
            t.push_str(&format!(
                "{},{level},{precision},{},{},{},{},{:.6},{:.4},{:.6},{:.4},{:.6},{:.6}\n",
                r.view.name(),
                c.size.0,
                c.size.1,
                c.frames,
                c.degrees_per_frame,
                r.flicker,
                r.ratio,
                r.flip,
                r.flip_ratio,
                r.error,
                r.bound(self.truth_flicker(r.view))
            ));
        }
        t
    }

    /// Flicker against the ground truth's, per level (log scale), one line per view.
    pub fn plot(&self) -> (u32, u32, Vec<u8>) {
        const W: u32 = 1200;
        const H: u32 = 700;
        let (left, right, top, bottom) = (120.0f32, 1140.0f32, 80.0f32, 560.0f32);
        let mut c = Canvas::new(W, H, [1.0; 3]);
        let (black, muted) = (super::plot::BLACK, super::plot::MUTED);
        c.text(
            left as i32,
            20,
            "WEFT BENCH --TEMPORAL: FLICKER AGAINST THE GROUND TRUTH",
            2,
            black,
        );
        c.text(
            left as i32,
            48,
            &format!(
                "consecutive-frame luminance change on fabric / the same for {} ({} frames, {} deg a frame)",
                self.config.ground_truth.name(),
                self.config.frames,
                self.config.degrees_per_frame
            ),
            1,
            muted,
        );
        let ratios: Vec<f64> = self.rows.iter().map(|r| r.ratio.max(1e-3)).collect();
        let lo = ratios
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min)
            .min(1.0);
        let hi = ratios.iter().copied().fold(0.0, f64::max).max(1.0);
        let y = LogAxis::fit(lo, hi, bottom, top);
        // The x axis is categorical (the levels): a grid and tick labels on y only.
        super::plot::log_y_grid(&mut c, &y, left, right);
        c.line((left, top), (left, bottom), 1.5, black);
        c.line((left, bottom), (right, bottom), 1.5, black);
        let levels = &self.config.variants;
        let n = levels.len() + 1;
        let px = |i: usize| left + (right - left) * (i as f32 + 0.5) / n as f32;
        // The ground truth's line: ratio 1.
        c.dashed(
            (left, y.map(1.0)),
            (right, y.map(1.0)),
            1.5,
            8.0,
            6.0,
            muted,
        );
        let label = |i: usize| -> String {
            if i == 0 {
                format!("GT {}", short_label(self.config.ground_truth))
            } else {
                let (l, p) = levels[i - 1];
                let short = short_label(l);
                if p == WeavePrecision::Analytic && !matches!(l, Accuracy::Supersampled(_)) {
                    format!("{short}/AN")
                } else {
                    short
                }
            }
        };
        for i in 0..n {
            let text = label(i);
            c.text(
                px(i) as i32 - text_width(&text, 2) / 2,
                bottom as i32 + 14,
                &text,
                2,
                black,
            );
        }
        c.text_up(
            30,
            (top + bottom) as i32 / 2 + 110,
            "FLICKER / GROUND TRUTH",
            2,
            black,
        );
        let palette = [[1.0, 0.5, 0.05], [0.17, 0.63, 0.17], [0.12, 0.47, 0.71]];
        let mut legend_y = bottom as i32 + 60;
        for (vi, view) in self.config.views.iter().enumerate() {
            let col = palette[vi % palette.len()];
            let pts: Vec<(f32, f32)> = self
                .rows
                .iter()
                .filter(|r| r.view == *view)
                .enumerate()
                .map(|(i, r)| (px(i), y.map(r.ratio.max(1e-3))))
                .collect();
            for pair in pts.windows(2) {
                c.line(pair[0], pair[1], 2.5, col);
            }
            for p in &pts {
                c.fill_rect(
                    p.0 as i32 - 5,
                    p.1 as i32 - 5,
                    p.0 as i32 + 5,
                    p.1 as i32 + 5,
                    col,
                );
            }
            c.fill_rect(left as i32, legend_y, left as i32 + 24, legend_y + 12, col);
            c.text(
                left as i32 + 34,
                legend_y,
                &view.name().to_uppercase(),
                2,
                black,
            );
            legend_y += 26;
        }
        c.text(
            left as i32 + 260,
            bottom as i32 + 60,
            "N NEAREST, FP FILTERED-PARAMS, MIX MIXTURE (RGBA16F; /AN ANALYTIC WEAVE), SSN SUPERSAMPLED:N",
            1,
            muted,
        );
        (W, H, c.to_rgba8())
    }
}
