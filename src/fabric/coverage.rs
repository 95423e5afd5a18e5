//! The weave: what lies under a point, and the exact coverage of an axis-aligned box (model page §2).
//! Part of the CPU reference (`reference::weave` is this module), kept beside the material because
//! the weave's summed-area table and far-field colours are built from it.
//!
//! One source, two precisions, as in [`crate::reference::brdf`]: [`single`] is the twin of
//! `glsl/include/weave.glsl`, [`double`] the f64 reference.
//!
//! Coordinates are in **cells**: `x = u / (s_p/2)`, `y = v / (s_p/2)` (one plain-weave repeat is
//! 2 × 2 cells). In cell `(i, j)` with local coordinates `(a, b) ∈ [0, 1)²`, `g = s_g/s_p` (half the
//! gap, in cells) and `d = shadow_width/2`:
//!
//! - the weft (horizontal) thread of row `j` occupies the band `g < b < 1 - g`, the warp of
//!   column `i` the band `g < a < 1 - g`; where both bands cross, the cell's top thread shows;
//!   where neither passes it is **gap**; points on a cell border (`a = 0` or `b = 0`, eq. 2's
//!   `δ = 0`) are gap too;
//! - a thread is darkened by `shadow_strength` (diffuse factor `1 - shadow_strength`) where it lies
//!   within distance `d` (along its own length) of the edge of a thread that crosses over it: the
//!   visible strip of an under-thread beside the top thread (the paper's grey region), and the end
//!   of a top thread next to a cell where it dives under. `d ≤ 1/2` keeps this to the cell and its
//!   two neighbours along the thread.
//!
//! Every region is a union of axis-aligned rectangles per cell, so the coverage of a box is a sum
//! of products of 1-D interval measures; each 1-D measure is taken per period with `floor`, so a
//! box spanning any number of repeats costs the same. The box returns
//! `(c_warp, c_weft, s_warp, s_weft)`: area fractions of warp on top and weft on top, and each
//! weighted by the diffuse shadow factor (`s_warp ≤ c_warp`, `s_weft ≤ c_weft`), the form
//! `fabric_brdf` takes. All four are areas, so the mean over pieces of a footprint is the
//! footprint's, and the diffuse term, linear in them, averages exactly even when warp and weft
//! differ in colour (one shadow-weighted total for both threads could not).
//!
//! For a plain weave over a whole repeat: `c_warp = c_weft = (1 - 4g²)/2`, gap `4g²`, and
//! `s_warp = s_weft = (1 - 4g² - shadow_strength·shadow_width·(1 - 2g))/2`: `shadow_width` is the
//! fraction of each thread's length that is darkened.

#![allow(clippy::neg_cmp_op_on_partial_ord)] // `!(x > 0.0)` is meant: it is true for NaN, as in the GLSL twin.

macro_rules! weave_precision {
    ($prec:ident, $t:ident, $doc:literal) => {
        #[doc = $doc]
        pub mod $prec {
            /// `(c_warp, c_weft, s_warp, s_weft)`.
            pub type Coverage = [$t; 4];

            /// Boxes narrower than this (cells) are treated as their centre point: below it an f32
            /// box is rounding noise (ulp(8) = 1e-6), and `1/(wx·wy)` stays far from overflow.
            pub const WEAVE_MIN_BOX: $t = 1e-6;

            /// The most pieces along a footprint's longer edge ([`weave_pieces`]).
            pub const WEAVE_MAX_PIECES: u32 = 4;

            /// What the weave functions need: the GPU's weave fields (of `GpuFabric` or `WeavePush`).
            #[derive(Clone, Copy, Debug, PartialEq)]
            pub struct Weave {
                pub pattern_lo: u32,
                pub pattern_hi: u32,
                pub cols: u32,
                pub rows: u32,
                /// `g = s_g / s_p`: half the gap between threads, in cells, in [0, 1/2].
                pub gap: $t,
                /// `d = shadow_width / 2`, in cells, in [0, 1/2].
                pub shadow_dist: $t,
                pub shadow_strength: $t,
            }

            impl Weave {
                pub fn from_gpu(f: &crate::fabric::GpuFabric) -> Self {
                    Weave {
                        pattern_lo: f.pattern_lo,
                        pattern_hi: f.pattern_hi,
                        cols: f.cols,
                        rows: f.rows,
                        gap: f.gap as $t,
                        shadow_dist: f.shadow_dist as $t,
                        shadow_strength: f.shadow_strength as $t,
                    }
                }
                pub fn from_push(p: &crate::fabric::WeavePush) -> Self {
                    Weave {
                        pattern_lo: p.pattern_lo,
                        pattern_hi: p.pattern_hi,
                        cols: p.cols,
                        rows: p.rows,
                        gap: p.gap as $t,
                        shadow_dist: p.shadow_dist as $t,
                        shadow_strength: p.shadow_strength as $t,
                    }
                }
            }

            /// Texture coordinates to cells: `uv · cell_per_uv` (reduce `uv` per repeat first).
            pub fn weave_cells(uv: [$t; 2], cell_per_uv: $t) -> [$t; 2] {
                [uv[0] * cell_per_uv, uv[1] * cell_per_uv]
            }

            /// Where to sample the weave texture (one repeat, REPEAT addressing) for texture
            /// coordinates `uv`: `uv · cell_per_uv / (cols, rows)`.
            pub fn weave_st(uv: [$t; 2], cell_per_uv: $t, cols: u32, rows: u32) -> [$t; 2] {
                [
                    uv[0] * cell_per_uv / cols as $t,
                    uv[1] * cell_per_uv / rows as $t,
                ]
            }

            /// Is cell `(i, j)` weft-up? `i < cols`, `j < rows`.
            pub fn weave_weft_up(w: &Weave, i: u32, j: u32) -> bool {
                let bit = 8 * j + i;
                let word = if bit < 32 {
                    w.pattern_lo >> bit
                } else {
                    w.pattern_hi >> (bit - 32)
                };
                (word & 1) != 0
            }

            /// `x` floor-modulo `period`, in [0, period). A result that rounds up to `period` (a
            /// tiny negative `x`) is returned as 0: the point rounds onto the border.
            pub fn weave_wrap(x: $t, period: $t) -> $t {
                let mut r = x - period * (x / period).floor();
                if r < 0.0 {
                    r += period;
                }
                if r >= period {
                    r = 0.0;
                }
                r
            }

            /// Measure of `{x ∈ [x0, x1] : x mod period ∈ [lo, hi]}`, `0 ≤ lo ≤ hi ≤ period`:
            /// the difference of the periodic antiderivative `G(x) = n·(hi-lo) + clamp(r - lo, 0, hi-lo)`
            /// with `x = n·period + r`, so the `n` of distant boxes cancel as integers.
            pub fn weave_measure(x0: $t, x1: $t, period: $t, lo: $t, hi: $t) -> $t {
                let n0 = (x0 / period).floor();
                let n1 = (x1 / period).floor();
                let r0 = x0 - n0 * period;
                let r1 = x1 - n1 * period;
                let len = hi - lo;
                (n1 - n0) * len + (r1 - lo).clamp(0.0, len) - (r0 - lo).clamp(0.0, len)
            }

            /// The weave at the point `(x, y)` (cells): `(c_warp, c_weft, s_warp, s_weft)` with one
            /// of the coverages 1 (or both 0: gap) and that thread's `s` its diffuse shadow factor
            /// (the other `s` 0).
            pub fn weave_point(w: &Weave, x: $t, y: $t) -> Coverage {
                let xr = weave_wrap(x, w.cols as $t);
                let yr = weave_wrap(y, w.rows as $t);
                let fi = xr.floor();
                let fj = yr.floor();
                let a = xr - fi;
                let b = yr - fj;
                if a == 0.0 || b == 0.0 {
                    return [0.0; 4];
                }
                let i = fi as u32;
                let j = fj as u32;
                let g = w.gap;
                let dive = (w.shadow_dist - g).clamp(0.0, 0.5);
                let q = (g - w.shadow_dist).max(0.0);
                let dark = 1.0 - w.shadow_strength;
                let in_weft_band = b > g && b < 1.0 - g;
                let in_warp_band = a > g && a < 1.0 - g;
                if weave_weft_up(w, i, j) {
                    if in_weft_band {
                        let left = !weave_weft_up(w, (i + w.cols - 1) % w.cols, j);
                        let right = !weave_weft_up(w, (i + 1) % w.cols, j);
                        let shadowed = (left && a < dive) || (right && a > 1.0 - dive);
                        return [0.0, 1.0, 0.0, if shadowed { dark } else { 1.0 }];
                    }
                    if in_warp_band {
                        let shadowed = b > q && b < 1.0 - q;
                        return [1.0, 0.0, if shadowed { dark } else { 1.0 }, 0.0];
                    }
                } else {
                    if in_warp_band {
                        let below = weave_weft_up(w, i, (j + w.rows - 1) % w.rows);
                        let above = weave_weft_up(w, i, (j + 1) % w.rows);
                        let shadowed = (below && b < dive) || (above && b > 1.0 - dive);
                        return [1.0, 0.0, if shadowed { dark } else { 1.0 }, 0.0];
                    }
                    if in_weft_band {
                        let shadowed = a > q && a < 1.0 - q;
                        return [0.0, 1.0, 0.0, if shadowed { dark } else { 1.0 }];
                    }
                }
                [0.0; 4]
            }

            /// The exact coverage of the box `[x0, x1] × [y0, y1]` (cells). `x0` and `y0` should be
            /// reduced to the repeat first in f32 (the GPU); any size of box works. A box narrower
            /// than [`WEAVE_MIN_BOX`] in either direction (or with NaN corners) is its centre point.
            pub fn weave_box(w: &Weave, x0: $t, y0: $t, x1: $t, y1: $t) -> Coverage {
                let wx = x1 - x0;
                let wy = y1 - y0;
                if !(wx >= WEAVE_MIN_BOX && wy >= WEAVE_MIN_BOX) {
                    return weave_point(w, 0.5 * (x0 + x1), 0.5 * (y0 + y1));
                }
                let px = w.cols as $t;
                let py = w.rows as $t;
                let g = w.gap;
                let dive = (w.shadow_dist - g).clamp(0.0, 0.5);
                let q = (g - w.shadow_dist).max(0.0);
                // Per column i, measures along x of: the whole cell, the warp band (g, 1-g), the
                // dive zones (0, dive) and (1-dive, 1) of a top thread, the under-thread strips
                // (0, g) ∪ (1-g, 1) and their shadowed parts (q, g) ∪ (1-g, 1-q).
                let mut x_full: [$t; 8] = [0.0; 8];
                let mut x_band: [$t; 8] = [0.0; 8];
                let mut x_low: [$t; 8] = [0.0; 8];
                let mut x_high: [$t; 8] = [0.0; 8];
                let mut x_strip: [$t; 8] = [0.0; 8];
                let mut x_strip_dark: [$t; 8] = [0.0; 8];
                for i in 0..w.cols {
                    let c = i as $t;
                    let k = i as usize;
                    x_full[k] = weave_measure(x0, x1, px, c, c + 1.0);
                    x_band[k] = weave_measure(x0, x1, px, c + g, c + 1.0 - g);
                    x_low[k] = weave_measure(x0, x1, px, c, c + dive);
                    x_high[k] = weave_measure(x0, x1, px, c + 1.0 - dive, c + 1.0);
                    x_strip[k] = weave_measure(x0, x1, px, c, c + g)
                        + weave_measure(x0, x1, px, c + 1.0 - g, c + 1.0);
                    x_strip_dark[k] = weave_measure(x0, x1, px, c + q, c + g)
                        + weave_measure(x0, x1, px, c + 1.0 - g, c + 1.0 - q);
                }
                let mut warp: $t = 0.0;
                let mut weft: $t = 0.0;
                let mut dark_warp: $t = 0.0;
                let mut dark_weft: $t = 0.0;
                for j in 0..w.rows {
                    let r = j as $t;
                    let y_full = weave_measure(y0, y1, py, r, r + 1.0);
                    if !(y_full > 0.0) {
                        continue;
                    }
                    let y_band = weave_measure(y0, y1, py, r + g, r + 1.0 - g);
                    let y_low = weave_measure(y0, y1, py, r, r + dive);
                    let y_high = weave_measure(y0, y1, py, r + 1.0 - dive, r + 1.0);
                    let y_strip = weave_measure(y0, y1, py, r, r + g)
                        + weave_measure(y0, y1, py, r + 1.0 - g, r + 1.0);
                    let y_strip_dark = weave_measure(y0, y1, py, r + q, r + g)
                        + weave_measure(y0, y1, py, r + 1.0 - g, r + 1.0 - q);
                    let below = (j + w.rows - 1) % w.rows;
                    let above = (j + 1) % w.rows;
                    for i in 0..w.cols {
                        let k = i as usize;
                        if weave_weft_up(w, i, j) {
                            // Weft on top across the cell; the warp shows in the strips beside it.
                            let left = !weave_weft_up(w, (i + w.cols - 1) % w.cols, j);
                            let right = !weave_weft_up(w, (i + 1) % w.cols, j);
                            let dive_x = (if left { x_low[k] } else { 0.0 })
                                + (if right { x_high[k] } else { 0.0 });
                            weft += x_full[k] * y_band;
                            warp += x_band[k] * y_strip;
                            dark_weft += dive_x * y_band;
                            dark_warp += x_band[k] * y_strip_dark;
                        } else {
                            let lo = weave_weft_up(w, i, below);
                            let hi = weave_weft_up(w, i, above);
                            let dive_y =
                                (if lo { y_low } else { 0.0 }) + (if hi { y_high } else { 0.0 });
                            warp += x_band[k] * y_full;
                            weft += x_strip[k] * y_band;
                            dark_warp += x_band[k] * dive_y;
                            dark_weft += x_strip_dark[k] * y_band;
                        }
                    }
                }
                let inv_area = 1.0 / (wx * wy);
                let c_warp = (warp * inv_area).clamp(0.0, 1.0);
                let c_weft = (weft * inv_area).clamp(0.0, 1.0);
                let s_warp = ((warp - w.shadow_strength * dark_warp) * inv_area).clamp(0.0, c_warp);
                let s_weft = ((weft - w.shadow_strength * dark_weft) * inv_area).clamp(0.0, c_weft);
                [c_warp, c_weft, s_warp, s_weft]
            }

            /// Pieces for [`weave_parallelogram`] along `dx` and along `dy` (`weave_pieces` of
            /// weave.glsl): 1 x 1 when the footprint's bounding box is within 2 % of its area
            /// (aligned with the weave), spans 4 cells or more (the weave averages out) or
            /// `most` <= 1; else `most` times the shorter edge's share of the longer (at least
            /// one) along the shorter, and along the longer as many as keep the pieces about
            /// as long as wide, from `most` to [`WEAVE_MAX_PIECES`].
            pub fn weave_pieces(dx: [$t; 2], dy: [$t; 2], most: u32) -> [u32; 2] {
                let box_area = (dx[0].abs() + dy[0].abs()) * (dx[1].abs() + dy[1].abs());
                let area = (dx[0] * dy[1] - dx[1] * dy[0]).abs();
                let extent = (dx[0].abs() + dy[0].abs()).max(dx[1].abs() + dy[1].abs());
                if !(box_area > 1.02 * area) || !(extent < 4.0) || most <= 1 {
                    return [1, 1];
                }
                let lx = (dx[0] * dx[0] + dx[1] * dx[1]).sqrt();
                let ly = (dy[0] * dy[0] + dy[1] * dy[1]).sqrt();
                let ratio = lx.max(ly) / lx.min(ly);
                let shorter = (most as $t / ratio + 0.5).floor().clamp(1.0, most as $t);
                let longer = (shorter * ratio + 0.5)
                    .floor()
                    .clamp(most as $t, most.max(WEAVE_MAX_PIECES) as $t)
                    as u32;
                let shorter = shorter as u32;
                if lx >= ly {
                    [longer, shorter]
                } else {
                    [shorter, longer]
                }
            }

            /// The half-extent of each piece's box when the parallelogram spanned by `dx`, `dy`
            /// is cut into `k[0] × k[1]` equal pieces: the piece's bounding box shrunk about its
            /// centre to the piece's area (`weave_piece_half` of weave.glsl). Scale-free per
            /// axis: the same in cells or in repeats.
            pub fn weave_piece_half(dx: [$t; 2], dy: [$t; 2], k: [u32; 2]) -> [$t; 2] {
                let kx = k[0].max(1) as $t;
                let ky = k[1].max(1) as $t;
                let half = [
                    (dx[0].abs() / kx + dy[0].abs() / ky) * 0.5,
                    (dx[1].abs() / kx + dy[1].abs() / ky) * 0.5,
                ];
                let box_area = 4.0 * half[0] * half[1];
                let area = (dx[0] * dy[1] - dx[1] * dy[0]).abs() / (kx * ky);
                let shrink = if box_area > area && area > 0.0 {
                    (area / box_area).sqrt()
                } else {
                    1.0
                };
                [half[0] * shrink, half[1] * shrink]
            }

            /// The centre of piece `n` (row by row: `i = n mod k[0]`, `j = n / k[0]`) when the
            /// parallelogram `{c + a·dx + b·dy : a, b in [-1/2, 1/2]}` is cut into `k[0] × k[1]`
            /// equal pieces (`weave_piece_centre` of weave.glsl).
            pub fn weave_piece_centre(
                c: [$t; 2],
                dx: [$t; 2],
                dy: [$t; 2],
                k: [u32; 2],
                n: u32,
            ) -> [$t; 2] {
                let (kx, ky) = (k[0].max(1), k[1].max(1));
                let a = ((n % kx) as $t + 0.5) / kx as $t - 0.5;
                let b = ((n / kx) as $t + 0.5) / ky as $t - 0.5;
                [c[0] + dx[0] * a + dy[0] * b, c[1] + dx[1] * a + dy[1] * b]
            }

            /// The coverage of the parallelogram `{c + a·dx + b·dy : a, b in [-1/2, 1/2]}` (cells,
            /// `c` reduced to the repeat) cut into `k[0] × k[1]` equal pieces: the mean of the
            /// exact box coverages of one box per piece, its bounding box shrunk about its centre
            /// to the piece's area. Twin of weave.glsl's `weave_parallelogram`.
            pub fn weave_parallelogram(
                w: &Weave,
                c: [$t; 2],
                dx: [$t; 2],
                dy: [$t; 2],
                k: [u32; 2],
            ) -> Coverage {
                let kx = k[0].max(1) as $t;
                let ky = k[1].max(1) as $t;
                let half = weave_piece_half(dx, dy, k);
                let mut sum = [0.0; 4];
                for n in 0..k[0].max(1) * k[1].max(1) {
                    let p = weave_piece_centre(c, dx, dy, k, n);
                    let cov = weave_box(
                        w,
                        p[0] - half[0],
                        p[1] - half[1],
                        p[0] + half[0],
                        p[1] + half[1],
                    );
                    for (s, v) in sum.iter_mut().zip(cov) {
                        *s += v;
                    }
                }
                sum.map(|s| s / (kx * ky))
            }
        }
    };
}

weave_precision!(
    single,
    f32,
    "The f32 path: the twin of `glsl/include/weave.glsl`."
);
weave_precision!(double, f64, "The f64 reference.");

use crate::fabric::FabricParams;

/// Texture coordinates to cells (`2/s_p` cells per texture unit), in f64.
pub fn uv_to_cells(params: &FabricParams, u: f64, v: f64) -> [f64; 2] {
    let k = 2.0 / params.repeat as f64;
    [u * k, v * k]
}

/// The f64 weave of a material (sanitised as the GPU sees it).
pub fn weave_of(params: &FabricParams) -> double::Weave {
    double::Weave::from_gpu(&params.to_gpu())
}

/// The weave at texture coordinates `(u, v)`, in f64 (any magnitude, any sign).
pub fn weave_point_uv(params: &FabricParams, u: f64, v: f64) -> double::Coverage {
    let [x, y] = uv_to_cells(params, u, v);
    double::weave_point(&weave_of(params), x, y)
}

/// The exact coverage of the footprint `[u0, u1] × [v0, v1]` (texture units), in f64: footprints
/// spanning many repeats, negative and huge coordinates included (each 1-D measure is reduced per
/// repeat before anything is subtracted).
pub fn weave_box_uv(params: &FabricParams, u0: f64, u1: f64, v0: f64, v1: f64) -> double::Coverage {
    let [x0, y0] = uv_to_cells(params, u0, v0);
    let [x1, y1] = uv_to_cells(params, u1, v1);
    double::weave_box(&weave_of(params), x0, y0, x1, y1)
}

/// Cell coordinates of `(u, v)` reduced to one repeat in f64, then rounded to f32: what the GPU
/// should be given (an f32 `u = 1e7` has lost the pattern; this has not).
pub fn reduce_to_repeat(params: &FabricParams, u: f64, v: f64) -> [f32; 2] {
    let [x, y] = uv_to_cells(params, u, v);
    let p = &params.pattern;
    [
        double::weave_wrap(x, p.cols() as f64) as f32,
        double::weave_wrap(y, p.rows() as f64) as f32,
    ]
}
