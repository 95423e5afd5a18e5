//! Issue 31 item 1, the measurement behind docs/performance.md "Where the default's remaining
//! error is": the default cloth under lebombo_1k.hdr (rotation 60, no lamps, 480x270, the bench's
//! close-up, mid or far camera) at the given IBL levels and pooling radii against `mc:TRUTH`, over
//! the cloth's own pixels (the coverage view's, as `weft bench --ibl` measures them). Per level:
//! the lighting pass (GPU ms, median of 7 frames), the mean relative luminance error and its
//! signed mean, and how much of the error survives a box blur of the signed error over 3, 7 and 15
//! pixels (pooled noise keeps what the pooling window's blur keeps; an error that follows the
//! surface, a filter's bias or one sample set's pattern repeated, keeps much more), and the error
//! by bands of 30 rows. Writes each level's signed error (red: too bright, blue: too dark, full at
//! ±20 %) to /tmp/ibl-error-LEVEL-POOL.png.
//!
//!     cargo run --release --example ibl_error_map -- close 2048 fis:8/1 fis:16/1 mc:256/0
//!
//! (LEVEL/POOL: an IBL level and a pooling radius, `--ibl-pool`'s 0, 1 or 2.)
use std::sync::Arc;
use weft::bench::View;
use weft::env::{Background, EnvLighting, Environment, IblLevel};
use weft::render::{DebugView, RenderOptions, Renderer, Submission};

const W: usize = 480;
const H: usize = 270;

fn lum(p: &[f32]) -> f64 {
    0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64
}

/// The box blur of `e` over k x k pixels where the whole box is covered (0 elsewhere).
fn blurred(e: &[f64], covered: &[bool], k: usize) -> Vec<f64> {
    let r = (k / 2) as i64;
    let mut out = vec![0.0; e.len()];
    for y in 0..H as i64 {
        for x in 0..W as i64 {
            let (mut s, mut all) = (0.0, true);
            'window: for dy in -r..=r {
                for dx in -r..=r {
                    let (u, v) = (x + dx, y + dy);
                    if u < 0 || v < 0 || u >= W as i64 || v >= H as i64 {
                        all = false;
                        break 'window;
                    }
                    let i = v as usize * W + u as usize;
                    if !covered[i] {
                        all = false;
                        break 'window;
                    }
                    s += e[i];
                }
            }
            if all {
                out[y as usize * W + x as usize] = s / (k * k) as f64;
            }
        }
    }
    out
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let view = match args.get(1).map(String::as_str) {
        Some("mid") => View::Mid,
        Some("far") => View::Far,
        _ => View::CloseUp,
    };
    let truth_n: u32 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(2048);
    let env = Arc::new(Environment::load(std::path::Path::new(
        "tests/data/env/lebombo_1k.hdr",
    ))?);
    let mut cloth = weft::scene::default_scene();
    cloth.lights.clear();
    let camera = view.camera(&cloth)?;
    let ctx = weft::vk::Context::new(&weft::vk::ContextOptions {
        validate: false,
        device: weft::vk::DeviceChoice::Cpu,
    })?;
    let mut renderer = Renderer::new(ctx)?;
    let gpu = renderer.upload(&cloth)?;
    let options = |level: IblLevel, pool: u32| {
        let mut e = EnvLighting::new(env.clone());
        e.rotation = 60.0;
        e.level = level;
        e.background = Background::None;
        e.pool = pool;
        RenderOptions {
            width: W as u32,
            height: H as u32,
            camera_override: Some(camera.clone()),
            environment: Some(e),
            submission: Submission::PerPass,
            ..Default::default()
        }
    };
    let truth = renderer.render_frame(&cloth, &gpu, &options(IblLevel::MonteCarlo(truth_n), 1))?;
    let mut coverage = options(IblLevel::Approx, 1);
    coverage.debug_view = DebugView::Coverage;
    let cv = renderer.render_frame(&cloth, &gpu, &coverage)?;
    let covered: Vec<bool> = truth
        .ldr
        .chunks_exact(4)
        .zip(cv.hdr.chunks_exact(4))
        .map(|(t, c)| t[3] > 0 && c[0] + c[1] + c[2] > 0.9)
        .collect();
    let total: f64 = (0..W * H)
        .filter(|&i| covered[i])
        .map(|i| lum(&truth.hdr[i * 4..]))
        .sum();
    println!(
        "{} view, truth mc:{truth_n}, {} cloth pixels",
        view.name(),
        covered.iter().filter(|c| **c).count()
    );
    println!(
        "{:<10} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8}   by 30-row bands",
        "level", "ms", "error", "signed", "blur 3", "blur 7", "blur 15"
    );
    for spec in &args[3..] {
        let (level, pool) = spec.split_once('/').ok_or("LEVEL/POOL, e.g. fis:8/1")?;
        let (level, pool) = (IblLevel::parse(level)?, pool.parse::<u32>()?);
        let o = options(level, pool);
        let mut frame = renderer.render_frame(&cloth, &gpu, &o)?; // warm-up (JIT)
        let mut ms = Vec::new();
        for _ in 0..7 {
            frame = renderer.render_frame(&cloth, &gpu, &o)?;
            ms.extend(
                frame
                    .timings
                    .iter()
                    .find(|t| t.name == "lighting")
                    .and_then(|t| t.gpu_ms.or(t.wall_ms)),
            );
        }
        ms.sort_by(f64::total_cmp);
        let e: Vec<f64> = (0..W * H)
            .map(|i| {
                if covered[i] {
                    lum(&frame.hdr[i * 4..]) - lum(&truth.hdr[i * 4..])
                } else {
                    0.0
                }
            })
            .collect();
        let share = |v: &[f64]| v.iter().map(|x| x.abs()).sum::<f64>() / total;
        let bands: Vec<String> = (0..H / 30)
            .map(|b| format!("{:.4}", share(&e[b * 30 * W..(b + 1) * 30 * W])))
            .collect();
        println!(
            "{:<10} {:>8.1} {:>8.4} {:>+8.4} {:>8.4} {:>8.4} {:>8.4}   {}",
            spec,
            ms.get(ms.len() / 2).copied().unwrap_or(0.0),
            share(&e),
            e.iter().sum::<f64>() / total,
            share(&blurred(&e, &covered, 3)),
            share(&blurred(&e, &covered, 7)),
            share(&blurred(&e, &covered, 15)),
            bands.join(" ")
        );
        let mut img = vec![0u8; W * H * 3];
        for i in 0..W * H {
            if covered[i] {
                let t = lum(&truth.hdr[i * 4..]).max(1e-9);
                let rel = (e[i] / t).clamp(-0.2, 0.2);
                let v = (rel.abs() / 0.2 * 255.0) as u8;
                img[i * 3 + if rel > 0.0 { 0 } else { 2 }] = v;
            }
        }
        let name = spec.replace([':', '/'], "-");
        image::save_buffer(
            format!("/tmp/ibl-error-{name}.png"),
            &img,
            W as u32,
            H as u32,
            image::ColorType::Rgb8,
        )?;
    }
    Ok(())
}
