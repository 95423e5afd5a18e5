//! The fabric BRDF: the Ashikhmin–Shirley lobe, Schlick's Fresnel, Lambert and the coupled
//! diffuse, and the two-lobe mixture of the model page (§1, §3).
//!
//! One source, two precisions: the macro below is instantiated as [`single`] (f32, the twin of
//! `glsl/include/fabric.glsl`, line for line and name for name) and [`double`] (f64, the
//! reference the GPU and the f32 path are measured against). The only other copy of these
//! functions is the GLSL one.
//!
//! Vectors are in the local shading frame: `x = k·t`, `y = k·b`, `z = k·n` (see [`single::fabric_frame`]).
//!
//! Numerical choices (model page §5):
//! - `hn^E` is computed by [`single::as_power`] from `s = hu² + hv²` (= 1 - hn², without
//!   cancellation) and `a = eu·hu² + ev·hv²` (= E·s): for `s < 1/4`,
//!   `hn^E = (1 - s)^(E/2) = exp(-a/(2 - s) · P(z²))` with `z = s/(2 - s)` and `P` the atanh series
//!   (`ln(1 - s) = -2·atanh(z)`), so `E` is never formed as 0/0, `hn > 1` after normalisation does
//!   not matter, and the error of the result grows with the exponent's *value* (`a/2`), not with
//!   `E` (which `pow(hn, E)` would: `1e6 · ulp(1)` is 6 %). For `s ≥ 1/4`, `exp(E·ln hn)` with
//!   `E = a/s`, where `ln hn` is well conditioned.
//! - Back-facing or grazing (`n·k1 ≤ 0` or `n·k2 ≤ 0`, or NaN) returns exactly 0.
//! - `h·k1 = h·k2 = |k1 + k2|/2` for unit vectors: computed that way it is exactly symmetric in
//!   `k1, k2` (reciprocity holds bit for bit) and is clamped to [0, 1] as the Fresnel argument.
//! - The lobe's denominator `(h·k)·max(n·k1, n·k2)` is at least `max(n·k)²/2`; it is clamped to
//!   [`single::DENOM_MIN`] = 1e-6, which only acts when both directions are within 0.08° of
//!   grazing, so the lobe stays finite (≤ 4e10 at exponents 1e6) for every input.

#![allow(clippy::neg_cmp_op_on_partial_ord)] // `!(x > 0.0)` is meant: it is true for NaN, as in the GLSL twin.

macro_rules! fabric_brdf_precision {
    ($prec:ident, $t:ident, $doc:literal) => {
        #[doc = $doc]
        pub mod $prec {
            use core::$t::consts::PI;

            /// A direction or a colour.
            pub type Vec3 = [$t; 3];
            /// A weave coverage `(c_warp, c_weft, s_warp, s_weft)` (see `reference::weave`).
            pub type Coverage = [$t; 4];

            /// Smallest value of the lobe's denominator `(h·k)·max(n·k1, n·k2)`: see the module docs.
            pub const DENOM_MIN: $t = 1e-6;

            /// Below this `s = hu² + hv²` (hn > 0.866) [`as_power`] uses the atanh series.
            pub const SERIES_MAX_S: $t = 0.25;

            pub fn dot(a: Vec3, b: Vec3) -> $t {
                a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
            }
            pub fn add(a: Vec3, b: Vec3) -> Vec3 {
                [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
            }
            pub fn sub(a: Vec3, b: Vec3) -> Vec3 {
                [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
            }
            pub fn scale(a: Vec3, s: $t) -> Vec3 {
                [a[0] * s, a[1] * s, a[2] * s]
            }
            pub fn cross(a: Vec3, b: Vec3) -> Vec3 {
                [
                    a[1] * b[2] - a[2] * b[1],
                    a[2] * b[0] - a[0] * b[2],
                    a[0] * b[1] - a[1] * b[0],
                ]
            }
            /// GLSL `inversesqrt`.
            pub fn inversesqrt(x: $t) -> $t {
                1.0 / x.sqrt()
            }

            /// The material as the BRDF sees it (the GPU's `GpuFabric`, less the weave).
            #[derive(Clone, Copy, Debug, PartialEq)]
            pub struct FabricMaterial {
                pub rd_warp: Vec3,
                pub rd_weft: Vec3,
                pub rs: $t,
                pub e_along: $t,
                pub e_across: $t,
                /// A–S eq. 5 instead of Lambert.
                pub coupled: bool,
                /// Thread-by-thread colours (`FLAG_THREAD_COLOURS`): the tint is both threads'
                /// colour (see `fabric_tinted`).
                pub threads: bool,
                /// A single sheet (`FLAG_SHEET`): its threads' diffuse transmittance τ.
                pub sheet: Option<$t>,
            }

            impl FabricMaterial {
                pub fn from_gpu(g: &crate::fabric::GpuFabric) -> Self {
                    let c = |v: [f32; 3]| [v[0] as $t, v[1] as $t, v[2] as $t];
                    FabricMaterial {
                        rd_warp: c(g.rd_warp),
                        rd_weft: c(g.rd_weft),
                        rs: g.rs as $t,
                        e_along: g.e_along as $t,
                        e_across: g.e_across as $t,
                        coupled: g.flags & crate::fabric::FLAG_COUPLED_DIFFUSE != 0,
                        threads: g.flags & crate::fabric::FLAG_THREAD_COLOURS != 0,
                        sheet: (g.flags & crate::fabric::FLAG_SHEET != 0)
                            .then_some(g.transmission as $t),
                    }
                }
            }

            /// Any unit vector perpendicular to unit `n` (Duff et al. 2017, branchless ONB).
            pub fn any_perpendicular(n: Vec3) -> Vec3 {
                let s: $t = if n[2] >= 0.0 { 1.0 } else { -1.0 };
                let a = -1.0 / (s + n[2]);
                let b = n[0] * n[1] * a;
                [1.0 + s * n[0] * n[0] * a, s * b, -s * n[0]]
            }

            /// The shading frame `[t, b, n]` from a normal and a glTF tangent (`t`, handedness
            /// `sign`): `n` normalised, `t` made orthogonal to it, `b = sign·cross(n, t)`. A zero,
            /// NaN or infinite normal becomes +z; a tangent (nearly) parallel to `n`, zero or NaN
            /// becomes an arbitrary perpendicular; a sign that is not negative counts as +1.
            pub fn fabric_frame(n: Vec3, t: Vec3, sign: $t) -> [Vec3; 3] {
                let nn = dot(n, n);
                let n = if nn > 1e-30 && nn < 1e30 {
                    scale(n, inversesqrt(nn))
                } else {
                    [0.0, 0.0, 1.0]
                };
                let tp = sub(t, scale(n, dot(n, t)));
                let tt = dot(tp, tp);
                let t = if tt > 1e-12 && tt < 1e30 {
                    scale(tp, inversesqrt(tt))
                } else {
                    any_perpendicular(n)
                };
                let s: $t = if sign < 0.0 { -1.0 } else { 1.0 };
                let b = scale(cross(n, t), s);
                [t, b, n]
            }

            /// `k` in the local frame: `(k·t, k·b, k·n)`.
            pub fn fabric_local(k: Vec3, frame: [Vec3; 3]) -> Vec3 {
                [dot(k, frame[0]), dot(k, frame[1]), dot(k, frame[2])]
            }

            /// The half vector `h = normalize(k1 + k2)` and `kh = h·k1 = h·k2 = |k1 + k2|/2`,
            /// clamped to [0, 1]. `k1 = -k2` gives `h = n`, `kh = 0`.
            pub fn fabric_half(k1: Vec3, k2: Vec3) -> (Vec3, $t) {
                let hs = add(k1, k2);
                let len2 = dot(hs, hs);
                if !(len2 > 0.0) {
                    return ([0.0, 0.0, 1.0], 0.0);
                }
                let inv_len = inversesqrt(len2);
                let h = scale(hs, inv_len);
                let kh = (0.5 * len2 * inv_len).min(1.0);
                (h, kh)
            }

            /// `E(h) = (eu·hu² + ev·hv²) / (hu² + hv²)`, scaled by `max(|hu|, |hv|)` first so that
            /// it does not underflow; `h = n` exactly (E undefined, `hn^E = 1` for any E) gives the
            /// mean of the exponents, which keeps the swap identity exact.
            pub fn as_exponent(hu: $t, hv: $t, eu: $t, ev: $t) -> $t {
                let m = hu.abs().max(hv.abs());
                if !(m > 0.0) {
                    return 0.5 * (eu + ev);
                }
                let x = hu / m;
                let y = hv / m;
                (eu * x * x + ev * y * y) / (x * x + y * y)
            }

            /// `hn^E(h)` for a unit `h = (hu, hv, hn)`; 0 for `hn ≤ 0`. See the module docs.
            pub fn as_power(hu: $t, hv: $t, hn: $t, eu: $t, ev: $t) -> $t {
                if !(hn > 0.0) {
                    return 0.0;
                }
                let hu2 = hu * hu;
                let hv2 = hv * hv;
                let s = hu2 + hv2;
                let a = eu * hu2 + ev * hv2;
                if s < SERIES_MAX_S {
                    let z = s / (2.0 - s);
                    let z2 = z * z;
                    let p = 1.0
                        + z2 * (1.0 / 3.0
                            + z2 * (1.0 / 5.0
                                + z2 * (1.0 / 7.0
                                    + z2 * (1.0 / 9.0
                                        + z2 * (1.0 / 11.0
                                            + z2 * (1.0 / 13.0
                                                + z2 * (1.0 / 15.0 + z2 * (1.0 / 17.0))))))));
                    (-(a / (2.0 - s)) * p).exp()
                } else {
                    (a / s * hn.ln()).exp()
                }
            }

            /// The microfacet density of the model page, eq. 1: `sqrt((eu+1)(ev+1))/(2π) · hn^E`
            /// (the pdf of `h` per unit solid angle).
            pub fn as_d(h: Vec3, eu: $t, ev: $t) -> $t {
                as_norm(eu, ev) / (2.0 * PI) * as_power(h[0], h[1], h[2], eu, ev)
            }

            /// The A–S normalisation `sqrt((eu+1)(ev+1))`, shared by D and the lobe.
            pub fn as_norm(eu: $t, ev: $t) -> $t {
                ((eu + 1.0) * (ev + 1.0)).sqrt()
            }

            /// The lobe without its `hn^E`: `norm/(8π)·F(kh)/max(kh·max(n·k1, n·k2), min)`.
            pub fn as_lobe_factor(nk1: $t, nk2: $t, kh: $t, eu: $t, ev: $t, rs: $t) -> $t {
                let denom = (kh * nk1.max(nk2)).max(DENOM_MIN);
                as_norm(eu, ev) / (8.0 * PI) * schlick(rs, kh) / denom
            }

            /// Schlick's Fresnel `rs + (1 - rs)(1 - c)^5`, `c` clamped to [0, 1].
            pub fn schlick(rs: $t, c: $t) -> $t {
                let x = 1.0 - c.clamp(0.0, 1.0);
                let x2 = x * x;
                rs + (1.0 - rs) * x2 * x2 * x
            }

            /// The Ashikhmin–Shirley specular lobe ρs with exponent `eu` along `t` and `ev` along
            /// `b`: exactly 0 when either direction is back-facing or grazing.
            pub fn as_lobe(k1: Vec3, k2: Vec3, eu: $t, ev: $t, rs: $t) -> $t {
                let nk1 = k1[2];
                let nk2 = k2[2];
                if !(nk1 > 0.0 && nk2 > 0.0) {
                    return 0.0;
                }
                let (h, kh) = fabric_half(k1, k2);
                as_lobe_factor(nk1, nk2, kh, eu, ev, rs) * as_power(h[0], h[1], h[2], eu, ev)
            }

            /// Lambert's `1/π` (times Rd).
            pub fn lambert() -> $t {
                1.0 / PI
            }

            /// A–S eq. 5 without its Rd: `28/(23π)·(1 - rs)·(1 - (1 - n·k1/2)^5)·(1 - (1 - n·k2/2)^5)`.
            pub fn coupled_diffuse(rs: $t, nk1: $t, nk2: $t) -> $t {
                let a = 1.0 - 0.5 * nk1.clamp(0.0, 1.0);
                let b = 1.0 - 0.5 * nk2.clamp(0.0, 1.0);
                let a2 = a * a;
                let b2 = b * b;
                28.0 / (23.0 * PI) * (1.0 - rs) * ((1.0 - a2 * a2 * a) * (1.0 - b2 * b2 * b))
            }

            /// The material with both threads' colours multiplied by `tint` (the thread
            /// texture's filtered value at the pixel, white without one): `fabric_tinted` of
            /// fabric.glsl. The BRDF is linear in the colours, so this multiplies the texture
            /// over the diffuse term wherever the model uses them. With thread-by-thread colours
            /// the tint (the footprint's thread colour times the texture) is both threads' colour.
            pub fn fabric_tinted(m: &FabricMaterial, tint: Vec3) -> FabricMaterial {
                let mut t = *m;
                if m.threads {
                    t.rd_warp = tint;
                    t.rd_weft = tint;
                    return t;
                }
                t.rd_warp = [
                    m.rd_warp[0] * tint[0],
                    m.rd_warp[1] * tint[1],
                    m.rd_warp[2] * tint[2],
                ];
                t.rd_weft = [
                    m.rd_weft[0] * tint[0],
                    m.rd_weft[1] * tint[1],
                    m.rd_weft[2] * tint[2],
                ];
                t
            }

            /// The diffuse albedo of a coverage: `s_warp·rd_warp + s_weft·rd_weft`, each thread's
            /// albedo times its shadow-weighted area (linear in the coverage).
            pub fn fabric_albedo(coverage: Coverage, m: &FabricMaterial) -> Vec3 {
                [
                    coverage[2] * m.rd_warp[0] + coverage[3] * m.rd_weft[0],
                    coverage[2] * m.rd_warp[1] + coverage[3] * m.rd_weft[1],
                    coverage[2] * m.rd_warp[2] + coverage[3] * m.rd_weft[2],
                ]
            }

            /// The material whose threads reflect what they do not pass through: a sheet's
            /// thread colours times `1 − τ`, any other cloth unchanged (`fabric_reflecting`).
            pub fn fabric_reflecting(m: &FabricMaterial) -> FabricMaterial {
                let keep = match m.sheet {
                    Some(t) => 1.0 - t.clamp(0.0, 1.0),
                    None => 1.0,
                };
                let mut r = *m;
                r.rd_warp = m.rd_warp.map(|x| x * keep);
                r.rd_weft = m.rd_weft.map(|x| x * keep);
                r
            }

            /// The light a sheet's threads pass through, for light from `k1` on the far side
            /// (`n·k1 < 0`) seen from `k2` on the near side: `τ/π` times [`fabric_albedo`]; 0
            /// otherwise and for a cloth that is not a sheet (`fabric_btdf`).
            pub fn fabric_btdf(k1: Vec3, k2: Vec3, coverage: Coverage, m: &FabricMaterial) -> Vec3 {
                if !(k1[2] < 0.0 && k2[2] > 0.0) {
                    return [0.0; 3];
                }
                fabric_passed(coverage, m).map(|x| x / PI)
            }

            /// What a sheet's threads pass to their other side of the diffuse light they receive
            /// there: `τ` times [`fabric_albedo`], 0 for a cloth that is not a sheet
            /// (`fabric_passed`).
            pub fn fabric_passed(coverage: Coverage, m: &FabricMaterial) -> Vec3 {
                let Some(t) = m.sheet else {
                    return [0.0; 3];
                };
                let t = t.clamp(0.0, 1.0);
                fabric_albedo(coverage, m).map(|x| t * x)
            }

            /// A sheet's opacity: `c_warp + c_weft` clamped to [0, 1] (`fabric_thread_cover`).
            pub fn fabric_thread_cover(coverage: Coverage) -> $t {
                (coverage[0] + coverage[1]).clamp(0.0, 1.0)
            }

            /// The fabric model of §3 at one shading point. `coverage = (c_warp, c_weft, s_warp,
            /// s_weft)`: area fractions of warp-on-top and weft-on-top, and the same weighted by
            /// the diffuse shadow factor (at a point `s_warp = s·c_warp`): the diffuse term is
            /// [`fabric_albedo`] times the diffuse lobe, the specular the coverages times each
            /// orientation's lobe.
            pub fn fabric_brdf(k1: Vec3, k2: Vec3, coverage: Coverage, m: &FabricMaterial) -> Vec3 {
                let nk1 = k1[2];
                let nk2 = k2[2];
                if !(nk1 > 0.0 && nk2 > 0.0) {
                    return [0.0; 3];
                }
                let c_warp = coverage[0];
                let c_weft = coverage[1];
                let rho_weft = as_lobe(k1, k2, m.e_along, m.e_across, m.rs);
                let rho_warp = as_lobe(k1, k2, m.e_across, m.e_along, m.rs);
                let diffuse = if m.coupled {
                    coupled_diffuse(m.rs, nk1, nk2)
                } else {
                    lambert()
                };
                let spec = c_weft * rho_weft + c_warp * rho_warp;
                let rd = fabric_albedo(coverage, m);
                [
                    diffuse * rd[0] + spec,
                    diffuse * rd[1] + spec,
                    diffuse * rd[2] + spec,
                ]
            }

            /// The `filtered-params` accuracy level (model page §4): ONE lobe whose exponents are
            /// the coverage-weighted means of the two orientations', times the thread coverage.
            /// Cheap and wrong at a distance (averaging exponents is not averaging lobes); kept so
            /// that its error can be measured. Equal to [`fabric_brdf`] at a point.
            pub fn fabric_brdf_averaged(
                k1: Vec3,
                k2: Vec3,
                coverage: Coverage,
                m: &FabricMaterial,
            ) -> Vec3 {
                let nk1 = k1[2];
                let nk2 = k2[2];
                let c_warp = coverage[0];
                let c_weft = coverage[1];
                let c_thread = c_warp + c_weft;
                if !(nk1 > 0.0 && nk2 > 0.0 && c_thread > 0.0) {
                    return [0.0; 3];
                }
                let t = c_weft / c_thread;
                let eu = t * m.e_along + (1.0 - t) * m.e_across;
                let ev = t * m.e_across + (1.0 - t) * m.e_along;
                let diffuse = if m.coupled {
                    coupled_diffuse(m.rs, nk1, nk2)
                } else {
                    lambert()
                };
                let spec = c_thread * as_lobe(k1, k2, eu, ev, m.rs);
                let rd = fabric_albedo(coverage, m);
                [
                    diffuse * rd[0] + spec,
                    diffuse * rd[1] + spec,
                    diffuse * rd[2] + spec,
                ]
            }

            // ---- The comparison models of `weft compare` (paper figs. 1, 2): the same material
            // without its weave.

            /// Mean diffuse albedo of the two threads.
            pub fn fabric_mean_rd(m: &FabricMaterial) -> Vec3 {
                [
                    0.5 * (m.rd_warp[0] + m.rd_weft[0]),
                    0.5 * (m.rd_warp[1] + m.rd_weft[1]),
                    0.5 * (m.rd_warp[2] + m.rd_weft[2]),
                ]
            }

            /// Exponent of the Phong lobe that stands for the material's A–S lobes: the mean A–S
            /// exponent over 4 (a half-vector lobe with exponent E is about as wide as a
            /// mirror-direction lobe with exponent E/4).
            pub fn fabric_phong_exponent(m: &FabricMaterial) -> $t {
                0.125 * (m.e_along + m.e_across)
            }

            /// The normalised Phong lobe `(e + 2)/(2π)·(r·k2)^e`, `r` = `k1` mirrored about `n`;
            /// exactly 0 when either direction is back-facing or `r·k2 <= 0`.
            pub fn phong_lobe(k1: Vec3, k2: Vec3, e: $t) -> $t {
                if !(k1[2] > 0.0 && k2[2] > 0.0) {
                    return 0.0;
                }
                let rk = k1[2] * k2[2] - k1[0] * k2[0] - k1[1] * k2[1];
                if !(rk > 0.0) {
                    return 0.0;
                }
                (e + 2.0) / (2.0 * PI) * (e * rk.min(1.0).ln()).exp()
            }

            /// The Phong reflection model: Lambert with the mean albedo plus `rs` times the Phong
            /// lobe.
            pub fn phong_brdf(k1: Vec3, k2: Vec3, m: &FabricMaterial) -> Vec3 {
                if !(k1[2] > 0.0 && k2[2] > 0.0) {
                    return [0.0; 3];
                }
                let rd = fabric_mean_rd(m);
                let spec = m.rs * phong_lobe(k1, k2, fabric_phong_exponent(m));
                let d = lambert();
                [rd[0] * d + spec, rd[1] * d + spec, rd[2] * d + spec]
            }

            /// Plain (single-lobe) Ashikhmin–Shirley: the mean albedo with the material's diffuse
            /// term, and one A–S lobe for threads along `t` everywhere (no weave, no gaps, no
            /// thread shadowing).
            pub fn plain_as_brdf(k1: Vec3, k2: Vec3, m: &FabricMaterial) -> Vec3 {
                let nk1 = k1[2];
                let nk2 = k2[2];
                if !(nk1 > 0.0 && nk2 > 0.0) {
                    return [0.0; 3];
                }
                let diffuse = if m.coupled {
                    coupled_diffuse(m.rs, nk1, nk2)
                } else {
                    lambert()
                };
                let rd = fabric_mean_rd(m);
                let spec = as_lobe(k1, k2, m.e_along, m.e_across, m.rs);
                [
                    rd[0] * diffuse + spec,
                    rd[1] * diffuse + spec,
                    rd[2] * diffuse + spec,
                ]
            }
        }
    };
}

fabric_brdf_precision!(
    single,
    f32,
    "The f32 path: the twin of `glsl/include/fabric.glsl`."
);
fabric_brdf_precision!(double, f64, "The f64 reference.");

/// Importance sampling of the A–S lobe (model page §1), in f64, for the furnace tests and the
/// reference integrators.
pub mod sampling {
    use super::double::{as_d, fabric_half, Vec3};
    use std::f64::consts::PI;

    /// A half vector with pdf `as_d(h, eu, ev)` per unit solid angle, from `xi1, xi2 ∈ [0, 1)`.
    /// `φ = atan(sqrt((eu+1)/(ev+1))·tan(πr/2))` in the first quadrant, mirrored to the quadrant
    /// `floor(4·xi1)`; `cos θ = xi2^(1/(eu cos²φ + ev sin²φ + 1))`.
    pub fn sample_h(eu: f64, ev: f64, xi1: f64, xi2: f64) -> Vec3 {
        let q = (4.0 * xi1).floor().clamp(0.0, 3.0);
        let r = 4.0 * xi1 - q;
        let phi0 = (((eu + 1.0) / (ev + 1.0)).sqrt() * (0.5 * PI * r).tan()).atan();
        let phi = match q as u32 {
            0 => phi0,
            1 => PI - phi0,
            2 => PI + phi0,
            _ => 2.0 * PI - phi0,
        };
        let (sp, cp) = phi.sin_cos();
        let cos_t = xi2.powf(1.0 / (eu * cp * cp + ev * sp * sp + 1.0));
        let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
        [sin_t * cp, sin_t * sp, cos_t]
    }

    /// `k2` reflected about a sampled `h`, and its pdf `D(h)/(4 k1·h)`; None when it falls below
    /// the surface (that sample contributes 0).
    pub fn sample_k2(k1: Vec3, eu: f64, ev: f64, xi1: f64, xi2: f64) -> Option<(Vec3, f64)> {
        let h = sample_h(eu, ev, xi1, xi2);
        let kh = super::double::dot(k1, h);
        let k2 = [
            2.0 * kh * h[0] - k1[0],
            2.0 * kh * h[1] - k1[1],
            2.0 * kh * h[2] - k1[2],
        ];
        if !(k2[2] > 0.0 && kh > 0.0) {
            return None;
        }
        Some((k2, as_d(h, eu, ev) / (4.0 * kh)))
    }

    /// The pdf of `k2` given `k1` under [`sample_k2`] (per unit solid angle of `k2`).
    pub fn pdf_k2(k1: Vec3, k2: Vec3, eu: f64, ev: f64) -> f64 {
        let (h, kh) = fabric_half(k1, k2);
        if !(kh > 0.0) {
            return 0.0;
        }
        as_d(h, eu, ev) / (4.0 * kh)
    }
}
