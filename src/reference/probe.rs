//! The probe: `glsl/fabric_probe.comp` evaluates every GLSL function of the BRDF and the weave on
//! a batch of inputs; this module holds the std430 twins of its buffers, the same evaluation on the
//! CPU (f64: the reference; f32: the line-for-line twin of the GLSL), the inputs (every hard case
//! of the model page's §5 plus seeded random ones), and the tolerance each output must meet.
//!
//! # The shader's interface
//! - set 0, binding 0: `readonly buffer` of [`ProbeInput`] (std430, 192 bytes each);
//! - set 0, binding 1: `writeonly buffer` of [`ProbeOutput`] (std430, 128 bytes each);
//! - push constant `uint count` (4 bytes); `local_size_x = 64`: dispatch `ceil(count/64)` groups.
//!
//! # Error bounds
//! Every output `y` must satisfy `|y - y64| ≤ tol` with `y64` from [`probe_cpu_f64`] and `tol` from
//! [`probe_tolerance`] (same shape as the output). The tolerance is built from a few constants
//! ([`ProbeBound`]) and the input's own condition numbers:
//!
//! - **Directions.** The local directions differ from the f64 ones by an absolute `dir` (the frame
//!   is built from f32 inputs: normalise, Gram–Schmidt, cross, three dot products: ~10 roundings
//!   of unit-size numbers; on the GPU `inversesqrt` is 2 ulp and products may be fused). `n·k`,
//!   `h·n`, `h·k` inherit `dir` (×2 for `h`).
//! - **The exponent** `X = -ln(hn^E)`. [`as_power`](super::brdf::single::as_power) forms it from
//!   `hu², hv²` without cancellation, so its relative error is a fixed number of roundings
//!   (`x_rel·X`; on the GPU `exp(x)` adds `(3 + 2|x|)` ulp and, for `hn < 0.866`, `log` adds an
//!   absolute `2^-21`, i.e. `X·2^-21/|ln 0.866| = 3.3e-6·X`), plus the effect of the direction
//!   error: `|∂X/∂hu|·dir ≤ 2(eu|hu| + ev|hv|)·dir` (and `E·dir/hn` on the log branch). At
//!   `E = 1e6` near the peak this term dominates: a direction known to 1e-7 moves a lobe of width
//!   1e-3 by 1e-4 of its width — the limit of f32 directions, not of the formula (`pow(hn, E)`
//!   would add `E·ulp(1) = 6 %` on top, which is why it is not used). The result's relative error
//!   is `expm1(ΔX)`.
//! - **The lobe** `ρs = norm · hn^E · F / (kh·max(n·k))`: relative `rel + expm1(ΔX) + 3·dir/max(n·k)`
//!   (the denominator's conditioning) of `ρs` with `F = 1` (F's absolute error
//!   `5·dir` then fits in `rel`), plus an absolute floor `floor·norm/denom` (`floor = 1e-6` of the
//!   lobe's peak): below it `exp` underflows differently in f32 (X > 87) and nothing is visible.
//! - **The weave point**: coverages exactly 0 or 1 and the same class (the random points keep
//!   1e-4 cell from every region border, and the hard cases on borders are dyadic, exact in
//!   both); `s_warp`, `s_weft` to `rel`.
//! - **The box coverage** is a sum of products of 1-D measures, each from `floor`, products and
//!   differences of numbers up to `M = max(|x0|, |x1|, cols)`: its absolute error is a few ulp of
//!   `M` per boundary crossed, divided by the box size: `box_ulps·ε·(Mx/wx + My/wy)`, times the
//!   number of cells `cols·rows` when the box spans whole repeats (every cell's measures then
//!   carry error).
//!
//! [`ProbeBound::CPU_F32`] is the bound the f32 CPU path is tested against
//! (`tests/fabric_reference.rs`); [`ProbeBound::GPU`] widens it by the GLSL precision rules of the
//! Vulkan spec (`exp`/`exp2` 3 + 2|x| ulp, `log` 3 ulp or 2^-21 absolute, division 2.5 ulp,
//! `inversesqrt` 2 ulp, `sqrt` inherited) and by fused multiply-adds, with a factor 2 to spare.
//! Measured: the f32 path reaches at most 0.12 of its bound on every output; lavapipe 0.11 of the
//! GPU bound (`tests/fabric_probe_gpu.rs`).
//!
//! Also: the local directions' error is divided by `sin∠(n, t)` (Gram–Schmidt) and, for `h`, by
//! `|k1 + k2|`; `E` itself is undetermined near `h = n` (its error is capped at `|eu − ev|`).

#![allow(clippy::neg_cmp_op_on_partial_ord)] // `!(x > 0.0)` is meant: it is true for NaN, as in the GLSL twin.

use super::brdf;
use super::weave;
use crate::fabric::{FabricParams, GpuFabric, WeavePattern};

/// One probe input (std430, 208 bytes; `ProbeInput` in `glsl/fabric_probe.comp`).
///
/// | offset | field | meaning |
/// |---|---|---|
/// | 0   | `n: vec4` | world normal (xyz), w unused |
/// | 16  | `t: vec4` | world tangent (xyz), w = handedness sign |
/// | 32  | `k1: vec4` | world direction to the light (xyz, unit) |
/// | 48  | `k2: vec4` | world direction to the viewer (xyz, unit) |
/// | 64  | `point: vec4` | xy: point for the weave classifier, in cells |
/// | 80  | `footprint: vec4` | (x0, y0, x1, y1): box for the weave coverage, in cells |
/// | 96  | `coverage: vec4` | (c_warp, c_weft, s_warp, s_weft) given to `fabric_brdf` |
/// | 112 | `tint: vec4` | rgb: the thread texture's value given to `fabric_tinted` |
/// | 128 | `fabric: GpuFabric` | the material (80 bytes) |
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ProbeInput {
    pub n: [f32; 4],
    pub t: [f32; 4],
    pub k1: [f32; 4],
    pub k2: [f32; 4],
    pub point: [f32; 4],
    pub footprint: [f32; 4],
    pub coverage: [f32; 4],
    pub tint: [f32; 4],
    pub fabric: GpuFabric,
}

/// One probe output (std430, 208 bytes; `ProbeOutput` in `glsl/fabric_probe.comp`).
///
/// | offset | field | x | y | z | w |
/// |---|---|---|---|---|---|
/// | 0  | `lobe` | ρs weft-oriented (eu = e_along) | ρs warp-oriented | D(h) weft-oriented | F(h·k) |
/// | 16 | `expo` | E(h) weft | E(h) warp | h·n | h·k (clamped) |
/// | 32 | `diffuse` | coupled diffuse (no Rd) | n·k1 | n·k2 | hn^E weft |
/// | 48 | `f` | fabric f, r | g | b | 0 |
/// | 64 | `point` | c_warp | c_weft | s_warp | s_weft |
/// | 80 | `footprint` | c_warp | c_weft | s_warp | s_weft |
/// | 96 | `f_point` | f with the point's coverage, r | g | b | 0 |
/// | 112 | `f_avg` | `fabric_brdf_averaged` with the input coverage, r | g | b | 0 |
/// | 128 | `phong` | `phong_brdf`, r | g | b | `phong_lobe` (exponent `fabric_phong_exponent`) |
/// | 144 | `plain_as` | `plain_as_brdf`, r | g | b | 0 |
/// | 160 | `f_tint` | `fabric_brdf` of `fabric_tinted(m, tint)`, input coverage, r | g | b | 0 |
/// | 176 | `sheet` | `fabric_btdf` with k1 mirrored to the far side, r | g | b | `fabric_thread_cover` |
/// | 192 | `f_sheet` | `fabric_brdf` of `fabric_reflecting(m)`, input coverage, r | g | b | 0 |
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ProbeOutput {
    pub lobe: [f32; 4],
    pub expo: [f32; 4],
    pub diffuse: [f32; 4],
    pub f: [f32; 4],
    pub point: [f32; 4],
    pub footprint: [f32; 4],
    pub f_point: [f32; 4],
    pub f_avg: [f32; 4],
    pub phong: [f32; 4],
    pub plain_as: [f32; 4],
    pub f_tint: [f32; 4],
    pub sheet: [f32; 4],
    pub f_sheet: [f32; 4],
}

const _: () = {
    assert!(std::mem::size_of::<ProbeInput>() == 208);
    assert!(std::mem::offset_of!(ProbeInput, coverage) == 96);
    assert!(std::mem::offset_of!(ProbeInput, fabric) == 128);
    assert!(std::mem::size_of::<ProbeOutput>() == 208);
    assert!(std::mem::offset_of!(ProbeOutput, f_point) == 96);
};

/// Names of the 52 output components, in memory order (for messages).
#[rustfmt::skip]
pub const PROBE_OUTPUT_NAMES: [&str; PROBE_OUTPUTS] = [
    "rho_weft", "rho_warp", "d_weft", "fresnel",
    "e_weft", "e_warp", "hn", "kh",
    "coupled_diffuse", "nk1", "nk2", "power_weft",
    "f.r", "f.g", "f.b", "f.w",
    "point.c_warp", "point.c_weft", "point.s_warp", "point.s_weft",
    "footprint.c_warp", "footprint.c_weft", "footprint.s_warp", "footprint.s_weft",
    "f_point.r", "f_point.g", "f_point.b", "f_point.w",
    "f_avg.r", "f_avg.g", "f_avg.b", "f_avg.w",
    "phong.r", "phong.g", "phong.b", "phong_lobe",
    "plain_as.r", "plain_as.g", "plain_as.b", "plain_as.w",
    "f_tint.r", "f_tint.g", "f_tint.b", "f_tint.w",
    "btdf.r", "btdf.g", "btdf.b", "thread_cover",
    "f_sheet.r", "f_sheet.g", "f_sheet.b", "f_sheet.w",
];

/// Number of f32 components of a [`ProbeOutput`].
pub const PROBE_OUTPUTS: usize = 52;

impl ProbeOutput {
    pub fn to_array(&self) -> [f32; PROBE_OUTPUTS] {
        let mut a = [0.0; PROBE_OUTPUTS];
        for (k, v) in [
            self.lobe,
            self.expo,
            self.diffuse,
            self.f,
            self.point,
            self.footprint,
            self.f_point,
            self.f_avg,
            self.phong,
            self.plain_as,
            self.f_tint,
            self.sheet,
            self.f_sheet,
        ]
        .iter()
        .enumerate()
        {
            a[4 * k..4 * k + 4].copy_from_slice(v);
        }
        a
    }

    pub fn from_array(a: &[f32; PROBE_OUTPUTS]) -> Self {
        let v = |k: usize| [a[4 * k], a[4 * k + 1], a[4 * k + 2], a[4 * k + 3]];
        ProbeOutput {
            lobe: v(0),
            expo: v(1),
            diffuse: v(2),
            f: v(3),
            point: v(4),
            footprint: v(5),
            f_point: v(6),
            f_avg: v(7),
            phong: v(8),
            plain_as: v(9),
            f_tint: v(10),
            sheet: v(11),
            f_sheet: v(12),
        }
    }

    /// Reads one output from the shader's buffer bytes (little-endian, 208 bytes).
    pub fn from_bytes(b: &[u8]) -> Self {
        let mut a = [0.0f32; PROBE_OUTPUTS];
        for (k, x) in a.iter_mut().enumerate() {
            *x = f32::from_le_bytes([b[4 * k], b[4 * k + 1], b[4 * k + 2], b[4 * k + 3]]);
        }
        Self::from_array(&a)
    }
}

impl ProbeInput {
    /// The input's bytes as the shader reads them (little-endian, 208 bytes).
    pub fn to_bytes(&self) -> [u8; 208] {
        let mut out = [0u8; 208];
        let vecs = [
            self.n,
            self.t,
            self.k1,
            self.k2,
            self.point,
            self.footprint,
            self.coverage,
            self.tint,
        ];
        for (k, v) in vecs.iter().enumerate() {
            for (c, x) in v.iter().enumerate() {
                out[16 * k + 4 * c..16 * k + 4 * c + 4].copy_from_slice(&x.to_le_bytes());
            }
        }
        out[128..].copy_from_slice(&self.fabric.to_bytes());
        out
    }
}

/// The probe's evaluation, in one precision: `single` mirrors `main()` of
/// `glsl/fabric_probe.comp` line for line.
macro_rules! probe_eval {
    ($name:ident, $prec:ident, $t:ident) => {
        pub fn $name(input: &ProbeInput) -> ProbeOutput {
            use brdf::$prec::*;
            use weave::$prec::{weave_box, weave_point, Weave};
            let v3 = |v: [f32; 4]| -> Vec3 { [v[0] as $t, v[1] as $t, v[2] as $t] };
            let m = FabricMaterial::from_gpu(&input.fabric);
            let w = Weave::from_gpu(&input.fabric);
            let frame = fabric_frame(v3(input.n), v3(input.t), input.t[3] as $t);
            let k1 = fabric_local(v3(input.k1), frame);
            let k2 = fabric_local(v3(input.k2), frame);
            let (h, kh) = fabric_half(k1, k2);
            let cov = input.coverage.map(|x| x as $t);
            let p = weave_point(&w, input.point[0] as $t, input.point[1] as $t);
            let fp = input.footprint;
            let b = weave_box(&w, fp[0] as $t, fp[1] as $t, fp[2] as $t, fp[3] as $t);
            let f = fabric_brdf(k1, k2, cov, &m);
            let f_point = fabric_brdf(k1, k2, p, &m);
            let f_avg = fabric_brdf_averaged(k1, k2, cov, &m);
            let phong = phong_brdf(k1, k2, &m);
            let plain_as = plain_as_brdf(k1, k2, &m);
            let tint = [
                input.tint[0] as $t,
                input.tint[1] as $t,
                input.tint[2] as $t,
            ];
            let f_tint = fabric_brdf(k1, k2, cov, &fabric_tinted(&m, tint));
            // The sheet's terms, with the light mirrored to the far side.
            let btdf = fabric_btdf([k1[0], k1[1], -k1[2]], k2, cov, &m);
            let f_sheet = fabric_brdf(k1, k2, cov, &fabric_reflecting(&m));
            let out: [$t; PROBE_OUTPUTS] = [
                as_lobe(k1, k2, m.e_along, m.e_across, m.rs),
                as_lobe(k1, k2, m.e_across, m.e_along, m.rs),
                as_d(h, m.e_along, m.e_across),
                schlick(m.rs, kh),
                as_exponent(h[0], h[1], m.e_along, m.e_across),
                as_exponent(h[0], h[1], m.e_across, m.e_along),
                h[2],
                kh,
                coupled_diffuse(m.rs, k1[2], k2[2]),
                k1[2],
                k2[2],
                as_power(h[0], h[1], h[2], m.e_along, m.e_across),
                f[0],
                f[1],
                f[2],
                0.0,
                p[0],
                p[1],
                p[2],
                p[3],
                b[0],
                b[1],
                b[2],
                b[3],
                f_point[0],
                f_point[1],
                f_point[2],
                0.0,
                f_avg[0],
                f_avg[1],
                f_avg[2],
                0.0,
                phong[0],
                phong[1],
                phong[2],
                phong_lobe(k1, k2, fabric_phong_exponent(&m)),
                plain_as[0],
                plain_as[1],
                plain_as[2],
                0.0,
                f_tint[0],
                f_tint[1],
                f_tint[2],
                0.0,
                btdf[0],
                btdf[1],
                btdf[2],
                fabric_thread_cover(cov),
                f_sheet[0],
                f_sheet[1],
                f_sheet[2],
                0.0,
            ];
            ProbeOutput::from_array(&out.map(|x| x as f32))
        }
    };
}

probe_eval!(probe_cpu_f64, double, f64);
probe_eval!(probe_cpu_f32, single, f32);

/// The constants of the error bound; see the module docs for what each one bounds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProbeBound {
    /// Absolute error of the local directions' components.
    pub dir: f64,
    /// Relative error of a value from a fixed number of roundings (and F's absolute error).
    pub rel: f64,
    /// Relative error of the exponent `X = -ln(hn^E)`.
    pub x_rel: f64,
    /// Absolute floor, as a fraction of the lobe's peak `norm/denom` (and of D's `norm`).
    pub floor: f64,
    /// Ulps of the largest coordinate, per boundary, for the box coverage.
    pub box_ulps: f64,
}

impl ProbeBound {
    /// The f32 CPU path ([`probe_cpu_f32`]): ~10 roundings of ε = 2^-24 per direction component
    /// (≈ 6e-7, taken as 1e-6), ~30 roundings in a lobe value (2e-6, taken as 4e-6), ~8 in the
    /// exponent (taken as 1e-6·X).
    pub const CPU_F32: ProbeBound = ProbeBound {
        dir: 1e-6,
        rel: 4e-6,
        x_rel: 1e-6,
        floor: 1e-6,
        box_ulps: 8.0,
    };
    /// A Vulkan GPU: the CPU bound plus the spec's precision of GLSL built-ins (see module docs),
    /// doubled: `dir` 2 ulp more per `inversesqrt` and fused products (4e-6), `rel` +20 ulp
    /// (division, sqrt, exp: 1.6e-5), `x_rel` + 2 ulp per unit of X for `exp` and 3.3e-6 for
    /// `log` (1e-5).
    pub const GPU: ProbeBound = ProbeBound {
        dir: 4e-6,
        rel: 1.6e-5,
        x_rel: 1e-5,
        floor: 1e-6,
        box_ulps: 16.0,
    };
}

/// `expm1` of an exponent error, capped so that a meaningless bound stays finite.
fn exp_err(dx: f64) -> f64 {
    dx.min(50.0).exp_m1()
}

/// The allowed `|y - y64|` for each output of `input` (same layout as [`ProbeOutput`]).
pub fn probe_tolerance(input: &ProbeInput, bound: &ProbeBound) -> ProbeOutput {
    use brdf::double::*;
    let v3 = |v: [f32; 4]| -> Vec3 { [v[0] as f64, v[1] as f64, v[2] as f64] };
    let m = FabricMaterial::from_gpu(&input.fabric);
    let frame = fabric_frame(v3(input.n), v3(input.t), input.t[3] as f64);
    // Gram–Schmidt divides the tangent's rounding error by its component orthogonal to n.
    let (nv, tv) = (v3(input.n), v3(input.t));
    let nn = dot(nv, nv).sqrt();
    let tt = dot(tv, tv).sqrt();
    let sin_nt = if nn > 0.0 && tt > 0.0 {
        let c = dot(nv, tv) / (nn * tt);
        (1.0 - c * c).max(0.0).sqrt()
    } else {
        1.0
    };
    let bound = ProbeBound {
        dir: bound.dir * (1.0 + 1.0 / sin_nt.max(1e-3)),
        ..*bound
    };
    let b = &bound;
    let k1 = fabric_local(v3(input.k1), frame);
    let k2 = fabric_local(v3(input.k2), frame);
    let (h, kh) = fabric_half(k1, k2);
    let (nk1, nk2) = (k1[2], k2[2]);
    let s = h[0] * h[0] + h[1] * h[1];
    let facing = nk1 > 0.0 && nk2 > 0.0;
    let nk_max = nk1.max(nk2).max(1e-300);
    let denom = (kh * nk1.max(nk2)).max(DENOM_MIN);
    // h = (k1 + k2)/|k1 + k2| divides the directions' error by |k1 + k2| = 2·kh.
    let dir_h = b.dir / kh.max(1e-300);

    // Per orientation: (error of the lobe, error of D, error of hn^E).
    let lobe_err = |eu: f64, ev: f64| -> (f64, f64, f64) {
        let power = as_power(h[0], h[1], h[2], eu, ev);
        let x = if power > 0.0 {
            -power.ln()
        } else {
            f64::INFINITY
        };
        let e = as_exponent(h[0], h[1], eu, ev);
        let log_branch = if s >= SERIES_MAX_S {
            e / h[2].max(1e-300)
        } else {
            0.0
        };
        let dx = b.x_rel * x + dir_h * (2.0 * (eu * h[0].abs() + ev * h[1].abs()) + log_branch);
        let rel = if x.is_finite() { exp_err(dx) } else { 0.0 };
        let norm8 = ((eu + 1.0) * (ev + 1.0)).sqrt() / (8.0 * std::f64::consts::PI);
        let norm2 = 4.0 * norm8;
        let rho_f1 = if facing { norm8 * power / denom } else { 0.0 };
        let rho = (rel + b.rel + 3.0 * b.dir / nk_max) * rho_f1
            + if facing { b.floor * norm8 / denom } else { 0.0 };
        let d = (rel + b.rel) * norm2 * power + b.floor * norm2;
        let p = (rel + b.rel) * power + b.floor;
        (rho + 1e-30, d + 1e-30, p + 1e-30)
    };
    let (rho_weft, d_weft, p_weft) = lobe_err(m.e_along, m.e_across);
    let (rho_warp, _, _) = lobe_err(m.e_across, m.e_along);
    let cov = input.coverage.map(|x| x as f64);
    let c_thread = cov[0] + cov[1];
    let rho_avg = if c_thread > 0.0 {
        let t = cov[1] / c_thread;
        // The averaged exponents carry a few roundings more: a relative error of X, within `x_rel`.
        lobe_err(
            t * m.e_along + (1.0 - t) * m.e_across,
            t * m.e_across + (1.0 - t) * m.e_along,
        )
        .0
    } else {
        0.0
    };

    let e_err = |eu: f64, ev: f64| -> f64 {
        let spread = (eu - ev).abs() * (4.0 * dir_h / s.sqrt()).min(1.0);
        b.rel * eu.max(ev) + spread + 1e-30
    };

    // fabric_brdf with coverage c: the lobes' errors weighted by coverage (`spec`), plus the
    // diffuse term to `rel` (Lambert) or to `rel` and its slope 0.97 times the error of n·k (coupled).
    let diffuse_err = |c: [f64; 4]| -> f64 {
        let c_thread = c[0] + c[1];
        if !facing || !(c_thread > 0.0) {
            return 0.0;
        }
        let rd_max = m
            .rd_warp
            .iter()
            .chain(m.rd_weft.iter())
            .fold(0.0f64, |a, &x| a.max(x));
        let diffuse = if m.coupled {
            coupled_diffuse(m.rs, nk1, nk2)
        } else {
            lambert()
        };
        let w = (c[2] + c[3]) * rd_max;
        b.rel * w * diffuse + if m.coupled { 2.0 * b.dir * w } else { 0.0 }
    };
    let f_err = |c: [f64; 4]| -> f64 {
        if !facing {
            return 1e-30;
        }
        c[1] * rho_weft + c[0] * rho_warp + diffuse_err(c) + 1e-30
    };
    let f_tol = f_err(cov);
    let f_avg_tol = if facing {
        c_thread * rho_avg + diffuse_err(cov) + 1e-30
    } else {
        1e-30
    };
    let p64 = weave::double::weave_point(
        &weave::double::Weave::from_gpu(&input.fabric),
        input.point[0] as f64,
        input.point[1] as f64,
    );
    let fp_tol = f_err(p64);

    let fp = input.footprint.map(|x| x as f64);
    let (wx, wy) = (fp[2] - fp[0], fp[3] - fp[1]);
    let box_tol = if wx >= weave::double::WEAVE_MIN_BOX && wy >= weave::double::WEAVE_MIN_BOX {
        let (px, py) = (input.fabric.cols as f64, input.fabric.rows as f64);
        let mx = fp[0].abs().max(fp[2].abs()).max(px);
        let my = fp[1].abs().max(fp[3].abs()).max(py);
        let cells = if wx >= px || wy >= py { px * py } else { 1.0 };
        b.box_ulps * f32::EPSILON as f64 * cells * (mx / wx + my / wy) + 1e-7
    } else {
        0.0
    };

    // The comparison models. Phong's lobe (e + 2)/(2π)·(r·k2)^e: r·k2 is a sum of three products
    // of direction components (error 3·dir), which the power multiplies by e/(r·k2); the
    // exponent e·ln(r·k2) carries x_rel. Where r·k2 is within that error of 0, either side of the
    // cut-off is right: allow the lobe's value there.
    let e_phong = fabric_phong_exponent(&m);
    let rk = k1[0] * -k2[0] + k1[1] * -k2[1] + k1[2] * k2[2];
    let lobe_norm = (e_phong + 2.0) / (2.0 * std::f64::consts::PI);
    let phong_lobe_tol = if facing {
        let p = phong_lobe(k1, k2, e_phong);
        let drk = 3.0 * b.dir;
        let rel = if rk > drk {
            exp_err(e_phong * drk / (rk - drk) + b.x_rel * e_phong * -rk.min(1.0).ln())
        } else {
            0.0
        };
        let cut = if rk.abs() <= drk {
            lobe_norm * (2.0 * drk).min(1.0).powf(e_phong)
        } else {
            0.0
        };
        (rel + b.rel) * p + cut + b.floor * lobe_norm + 1e-30
    } else {
        1e-30
    };
    let phong_tol = if facing {
        m.rs * phong_lobe_tol + diffuse_err([0.5, 0.5, 0.5, 0.5]) + 1e-30
    } else {
        1e-30
    };
    let plain_tol = if facing {
        rho_weft + diffuse_err([0.5, 0.5, 0.5, 0.5]) + 1e-30
    } else {
        1e-30
    };

    let btdf_tol = match m.sheet {
        Some(t) if nk2 > 0.0 => {
            let rd_max = m
                .rd_warp
                .iter()
                .chain(m.rd_weft.iter())
                .fold(0.0f64, |a, &x| a.max(x));
            b.rel * t * rd_max * (cov[2].abs() + cov[3].abs()) / std::f64::consts::PI + 1e-30
        }
        _ => 1e-30,
    };
    #[rustfmt::skip]
    let out = [
        rho_weft, rho_warp, d_weft, b.rel + 5.0 * b.dir,
        e_err(m.e_along, m.e_across), e_err(m.e_across, m.e_along), 2.0 * dir_h, 2.0 * b.dir,
        b.rel + 2.0 * b.dir, b.dir, b.dir, p_weft,
        f_tol, f_tol, f_tol, 0.0,
        0.0, 0.0, b.rel, b.rel,
        box_tol, box_tol, box_tol * (1.0 + input.fabric.shadow_strength as f64),
        box_tol * (1.0 + input.fabric.shadow_strength as f64),
        fp_tol, fp_tol, fp_tol, 0.0,
        f_avg_tol, f_avg_tol, f_avg_tol, 0.0,
        phong_tol, phong_tol, phong_tol, phong_lobe_tol,
        plain_tol, plain_tol, plain_tol, 0.0,
        // f_tint: the tint (each in [0, 1]) scales the diffuse term down, with one more
        // rounding, well within `rel`: f's bound holds.
        f_tol, f_tol, f_tol, 0.0,
        // The sheet's transmitted light: τ/π times the albedo, a few roundings (`rel`); the
        // thread cover: one addition and a clamp. f_sheet: f's bound (the colours scaled by
        // 1 − τ ≤ 1, one more rounding).
        btdf_tol, btdf_tol, btdf_tol, b.rel,
        f_tol, f_tol, f_tol, 0.0,
    ];
    ProbeOutput::from_array(&out.map(|x| x as f32))
}

/// Compares `got` (GPU or f32 CPU) with `reference` (from [`probe_cpu_f64`]) under `bound`: one
/// message per output component that is not finite or differs by more than its tolerance.
pub fn probe_check(
    input: &ProbeInput,
    reference: &ProbeOutput,
    got: &ProbeOutput,
    bound: &ProbeBound,
) -> Vec<String> {
    let tol = probe_tolerance(input, bound).to_array();
    let r = reference.to_array();
    let g = got.to_array();
    let mut out = Vec::new();
    for k in 0..PROBE_OUTPUTS {
        let diff = (g[k] as f64 - r[k] as f64).abs();
        if !g[k].is_finite() || !(diff <= tol[k] as f64) {
            out.push(format!(
                "{}: got {:e}, reference {:e}, |diff| {:e} > tolerance {:e}",
                PROBE_OUTPUT_NAMES[k], g[k], r[k], diff, tol[k]
            ));
        }
    }
    out
}

/// The largest `|y - y64| / tol` over the outputs (≤ 1 passes), with the component's name.
pub fn probe_worst_ratio(
    input: &ProbeInput,
    reference: &ProbeOutput,
    got: &ProbeOutput,
    bound: &ProbeBound,
) -> (f64, &'static str) {
    let tol = probe_tolerance(input, bound).to_array();
    let r = reference.to_array();
    let g = got.to_array();
    let mut worst = (0.0, PROBE_OUTPUT_NAMES[0]);
    for k in 0..PROBE_OUTPUTS {
        let diff = (g[k] as f64 - r[k] as f64).abs();
        let ratio = if diff == 0.0 {
            0.0
        } else if tol[k] > 0.0 {
            diff / tol[k] as f64
        } else {
            f64::INFINITY
        };
        let ratio = if ratio.is_nan() { f64::INFINITY } else { ratio };
        if ratio > worst.0 {
            worst = (ratio, PROBE_OUTPUT_NAMES[k]);
        }
    }
    worst
}

/// A named probe input.
#[derive(Clone, Debug)]
pub struct ProbeCase {
    pub name: String,
    pub input: ProbeInput,
}

/// A small deterministic generator (xorshift64*), so the probe needs no extra crate.
#[derive(Clone, Debug)]
pub struct XorShift(u64);

impl XorShift {
    pub fn new(seed: u64) -> Self {
        XorShift(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }
    pub fn next_u64(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        x.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    /// Uniform in [0, 1).
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next_f64()
    }
    /// Log-uniform in [lo, hi), lo > 0.
    pub fn log_range(&mut self, lo: f64, hi: f64) -> f64 {
        (lo.ln() + (hi.ln() - lo.ln()) * self.next_f64()).exp()
    }
    /// A uniformly distributed unit vector.
    pub fn unit(&mut self) -> [f64; 3] {
        let z = self.range(-1.0, 1.0);
        let phi = self.range(0.0, 2.0 * std::f64::consts::PI);
        let r = (1.0 - z * z).max(0.0).sqrt();
        [r * phi.cos(), r * phi.sin(), z]
    }
}

fn v4(v: [f64; 3], w: f32) -> [f32; 4] {
    [v[0] as f32, v[1] as f32, v[2] as f32, w]
}

/// A unit vector rounded to f32 and renormalised there (so its f32 length is as close to 1 as f32
/// allows: the shaders get directions a renderer would give them).
fn unit32(v: [f64; 3]) -> [f64; 3] {
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let w = [(v[0] / l) as f32, (v[1] / l) as f32, (v[2] / l) as f32];
    [w[0] as f64, w[1] as f64, w[2] as f64]
}

fn base_input(fabric: GpuFabric) -> ProbeInput {
    ProbeInput {
        n: [0.0, 0.0, 1.0, 0.0],
        t: [1.0, 0.0, 0.0, 1.0],
        k1: [0.0, 0.0, 1.0, 0.0],
        k2: [0.0, 0.0, 1.0, 0.0],
        point: [0.5, 0.5, 0.0, 0.0],
        footprint: [0.25, 0.25, 0.75, 0.75],
        coverage: [0.3, 0.5, 0.2, 0.4],
        tint: [0.75, 0.5, 0.25, 0.0],
        fabric,
    }
}

fn material(e_along: f32, e_across: f32, rs: f32) -> GpuFabric {
    FabricParams {
        e_along,
        e_across,
        rs,
        rd_warp: [0.7, 0.2, 0.1],
        rd_weft: [0.1, 0.3, 0.8],
        ..Default::default()
    }
    .to_gpu()
}

/// Every hard case of the model page's §5 that a probe can express, named.
pub fn probe_hard_cases() -> Vec<ProbeCase> {
    let mut cases = Vec::new();
    let mut add = |name: String, input: ProbeInput| cases.push(ProbeCase { name, input });
    let exps: [(f32, f32); 9] = [
        (0.0, 0.0),
        (0.1, 0.1),
        (0.0, 1e6),
        (200.0, 10.0),
        (1e4, 1e4),
        (1e6, 1e6),
        (1e6, 1.0),
        (1.0, 1e6),
        (1e4, 0.1),
    ];

    // 1. hn = 1 exactly.
    for &(ea, ec) in &exps {
        for rs in [0.0, 0.04, 1.0] {
            add(
                format!("§5.1 hn=1 e=({ea},{ec}) rs={rs}"),
                base_input(material(ea, ec, rs)),
            );
        }
    }
    // 2. hn slightly above 1 after normalisation; hu² + hv² underflowing.
    for &(ea, ec) in &exps {
        let m = material(ea, ec, 0.04);
        let mut i = base_input(m);
        i.k1 = [0.0, 0.0, 1.000_000_1, 0.0];
        i.k2 = [0.0, 0.0, 1.000_000_1, 0.0];
        add(format!("§5.2 |k|>1 along n e=({ea},{ec})"), i);
        let mut i = base_input(m);
        i.k1 = [3e-4, 0.0, 1.0, 0.0];
        i.k2 = [-3e-4, 1e-4, 1.0, 0.0];
        add(format!("§5.2 hn rounds to 1 e=({ea},{ec})"), i);
        let mut i = base_input(m);
        i.k1 = [1e-23, 1e-23, 1.0, 0.0];
        i.k2 = [1e-23, -1e-23, 1.0, 0.0];
        add(format!("§5.2 hu^2+hv^2 underflows e=({ea},{ec})"), i);
        let mut i = base_input(m);
        i.k1 = [1e-20, 0.0, 1.0, 0.0];
        i.k2 = [1e-20, 0.0, 1.0, 0.0];
        add(format!("§5.2 hu tiny e=({ea},{ec})"), i);
    }
    // 3. Exponents at their limits in a generic configuration near the peak, and the ratios;
    //    NaN, negative and infinite exponents clamped before they reach the GPU.
    let dirs: [([f64; 3], [f64; 3]); 4] = [
        ([0.3, 0.1, 0.95], [-0.3, -0.1, 0.95]),
        ([0.3, 0.1, 0.95], [-0.2999, -0.1002, 0.95]),
        ([0.6, 0.0, 0.8], [-0.58, 0.01, 0.81]),
        ([0.0, 0.7, 0.714], [0.001, -0.7, 0.714]),
    ];
    for &(ea, ec) in &exps {
        for (d, (a, b)) in dirs.iter().enumerate() {
            let mut i = base_input(material(ea, ec, 0.04));
            i.k1 = v4(unit32(*a), 0.0);
            i.k2 = v4(unit32(*b), 0.0);
            add(format!("§5.3 exponents ({ea},{ec}) dir {d}"), i);
        }
    }
    for (name, ea, ec) in [
        ("NaN", f32::NAN, 10.0),
        ("negative", -5.0, 10.0),
        ("infinite", f32::INFINITY, f32::NEG_INFINITY),
    ] {
        let g = FabricParams {
            e_along: ea,
            e_across: ec,
            ..Default::default()
        }
        .to_gpu();
        let mut i = base_input(g);
        i.k1 = v4(unit32([0.3, 0.1, 0.95]), 0.0);
        i.k2 = v4(unit32([-0.29, -0.1, 0.95]), 0.0);
        add(format!("§5.3 {name} exponents clamped at load"), i);
    }
    // 4. Grazing, back-facing, k1 = -k2.
    let m = material(200.0, 10.0, 0.04);
    let grazing: [(&str, [f32; 3], [f32; 3]); 10] = [
        ("n.k1 = 0", [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
        ("n.k2 = 0", [0.0, 0.6, 0.8], [0.0, -1.0, 0.0]),
        ("both 0", [1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]),
        ("n.k1 = 1e-7", [1.0, 0.0, 1e-7], [0.0, 0.0, 1.0]),
        ("both 1e-7, opposite", [1.0, 0.0, 1e-7], [-1.0, 0.0, 1e-7]),
        ("both 1e-7, same", [1.0, 0.0, 1e-7], [1.0, 0.0, 1e-7]),
        ("back-facing k1", [0.0, 0.6, -0.8], [0.0, 0.0, 1.0]),
        ("back-facing k2", [0.0, 0.0, 1.0], [0.6, 0.0, -0.8]),
        ("back-facing both", [0.0, 0.6, -0.8], [0.6, 0.0, -0.8]),
        ("k1 = -k2", [0.6, 0.0, 0.8], [-0.6, 0.0, -0.8]),
    ];
    for (name, a, b) in grazing {
        for coupled in [false, true] {
            let mut g = m;
            g.flags = if coupled {
                crate::fabric::FLAG_COUPLED_DIFFUSE
            } else {
                0
            };
            let mut i = base_input(g);
            i.k1 = [a[0], a[1], a[2], 0.0];
            i.k2 = [b[0], b[1], b[2], 0.0];
            add(format!("§5.4 {name} coupled={coupled}"), i);
        }
    }
    for &(ea, ec) in &[(0.0f32, 0.0f32), (1e6, 1e6)] {
        let mut i = base_input(material(ea, ec, 0.0));
        i.k1 = [1.0, 0.0, 1e-7, 0.0];
        i.k2 = [-1.0, 0.0, 1e-7, 0.0];
        add(format!("§5.4 grazing retro e=({ea},{ec})"), i);
    }
    // 5. Fresnel argument slightly outside [0, 1].
    for rs in [0.0, 0.04] {
        let mut i = base_input(material(200.0, 10.0, rs));
        i.k1 = [0.0, 0.0, 1.000_000_2, 0.0];
        i.k2 = [0.0, 0.0, 1.000_000_2, 0.0];
        add(format!("§5.5 h.k > 1 rs={rs}"), i);
    }
    // 6. Reciprocity: both orders.
    for (d, (a, b)) in dirs.iter().enumerate() {
        for swap in [false, true] {
            let mut i = base_input(material(200.0, 10.0, 0.04));
            let (a, b) = if swap { (b, a) } else { (a, b) };
            i.k1 = v4(unit32(*a), 0.0);
            i.k2 = v4(unit32(*b), 0.0);
            add(format!("§5.6 reciprocity dir {d} swapped={swap}"), i);
        }
    }
    // 7. Swap identity ρs(eu,ev;t,b) = ρs(ev,eu;b,-t): tangent b instead of t; mirrored UVs.
    for (d, (a, b)) in dirs.iter().enumerate() {
        for (frame, t) in [
            ("t", [1.0, 0.0, 0.0, 1.0]),
            ("b", [0.0, 1.0, 0.0, 1.0]),
            ("-t mirrored", [-1.0, 0.0, 0.0, -1.0]),
        ] {
            let mut i = base_input(material(200.0, 10.0, 0.04));
            i.t = t;
            i.k1 = v4(unit32(*a), 0.0);
            i.k2 = v4(unit32(*b), 0.0);
            add(format!("§5.7 swap/mirror frame {frame} dir {d}"), i);
        }
    }
    // 8. Weave: borders, negative and (pre-reduced) huge coordinates, s_g = 0, s_g → s_p/2,
    //    s_p → 0, boxes over many repeats, degenerate boxes. Dyadic values so the borders are
    //    exact in f32 and f64 alike.
    let weave_params =
        |pattern: WeavePattern, repeat: f32, gap: f32, sw: f32, ss: f32| FabricParams {
            pattern,
            repeat,
            gap,
            shadow_width: sw,
            shadow_strength: ss,
            ..Default::default()
        };
    let variants = [
        (
            "plain",
            weave_params(WeavePattern::plain(), 0.5, 0.0625, 0.25, 0.5),
        ),
        (
            "plain s_g=0",
            weave_params(WeavePattern::plain(), 0.5, 0.0, 0.25, 0.5),
        ),
        (
            "plain s_g=s_p/2",
            weave_params(WeavePattern::plain(), 0.5, 0.25, 0.25, 0.5),
        ),
        (
            "plain s_g->s_p/2",
            weave_params(WeavePattern::plain(), 0.5, 0.25 - 0.25 / 1024.0, 0.25, 0.5),
        ),
        (
            "plain s_p=1e-6",
            weave_params(WeavePattern::plain(), 1e-6, 1.25e-7, 0.5, 1.0),
        ),
        (
            "plain shadow 1/1",
            weave_params(WeavePattern::plain(), 0.5, 0.0625, 1.0, 1.0),
        ),
        (
            "twill",
            weave_params(WeavePattern::twill(), 0.5, 0.0625, 0.5, 0.5),
        ),
        (
            "satin",
            weave_params(WeavePattern::satin(), 0.5, 0.125, 0.75, 0.25),
        ),
        (
            "custom 3x2",
            weave_params(
                WeavePattern::from_rows(&["--|", "|-|"]).expect("valid rows"),
                0.5,
                0.03125,
                0.5,
                0.5,
            ),
        ),
    ];
    let huge = weave::reduce_to_repeat(&variants[0].1, 1e7 + 0.0123, -1e7 - 0.0456);
    let points: [(&str, [f32; 2]); 12] = [
        ("cell centre", [0.5, 0.5]),
        ("u border", [1.0, 0.5]),
        ("v border", [0.5, 0.0]),
        ("corner", [0.0, 0.0]),
        ("repeat border", [2.0, 0.75]),
        ("negative", [-0.3, -2.7]),
        ("negative border", [-1.0, 0.25]),
        ("band edge g", [0.0625, 0.5]),
        ("band edge 1-g", [0.5, 0.9375]),
        ("under strip", [0.5, 0.03125]),
        ("reduced huge", huge),
        ("far negative", [-1000.375, -77.625]),
    ];
    let boxes: [(&str, [f32; 4]); 9] = [
        ("texel", [0.25, 0.5, 0.28125, 0.53125]),
        ("whole repeat", [0.0, 0.0, 2.0, 2.0]),
        ("whole pattern 8x8", [0.0, 0.0, 8.0, 8.0]),
        ("many repeats", [-37.3, -12.1, 61.9, 40.7]),
        ("negative", [-3.75, -1.5, -2.5, -0.25]),
        ("tiny", [0.5, 0.5, 0.501, 0.501]),
        ("zero width", [0.5, 0.25, 0.5, 0.75]),
        ("zero area on border", [1.0, 0.5, 1.0, 0.5]),
        ("straddling cells", [0.875, 0.875, 1.125, 1.125]),
    ];
    for (vname, params) in &variants {
        let g = params.to_gpu();
        for (pname, p) in &points {
            let mut i = base_input(g);
            i.k1 = v4(unit32([0.3, 0.1, 0.95]), 0.0);
            i.k2 = v4(unit32([-0.3, -0.05, 0.95]), 0.0);
            i.point = [p[0], p[1], 0.0, 0.0];
            add(format!("§5.8 {vname} point {pname}"), i);
        }
        for (bname, b) in &boxes {
            let mut i = base_input(g);
            i.footprint = *b;
            add(format!("§5.8 {vname} box {bname}"), i);
        }
    }
    // 10 (what the BRDF can see of it): zero and parallel normals and tangents. NaN inputs are
    // left out: Vulkan does not require NaN to compare as IEEE says without float controls, so
    // NaN must be stopped on the CPU (the loader repairs NaN normals; `to_gpu` clamps NaN
    // params); the CPU twins' NaN handling is tested in tests/fabric_reference.rs.
    let degenerate: [(&str, [f32; 4], [f32; 4]); 4] = [
        ("zero normal", [0.0, 0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 1.0]),
        ("zero tangent", [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]),
        (
            "tangent along n",
            [0.0, 0.0, 1.0, 0.0],
            [0.0, 0.0, 2.0, 1.0],
        ),
        ("sign 0", [0.0, 0.0, 1.0, 0.0], [1.0, 0.0, 0.0, 0.0]),
    ];
    for (name, n, t) in degenerate {
        let mut i = base_input(material(200.0, 10.0, 0.04));
        i.n = n;
        i.t = t;
        i.k1 = v4(unit32([0.3, 0.1, 0.95]), 0.0);
        i.k2 = v4(unit32([-0.3, -0.05, 0.95]), 0.0);
        add(format!("§5.10 {name}"), i);
    }
    cases
}

/// Distance of `a ∈ [0, 1)` (local cell coordinate) to the nearest region border of `g`.
fn border_distance(a: f64, g: &GpuFabric) -> f64 {
    let gap = g.gap as f64;
    let d = g.shadow_dist as f64;
    let dive = (d - gap).clamp(0.0, 0.5);
    let q = (gap - d).max(0.0);
    [0.0, 1.0, gap, 1.0 - gap, q, 1.0 - q, dive, 1.0 - dive]
        .iter()
        .map(|b| (a - b).abs())
        .fold(f64::INFINITY, f64::min)
}

/// `count` seeded random inputs: random frames, directions (half of them near the mirror
/// direction, so narrow lobes are seen near their peak), materials (exponents log-uniform in
/// [0.1, 1e6] or 0, random named or custom patterns), coverages, points and boxes. Directions
/// within 1e-3 of the horizon (where f32 cannot decide the side) and points within 1e-4 cell of a
/// region border are drawn again.
pub fn probe_random(seed: u64, count: usize) -> Vec<ProbeCase> {
    use brdf::double::{fabric_frame, fabric_local};
    let mut rng = XorShift::new(seed);
    let mut out = Vec::with_capacity(count);
    while out.len() < count {
        let idx = out.len();
        // Material.
        let exponent = |rng: &mut XorShift| {
            if rng.next_f64() < 0.1 {
                0.0
            } else {
                rng.log_range(0.1, 1e6) as f32
            }
        };
        let pattern = match rng.next_u64() % 4 {
            0 => WeavePattern::plain(),
            1 => WeavePattern::twill(),
            2 => WeavePattern::satin(),
            _ => {
                let cols = 1 + (rng.next_u64() % 8) as usize;
                let rows = 1 + (rng.next_u64() % 8) as usize;
                let bits = rng.next_u64();
                WeavePattern::from_fn(cols, rows, |i, j| bits >> (8 * j + i) & 1 == 1)
            }
        };
        let repeat = rng.log_range(1e-3, 10.0) as f32;
        let params = FabricParams {
            pattern,
            repeat,
            gap: if rng.next_f64() < 0.2 {
                0.0
            } else {
                (rng.range(0.0, 0.5) * repeat as f64) as f32
            },
            e_along: exponent(&mut rng),
            e_across: exponent(&mut rng),
            rd_warp: [
                rng.next_f64() as f32,
                rng.next_f64() as f32,
                rng.next_f64() as f32,
            ],
            rd_weft: [
                rng.next_f64() as f32,
                rng.next_f64() as f32,
                rng.next_f64() as f32,
            ],
            rs: rng.next_f64() as f32,
            shadow_strength: rng.next_f64() as f32,
            shadow_width: rng.next_f64() as f32,
            coupled_diffuse: rng.next_f64() < 0.5,
            // Half the materials are sheets (light through the weave), τ anywhere in [0, 1].
            transmission: {
                let t = rng.next_f64();
                (t < 0.5).then_some((2.0 * t) as f32)
            },
            ..Default::default()
        };
        let fabric = params.to_gpu();
        // Frame and directions.
        let n = unit32(rng.unit());
        let t = unit32(rng.unit());
        let sign: f32 = if rng.next_f64() < 0.5 { -1.0 } else { 1.0 };
        let k1 = unit32(rng.unit());
        let k2 = if rng.next_f64() < 0.5 {
            unit32(rng.unit())
        } else {
            // Mirror of k1 about a half vector tilted from n by about the lobe's width.
            let e = (fabric.e_along.max(fabric.e_across) as f64).max(1.0);
            let tilt = rng.range(0.0, 3.0) / e.sqrt();
            let r = rng.unit();
            let hv = [n[0] + tilt * r[0], n[1] + tilt * r[1], n[2] + tilt * r[2]];
            let l = (hv[0] * hv[0] + hv[1] * hv[1] + hv[2] * hv[2]).sqrt();
            let h = [hv[0] / l, hv[1] / l, hv[2] / l];
            let kh = k1[0] * h[0] + k1[1] * h[1] + k1[2] * h[2];
            unit32([
                2.0 * kh * h[0] - k1[0],
                2.0 * kh * h[1] - k1[1],
                2.0 * kh * h[2] - k1[2],
            ])
        };
        let frame = fabric_frame(n, t, sign as f64);
        let (l1, l2) = (fabric_local(k1, frame), fabric_local(k2, frame));
        if l1[2].abs() < 1e-3 || l2[2].abs() < 1e-3 {
            continue;
        }
        // Point, away from region borders.
        let (cols, rows) = (fabric.cols as f64, fabric.rows as f64);
        let px = rng.range(-20.0, 20.0) as f32;
        let py = rng.range(-20.0, 20.0) as f32;
        let a = weave::double::weave_wrap(px as f64, cols).fract();
        let b = weave::double::weave_wrap(py as f64, rows).fract();
        if border_distance(a, &fabric) < 1e-4 || border_distance(b, &fabric) < 1e-4 {
            continue;
        }
        // Footprint.
        let x0 = rng.range(-10.0, 10.0);
        let y0 = rng.range(-10.0, 10.0);
        let wx = rng.log_range(1e-3, 50.0);
        let wy = rng.log_range(1e-3, 50.0);
        // Coverage given to fabric_brdf: c_warp + c_weft ≤ 1, s_warp ≤ c_warp, s_weft ≤ c_weft.
        let c_warp = rng.next_f64();
        let c_weft = rng.next_f64() * (1.0 - c_warp);
        let s_warp = rng.next_f64() * c_warp;
        let s_weft = rng.next_f64() * c_weft;
        out.push(ProbeCase {
            name: format!("random {idx} (seed {seed})"),
            input: ProbeInput {
                n: v4(n, 0.0),
                t: v4(t, sign),
                k1: v4(k1, 0.0),
                k2: v4(k2, 0.0),
                point: [px, py, 0.0, 0.0],
                footprint: [x0 as f32, y0 as f32, (x0 + wx) as f32, (y0 + wy) as f32],
                coverage: [c_warp as f32, c_weft as f32, s_warp as f32, s_weft as f32],
                tint: [
                    rng.next_f64() as f32,
                    rng.next_f64() as f32,
                    rng.next_f64() as f32,
                    0.0,
                ],
                fabric,
            },
        });
    }
    out
}

/// All hard cases followed by `random` seeded random ones: the probe's standard batch.
pub fn probe_inputs(seed: u64, random: usize) -> Vec<ProbeCase> {
    let mut v = probe_hard_cases();
    v.extend(probe_random(seed, random));
    v
}
