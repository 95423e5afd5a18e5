//! Side by side with the other glTF renderers: Khronos' glTF-Render-Fidelity scenarios, their
//! published thumbnails and the comparison generator's metric (`weft fidelity`, docs/fidelity.md).
//!
//! A scenario is a model, a camera (eye, target, vertical field of view), an HDR environment,
//! whether the environment is the background, and an image size, as transcribed in
//! `../shared/fidelity/scenarios.json`. The metric is the generator's: both images blended over
//! white by their own alpha, per pixel the YIQ colour difference of pixelmatch (`0.5053 ΔY² +
//! 0.299 ΔI² + 0.1957 ΔQ²` on 0..255 values, the pixel's distance `d`) over the pixels where the
//! candidate's alpha is not zero; the score is `10·log10(sqrt(mean d²) / 35215)` (35215: the
//! largest `d`), in dB, more negative = closer. Checked against the values the shared README
//! quotes from the published site: this form reproduces them to 0.1 dB from the thumbnails
//! (Box: filament -31.4; SheenChair: the sample viewer -18.7; Duck -24.7; DamagedHelmet:
//! model-viewer -17.8; TextureTransformTest -29.7), where `10·log10(sqrt(mean d) / sqrt(35215))`
//! gives about half those figures.

use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::Error;

/// The rasterizers among the published engines (weft is ranked among them).
pub const RASTERIZERS: [&str; 5] = [
    "babylon",
    "filament",
    "gltf-sample-viewer",
    "model-viewer",
    "rhodonite",
];

/// The path tracers among the published engines; `blender-cycles` is the default reference.
pub const PATH_TRACERS: [&str; 4] = [
    "blender-cycles",
    "vray",
    "dassault-stellar",
    "three-gpu-pathtracer",
];

/// One scenario.
#[derive(Clone, Debug, PartialEq)]
pub struct Scenario {
    pub name: String,
    /// The model, relative to the folder above `fidelity/` (`realworld/khronos/...`).
    pub model: PathBuf,
    pub eye: [f32; 3],
    pub target: [f32; 3],
    pub vertical_fov_deg: f32,
    /// The scenario's own size (the goldens are rendered at twice this).
    pub size: [u32; 2],
    /// The environment, relative to the fidelity folder.
    pub environment: PathBuf,
    /// The environment is the background; otherwise the background is transparent.
    pub skybox: bool,
}

fn bad(name: &str, key: &str, what: &str) -> Error {
    Error::input(format!(
        "scenario '{name}': '{key}' {what}; see ../shared/fidelity/README.md for the fields"
    ))
}

impl Scenario {
    /// One scenario from its JSON object (the fields of `scenarios.json`).
    pub fn from_json(name: &str, v: &Value) -> crate::Result<Scenario> {
        let vec3 = |key: &str| -> crate::Result<[f32; 3]> {
            let a = v[key]
                .as_array()
                .filter(|a| a.len() == 3)
                .ok_or_else(|| bad(name, key, "is not an array of three numbers"))?;
            let mut out = [0.0f32; 3];
            for (o, x) in out.iter_mut().zip(a) {
                *o =
                    x.as_f64().filter(|x| x.is_finite()).ok_or_else(|| {
                        bad(name, key, "holds something that is not a finite number")
                    })? as f32;
            }
            Ok(out)
        };
        let text = |key: &str| -> crate::Result<PathBuf> {
            v[key]
                .as_str()
                .filter(|s| !s.is_empty())
                .map(PathBuf::from)
                .ok_or_else(|| bad(name, key, "is not a path"))
        };
        let size = v["size"]
            .as_array()
            .filter(|a| a.len() == 2)
            .and_then(|a| {
                Some([
                    u32::try_from(a[0].as_u64()?).ok()?,
                    u32::try_from(a[1].as_u64()?).ok()?,
                ])
            })
            .filter(|s| (1..=16384).contains(&s[0]) && (1..=16384).contains(&s[1]))
            .ok_or_else(|| bad(name, "size", "is not [width, height] in 1..=16384"))?;
        let fov = v["vertical_fov_deg"]
            .as_f64()
            .filter(|f| *f > 0.0 && *f < 180.0)
            .ok_or_else(|| bad(name, "vertical_fov_deg", "is not an angle in (0, 180)"))?;
        Ok(Scenario {
            name: name.to_string(),
            model: text("model")?,
            eye: vec3("eye")?,
            target: vec3("target")?,
            vertical_fov_deg: fov as f32,
            size,
            environment: text("environment")?,
            skybox: v["skybox"].as_bool().unwrap_or(false),
        })
    }

    /// Every scenario of a `scenarios.json` (an object of name → scenario), in the file's order.
    pub fn load_all(path: &Path) -> crate::Result<Vec<Scenario>> {
        let text = std::fs::read_to_string(path).map_err(|e| {
            Error::input(format!(
                "cannot read the scenarios '{}': {e}",
                path.display()
            ))
        })?;
        let v: Value = serde_json::from_str(&text)
            .map_err(|e| Error::input(format!("'{}' is not JSON: {e}", path.display())))?;
        let obj = v.as_object().ok_or_else(|| {
            Error::input(format!(
                "'{}' should be an object of scenario name to scenario",
                path.display()
            ))
        })?;
        obj.iter()
            .map(|(name, s)| Scenario::from_json(name, s))
            .collect()
    }

    /// The model's name without the `khronos-` prefix the published site uses.
    pub fn short_name(&self) -> &str {
        self.name.strip_prefix("khronos-").unwrap_or(&self.name)
    }
}

/// RGB of an RGBA8 pixel blended over white by its own alpha, as the generator does (and as the
/// side-by-side sheet shows it).
pub fn over_white(p: [u8; 4]) -> [f64; 3] {
    let a = p[3] as f64 / 255.0;
    [0, 1, 2].map(|k| 255.0 + (p[k] as f64 - 255.0) * a)
}

/// pixelmatch's YIQ difference of two RGB colours (0..255): a squared distance, at most 35215.
pub fn yiq_delta(a: [f64; 3], b: [f64; 3]) -> f64 {
    let y = |c: [f64; 3]| c[0] * 0.298_895_31 + c[1] * 0.586_622_47 + c[2] * 0.114_482_23;
    let i = |c: [f64; 3]| c[0] * 0.595_977_99 - c[1] * 0.274_176_11 - c[2] * 0.321_801_88;
    let q = |c: [f64; 3]| c[0] * 0.211_470_17 - c[1] * 0.522_617_24 + c[2] * 0.311_147_07;
    let (dy, di, dq) = (y(a) - y(b), i(a) - i(b), q(a) - q(b));
    0.5053 * dy * dy + 0.299 * di * di + 0.1957 * dq * dq
}

/// The largest value of [`yiq_delta`] (pixelmatch's constant; reached by colour pairs such as
/// blue and yellow).
pub const MAX_YIQ_DELTA: f64 = 35215.0;

/// The generator's score of `candidate` against `reference` (both RGBA8, the same size), in dB;
/// None when the sizes differ or the candidate has no opaque pixel. Identical images score
/// `-inf`.
pub fn score(reference: &image::RgbaImage, candidate: &image::RgbaImage) -> Option<f64> {
    score_where(reference, candidate, |_, c| c[3] != 0)
}

/// [`score`] over the pixels the reference covers (its alpha not zero), whatever the candidate's
/// alpha (a pixel the candidate leaves empty there counts as white): the same scale, but a
/// candidate that is opaque over the background the reference leaves empty is not credited with
/// those pixels' zero difference. The generator's mean is over the candidate's own pixels, so an
/// engine whose thumbnail is opaque white around the object (filament's SheenCloth: 90,085
/// pixels where every other engine has about 67,170) averages its error over a third more
/// pixels, all exact, and scores about 0.6 dB closer than the object's own pixels say. None
/// when the sizes differ or the reference covers nothing.
pub fn score_over_reference(
    reference: &image::RgbaImage,
    candidate: &image::RgbaImage,
) -> Option<f64> {
    score_where(reference, candidate, |r, _| r[3] != 0)
}

/// How many pixels the candidate covers (alpha not zero) per pixel the reference covers: about 1
/// for an engine that draws the object alone; more for one whose thumbnail has an opaque
/// background.
pub fn coverage_ratio(reference: &image::RgbaImage, candidate: &image::RgbaImage) -> f64 {
    let covered = |img: &image::RgbaImage| img.pixels().filter(|p| p.0[3] != 0).count() as f64;
    covered(candidate) / covered(reference).max(1.0)
}

/// The generator's score over the pixels `keep(reference pixel, candidate pixel)` selects.
fn score_where(
    reference: &image::RgbaImage,
    candidate: &image::RgbaImage,
    keep: impl Fn(&[u8; 4], &[u8; 4]) -> bool,
) -> Option<f64> {
    if reference.dimensions() != candidate.dimensions() {
        return None;
    }
    let (mut sum, mut n) = (0.0f64, 0u64);
    for (r, c) in reference.pixels().zip(candidate.pixels()) {
        if !keep(&r.0, &c.0) {
            continue;
        }
        let d = yiq_delta(over_white(r.0), over_white(c.0));
        sum += d * d;
        n += 1;
    }
    if n == 0 {
        return None;
    }
    let rms = (sum / n as f64).sqrt();
    Some(10.0 * (rms / MAX_YIQ_DELTA).log10())
}

/// Resizes an RGBA8 image with a Lanczos-3 filter on premultiplied colour, as the site made its
/// thumbnails from the 2x goldens: by one scale on both axes about the image's centre, the one
/// that gives the exact width (or, when the width is the rounded one, the exact height). A
/// 4800 x 3072 golden becomes a 512 x 328 thumbnail whose 328 rows cover 3075 of the golden's
/// (3072 · 512 / 4800 = 327.68, rounded up), not a stretched 3072: stretching put SheenCloth's
/// silhouette 0.1 % too tall against every engine's (they agree with each other to 0.002 px). Rows
/// or columns beyond the image repeat its edge.
pub fn resize_premultiplied(img: &image::RgbaImage, width: u32, height: u32) -> image::RgbaImage {
    use fast_image_resize as fr;
    let (w, h) = img.dimensions();
    if w == 0 || h == 0 || width == 0 || height == 0 {
        return image::RgbaImage::new(width, height);
    }
    // One scale: the width's, unless the height is the exact one (a tall image).
    let sx = width as f64 / w as f64;
    let sy = height as f64 / h as f64;
    let scale = if (h as f64 * sx).round() as u32 == height {
        sx
    } else {
        sy
    };
    let (box_w, box_h) = (width as f64 / scale, height as f64 / scale);
    // Pad with the edge so that the centred box lies inside the source.
    let pad_x = ((box_w - w as f64) / 2.0).max(0.0).ceil() as u32 + 1;
    let pad_y = ((box_h - h as f64) / 2.0).max(0.0).ceil() as u32 + 1;
    let (pw, ph) = (w + 2 * pad_x, h + 2 * pad_y);
    let mut pre: Vec<f32> = Vec::with_capacity(4 * (pw * ph) as usize);
    for y in 0..ph {
        let sy = y.saturating_sub(pad_y).min(h - 1);
        for x in 0..pw {
            let p = img.get_pixel(x.saturating_sub(pad_x).min(w - 1), sy).0;
            let a = p[3] as f32 / 255.0;
            pre.extend_from_slice(&[
                p[0] as f32 / 255.0 * a,
                p[1] as f32 / 255.0 * a,
                p[2] as f32 / 255.0 * a,
                a,
            ]);
        }
    }
    let src = fr::images::Image::from_vec_u8(
        pw,
        ph,
        bytemuck::cast_slice(&pre).to_vec(),
        fr::PixelType::F32x4,
    )
    .expect("the padded image's buffer is its size");
    let mut dst = fr::images::Image::new(width, height, fr::PixelType::F32x4);
    let options = fr::ResizeOptions::new()
        .resize_alg(fr::ResizeAlg::Convolution(fr::FilterType::Lanczos3))
        .use_alpha(false)
        .crop(
            pad_x as f64 + (w as f64 - box_w) / 2.0,
            pad_y as f64 + (h as f64 - box_h) / 2.0,
            box_w,
            box_h,
        );
    fr::Resizer::new()
        .resize(&src, &mut dst, &options)
        .expect("the crop box lies inside the padded image");
    let small: &[f32] = bytemuck::cast_slice(dst.buffer());
    let mut out = image::RgbaImage::new(width, height);
    for (i, p) in out.pixels_mut().enumerate() {
        let q = &small[4 * i..4 * i + 4];
        let a = q[3].clamp(0.0, 1.0);
        let un = |c: f32| {
            if a > 0.0 {
                (c / a).clamp(0.0, 1.0)
            } else {
                0.0
            }
        };
        *p = image::Rgba([
            (un(q[0]) * 255.0).round() as u8,
            (un(q[1]) * 255.0).round() as u8,
            (un(q[2]) * 255.0).round() as u8,
            (a * 255.0).round() as u8,
        ]);
    }
    out
}

/// The site's thumbnail of a golden: [`resize_premultiplied`] to `width` x `height`, then the lossy
/// WebP encoding at quality 90 the published thumbnails went through (libwebp's defaults: 4:2:0
/// chroma, alpha kept losslessly), decoded back. Scoring weft's render against those thumbnails
/// without this step compares a full-chroma image with subsampled ones: on SheenCloth the fine
/// pattern's correlation with STELLAR's was 0.906 without it and 0.953 with it (the other engines
/// 0.946-0.976), the cyan dots inside the dark cells kept where the references' chroma blurs them.
pub fn thumbnail(
    full: &image::RgbaImage,
    width: u32,
    height: u32,
) -> Result<image::RgbaImage, Error> {
    let small = resize_premultiplied(full, width, height);
    let encoded = webp::Encoder::from_rgba(small.as_raw(), width, height)
        .encode_simple(false, 90.0)
        .map_err(|e| {
            Error::input(format!(
                "libwebp could not encode a {width}x{height} thumbnail: {e:?}"
            ))
        })?;
    let decoded =
        image::load_from_memory_with_format(&encoded, image::ImageFormat::WebP).map_err(|e| {
            Error::input(format!(
                "the {width}x{height} WebP thumbnail libwebp made does not decode: {e}"
            ))
        })?;
    Ok(decoded.to_rgba8())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_metric_is_the_generators() {
        // Black against white: d = 0.5053 · 255² (a grey has no I or Q), just under the largest
        // d (35215, reached by colour pairs), so -0.30 dB.
        assert!((yiq_delta([0.0; 3], [255.0; 3]) - 0.5053 * 255.0 * 255.0).abs() < 1.0);
        let most = (0..8)
            .flat_map(|a| (0..8).map(move |b| (a, b)))
            .map(|(a, b): (u32, u32)| {
                let c = |k: u32| [0, 1, 2].map(|i| if k >> i & 1 == 1 { 255.0 } else { 0.0 });
                yiq_delta(c(a), c(b))
            })
            .fold(0.0f64, f64::max);
        assert!(
            most <= MAX_YIQ_DELTA + 1.0 && most > 0.99 * MAX_YIQ_DELTA,
            "{most}"
        );
        let white = image::RgbaImage::from_pixel(4, 4, image::Rgba([255, 255, 255, 255]));
        let black = image::RgbaImage::from_pixel(4, 4, image::Rgba([0, 0, 0, 255]));
        assert!((score(&white, &black).unwrap() + 0.30).abs() < 0.01);
        assert_eq!(score(&white, &white), Some(f64::NEG_INFINITY));
        // A grey 10 levels off everywhere: d = 0.5053 · 100 (I and Q of a grey are zero), so
        // 10·log10(50.53 / 35215) = -28.4 dB.
        let g1 = image::RgbaImage::from_pixel(4, 4, image::Rgba([100, 100, 100, 255]));
        let g2 = image::RgbaImage::from_pixel(4, 4, image::Rgba([110, 110, 110, 255]));
        let s = score(&g1, &g2).unwrap();
        let want = 10.0 * (0.5053f64 * 100.0 / MAX_YIQ_DELTA).log10();
        assert!((want + 28.43).abs() < 0.01, "{want}");
        assert!((s - want).abs() < 1e-3, "{s} vs {want}");
        // Transparent candidate pixels do not count; transparent reference pixels are white.
        let mut c = g1.clone();
        c.put_pixel(0, 0, image::Rgba([0, 0, 0, 0]));
        assert_eq!(score(&g1, &c), Some(f64::NEG_INFINITY));
        let clear = image::RgbaImage::from_pixel(4, 4, image::Rgba([0, 0, 0, 0]));
        assert!(score(&clear, &white).unwrap() == f64::NEG_INFINITY);
        assert_eq!(score(&white, &clear), None);
    }

    #[test]
    fn an_opaque_background_is_not_credited_over_the_references_pixels() {
        // A reference covering the left half (grey 100) over an empty right half; two candidates
        // 10 levels off on the object, one empty around it, one opaque white there.
        let (w, h) = (8u32, 4u32);
        let reference = image::RgbaImage::from_fn(w, h, |x, _| {
            if x < w / 2 {
                image::Rgba([100, 100, 100, 255])
            } else {
                image::Rgba([0, 0, 0, 0])
            }
        });
        let object = |background: [u8; 4]| {
            image::RgbaImage::from_fn(w, h, |x, _| {
                image::Rgba(if x < w / 2 {
                    [110, 110, 110, 255]
                } else {
                    background
                })
            })
        };
        let alone = object([0, 0, 0, 0]);
        let opaque = object([255, 255, 255, 255]);
        let want = 10.0 * (0.5053f64 * 100.0 / MAX_YIQ_DELTA).log10();
        // The generator's mean: the opaque one's exact background halves its mean square
        // (sqrt: -1.5 dB); over the reference's pixels both are the object's own -28.4 dB.
        let (a, o) = (
            score(&reference, &alone).unwrap(),
            score(&reference, &opaque).unwrap(),
        );
        assert!((a - want).abs() < 1e-3, "{a}");
        assert!(
            (o - (want + 10.0 * 0.5f64.sqrt().log10())).abs() < 1e-3,
            "{o}"
        );
        for c in [&alone, &opaque] {
            let s = score_over_reference(&reference, c).unwrap();
            assert!((s - want).abs() < 1e-3, "{s}");
        }
        assert_eq!(coverage_ratio(&reference, &alone), 1.0);
        assert_eq!(coverage_ratio(&reference, &opaque), 2.0);
        // A candidate that leaves part of the object empty is white there, and counted.
        let holed = image::RgbaImage::from_fn(w, h, |x, _| {
            image::Rgba(if x < 2 {
                [110, 110, 110, 255]
            } else {
                [0, 0, 0, 0]
            })
        });
        assert!(score_over_reference(&reference, &holed).unwrap() > want + 5.0);
    }

    #[test]
    fn the_thumbnail_scales_both_axes_alike_about_the_centre() {
        // A disc at the centre of a 600 x 389 image, thumbnailed to 64 x 41 (389 · 64 / 600 =
        // 41.49, rounded down): one scale keeps it round and centred, where stretching the 389
        // rows onto 41 would make it 1.2 % flatter.
        let (w, h, r) = (600u32, 389u32, 120.0f64);
        let (cx, cy) = (w as f64 / 2.0, h as f64 / 2.0);
        let full = image::RgbaImage::from_fn(w, h, |x, y| {
            let (dx, dy) = (x as f64 + 0.5 - cx, y as f64 + 0.5 - cy);
            let a = if dx * dx + dy * dy < r * r { 255 } else { 0 };
            image::Rgba([200, 100, 50, a])
        });
        let small = resize_premultiplied(&full, 64, 41);
        let (mut m, mut mx, mut my, mut mxx, mut myy) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for (x, y, p) in small.enumerate_pixels() {
            let a = p.0[3] as f64 / 255.0;
            let (px, py) = (x as f64 + 0.5 - 32.0, y as f64 + 0.5 - 20.5);
            m += a;
            mx += a * px;
            my += a * py;
            mxx += a * px * px;
            myy += a * py * py;
        }
        let (ex, ey) = (mx / m, my / m);
        let (vx, vy) = (mxx / m - ex * ex, myy / m - ey * ey);
        // Measured: centre (0.0000, 0.0000) px, second moments equal to 0.04 % (vy / vx 0.99962);
        // stretched, vy / vx would be (41 / 41.49)² = 0.976.
        assert!(ex.abs() < 0.01 && ey.abs() < 0.01, "centre ({ex}, {ey})");
        assert!((vy / vx - 1.0).abs() < 0.003, "x {vx} y {vy}");
        // Its radius is the scale's: 120 · 64 / 600 = 12.8 thumbnail pixels (a disc's second
        // moment is r²/4; measured 12.83, the edge's filtering).
        let radius = (4.0 * vx).sqrt();
        assert!((radius - 12.8).abs() < 0.05, "radius {radius}");
        // Same size: the identity, to the rounding of 8 bits.
        let same = resize_premultiplied(&full, w, h);
        for (a, b) in same.pixels().zip(full.pixels()) {
            for c in 0..4 {
                assert!(
                    (a.0[c] as i32 - b.0[c] as i32).abs() <= 1 || b.0[3] == 0,
                    "{a:?} {b:?}"
                );
            }
        }
    }

    #[test]
    fn the_thumbnail_takes_the_published_ones_lossy_webp_step() {
        // Columns alternating between two colours of about equal luma and opposite chroma (a
        // bright red and a teal), half transparent in the right half: WebP's 4:2:0 chroma averages
        // each pair of columns, so the colour contrast between neighbours falls to a fraction,
        // while the luma and the alpha (kept losslessly) stay. Measured: the mean I difference of
        // neighbours 191 -> 0.12 (libwebp 1.x at quality 90); without the step it stays 191.
        let (w, h) = (64, 32);
        let full = image::RgbaImage::from_fn(w, h, |x, _| {
            let a = if x < w / 2 { 255 } else { 128 };
            if x % 2 == 0 {
                image::Rgba([230, 60, 60, a])
            } else {
                image::Rgba([0, 150, 150, a])
            }
        });
        let thumb = thumbnail(&full, w, h).unwrap();
        assert_eq!(thumb.dimensions(), (w, h));
        let i = |p: &image::Rgba<u8>| {
            0.595_977_99 * p.0[0] as f64
                - 0.274_176_11 * p.0[1] as f64
                - 0.321_801_88 * p.0[2] as f64
        };
        let contrast = |img: &image::RgbaImage| {
            let (mut sum, mut n) = (0.0, 0);
            for y in 4..h - 4 {
                for x in 4..w / 2 - 4 {
                    sum += (i(img.get_pixel(x, y)) - i(img.get_pixel(x + 1, y))).abs();
                    n += 1;
                }
            }
            sum / n as f64
        };
        let (before, after) = (contrast(&full), contrast(&thumb));
        assert!(after < 0.05 * before, "chroma contrast {before} -> {after}");
        for (x, y, p) in thumb.enumerate_pixels() {
            assert_eq!(p.0[3], full.get_pixel(x, y).0[3], "alpha at ({x}, {y})");
        }
        // A flat colour comes back within the encoder's rounding.
        let flat = image::RgbaImage::from_pixel(32, 32, image::Rgba([40, 90, 160, 255]));
        let back = thumbnail(&flat, 32, 32).unwrap();
        for p in back.pixels() {
            for c in 0..3 {
                assert!(
                    (p.0[c] as i32 - flat.get_pixel(0, 0).0[c] as i32).abs() <= 3,
                    "{p:?}"
                );
            }
        }
    }

    #[test]
    fn scenarios_parse_and_bad_ones_say_which_field() {
        let v: Value = serde_json::json!({
            "model": "realworld/khronos/Box/glTF/Box.gltf", "eye": [0, 0, 3], "target": [0, 0, 0],
            "vertical_fov_deg": 45.0, "size": [1536, 1536],
            "environment": "environments/lightroom_14b.hdr", "skybox": false
        });
        let s = Scenario::from_json("khronos-Box", &v).unwrap();
        assert_eq!(s.short_name(), "Box");
        assert_eq!(s.size, [1536, 1536]);
        for (key, value) in [
            ("eye", serde_json::json!([0, 0])),
            ("size", serde_json::json!([0, 10])),
            ("vertical_fov_deg", serde_json::json!(190)),
            ("model", serde_json::json!(3)),
        ] {
            let mut w = v.clone();
            w[key] = value;
            let e = Scenario::from_json("khronos-Box", &w)
                .unwrap_err()
                .to_string();
            assert!(e.contains(key) && e.contains("khronos-Box"), "{e}");
        }
    }
}
