//! The pixel-integrating ground truth and the measurement of one configuration against it.

use super::*;

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
pub(crate) fn measure(
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
pub(crate) fn mark_pareto_front(rows: &mut [AccuracyRow]) {
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
