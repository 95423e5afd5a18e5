//! Issue 31 item 1, the measurement behind docs/performance.md "Estimators for the A–S lobes
//! under the environment": candidate estimators of one A–S lobe's environment light (the
//! default cloth's exponents 200/10, rs 0.04) against the f64 quadrature over every pixel of
//! lebombo_1k.hdr (rotation 60), over random shading frames and views (n·v in [0.15, 1]), on the
//! CPU with a radiance cube built like the GPU's (256² bilinear from the map, box mips, trilinear,
//! seamless across faces). Prints mean relative error, bias and PSNR (peak over RMS) per
//! estimator:
//!
//!     cargo run --release --example ibl_lobe_estimators -- [configurations, default 40]
//!
//! `fis:N` is weft's default estimator's structure (the mixture sampler, Hammersley points, a
//! mip level per sample); `ratio` divides by the samples' own albedo estimate and multiplies by
//! the exact albedo (65 536 samples); `tN` looks up N taps along each sample's footprint's long
//! axis at the level of its short one; `gauss KxM` is a deterministic quadrature on a Gaussian
//! approximation of the lobe (K x M quantile points, `s1`: weighted by the true lobe).
//!
//! `NV=LO,HI` draws the views from n·v in [LO, HI]; `QUICK=1` runs only the ratio estimator at
//! 8, 16 and 32 samples (`QN=A,B,...`: at those counts); `FOLD=1` mirrors each sample that falls
//! below the horizon above it (its pdf then the sum of its direction's and its mirror image's)
//! instead of losing it.
//!
//! With `GH=1` (and `GHQ=1` to skip the slow grid), the session-23 candidates instead: the ratio
//! estimator at 8-24 samples and with the two lobes' mixture at weights 0.5 and 0.8 (the mid and
//! far field's), a Gauss–Hermite quadrature of the lobe in the half vector's angle plane with
//! each node looked up through an ideal isotropic Gaussian prefilter (`ideal`: the cube's level
//! 0 averaged over the kernel) or the box mips, and the best case of an anisotropic split sum
//! (the radiance averaged over the lobe seen at normal incidence about the mirror direction,
//! computed exactly, times the exact albedo); `IDEAL_K=k` replaces fis's mip look-ups by the
//! ideal Gaussian of k times each sample's solid angle's side.
#![allow(
    dead_code,
    clippy::needless_range_loop,
    clippy::type_complexity,
    clippy::too_many_arguments
)]
use weft::env::quadrature::EnvQuadrature;
use weft::env::{env_from_world, Environment};
use weft::reference::brdf::double as fd;
use weft::reference::brdf::sampling::sample_h;
use weft::reference::ibl_twin::formula::{cube_texel_dir, equirect_uv};

type V = [f64; 3];
fn dot(a: V, b: V) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn norm(a: V) -> V {
    let l = dot(a, a).sqrt();
    [a[0] / l, a[1] / l, a[2] / l]
}
fn cross(a: V, b: V) -> V {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn add(a: V, b: V, s: f64) -> V {
    [a[0] + b[0] * s, a[1] + b[1] * s, a[2] + b[2] * s]
}
fn lum(c: V) -> f64 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

struct Cube {
    size: usize,
    levels: Vec<(usize, Vec<V>)>,
    rows: [[f32; 3]; 3],
}

impl Cube {
    fn new(env: &Environment, size: usize, rotation: f32) -> Cube {
        let mut l0 = vec![[0.0; 3]; 6 * size * size];
        for f in 0..6 {
            for y in 0..size {
                for x in 0..size {
                    let d: [f64; 3] = cube_texel_dir(f as u32, x as u32, y as u32, size as u32);
                    let uv: [f64; 2] = equirect_uv(d);
                    l0[(f * size + y) * size + x] = bilinear_eq(env, uv);
                }
            }
        }
        let mut levels = vec![(size, l0)];
        while levels.last().unwrap().0 > 1 {
            let (s, ref p) = *levels.last().unwrap();
            let h = s / 2;
            let mut q = vec![[0.0; 3]; 6 * h * h];
            for f in 0..6 {
                for y in 0..h {
                    for x in 0..h {
                        let mut c = [0.0; 3];
                        for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                            let v = p[(f * s + 2 * y + dy) * s + 2 * x + dx];
                            for k in 0..3 {
                                c[k] += 0.25 * v[k];
                            }
                        }
                        q[(f * h + y) * h + x] = c;
                    }
                }
            }
            levels.push((h, q));
        }
        Cube {
            size,
            levels,
            rows: env_from_world(rotation),
        }
    }
    fn face_st(d: V) -> (usize, f64, f64) {
        let (ax, ay, az) = (d[0].abs(), d[1].abs(), d[2].abs());
        if ax >= ay && ax >= az {
            if d[0] > 0.0 {
                (0, -d[2] / ax, -d[1] / ax)
            } else {
                (1, d[2] / ax, -d[1] / ax)
            }
        } else if ay >= az {
            if d[1] > 0.0 {
                (2, d[0] / ay, d[2] / ay)
            } else {
                (3, d[0] / ay, -d[2] / ay)
            }
        } else if d[2] > 0.0 {
            (4, d[0] / az, -d[1] / az)
        } else {
            (5, -d[0] / az, -d[1] / az)
        }
    }
    fn texel(&self, li: usize, f: usize, xi: i64, yi: i64) -> V {
        let (n, ref p) = self.levels[li];
        let ni = n as i64;
        if xi >= 0 && yi >= 0 && xi < ni && yi < ni {
            return p[(f * n + yi as usize) * n + xi as usize];
        }
        let s = (xi as f64 + 0.5) / n as f64 * 2.0 - 1.0;
        let t = (yi as f64 + 0.5) / n as f64 * 2.0 - 1.0;
        let d = match f {
            0 => [1.0, -t, -s],
            1 => [-1.0, -t, s],
            2 => [s, 1.0, t],
            3 => [s, -1.0, -t],
            4 => [s, -t, 1.0],
            _ => [-s, -t, -1.0],
        };
        let (f2, s2, t2) = Cube::face_st(d);
        let x = (((s2 + 1.0) * 0.5 * n as f64) as i64).clamp(0, ni - 1) as usize;
        let y = (((t2 + 1.0) * 0.5 * n as f64) as i64).clamp(0, ni - 1) as usize;
        p[(f2 * n + y) * n + x]
    }
    fn level(&self, li: usize, f: usize, s: f64, t: f64) -> V {
        let n = self.levels[li].0;
        let x = (s + 1.0) * 0.5 * n as f64 - 0.5;
        let y = (t + 1.0) * 0.5 * n as f64 - 0.5;
        let (x0, y0) = (x.floor() as i64, y.floor() as i64);
        let (fx, fy) = (x - x0 as f64, y - y0 as f64);
        let g = |xx: i64, yy: i64| self.texel(li, f, xx, yy);
        let (a, b, cc, d) = (g(x0, y0), g(x0 + 1, y0), g(x0, y0 + 1), g(x0 + 1, y0 + 1));
        let mut c = [0.0; 3];
        for k in 0..3 {
            c[k] = (a[k] * (1.0 - fx) + b[k] * fx) * (1.0 - fy)
                + (cc[k] * (1.0 - fx) + d[k] * fx) * fy;
        }
        c
    }
    /// world direction
    fn sample(&self, w: V, lod: f64) -> V {
        let r = self.rows;
        let d = [
            r[0][0] as f64 * w[0] + r[0][1] as f64 * w[1] + r[0][2] as f64 * w[2],
            r[1][0] as f64 * w[0] + r[1][1] as f64 * w[1] + r[1][2] as f64 * w[2],
            r[2][0] as f64 * w[0] + r[2][1] as f64 * w[1] + r[2][2] as f64 * w[2],
        ];
        let (f, s, t) = Cube::face_st(d);
        let lod = lod.clamp(0.0, (self.levels.len() - 1) as f64);
        let l0 = lod.floor() as usize;
        let l1 = (l0 + 1).min(self.levels.len() - 1);
        let fr = lod - l0 as f64;
        let a = self.level(l0, f, s, t);
        let b = self.level(l1, f, s, t);
        [
            a[0] * (1.0 - fr) + b[0] * fr,
            a[1] * (1.0 - fr) + b[1] * fr,
            a[2] * (1.0 - fr) + b[2] * fr,
        ]
    }
}

fn bilinear_eq(env: &Environment, uv: [f64; 2]) -> V {
    let (w, h) = (env.width as i64, env.height as i64);
    let x = uv[0] * w as f64 - 0.5;
    let y = (uv[1] * h as f64 - 0.5).clamp(0.0, h as f64 - 1.0);
    let (x0, y0) = (x.floor() as i64, y.floor() as i64);
    let (fx, fy) = (x - x0 as f64, y - y0 as f64);
    let g = |xx: i64, yy: i64| {
        let p = env.pixel(xx.rem_euclid(w) as u32, yy.clamp(0, h - 1) as u32);
        [p[0] as f64, p[1] as f64, p[2] as f64]
    };
    let mut c = [0.0; 3];
    for k in 0..3 {
        c[k] = (g(x0, y0)[k] * (1.0 - fx) + g(x0 + 1, y0)[k] * fx) * (1.0 - fy)
            + (g(x0, y0 + 1)[k] * (1.0 - fx) + g(x0 + 1, y0 + 1)[k] * fx) * fy;
    }
    c
}

struct Cfg {
    t: V,
    b: V,
    n: V,
    k2: V, // local
}
impl Cfg {
    fn world(&self, l: V) -> V {
        [
            self.t[0] * l[0] + self.b[0] * l[1] + self.n[0] * l[2],
            self.t[1] * l[0] + self.b[1] * l[1] + self.n[1] * l[2],
            self.t[2] * l[0] + self.b[2] * l[1] + self.n[2] * l[2],
        ]
    }
    fn local(&self, w: V) -> V {
        [dot(w, self.t), dot(w, self.b), dot(w, self.n)]
    }
}

const EU: f64 = 200.0;
const EV: f64 = 10.0;
const RS: f64 = 0.04;

fn truth(q: &EnvQuadrature, c: &Cfg) -> V {
    let mut s = [0.0; 3];
    for (d, l) in &q.points {
        let k1 = c.local(*d);
        if k1[2] <= 0.0 {
            continue;
        }
        let f = fd::as_lobe(k1, c.k2, EU, EV, RS) * k1[2];
        for k in 0..3 {
            s[k] += l[k] * f;
        }
    }
    s
}

fn radinv(mut i: u32) -> f64 {
    i = i.reverse_bits();
    i as f64 * 2.3283064365386963e-10
}

#[derive(Clone, Copy)]
enum Pat {
    Hammersley,
    Grid(u32, u32),
}

/// fis with the lobe's own sampler. bias: lod bias; taps: anisotropic taps along the major axis (0 = iso)
fn fis(cube: &Cube, c: &Cfg, n: u32, pat: Pat, bias: f64, aniso: u32, w_self: f64) -> V {
    fis_w(cube, c, n, pat, bias, aniso, w_self).0
}
fn fis_w(cube: &Cube, c: &Cfg, n: u32, pat: Pat, bias: f64, aniso: u32, w_self: f64) -> (V, f64) {
    let mut sw = 0.0;
    let size = cube.size as f64;
    let omega_p = 4.0 * std::f64::consts::PI / (6.0 * size * size);
    let mut s = [0.0; 3];
    let k2 = c.k2;
    let fold = std::env::var("FOLD").is_ok();
    for i in 0..n {
        let (mut x, y) = match pat {
            Pat::Hammersley => (i as f64 / n as f64, radinv(i)),
            Pat::Grid(a, b) => {
                let (ia, ib) = (i % a, i / a);
                ((ia as f64 + 0.5) / a as f64, (ib as f64 + 0.5) / b as f64)
            }
        };
        // mixture: self with w_self, other orientation otherwise
        let pick_self = x < w_self;
        x = if pick_self {
            x / w_self
        } else {
            (x - w_self) / (1.0 - w_self)
        };
        x = x.min(0.99999994);
        let h = if pick_self {
            sample_h(EU, EV, x, y)
        } else {
            sample_h(EV, EU, x, y)
        };
        let kh = dot(k2, h);
        if !(kh > 0.0) {
            continue;
        }
        let mut k1 = [
            2.0 * kh * h[0] - k2[0],
            2.0 * kh * h[1] - k2[1],
            2.0 * kh * h[2] - k2[2],
        ];
        // FOLD=1: a sample below the horizon is mirrored above it instead of lost; every
        // sample's pdf is then the sum of its direction's and its mirror image's.
        if fold {
            k1[2] = k1[2].abs();
        }
        if !(k1[2] > 0.0) {
            continue;
        }
        let pdf_of = |k: V| -> (f64, f64, f64) {
            let hs = norm(add(k, k2, 1.0));
            let kh = dot(k2, hs);
            if !(kh > 0.0 && hs[2] > 0.0) {
                return (0.0, 0.0, 0.0);
            }
            let p_self = fd::as_power(hs[0], hs[1], hs[2], EU, EV);
            let p_other = fd::as_power(hs[0], hs[1], hs[2], EV, EU);
            let mixed = w_self * p_self + (1.0 - w_self) * p_other;
            let pdf = fd::as_norm(EU, EV) / (2.0 * std::f64::consts::PI) * mixed / (4.0 * kh);
            (pdf, p_self, kh)
        };
        let (pdf, p_self, kh) = if fold {
            let (p1, p_self, kh1) = pdf_of(k1);
            let (p2, _, _) = pdf_of([k1[0], k1[1], -k1[2]]);
            (p1 + p2, p_self, kh1)
        } else {
            let p_self = fd::as_power(h[0], h[1], h[2], EU, EV);
            let p_other = fd::as_power(h[0], h[1], h[2], EV, EU);
            let mixed = w_self * p_self + (1.0 - w_self) * p_other;
            let pdf = fd::as_norm(EU, EV) / (2.0 * std::f64::consts::PI) * mixed / (4.0 * kh);
            (pdf, p_self, kh)
        };
        if !(pdf > 0.0) {
            continue;
        }
        let factor = fd::as_lobe_factor(k1[2], k2[2], kh.min(1.0), EU, EV, RS);
        let wgt = factor * k1[2] / pdf * p_self;
        let omega_s = 1.0 / (n as f64 * pdf);
        let l = if aniso == 0 {
            if let Some(k) = ideal_k() {
                ideal(cube, c.world(k1), omega_s.sqrt() * k)
            } else {
                let lod = (0.5 * (omega_s / omega_p).log2() + bias).max(0.0);
                cube.sample(c.world(k1), lod)
            }
        } else {
            // major axis in h space: the axis with the smaller exponent of the picked lobe
            let (eu, ev) = if pick_self { (EU, EV) } else { (EV, EU) };
            let axis_major: V = if eu < ev {
                [1.0, 0.0, 0.0]
            } else {
                [0.0, 1.0, 0.0]
            };
            let axis_minor: V = if eu < ev {
                [0.0, 1.0, 0.0]
            } else {
                [1.0, 0.0, 0.0]
            };
            let proj = |a: V| norm(add(a, h, -dot(a, h)));
            let (um, un) = (proj(axis_major), proj(axis_minor));
            let dk = |u: V| {
                let d = add(
                    [
                        2.0 * dot(k2, u) * h[0],
                        2.0 * dot(k2, u) * h[1],
                        2.0 * dot(k2, u) * h[2],
                    ],
                    u,
                    2.0 * kh,
                );
                d
            };
            let (am, an) = (dk(um), dk(un));
            let (lm, ln) = (dot(am, am).sqrt(), dot(an, an).sqrt());
            let (emaj, emin) = (eu.min(ev), eu.max(ev));
            let a = (lm / ln * ((emin + 1.0) / (emaj + 1.0)).sqrt()).max(1.0);
            let m = (omega_s / a).sqrt();
            let major = a * m;
            let taps = (a.ceil() as u32).clamp(1, aniso);
            let side = m.max(major / taps as f64);
            let lod = ((side * side / omega_p).log2() * 0.5 + bias).max(0.0);
            let dir = norm(am);
            let mut acc = [0.0; 3];
            for j in 0..taps {
                let o = ((j as f64 + 0.5) / taps as f64 - 0.5) * major;
                let kk = norm(add(k1, dir, o));
                let v = cube.sample(c.world(kk), lod);
                for k in 0..3 {
                    acc[k] += v[k] / taps as f64;
                }
            }
            acc
        };
        for k in 0..3 {
            s[k] += l[k] * wgt;
        }
        sw += wgt;
    }
    (s.map(|x| x / n as f64), sw / n as f64)
}
fn ideal_k() -> Option<f64> {
    std::env::var("IDEAL_K").ok().map(|v| v.parse().unwrap())
}
fn albedo(c: &Cfg) -> f64 {
    // exact-ish: many samples
    let n = 65536u32;
    let mut s = 0.0;
    let k2 = c.k2;
    for i in 0..n {
        let (x, y) = ((i as f64 + 0.5) / n as f64, radinv(i));
        let h = sample_h(EU, EV, x, y);
        let kh = dot(k2, h);
        if !(kh > 0.0) {
            continue;
        }
        let k1 = [
            2.0 * kh * h[0] - k2[0],
            2.0 * kh * h[1] - k2[1],
            2.0 * kh * h[2] - k2[2],
        ];
        if !(k1[2] > 0.0) {
            continue;
        }
        let pdf = fd::as_d(h, EU, EV) / (4.0 * kh);
        s += fd::as_lobe(k1, k2, EU, EV, RS) * k1[2] / pdf;
    }
    s / n as f64
}
fn ratio(cube: &Cube, c: &Cfg, n: u32, pat: Pat, bias: f64, aniso: u32, w_self: f64) -> V {
    let (v, w) = fis_w(cube, c, n, pat, bias, aniso, w_self);
    let a = albedo(c);
    if w > 0.0 {
        v.map(|x| x / w * a)
    } else {
        [0.0; 3]
    }
}

fn inv_phi(p: f64) -> f64 {
    // bisection on erf-based cdf
    let (mut lo, mut hi) = (-10.0f64, 10.0f64);
    for _ in 0..100 {
        let m = 0.5 * (lo + hi);
        let c = 0.5 * (1.0 + erf(m / 2f64.sqrt()));
        if c < p {
            lo = m
        } else {
            hi = m
        }
    }
    0.5 * (lo + hi)
}
fn erf(x: f64) -> f64 {
    // Abramowitz-Stegun 7.1.26 is too coarse; use series/continued via libm-like
    let t = 1.0 / (1.0 + 0.5 * x.abs());
    let y = 1.0
        - t * (-x * x - 1.26551223
            + t * (1.00002368
                + t * (0.37409196
                    + t * (0.09678418
                        + t * (-0.18628806
                            + t * (0.27886807
                                + t * (-1.13520398
                                    + t * (1.48851587 + t * (-0.82215223 + t * 0.17087277)))))))))
            .exp();
    if x >= 0.0 {
        y
    } else {
        -y
    }
}
/// Gaussian-lobe quadrature: taps on a quantile grid (kx along t, ky along b) around the mirror
/// direction, ratio-normalised, times the exact albedo. mode: 0 = fis-like area side, 1 = min side, 2 = max side
fn gauss(cube: &Cube, c: &Cfg, kx: u32, ky: u32, bias: f64, shape: bool, mode: u32) -> V {
    let size = cube.size as f64;
    let omega_p = 4.0 * std::f64::consts::PI / (6.0 * size * size);
    let k2 = c.k2;
    let r = [-k2[0], -k2[1], k2[2]];
    let jx = [2.0 * k2[2], 0.0, 2.0 * k2[0]];
    let jy = [0.0, 2.0 * k2[2], 2.0 * k2[1]];
    let (sx, sy) = (1.0 / (EU + 1.0).sqrt(), 1.0 / (EV + 1.0).sqrt());
    let q = |k: u32| -> Vec<(f64, f64)> {
        (0..k)
            .map(|i| {
                if k == 1 {
                    return (0.0, (2.0 * std::f64::consts::PI).sqrt());
                }
                let x = inv_phi((i as f64 + 0.5) / k as f64);
                let pdf = (-0.5 * x * x).exp() / (2.0 * std::f64::consts::PI).sqrt();
                (x, 1.0 / (k as f64 * pdf))
            })
            .collect()
    };
    let (qx, qy) = (q(kx), q(ky));
    let lx = dot(jx, jx).sqrt() * sx;
    let ly = dot(jy, jy).sqrt() * sy;
    let mut s = [0.0; 3];
    let mut sw = 0.0;
    for &(x, dx) in &qx {
        for &(y, dy) in &qy {
            let v = add(add(r, jx, x * sx), jy, y * sy);
            let vl = dot(v, v).sqrt();
            let k1 = norm(v);
            if !(k1[2] > 0.0) {
                continue;
            }
            let (ax, ay) = (lx * dx, ly * dy);
            let side = match mode {
                0 => (ax * ay).sqrt(),
                1 => ax.min(ay),
                _ => ax.max(ay),
            };
            let lod = ((side * side / omega_p).log2() * 0.5 + bias).max(0.0);
            let mut w = 1.0;
            if shape {
                let g = fd::as_lobe(k1, k2, EU, EV, RS) * k1[2];
                let jxy = cross(jx, jy);
                w = g * dot(jxy, jxy).sqrt() * sx * sy * dx * dy / (vl * vl * vl);
            }
            let l = cube.sample(c.world(k1), lod);
            for k in 0..3 {
                s[k] += w * l[k];
            }
            sw += w;
        }
    }
    if shape && std::env::var("DIRECT").is_ok() {
        return s;
    }
    let a = albedo(c);
    if sw > 0.0 {
        s.map(|v| v / sw * a)
    } else {
        [0.0; 3]
    }
}

/// Gauss–Hermite nodes and weights for the standard normal (weights sum to 1).
fn gauss_hermite(n: usize) -> Vec<(f64, f64)> {
    if n == 1 {
        return vec![(0.0, 1.0)];
    }
    let he = |k: usize, x: f64| -> f64 {
        let (mut a, mut b) = (1.0, x);
        if k == 0 {
            return 1.0;
        }
        for j in 1..k {
            let c = x * b - j as f64 * a;
            a = b;
            b = c;
        }
        b
    };
    let mut roots = Vec::new();
    let steps = 200000;
    let (lo, hi) = (-12.0, 12.0);
    let mut px = lo;
    let mut pv = he(n, px);
    for s in 1..=steps {
        let x = lo + (hi - lo) * s as f64 / steps as f64;
        let v = he(n, x);
        if pv == 0.0 || pv * v < 0.0 {
            let (mut a, mut b) = (px, x);
            for _ in 0..80 {
                let m = 0.5 * (a + b);
                if he(n, a) * he(n, m) <= 0.0 {
                    b = m
                } else {
                    a = m
                }
            }
            roots.push(0.5 * (a + b));
        }
        px = x;
        pv = v;
    }
    let fact: f64 = (1..=n).map(|k| k as f64).product();
    roots
        .into_iter()
        .map(|x| (x, fact / ((n * n) as f64 * he(n - 1, x).powi(2))))
        .collect()
}

/// The radiance averaged over an isotropic Gaussian of angular sigma around `d` (world), from the
/// cube's level 0 (an ideal prefilter, to tell the mips' error from the quadrature's).
fn ideal(cube: &Cube, d: V, sigma: f64) -> V {
    if sigma < 1e-4 {
        return cube.sample(d, 0.0);
    }
    let a = if d[0].abs() < 0.9 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 1.0, 0.0]
    };
    let t1 = norm(cross(d, a));
    let t2 = cross(d, t1);
    let gh = gauss_hermite(10);
    let mut c = [0.0; 3];
    for &(x, wx) in &gh {
        for &(y, wy) in &gh {
            let p = norm(add(add(d, t1, x * sigma), t2, y * sigma));
            let v = cube.sample(p, 0.0);
            for k in 0..3 {
                c[k] += wx * wy * v[k];
            }
        }
    }
    c
}

/// Slope-space Gauss–Hermite quadrature of the lobe: kx x ky nodes of the Gaussian the A–S lobe
/// is for small slopes (sigma 1/sqrt(e) per axis), each looked up prefiltered by an isotropic
/// kernel covering what the nodes leave out (`pre` scales it), weighted by the true lobe over the
/// Gaussian, ratio-normalised, times the exact albedo. lookup: 0 ideal Gaussian, 1 box mips.
fn gh(cube: &Cube, c: &Cfg, kx: usize, ky: usize, pre: f64, lookup: u32, mipk: f64) -> V {
    let k2 = c.k2;
    let (sx, sy) = (1.0 / EU.sqrt(), 1.0 / EV.sqrt());
    // Jacobian of l(slopes) at 0: l = reflect(k2, h), h = normalize(x, y, 1)
    let hof = |x: f64, y: f64| -> V {
        let th = (x * x + y * y).sqrt();
        if th < 1e-12 {
            return [0.0, 0.0, 1.0];
        }
        let st = th.sin() / th;
        [x * st, y * st, th.cos()]
    };
    let lof = |x: f64, y: f64| -> (V, f64) {
        let h = hof(x, y);
        let kh = dot(k2, h);
        (add([-k2[0], -k2[1], -k2[2]], h, 2.0 * kh), kh)
    };
    let e = 1e-4;
    let (l0, _) = lof(0.0, 0.0);
    let jx = {
        let (a, _) = lof(e, 0.0);
        let d = add(a, l0, -1.0);
        dot(d, d).sqrt() / e
    };
    let jy = {
        let (a, _) = lof(0.0, e);
        let d = add(a, l0, -1.0);
        dot(d, d).sqrt() / e
    };
    // residual widths (slope units) per axis the prefilter must cover
    let rx = if kx == 1 { sx } else { sx / kx as f64 * pre };
    let ry = if ky == 1 { sy } else { sy / ky as f64 * pre };
    let sig_l = (rx * jx).min(ry * jy);
    let sig_l = if kx == 1 && ky == 1 {
        (rx * jx * ry * jy).sqrt()
    } else {
        sig_l
    };
    // node spreads shrunk by what the prefilter blurs
    let nx = (sx * sx - (sig_l / jx).powi(2)).max(0.0).sqrt();
    let ny = (sy * sy - (sig_l / jy).powi(2)).max(0.0).sqrt();
    let (gx, gy) = (gauss_hermite(kx), gauss_hermite(ky));
    let size = cube.size as f64;
    let texel = (4.0 * std::f64::consts::PI / (6.0 * size * size)).sqrt();
    let mut s = [0.0; 3];
    let mut sw = 0.0;
    for &(ax, wx) in &gx {
        for &(ay, wy) in &gy {
            let (x, y) = (ax * nx, ay * ny);
            let (l, _) = lof(x, y);
            if !(l[2] > 0.0) {
                continue;
            }
            // true lobe·cos·|dl/ds| over the node Gaussian's density (up to constants)
            let h = hof(x, y);
            let kh = dot(k2, h);
            if !(kh > 0.0) || !(h[2] > 0.0) {
                continue;
            }
            let th = (x * x + y * y).sqrt();
            // dω_h/ds = sin θ / θ ; dω_l/dω_h = 4 kh
            let jac = 4.0 * kh * if th > 1e-9 { th.sin() / th } else { 1.0 };
            let g = -(x * x / (sx * sx) + y * y / (sy * sy)) * 0.5;
            let w = fd::as_lobe(l, k2, EU, EV, RS) * l[2] * jac / g.exp();
            let v = if lookup == 0 {
                ideal(cube, c.world(l), sig_l)
            } else {
                let lod = ((sig_l * mipk / texel).log2()).max(0.0);
                cube.sample(c.world(l), lod)
            };
            for k in 0..3 {
                s[k] += wx * wy * w * v[k];
            }
            sw += wx * wy * w;
        }
    }
    let a = albedo(c);
    if sw > 0.0 {
        s.map(|v| v / sw * a)
    } else {
        [0.0; 3]
    }
}

fn main() {
    let env = if std::env::var("WHITE").is_ok() {
        Environment::uniform([1.0, 1.0, 1.0])
    } else {
        Environment::load(
            &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/env/lebombo_1k.hdr"),
        )
        .expect("tests/data/env/lebombo_1k.hdr")
    };
    let rot = 60.0;
    let q = EnvQuadrature::new(&env, rot, 1.0, 1);
    let cube = Cube::new(&env, 256, rot);
    // configs
    let mut rng = 12345u64;
    let mut rnd = || {
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        (rng >> 11) as f64 / (1u64 << 53) as f64
    };
    let ncfg: usize = std::env::args()
        .nth(1)
        .map(|s| s.parse().unwrap())
        .unwrap_or(60);
    let mut cfgs = Vec::new();
    while cfgs.len() < ncfg {
        let n = norm([rnd() * 2.0 - 1.0, rnd() * 1.3 - 0.3, rnd() * 2.0 - 1.0]);
        let a = norm([rnd() * 2.0 - 1.0, rnd() * 2.0 - 1.0, rnd() * 2.0 - 1.0]);
        let t = norm(add(a, n, -dot(a, n)));
        let b = cross(n, t);
        // NV=LO,HI: views with n·v in [LO, HI] (default 0.15 to 1).
        let (zlo, zhi) = std::env::var("NV")
            .ok()
            .and_then(|v| {
                let (a, b) = v.split_once(',')?;
                Some((a.parse::<f64>().ok()?, b.parse::<f64>().ok()?))
            })
            .unwrap_or((0.15, 1.0));
        let z: f64 = zlo + (zhi - zlo) * rnd();
        let ph = rnd() * 2.0 * std::f64::consts::PI;
        let r = (1.0 - z * z).sqrt();
        cfgs.push(Cfg {
            t,
            b,
            n,
            k2: [r * ph.cos(), r * ph.sin(), z],
        });
    }
    let truths: Vec<V> = cfgs.iter().map(|c| truth(&q, c)).collect();
    let mut ests: Vec<(String, Box<dyn Fn(&Cfg) -> V>)> = Vec::new();
    if std::env::var("QUICK").is_ok() {
        // QUICK=1: the ratio estimator (exact albedo) at 8, 16 and 32 samples alone.
        let cube = &cube;
        let ns: Vec<u32> = std::env::var("QN")
            .map(|v| v.split(',').map(|x| x.parse().unwrap()).collect())
            .unwrap_or(vec![8, 16, 32]);
        for n in ns {
            ests.push((
                format!("ratio fis:{n}"),
                Box::new(move |c| ratio(cube, c, n, Pat::Hammersley, 0.0, 0, 0.95)),
            ));
        }
    } else if std::env::var("GH").is_ok() {
        let cube = &cube;
        ests.push((
            "ratio fis:8".into(),
            Box::new(move |c| ratio(cube, c, 8, Pat::Hammersley, 0.0, 0, 0.95)),
        ));
        ests.push((
            "aniso split sum (normal-incidence lobe about r)".into(),
            Box::new(move |c| {
                let k2 = c.k2;
                let r = c.world([-k2[0], -k2[1], k2[2]]);
                let t = norm(add(c.t, r, -dot(c.t, r)));
                let cn = Cfg {
                    t,
                    b: cross(r, t),
                    n: r,
                    k2: [0.0, 0.0, 1.0],
                };
                let (v, w) = fis_w(cube, &cn, 4096, Pat::Hammersley, -20.0, 0, 1.0);
                let a = albedo(c);
                v.map(|x| x / w * a)
            }),
        ));
        for ws in [0.5f64, 0.8] {
            for n in [8u32, 16, 256] {
                ests.push((
                    format!("fis:{n} mixture {ws}"),
                    Box::new(move |c| fis(cube, c, n, Pat::Hammersley, 0.0, 0, ws)),
                ));
                ests.push((
                    format!("ratio fis:{n} mixture {ws}"),
                    Box::new(move |c| ratio(cube, c, n, Pat::Hammersley, 0.0, 0, ws)),
                ));
            }
        }
        for n in [8u32, 12, 16, 24] {
            ests.push((
                format!("ratio fis:{n}"),
                Box::new(move |c| ratio(cube, c, n, Pat::Hammersley, 0.0, 0, 0.95)),
            ));
        }
        for (kx, ky, pre) in [(12usize, 24usize, 0.3), (24, 48, 0.3), (12, 24, 0.01)] {
            if std::env::var("GHQ").is_ok() {
                break;
            }
            ests.push((
                format!("gh {kx}x{ky} ideal pre {pre}"),
                Box::new(move |c| gh(cube, c, kx, ky, pre, 0, 0.0)),
            ));
        }
        for (kx, ky) in [
            (1usize, 1usize),
            (1, 3),
            (1, 4),
            (1, 6),
            (1, 8),
            (2, 4),
            (2, 6),
            (3, 6),
        ] {
            if std::env::var("GHQ").is_ok() {
                break;
            }
            for pre in [1.0, 1.5] {
                ests.push((
                    format!("gh {kx}x{ky} ideal pre {pre}"),
                    Box::new(move |c| gh(cube, c, kx, ky, pre, 0, 0.0)),
                ));
            }
            for mipk in [1.0, 2.0, 3.0] {
                ests.push((
                    format!("gh {kx}x{ky} mips k{mipk}"),
                    Box::new(move |c| gh(cube, c, kx, ky, 1.0, 1, mipk)),
                ));
            }
        }
    } else {
        for n in [8u32, 16, 32, 64] {
            let cube = &cube;
            ests.push((
                format!("fis:{n}"),
                Box::new(move |c| fis(cube, c, n, Pat::Hammersley, 0.0, 0, 0.95)),
            ));
            ests.push((
                format!("ratio fis:{n}"),
                Box::new(move |c| ratio(cube, c, n, Pat::Hammersley, 0.0, 0, 0.95)),
            ));
        }
        for (n, taps) in [(8u32, 4u32), (16, 3), (24, 4), (32, 4)] {
            let cube = &cube;
            ests.push((
                format!("fis:{n} t{taps}"),
                Box::new(move |c| fis(cube, c, n, Pat::Hammersley, 0.0, taps, 0.95)),
            ));
            ests.push((
                format!("ratio fis:{n} t{taps}"),
                Box::new(move |c| ratio(cube, c, n, Pat::Hammersley, 0.0, taps, 0.95)),
            ));
        }
        for bias in [-0.5, 0.5] {
            let cube = &cube;
            ests.push((
                format!("fis:8 lod {bias:+}"),
                Box::new(move |c| fis(cube, c, 8, Pat::Hammersley, bias, 0, 0.95)),
            ));
        }
        for (kx, ky, mode, shape) in [
            (1u32, 12u32, 1u32, false),
            (2, 8, 0, true),
            (3, 6, 0, true),
            (16, 64, 1, true),
        ] {
            let cube = &cube;
            let bias = if kx == 16 { -20.0 } else { 0.0 };
            ests.push((
                format!("gauss {kx}x{ky}{}", if shape { " s1" } else { "" }),
                Box::new(move |c| gauss(cube, c, kx, ky, bias, shape, mode)),
            ));
        }
        {
            let cube = &cube;
            ests.push((
                "fis:4096 at level 0 (check)".into(),
                Box::new(move |c| fis(cube, c, 4096, Pat::Hammersley, -20.0, 0, 0.95)),
            ));
        }
    }
    println!(
        "{:<34} {:>9} {:>9} {:>8}",
        "estimator", "rel.err", "bias", "psnr"
    );
    let peak = truths.iter().map(|t| lum(*t)).fold(0.0, f64::max);
    for (name, f) in &ests {
        let (mut se, mut st, mut sb, mut sq) = (0.0, 0.0, 0.0, 0.0);
        for (c, t) in cfgs.iter().zip(&truths) {
            let e = f(c);
            let (le, lt) = (lum(e), lum(*t));
            se += (le - lt).abs();
            sb += le - lt;
            st += lt;
            sq += (le - lt) * (le - lt);
        }
        let rms = (sq / cfgs.len() as f64).sqrt();
        println!(
            "{:<34} {:>9.4} {:>9.4} {:>8.2}",
            name,
            se / st,
            sb / st,
            20.0 * (peak / rms).log10()
        );
    }
}
