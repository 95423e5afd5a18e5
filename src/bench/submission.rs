//! `weft bench --submission`: the frame as one queue submission (the normal path) against one
//! submission per pass (what `--timings` and the other benches use for honest per-pass times),
//! the same scene and options, frames interleaved in one run.

use std::fmt::Write;
use std::time::Instant;

use crate::render::{GpuScene, RenderOptions, Renderer, Submission};
use crate::scene::Scene;

/// One submission mode, measured.
#[derive(Clone, Debug)]
pub struct SubmissionRow {
    pub mode: Submission,
    /// Queue submissions a frame made.
    pub submissions: u64,
    /// Median wall time of `Renderer::render_frame` (the frame, submitted, waited for, read back).
    pub frame_ms: f64,
    /// Median of the passes' GPU times summed (None without timestamps).
    pub passes_gpu_ms: Option<f64>,
}

/// Renders `frames` interleaved rounds (after one warm-up frame of each mode) of `options` as one
/// submission and as one per pass.
pub fn run(
    renderer: &mut Renderer,
    scene: &Scene,
    gpu: &GpuScene,
    options: &RenderOptions,
    frames: u32,
) -> crate::Result<Vec<SubmissionRow>> {
    let modes = [Submission::Frame, Submission::PerPass];
    let mut walls: Vec<Vec<f64>> = vec![Vec::new(); modes.len()];
    let mut gpus: Vec<Vec<f64>> = vec![Vec::new(); modes.len()];
    let mut submissions = vec![0; modes.len()];
    for round in 0..=frames {
        for (i, &mode) in modes.iter().enumerate() {
            let o = RenderOptions {
                submission: mode,
                ..options.clone()
            };
            let start = Instant::now();
            let frame = renderer.render_frame(scene, gpu, &o)?;
            let wall = start.elapsed().as_secs_f64() * 1e3;
            submissions[i] = frame.stats.submissions;
            if round == 0 {
                continue; // warm-up: shader JIT, caches
            }
            walls[i].push(wall);
            let passes: Option<f64> = frame
                .timings
                .iter()
                .filter(|t| frame.stats.passes.contains(&t.name))
                .map(|t| t.gpu_ms)
                .sum();
            gpus[i].extend(passes);
        }
    }
    Ok(modes
        .iter()
        .enumerate()
        .map(|(i, &mode)| SubmissionRow {
            mode,
            submissions: submissions[i],
            frame_ms: super::median(walls[i].clone()),
            passes_gpu_ms: (!gpus[i].is_empty()).then(|| super::median(gpus[i].clone())),
        })
        .collect())
}

/// The rows as a table, with the per-pass frame time against the one-submission frame's.
pub fn table(rows: &[SubmissionRow], width: u32, height: u32, frames: u32) -> String {
    let mut t = String::new();
    let _ = writeln!(
        t,
        "one submission per frame against one per pass: default scene {width}x{height}, median of {frames} interleaved frames"
    );
    let _ = writeln!(
        t,
        "{:<10} {:>12} {:>10} {:>16} {:>8}",
        "submit", "submissions", "frame ms", "passes gpu ms", "ratio"
    );
    let base = rows.first().map(|r| r.frame_ms).unwrap_or(1.0);
    for r in rows {
        let gpu = r
            .passes_gpu_ms
            .map(|g| format!("{g:.1}"))
            .unwrap_or_else(|| "-".into());
        let _ = writeln!(
            t,
            "{:<10} {:>12} {:>10.1} {:>16} {:>8.2}",
            r.mode.name(),
            r.submissions,
            r.frame_ms,
            gpu,
            r.frame_ms / base
        );
    }
    t
}
