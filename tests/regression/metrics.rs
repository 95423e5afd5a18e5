//! The figures of one image comparison: FLIP (NVIDIA's perceptual metric for LDR images, through
//! the `nv-flip` crate) and the per-channel absolute difference, and the tolerance they are held to.

/// How far a test image may be from its reference.
#[derive(Clone, Copy, Debug)]
pub struct Tolerance {
    /// Mean FLIP over the image.
    pub flip_mean: f32,
    /// 99th percentile of the per-pixel FLIP error.
    pub flip_p99: f32,
    /// A pixel fails when any of its R, G, B bytes differs by more than this.
    pub abs: u8,
    /// At most this fraction of the pixels may fail.
    pub fail_fraction: f64,
    /// The largest mean signed difference over a block of about `BIAS_BLOCK` pixels a side (all
    /// three channels), in 1/255, when checked. Another CPU's code rounds scattered pixels up or
    /// down by 1/255 and averages out over a block; a real change (a colour 2 % darker, a light
    /// moved) shifts every pixel of a region the same way, below any per-pixel tolerance.
    pub block_bias: Option<f32>,
}

/// About the side of the blocks of `Tolerance::block_bias`, in pixels.
pub const BIAS_BLOCK: u32 = 32;

/// What a comparison measured.
#[derive(Clone, Copy, Debug, Default)]
pub struct Figures {
    pub flip_mean: f32,
    pub flip_p99: f32,
    pub flip_max: f32,
    /// Largest difference of one channel, in 1/255.
    pub max_abs: u8,
    /// Pixels with a channel difference above the tolerance's `abs`.
    pub failing_pixels: usize,
    pub pixels: usize,
    /// The largest |mean signed difference| (test − reference) over a block (`block_bias`), 1/255.
    pub block_bias: f32,
}

impl Figures {
    pub fn failing_fraction(&self) -> f64 {
        self.failing_pixels as f64 / self.pixels.max(1) as f64
    }

    /// One line: `FLIP mean 0.0012, p99 0.010, max 0.12; max |Δ| 3/255, 0.05 % of pixels > 2/255`.
    pub fn summary(&self, tol: &Tolerance) -> String {
        format!(
            "FLIP mean {:.4}, p99 {:.4}, max {:.3}; max |Δ| {}/255, {:.3} % of pixels > {}/255; block bias {:.3}/255",
            self.flip_mean,
            self.flip_p99,
            self.flip_max,
            self.max_abs,
            self.failing_fraction() * 100.0,
            tol.abs,
            self.block_bias
        )
    }
}

impl Tolerance {
    /// What exceeds the tolerance, one phrase each; empty = within it.
    pub fn violations(&self, f: &Figures) -> Vec<String> {
        let mut out = Vec::new();
        if !(f.flip_mean <= self.flip_mean) {
            out.push(format!(
                "mean FLIP {:.4} > {:.4}",
                f.flip_mean, self.flip_mean
            ));
        }
        if !(f.flip_p99 <= self.flip_p99) {
            out.push(format!(
                "99th-percentile FLIP {:.4} > {:.4}",
                f.flip_p99, self.flip_p99
            ));
        }
        if f.failing_fraction() > self.fail_fraction {
            out.push(format!(
                "{:.3} % of pixels differ by more than {}/255 (at most {:.3} % allowed)",
                f.failing_fraction() * 100.0,
                self.abs,
                self.fail_fraction * 100.0
            ));
        }
        if let Some(bound) = self.block_bias {
            if !(f.block_bias <= bound) {
                out.push(format!(
                    "a block of ~{BIAS_BLOCK}x{BIAS_BLOCK} pixels is {:.3}/255 brighter or darker on average (at most {bound}/255)",
                    f.block_bias
                ));
            }
        }
        out
    }

    pub fn describe(&self) -> String {
        format!(
            "FLIP mean ≤ {}, p99 ≤ {}; > {}/255 on ≤ {} % of pixels{}",
            self.flip_mean,
            self.flip_p99,
            self.abs,
            self.fail_fraction * 100.0,
            self.block_bias
                .map(|b| format!("; block bias ≤ {b}/255"))
                .unwrap_or_default()
        )
    }
}

/// An image comparison: the figures and the FLIP error map in the magma colour map (RGB8).
pub struct Comparison {
    pub figures: Figures,
    pub error_map: Vec<u8>,
}

fn rgb(rgba: &[u8]) -> Vec<u8> {
    rgba.chunks_exact(4)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect()
}

/// Compares two RGBA8 sRGB images of `width × height` (alpha ignored).
pub fn compare(reference: &[u8], test: &[u8], width: u32, height: u32, abs: u8) -> Comparison {
    let pixels = (width * height) as usize;
    assert_eq!(
        reference.len(),
        pixels * 4,
        "reference image is not {width}x{height} RGBA8"
    );
    assert_eq!(
        test.len(),
        pixels * 4,
        "test image is not {width}x{height} RGBA8"
    );
    let mut max_abs = 0u8;
    let mut failing_pixels = 0;
    for (r, t) in reference.chunks_exact(4).zip(test.chunks_exact(4)) {
        let d = (0..3).map(|c| r[c].abs_diff(t[c])).max().unwrap_or(0);
        max_abs = max_abs.max(d);
        if d > abs {
            failing_pixels += 1;
        }
    }
    let block_bias = block_bias(reference, test, width, height);
    let error = nv_flip::flip(
        nv_flip::FlipImageRgb8::with_data(width, height, &rgb(reference)),
        nv_flip::FlipImageRgb8::with_data(width, height, &rgb(test)),
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    );
    let error_map = error.apply_color_lut(&nv_flip::magma_lut()).to_vec();
    let mut values = error.to_vec();
    let flip_mean = (values.iter().map(|v| *v as f64).sum::<f64>() / pixels.max(1) as f64) as f32;
    values.sort_by(f32::total_cmp);
    let at = |q: f64| {
        values
            .get(((values.len() as f64 - 1.0) * q).round() as usize)
            .copied()
            .unwrap_or(0.0)
    };
    Comparison {
        figures: Figures {
            flip_mean,
            flip_p99: at(0.99),
            flip_max: at(1.0),
            max_abs,
            failing_pixels,
            pixels,
            block_bias,
        },
        error_map,
    }
}

/// The largest |mean of (test − reference)| over the R, G, B bytes of a block, in 1/255. The
/// image is cut into `round(width / BIAS_BLOCK) × round(height / BIAS_BLOCK)` blocks of about
/// `BIAS_BLOCK` pixels a side that cover every pixel (the remainder spread over the blocks).
fn block_bias(reference: &[u8], test: &[u8], width: u32, height: u32) -> f32 {
    let blocks = |n: u32| ((n as f32 / BIAS_BLOCK as f32).round() as u32).clamp(1, n.max(1));
    let (nx, ny) = (blocks(width), blocks(height));
    let mut worst = 0f64;
    for by in 0..ny {
        for bx in 0..nx {
            let (x0, x1) = (bx * width / nx, (bx + 1) * width / nx);
            let (y0, y1) = (by * height / ny, (by + 1) * height / ny);
            let mut sum = 0i64;
            for y in y0..y1 {
                for x in x0..x1 {
                    let i = ((y * width + x) * 4) as usize;
                    for c in 0..3 {
                        sum += test[i + c] as i64 - reference[i + c] as i64;
                    }
                }
            }
            let n = (3 * (x1 - x0) * (y1 - y0)).max(1) as f64;
            worst = worst.max((sum as f64 / n).abs());
        }
    }
    worst as f32
}

/// The image mirrored left to right (RGBA8).
pub fn mirror_x(rgba: &[u8], width: u32) -> Vec<u8> {
    rgba.chunks_exact(width as usize * 4)
        .flat_map(|row| {
            row.chunks_exact(4)
                .rev()
                .flatten()
                .copied()
                .collect::<Vec<_>>()
        })
        .collect()
}
