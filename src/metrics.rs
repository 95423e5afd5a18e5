//! Image metrics shared by the bench, the tests and the comparisons: FLIP (Andersson et al.
//! 2020) on the sRGB images, RMSE and PSNR on the linear HDR ones, masked or whole; the median and
//! a least-squares line for timings.

use crate::render::Frame;

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
pub(crate) fn flip_map(reference: &Frame, test: &Frame) -> Vec<f32> {
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
pub(crate) fn masked_sse(reference: &[f32], test: &[f32], mask: &[bool]) -> (f64, usize, f64) {
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
pub(crate) fn psnr_db(peak: f64, mse: f64) -> f64 {
    10.0 * (peak * peak / mse).log10()
}

/// `frames` frames of `scene` (at least one) and the warm frame's times: the first frame (upload
/// included) pays lavapipe's JIT compiling and pipeline creation, so with more than one frame
/// each pass's times and the whole frame's wall time are the medians of the frames after it.
/// `weft render --timings --frames N` prints this; `weft bench --startup` divides by it. Returns
/// the last frame with its timings replaced by the medians, and the frame's wall ms.
pub fn render_warm(
    renderer: &mut crate::render::Renderer,
    scene: &crate::scene::Scene,
    options: &crate::render::RenderOptions,
    frames: u32,
) -> crate::Result<(Frame, f64)> {
    let start = std::time::Instant::now();
    let gpu_scene = renderer.upload(scene)?;
    let mut frame = renderer.render_frame(scene, &gpu_scene, options)?;
    let mut wall_ms = vec![start.elapsed().as_secs_f64() * 1e3];
    let mut history = vec![frame.timings.clone()];
    for _ in 1..frames {
        let t = std::time::Instant::now();
        frame = renderer.render_frame(scene, &gpu_scene, options)?;
        wall_ms.push(t.elapsed().as_secs_f64() * 1e3);
        history.push(frame.timings.clone());
    }
    if frames > 1 {
        // Warm frames only.
        history.remove(0);
        wall_ms.remove(0);
        for (i, t) in frame.timings.iter_mut().enumerate() {
            t.wall_ms = t
                .wall_ms
                .map(|_| median(history.iter().filter_map(|h| h[i].wall_ms).collect()));
            t.gpu_ms = t
                .gpu_ms
                .map(|_| median(history.iter().filter_map(|h| h[i].gpu_ms).collect()));
        }
    }
    Ok((frame, median(wall_ms)))
}
