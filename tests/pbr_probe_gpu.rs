//! The glTF BRDF of `glsl/include/pbr.glsl` (core, KHR_materials_specular, _sheen, _anisotropy)
//! against its Rust twin (`weft::reference::shading`), through `glsl/pbr_probe.comp` on a Vulkan
//! device (lavapipe by default, or WEFT_DEVICE) with validation on.
//!
//! The bound of each output is derived per input by first-order error propagation of the Vulkan
//! precision rules (correctly rounded +, −, ×; division 2.5 ulp; inversesqrt 2 ulp; exp, exp2
//! 3 + 2|x| ulp; log2 3 ulp, or 2^-21 absolute in [0.5, 2]; pow inherited from
//! exp2(y·log2 x)) through the formulas' condition numbers: what a unit error of n·h does to GGX
//! (4(1 − α²)n·h²/d, d = n·h²(α² − 1) + 1) and to Charlie (2y·n·h/sin²θ_h, y = 1/(2α)), what the
//! rounding of sin²θ_h = 1 − n·h² does to pow(sin²θ_h, y), and what 1 − v·h does to the Schlick
//! weight (5/(1 − v·h)). Each output's bound is |twin|·R + 1e-9 (the absolute floor covers
//! denormals flushed to zero). The twin is f32 too, so the bound covers both sides' rounding:
//! every contribution is counted twice. The worst ratio |gpu − twin| / bound is printed.

mod common;

use bytemuck::{Pod, Zeroable};
use weft::reference::probe::XorShift;
use weft::reference::shading as sh;
use weft::reference::shading::{
    charlie_d, ggx_aniso_d, gltf_brdf_cos, sheen_brdf_cos, GltfSurface,
};
use weft::vk::shaders;

const U: f64 = f32::EPSILON as f64 * 0.5;

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct PbrProbeInput {
    n: [f32; 4],
    v: [f32; 4],
    l: [f32; 4],
    base_metallic: [f32; 4],
    f0_specular: [f32; 4],
    sheen: [f32; 4],
    t_anisotropy: [f32; 4],
    params: [f32; 4],
    terms_in: [f32; 4],
    /// Transmission: thickness, ior, attenuation distance (0: infinite), backdrop width.
    volume: [f32; 4],
    /// Attenuation colour (rgb), the surface's transmission factor (w).
    attenuation: [f32; 4],
    /// Clearcoat factor, roughness (its normal: n), two unused.
    coat: [f32; 4],
    /// KHR_materials_iridescence: factor, film ior, film thickness (nm); w: the dispersion.
    film: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, Default)]
struct PbrProbeOutput {
    brdf: [f32; 4],
    terms: [f32; 4],
    exit_lod: [f32; 4],
    transmitted: [f32; 4],
    coated: [f32; 4],
    through: [f32; 4],
    film: [f32; 4],
    dispersed: [f32; 4],
    lamp_through: [f32; 4],
}

fn unit(v: [f64; 3]) -> [f32; 3] {
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    [(v[0] / l) as f32, (v[1] / l) as f32, (v[2] / l) as f32]
}

fn v4(v: [f32; 3], w: f32) -> [f32; 4] {
    [v[0], v[1], v[2], w]
}

fn xyz4(a: [f32; 4]) -> [f32; 3] {
    [a[0], a[1], a[2]]
}

fn dot(a: [f32; 3], b: [f32; 3]) -> f64 {
    a[0] as f64 * b[0] as f64 + a[1] as f64 * b[1] as f64 + a[2] as f64 * b[2] as f64
}

/// A direction in the upper hemisphere of +z with the given cosine and azimuth.
fn dir(cos: f64, phi: f64) -> [f32; 3] {
    let s = (1.0 - cos * cos).max(0.0).sqrt();
    unit([s * phi.cos(), s * phi.sin(), cos])
}

fn surface(inp: &PbrProbeInput) -> GltfSurface {
    GltfSurface {
        base: [
            inp.base_metallic[0],
            inp.base_metallic[1],
            inp.base_metallic[2],
        ],
        metallic: inp.base_metallic[3],
        roughness: inp.params[0],
        specular: inp.f0_specular[3],
        f0: [inp.f0_specular[0], inp.f0_specular[1], inp.f0_specular[2]],
        sheen: [inp.sheen[0], inp.sheen[1], inp.sheen[2]],
        sheen_roughness: inp.sheen[3],
        t: [
            inp.t_anisotropy[0],
            inp.t_anisotropy[1],
            inp.t_anisotropy[2],
        ],
        anisotropy: inp.t_anisotropy[3],
        transmission: inp.attenuation[3],
        iridescence: inp.film[0],
        film_ior: inp.film[1],
        film_thickness: inp.film[2],
    }
}

/// The Rust twin of pbr_probe.comp's main().
fn twin(inp: &PbrProbeInput) -> [f32; 36] {
    let s = surface(inp);
    let xyz = |a: [f32; 4]| [a[0], a[1], a[2]];
    let b = gltf_brdf_cos(
        xyz(inp.n),
        xyz(inp.v),
        xyz(inp.l),
        &s,
        [inp.params[1], inp.params[2]],
        inp.params[3],
    );
    let nh = inp.terms_in[0];
    let sr = inp.terms_in[3];
    let th = ((1.0 - nh * nh).max(0.0) * 0.5).sqrt();
    let alpha = (inp.params[0] * inp.params[0]).max(1e-3);
    let at = alpha * 0.5 + 0.5;
    let (thickness, ior, distance, width) =
        (inp.volume[0], inp.volume[1], inp.volume[2], inp.volume[3]);
    let l = xyz(inp.l);
    let through = sh::diffuse_btdf_cos(
        xyz(inp.n),
        xyz(inp.v),
        [-l[0], -l[1], -l[2]],
        &s,
        xyz(inp.attenuation),
    );
    let coated = sh::clearcoat_brdf_cos(
        b,
        xyz(inp.n),
        xyz(inp.v),
        xyz(inp.l),
        inp.coat[0],
        inp.coat[1],
    );
    let dispersed = sh::dispersion_iors(inp.volume[1], inp.film[3]);
    let lamp_through = sh::specular_btdf_cos(
        xyz(inp.n),
        xyz(inp.v),
        [-l[0], -l[1], -l[2]],
        &s,
        inp.volume[1],
    );
    let film = sh::iridescence_fresnel(
        inp.film[1],
        inp.n[0] * inp.v[0] + inp.n[1] * inp.v[1] + inp.n[2] * inp.v[2],
        inp.film[2],
        xyz(inp.f0_specular),
    );
    let exit = sh::transmission_exit(xyz(inp.l), xyz(inp.n), xyz(inp.v), thickness, ior);
    let att = sh::volume_attenuation(thickness, xyz(inp.attenuation), distance);
    let weight = sh::transmission_weight(
        xyz(inp.f0_specular),
        inp.f0_specular[3],
        xyz(inp.base_metallic),
        [inp.params[1], inp.params[2]],
    );
    [
        b[0],
        b[1],
        b[2],
        0.0,
        charlie_d(nh, sr),
        sheen_brdf_cos(inp.terms_in[1], inp.terms_in[2], nh, sr),
        ggx_aniso_d(th, th, nh, at, alpha),
        weft::reference::shading::sheen_lambda(inp.terms_in[2], (sr * sr).max(1e-3)),
        exit[0],
        exit[1],
        exit[2],
        sh::transmission_lod(inp.params[0], ior, width),
        att[0] * weight[0],
        att[1] * weight[1],
        att[2] * weight[2],
        0.0,
        coated[0],
        coated[1],
        coated[2],
        sh::clearcoat_fresnel(inp.n[0] * inp.v[0] + inp.n[1] * inp.v[1] + inp.n[2] * inp.v[2]),
        through[0],
        through[1],
        through[2],
        0.0,
        film[0],
        film[1],
        film[2],
        0.0,
        dispersed[0],
        dispersed[1],
        dispersed[2],
        0.0,
        lamp_through[0],
        lamp_through[1],
        lamp_through[2],
        sh::transmission_alpha(inp.params[0], inp.volume[1]),
    ]
}

/// Absolute bound (rgb) of `specular_btdf_cos(n, v, −l, …)`: the GGX terms of the reflected
/// lobe's bound (`bounds`) at the mirrored light direction and the transmitted alpha, plus
/// what an absolute error of the Schlick weight at v·h does to 1 − specular·F (the factor can
/// cancel), times D·V·|n·l| (f64) and the base colour.
fn lamp_through_bound(inp: &PbrProbeInput, want: &[f32; 36]) -> [f64; 3] {
    let l = xyz4(inp.l);
    let mut m = *inp;
    let (n, v) = (xyz4(inp.n), xyz4(inp.v));
    let nl = dot(n, l);
    // The light from behind, −l, mirrored through the plane: −l + 2(n·l)n.
    m.l = v4(
        unit([
            2.0 * nl * n[0] as f64 - l[0] as f64,
            2.0 * nl * n[1] as f64 - l[1] as f64,
            2.0 * nl * n[2] as f64 - l[2] as f64,
        ]),
        0.0,
    );
    let alpha = want[35] as f64;
    m.params[0] = alpha.sqrt() as f32;
    m.sheen = [0.0; 4];
    m.t_anisotropy[3] = 0.0;
    let rel = bounds(&m)[0];
    let (ml, nv) = (xyz4(m.l), dot(n, v));
    let h = unit([
        ml[0] as f64 + v[0] as f64,
        ml[1] as f64 + v[1] as f64,
        ml[2] as f64 + v[2] as f64,
    ]);
    let (nh, vh) = (dot(n, h).clamp(0.0, 1.0), dot(v, h).clamp(0.0, 1.0));
    let a2 = alpha * alpha;
    let dd = nh * nh * (a2 - 1.0) + 1.0;
    let d = a2 / (std::f64::consts::PI * dd * dd);
    let vis =
        0.5 / (nl * (nv * nv * (1.0 - a2) + a2).sqrt() + nv * (nl * nl * (1.0 - a2) + a2).sqrt());
    let dv_cos = d * vis * nl;
    let schlick =
        5.0 * (1.0 - vh).powi(4) * 6.0 * U + (1.0 - vh).powi(5) * pow_rel(1.0 - vh + 1e-30, 5.0, U);
    let spec = inp.f0_specular[3].abs() as f64;
    [0, 1, 2].map(|k| {
        let base = inp.base_metallic[k].abs() as f64;
        2.0 * (want[32 + k].abs() as f64 * rel + base * dv_cos * (spec * schlick + 8.0 * U))
    })
}

/// Absolute bounds of the transmission outputs (indices 8–14 of the twin), under the Vulkan
/// precision rules: refract, normalize and the scaled sum inherit a few ulp per operation (64 ulp
/// of |p| + thickness covers the dozen of them with a factor 2 to spare); log2 is 2^-21 absolute
/// in [0.5, 2] and 3 ulp elsewhere; pow is exp2(y·log2 x) (`pow_rel`); 1 − specular·(F0·A + B)
/// carries the absolute error of the product and sum (4 ulp of the larger term), times the base.
fn transmission_bounds(inp: &PbrProbeInput, want: &[f32; 36]) -> [f64; 7] {
    let p = inp.l;
    let thickness = inp.volume[0] as f64;
    let ior = inp.volume[1] as f64;
    let width = (inp.volume[3] as f64).max(1.0);
    let scale = (p[0].abs() + p[1].abs() + p[2].abs()) as f64 + thickness;
    let e_exit = 64.0 * U * scale;
    let c = (2.0 * ior - 2.0).clamp(0.0, 1.0);
    let r = inp.params[0] as f64;
    let log_err = if width <= 2.0 {
        2f64.powi(-21)
    } else {
        3.0 * U * width.log2()
    };
    let e_lod = (log_err + 8.0 * U * width.log2()) * r * c;
    let distance = inp.volume[2] as f64;
    let mut out = [e_exit, e_exit, e_exit, e_lod, 0.0, 0.0, 0.0];
    for k in 0..3 {
        let colour = inp.attenuation[k] as f64;
        let rel_att = if distance > 0.0 && colour > 0.0 {
            pow_rel(colour, thickness / distance, U) + 4.0 * U
        } else if distance > 0.0 {
            0.0
        } else {
            0.0
        };
        let x = inp.f0_specular[3] as f64
            * (inp.f0_specular[k] as f64 * inp.params[1] as f64 + inp.params[2] as f64);
        let base = inp.base_metallic[k] as f64;
        let att = want[12 + k].abs() as f64 / ((1.0 - x).max(0.0) * base).max(1e-30);
        out[4 + k] = 2.0
            * (base * (4.0 * U * x.max(1.0)) * att
                + want[12 + k].abs() as f64 * (rel_att + 4.0 * U));
    }
    out
}

/// Relative error bound of pow(x, y) evaluated as exp2(y·log2 x) with x carrying a relative
/// error `rx` of its own.
fn pow_rel(x: f64, y: f64, rx: f64) -> f64 {
    let lg = x.log2();
    let e_log = if (0.5..=2.0).contains(&x) {
        2f64.powi(-21)
    } else {
        3.0 * U * lg.abs()
    };
    let t = y * lg;
    std::f64::consts::LN_2 * (y.abs() * e_log + (3.0 + 2.0 * t.abs()) * U) + y.abs() * rx
}

/// Relative bound of Charlie's D at (n·h, roughness) with n·h off by `dnh` (absolute).
fn charlie_rel(nh: f64, r: f64, dnh: f64) -> f64 {
    let alpha = (r * r).max(1e-3);
    let y = 0.5 / alpha;
    let sin2 = (1.0 - nh * nh).max(1e-30);
    // sin² = 1 − n·h²: the square rounds (u·n·h²), the subtraction is exact near 1 (Sterbenz).
    let rx = (U * nh * nh + 2.0 * nh * dnh) / sin2;
    pow_rel(sin2, y, rx) + 8.0 * U
}

/// Relative bound of the Charlie Λ fit and of 1 + Λ_v + Λ_l.
fn lambda_rel(c: f64, alpha: f64) -> f64 {
    // l(x) ≈ 25 at most; its absolute error is a few ulp of its terms; exp(l) gets (3 + 2|l|) ulp
    // plus the absolute error of l; pow(x, c) with c ≈ 0.2 is well conditioned.
    let l_abs = 30.0 * 8.0 * U + 25.0 * pow_rel(c.max(1e-30), 0.2, U);
    let _ = alpha;
    (3.0 + 2.0 * 25.0) * U + l_abs * 2.0
}

fn bounds(inp: &PbrProbeInput) -> [f64; 8] {
    let xyz = |a: [f32; 4]| [a[0], a[1], a[2]];
    let (n, v, l) = (xyz(inp.n), xyz(inp.v), xyz(inp.l));
    let h = unit([
        l[0] as f64 + v[0] as f64,
        l[1] as f64 + v[1] as f64,
        l[2] as f64 + v[2] as f64,
    ]);
    let nh = dot(n, h).clamp(0.0, 1.0);
    let vh = dot(v, h).clamp(0.0, 1.0);
    // n·h and v·h through normalize (inversesqrt 2 ulp, the sum and the dot products).
    let dnh = 6.0 * U;
    let r = inp.params[0] as f64;
    let alpha = (r * r).max(1e-3);
    let a2 = alpha * alpha;
    let d = nh * nh * (a2 - 1.0) + 1.0;
    let ggx = 4.0 * (1.0 - a2) * nh * nh / d * dnh + 4.0 * U * (nh * nh / d);
    let aniso = if inp.t_anisotropy[3] > 0.0 {
        // Anisotropic D: the same sensitivity with the smaller alpha, plus t·h and b·h.
        ggx * 2.0 + 8.0 * dnh / alpha
    } else {
        0.0
    };
    let schlick = 5.0 * dnh / (1.0 - vh).max(1e-30) * (1.0 - vh).powi(5);
    let sr = inp.sheen[3] as f64;
    let sheen = if inp.sheen[..3].iter().any(|&c| c > 0.0) {
        charlie_rel(nh, sr, dnh)
            + lambda_rel(0.5, sr)
            + 2.0 * 2.0 * nh * dnh / (1.0 - nh * nh).max(1e-30) / (2.0 * sr * sr).max(2e-3)
    } else {
        0.0
    };
    // 64 ulp for the products and sums, 8 more for the energy compensation (a division, a
    // product and a sum per lobe).
    let r_brdf = 2.0 * (72.0 * U + ggx + aniso + schlick + sheen);
    let tnh = inp.terms_in[0] as f64;
    let tsr = inp.terms_in[3] as f64;
    let r_charlie = 2.0 * charlie_rel(tnh, tsr, 0.0);
    let r_sheen = r_charlie
        + 2.0
            * (lambda_rel(inp.terms_in[1] as f64, tsr)
                + lambda_rel(inp.terms_in[2] as f64, tsr)
                + 8.0 * U);
    // ggx_aniso_d at t·h = b·h = sqrt(sin²/2): sin² from n·h rounds as above.
    let talpha = alpha;
    let at = talpha * 0.5 + 0.5;
    let f2 = (at * at + talpha * talpha) * (1.0 - tnh * tnh) * 0.5 + (at * talpha * tnh).powi(2);
    let r_ad = 2.0
        * (24.0 * U
            + 2.0 * U * (at * talpha * tnh).powi(2) / f2 * 4.0
            + 2.0 * U / (1.0 - tnh * tnh).max(1e-30));
    let r_lambda = 2.0 * lambda_rel(inp.terms_in[2] as f64, tsr);
    [
        r_brdf, r_brdf, r_brdf, 0.0, r_charlie, r_sheen, r_ad, r_lambda,
    ]
}

struct Case {
    name: String,
    input: PbrProbeInput,
}

fn case(
    name: String,
    n: [f32; 3],
    v: [f32; 3],
    l: [f32; 3],
    s: &GltfSurface,
    e: [f32; 2],
    terms: [f32; 4],
    volume: [f32; 4],
    attenuation: [f32; 3],
    coat: [f32; 4],
) -> Case {
    // No film unless the surface has one (its thickness in film[2]).
    Case {
        name,
        input: PbrProbeInput {
            n: v4(n, 0.0),
            v: v4(v, 0.0),
            l: v4(l, 0.0),
            base_metallic: v4(s.base, s.metallic),
            f0_specular: v4(s.f0, s.specular),
            sheen: v4(s.sheen, s.sheen_roughness),
            t_anisotropy: v4(s.t, s.anisotropy),
            // Ess at n·v (n = +z) for the energy compensation, as the lighting pass reads it.
            params: [
                s.roughness,
                e[0],
                e[1],
                weft::reference::shading::ggx_albedo_lookup(v[2], s.roughness),
            ],
            terms_in: terms,
            volume,
            attenuation: v4(attenuation, s.transmission),
            coat,
            film: [s.iridescence, s.film_ior, s.film_thickness, 0.0],
        },
    }
}

fn cases() -> Vec<Case> {
    let n = [0.0, 0.0, 1.0];
    let mut out = Vec::new();
    let mut rng = XorShift::new(0x5eed_bdf5);
    let roughnesses = [0.0f32, 0.02, 0.1, 0.3, 0.6, 1.0];
    let sheen_r = [0.0f32, 0.05, 0.3, 0.7, 1.0];
    let cosines = [1e-4f64, 0.01, 0.2, 0.5, 0.9, 1.0];
    // Hard cases: grazing view or light, the mirror direction (n·h = 1), retro-reflection.
    for &r in &roughnesses {
        for &sr in &sheen_r {
            for &cv in &cosines {
                for &cl in &cosines {
                    for (azimuth, tag) in [
                        (std::f64::consts::PI, "mirror"),
                        (0.0, "retro"),
                        (1.3, "side"),
                    ] {
                        let v = dir(cv, 0.0);
                        let l = dir(cl, azimuth);
                        let s = GltfSurface {
                            base: [0.8, 0.4, 0.1],
                            metallic: 0.3,
                            roughness: r,
                            specular: 0.7,
                            f0: [0.04, 0.2, 1.0],
                            sheen: [1.0, 0.5, 0.0],
                            sheen_roughness: sr,
                            t: unit([1.0, 0.0, 0.0]),
                            anisotropy: if tag == "side" { 0.8 } else { 0.0 },
                            transmission: if tag == "retro" { 0.6 } else { 0.0 },
                            ..GltfSurface::core([0.0; 3], 0.0, 0.0)
                        };
                        let e = [0.3, 0.6];
                        let h = unit([
                            (v[0] + l[0]) as f64,
                            (v[1] + l[1]) as f64,
                            (v[2] + l[2]) as f64,
                        ]);
                        let nh = dot(n, h) as f32;
                        out.push(case(
                            format!("{tag} r={r} sheen_r={sr} n·v={cv} n·l={cl}"),
                            n,
                            v,
                            l,
                            &s,
                            e,
                            [nh.clamp(0.0, 1.0), cl as f32, cv as f32, sr],
                            [0.3, 1.0 + r, if sr > 0.5 { 0.0 } else { 0.5 }, 1024.0],
                            [0.8, 0.5, 0.1],
                            // The coat at the base's roughness (so the bound's GGX terms
                            // cover it), on the mirror and side cases.
                            [if tag == "retro" { 0.0 } else { 0.7 }, r, 0.0, 0.0],
                        ));
                    }
                }
            }
        }
    }
    // Seeded random surfaces and directions.
    for i in 0..3000 {
        let mut u = || rng.next_f64();
        let v = dir(u().max(1e-4), u() * 6.283);
        let l = dir(u().max(1e-4), u() * 6.283);
        let phi = u() * 6.283;
        let s = GltfSurface {
            base: [u() as f32, u() as f32, u() as f32],
            metallic: if i % 3 == 0 { 0.0 } else { u() as f32 },
            roughness: u() as f32,
            specular: u() as f32,
            f0: [u() as f32, u() as f32, u() as f32],
            sheen: if i % 2 == 0 {
                [0.0; 3]
            } else {
                [u() as f32, u() as f32, u() as f32]
            },
            sheen_roughness: u() as f32,
            t: unit([phi.cos(), phi.sin(), 0.0]),
            anisotropy: if i % 4 == 0 { u() as f32 } else { 0.0 },
            transmission: if i % 5 == 0 { u() as f32 } else { 0.0 },
            ..GltfSurface::core([0.0; 3], 0.0, 0.0)
        };
        let e = [u() as f32 * 0.8, u() as f32 * 0.8];
        let nh = u() as f32;
        let terms = [nh, u().max(1e-4) as f32, u().max(1e-4) as f32, u() as f32];
        // Transmission: thin walls (0) and volumes, ior 1 (no refraction, no blur) to 2.5,
        // infinite (0) and finite attenuation distances, backdrops from 1 to 1920 texels wide.
        let volume = [
            if i % 6 == 0 { 0.0 } else { (u() * 2.0) as f32 },
            if i % 7 == 0 {
                1.0
            } else {
                (1.0 + u() * 1.5) as f32
            },
            if i % 3 == 0 {
                0.0
            } else {
                (u() * 2.0 + 0.01) as f32
            },
            [1.0f32, 2.0, 64.0, 1920.0][i % 4],
        ];
        let attenuation = [u() as f32, u() as f32, u() as f32];
        out.push(case(
            format!("random {i}"),
            n,
            v,
            l,
            &s,
            e,
            terms,
            volume,
            attenuation,
            [
                if i % 2 == 0 { u() as f32 } else { 0.0 },
                s.roughness,
                0.0,
                0.0,
            ],
        ));
    }
    // KHR_materials_iridescence: films from none to 1.5 µm, of index 1 (no film) to 2.5, over
    // dielectric and metal bases, weighted 0 to 1; isotropic and without sheen, so the BRDF's
    // bound is the base's plus what the film's own bound does through the lobes (film_bound).
    for i in 0..1500 {
        let mut u = || rng.next_f64();
        let v = dir(u().max(1e-4), u() * 6.283);
        let l = dir(u().max(1e-4), u() * 6.283);
        let s = GltfSurface {
            base: [u() as f32, u() as f32, u() as f32],
            metallic: if i % 2 == 0 { 0.0 } else { u() as f32 },
            roughness: u() as f32,
            specular: u() as f32,
            f0: [(u() * 0.3) as f32, (u() * 0.3) as f32, (u() * 0.3) as f32],
            iridescence: if i % 7 == 0 { 1.0 } else { u() as f32 },
            film_ior: if i % 13 == 0 {
                1.0
            } else {
                (1.0 + u() * 1.5) as f32
            },
            film_thickness: if i % 11 == 0 {
                0.0
            } else {
                (u() * 1500.0) as f32
            },
            ..GltfSurface::core([0.0; 3], 0.0, 0.0)
        };
        out.push(case(
            format!("film {i}"),
            n,
            v,
            l,
            &s,
            [0.0, 0.0],
            [0.5, 0.5, 0.5, 0.5],
            [0.0, 1.0, 0.0, 1.0],
            [1.0; 3],
            [0.0; 4],
        ));
    }
    // KHR_materials_dispersion on every case: 0 (none) to 20 (the loader's limit).
    for (k, c) in out.iter_mut().enumerate() {
        c.input.film[3] = [0.0f32, 0.5, 2.0, 6.7, 20.0][k % 5];
    }
    out
}

/// Absolute bound (rgb) of `iridescence_fresnel(film_ior, cos1, thickness, f0)` under the Vulkan
/// precision rules. Its colour is a sum of cosines of the optical path: cos has an absolute error
/// of 2^-11 (the rule for [−π, π]; lavapipe's range reduction keeps it beyond), and its argument
/// carries 8 ulp of itself. Each order m adds 2|Cm| times the sensitivity's error: the Gaussian
/// amplitudes of the XYZ fits times the rows of the XYZ to Rec. 709 matrix (absolute). n·v (a dot
/// product, 4 ulp) moves the optical path by 2d·cos1/(η·cos2) of it. The rest (Schlick, the Airy
/// coefficients) is a few dozen correctly rounded operations on numbers at most 1: 64 ulp of the
/// sum of the terms' magnitudes. Counted twice, as the twin is f32 too.
fn film_bound(film_ior: f64, cos1: f64, thickness: f64, f0: [f64; 3]) -> [f64; 3] {
    const M: [[f64; 3]; 3] = [
        [3.2404542, 1.5371385, 0.4985314],
        [0.9692660, 1.8760108, 0.0415560],
        [0.0556434, 0.2040259, 1.0572252],
    ];
    let val = [5.4856e-13, 4.4201e-13, 5.2481e-13];
    let pos = [1.6810e+06, 1.7953e+06, 2.2084e+06];
    let var = [4.3278e+09, 9.3046e+09, 6.6121e+09];
    let tau = std::f64::consts::TAU;
    let t = (thickness / 0.03).clamp(0.0, 1.0);
    let eta = 1.0 + (film_ior - 1.0) * t * t * (3.0 - 2.0 * t);
    let c1 = cos1.clamp(0.0, 1.0);
    let cos2_sq = 1.0 - (1.0 - c1 * c1) / (eta * eta);
    if cos2_sq < 0.0 {
        return [0.0; 3];
    }
    let cos2 = cos2_sq.sqrt().max(1e-6);
    let opd = 2.0 * eta * thickness * cos2;
    let d_opd = 2.0 * thickness * c1 / (eta * cos2) * 4.0 * U + opd * 8.0 * U;
    let f0_12 = ((eta - 1.0) / (eta + 1.0)).powi(2);
    let r12 = f0_12 + (1.0 - f0_12) * (1.0 - c1).powi(5);
    let t121 = 1.0 - r12;
    let mut out = [0.0; 3];
    for (k, o) in out.iter_mut().enumerate() {
        let sq = f0[k].clamp(0.0, 0.9999).sqrt();
        let base_ior = (1.0 + sq) / (1.0 - sq);
        let r0 = (base_ior - eta) / (base_ior + eta);
        let r23 = r0 * r0 + (1.0 - r0 * r0) * (1.0 - cos2).powi(5);
        let r123 = (r12 * r23).clamp(1e-5, 0.9999);
        let rs = t121 * t121 * r23 / (1.0 - r123);
        let mut cm = rs - t121;
        let mut err = 0.0;
        let mut magnitude = r12 + rs;
        for m in 1..=2 {
            cm *= r123.sqrt();
            let phase = tau * m as f64 * opd * 1e-9;
            let mut s_err = 0.0;
            let mut s_max = 0.0;
            for j in 0..3 {
                let amp =
                    val[j] * (tau * var[j]).sqrt() * (-phase * phase * var[j]).exp() / 1.0685e-7;
                let arg = pos[j] * phase + tau;
                let slope = pos[j] * tau * m as f64 * 1e-9 * d_opd;
                s_err += M[k][j] * amp * (2f64.powi(-11) + arg * 8.0 * U + slope);
                s_max += M[k][j] * amp;
            }
            let amp_x =
                9.7470e-14 * (tau * 4.5282e+09f64).sqrt() * (-phase * phase * 4.5282e+09).exp()
                    / 1.0685e-7;
            let arg_x = 2.2399e+06 * phase + tau;
            s_err += M[k][0]
                * amp_x
                * (2f64.powi(-11) + arg_x * 8.0 * U + 2.2399e+06 * tau * m as f64 * 1e-9 * d_opd);
            s_max += M[k][0] * amp_x;
            err += 2.0 * cm.abs() * s_err;
            magnitude += 2.0 * cm.abs() * s_max;
        }
        *o = 2.0 * (err + 64.0 * U * magnitude);
    }
    out
}

/// What a film's error (film_bound of the dielectric's F0 and of the metal's base colour) does
/// to gltf_brdf_cos: the Fresnel multiplies the GGX lobe (D·V times its energy compensation),
/// and its maximum the diffuse's 1 − specular·max F; the film's weight mixes them in.
fn film_brdf_bound(inp: &PbrProbeInput) -> [f64; 3] {
    if inp.film[0] <= 0.0 {
        return [0.0; 3];
    }
    let f = |a: [f32; 4]| [a[0] as f64, a[1] as f64, a[2] as f64];
    let (n, v, l) = (xyz4(inp.n), xyz4(inp.v), xyz4(inp.l));
    let (nl, nv) = (dot(n, l), dot(n, v));
    if nl <= 0.0 || nv <= 0.0 {
        return [0.0; 3];
    }
    let h = unit([
        l[0] as f64 + v[0] as f64,
        l[1] as f64 + v[1] as f64,
        l[2] as f64 + v[2] as f64,
    ]);
    let nh = dot(n, h).clamp(0.0, 1.0);
    let vh = dot(v, h).clamp(0.0, 1.0);
    let r = inp.params[0] as f64;
    let alpha = (r * r).max(1e-3);
    let a2 = alpha * alpha;
    let dd = nh * nh * (a2 - 1.0) + 1.0;
    let d = a2 / (std::f64::consts::PI * dd * dd);
    let vis =
        0.5 / (nl * (nv * nv * (1.0 - a2) + a2).sqrt() + nv * (nl * nl * (1.0 - a2) + a2).sqrt());
    let ess = (inp.params[3] as f64).max(1e-2);
    let (film, ior, thick) = (inp.film[0] as f64, inp.film[1] as f64, inp.film[2] as f64);
    let f0 = f(inp.f0_specular);
    let base = f(inp.base_metallic);
    let e_d = film_bound(ior, vh, thick, f0);
    let e_m = film_bound(ior, vh, thick, base);
    let max_d = e_d[0].max(e_d[1]).max(e_d[2]);
    let metallic = inp.base_metallic[3] as f64;
    let spec = inp.f0_specular[3] as f64;
    let mut out = [0.0; 3];
    for k in 0..3 {
        let comp_d = 1.0 + f0[k] * (1.0 / ess - 1.0);
        let comp_m = 1.0 + base[k] * (1.0 / ess - 1.0);
        let dielectric =
            spec * d * vis * comp_d * e_d[k] + spec * base[k] / std::f64::consts::PI * max_d;
        let metal = d * vis * comp_m * e_m[k];
        out[k] = 1.5 * film * nl * ((1.0 - metallic) * dielectric + metallic * metal);
    }
    out
}

#[test]
fn pbr_probe_matches_the_twin_within_the_derived_bounds() {
    let ctx = common::context();
    let cases = cases();
    let inputs: Vec<PbrProbeInput> = cases.iter().map(|c| c.input).collect();
    let size = std::mem::size_of::<PbrProbeOutput>();
    let bytes = common::run_probe_shader(&ctx, &shaders::PBR_PROBE_COMP, &inputs, size);
    let names = [
        "brdf.r",
        "brdf.g",
        "brdf.b",
        "-",
        "charlie_d",
        "sheen_brdf_cos",
        "ggx_aniso_d",
        "sheen_lambda",
        "exit.x",
        "exit.y",
        "exit.z",
        "transmission_lod",
        "transmitted.r",
        "transmitted.g",
        "transmitted.b",
        "-",
        "coated.r",
        "coated.g",
        "coated.b",
        "clearcoat_fresnel",
        "through.r",
        "through.g",
        "through.b",
        "-",
        "film.r",
        "film.g",
        "film.b",
        "-",
        "dispersed.r",
        "dispersed.g",
        "dispersed.b",
        "-",
        "lamp_through.r",
        "lamp_through.g",
        "lamp_through.b",
        "trans_alpha",
    ];
    let mut worst: [(f64, String); 36] = std::array::from_fn(|_| (0.0, String::new()));
    let mut failures = Vec::new();
    for (k, c) in cases.iter().enumerate() {
        let g: PbrProbeOutput = bytemuck::pod_read_unaligned(&bytes[k * size..(k + 1) * size]);
        let got = [
            g.brdf,
            g.terms,
            g.exit_lod,
            g.transmitted,
            g.coated,
            g.through,
            g.film,
            g.dispersed,
            g.lamp_through,
        ]
        .concat();
        let want = twin(&c.input);
        let rel = bounds(&c.input);
        let abs = transmission_bounds(&c.input, &want);
        let film_abs = film_brdf_bound(&c.input);
        let lamp_abs = lamp_through_bound(&c.input, &want);
        let i = &c.input;
        let film_out = film_bound(
            i.film[1] as f64,
            dot(xyz4(i.n), xyz4(i.v)),
            i.film[2] as f64,
            [
                i.f0_specular[0] as f64,
                i.f0_specular[1] as f64,
                i.f0_specular[2] as f64,
            ],
        );
        for j in 0..36 {
            if j == 3 || j == 15 || j == 23 || j == 27 || j == 31 {
                continue;
            }
            let (x, t) = (got[j] as f64, want[j] as f64);
            assert!(x.is_finite(), "{}: {} is {x} on the GPU", c.name, names[j]);
            assert!(t.is_finite(), "{}: {} is {t} in the twin", c.name, names[j]);
            let bound = if j == 35 {
                // roughness² × clamp(2·ior − 2, 0, 1): four correctly rounded operations.
                8.0 * U * t.abs() + 1e-9
            } else if j >= 32 {
                lamp_abs[j - 32] + 1e-9
            } else if j < 3 {
                t.abs() * rel[j] + film_abs[j] + 1e-9
            } else if j >= 28 {
                // ior ∓ (ior − 1)·0.025·dispersion: three products and two sums, correctly
                // rounded, of terms at most |ior|: 8 ulp of it, both sides.
                8.0 * U * (c.input.volume[1].abs() as f64 + 1.0) + 1e-9
            } else if j >= 24 {
                film_out[j - 24] + 1e-9
            } else if j < 8 {
                t.abs() * rel[j] + 1e-9
            } else if j < 16 {
                abs[j - 8] + 1e-9
            } else if j < 19 {
                // The coated BRDF: the base's relative bound (the coat shares its roughness, so
                // its GGX terms are bounded alike) on each of its two parts, twice for the
                // mix and the coat's Fresnel at v·h.
                let base = want[j - 16].abs() as f64;
                2.0 * rel[0] * (base + t.abs()) + 1e-9
            } else if j >= 20 {
                // The Lambertian BTDF: n·l and n·v (dot products, 4 ulp absolute each), Schlick
                // at n·v (as below) under 1 − specular·max F, the products (8 ulp).
                let cv = dot(xyz4(c.input.n), xyz4(c.input.v)).clamp(0.0, 1.0);
                let fresnel = 5.0 * (1.0 - cv).powi(4) * 4.0 * U
                    + (1.0 - cv).powi(5) * pow_rel(1.0 - cv + 1e-30, 5.0, U);
                let nl = dot(xyz4(c.input.n), xyz4(c.input.l)).abs();
                let colour = c.input.attenuation[j - 20].abs() as f64;
                t.abs() * 16.0 * U
                    + colour / std::f64::consts::PI
                        * (4.0 * U + nl * fresnel * c.input.f0_specular[3].abs() as f64)
                    + 1e-9
            } else {
                // Schlick: 5 (1 − c)^4 times the absolute error of c (a dot product, 4 ulp), and
                // pow's own.
                let c = dot(xyz4(c.input.n), xyz4(c.input.v)).clamp(0.0, 1.0);
                0.96 * (5.0 * (1.0 - c).powi(4) * 4.0 * U
                    + (1.0 - c).powi(5) * pow_rel(1.0 - c + 1e-30, 5.0, U))
                    + 8.0 * U
            };
            let ratio = (x - t).abs() / bound;
            if ratio > worst[j].0 {
                worst[j] = (ratio, c.name.clone());
            }
            if ratio > 1.0 {
                failures.push(format!(
                    "{}: {} GPU {x:e} twin {t:e} (bound {bound:e}, ratio {ratio:.2})",
                    c.name, names[j]
                ));
            }
        }
    }
    for j in 0..36 {
        if j != 3 && j != 15 && j != 23 && j != 27 && j != 31 {
            println!(
                "{:>15}: worst {:.3} of its bound ({})",
                names[j], worst[j].0, worst[j].1
            );
        }
    }
    ctx.check_validation().unwrap();
    assert!(
        failures.is_empty(),
        "{} of {} outputs outside their bound, e.g.:\n{}",
        failures.len(),
        cases.len() * 31,
        failures
            .iter()
            .take(20)
            .cloned()
            .collect::<Vec<_>>()
            .join("\n")
    );
}

/// The sheen's directional albedo (the DFG table's third channel) against an independent
/// estimate: Monte Carlo over the hemisphere in f64 of the same BRDF (uniform directions,
/// 200,000 samples per point), within 4 standard errors plus the quadrature's own 1e-3.
#[test]
fn sheen_albedo_table_matches_monte_carlo() {
    let mut rng = XorShift::new(7);
    for &(cv, r) in &[
        (0.05f64, 0.3f32),
        (0.5, 0.3),
        (1.0, 0.3),
        (0.2, 1.0),
        (0.8, 0.7),
        (0.3, 0.1),
    ] {
        let q = weft::reference::shading::sheen_albedo(cv, r, 24);
        let v = [(1.0 - cv * cv).sqrt(), 0.0, cv];
        let n = 200_000;
        let (mut sum, mut sum2) = (0.0, 0.0);
        for _ in 0..n {
            let z = rng.next_f64();
            let phi = rng.next_f64() * std::f64::consts::TAU;
            let s = (1.0 - z * z).max(0.0).sqrt();
            let l = [s * phi.cos(), s * phi.sin(), z];
            let h = [v[0] + l[0], v[1] + l[1], v[2] + l[2]];
            let hn = h[2] / (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
            let f =
                sheen_brdf_cos(z as f32, cv as f32, hn as f32, r) as f64 * std::f64::consts::TAU;
            sum += f;
            sum2 += f * f;
        }
        let mean = sum / n as f64;
        let se = ((sum2 / n as f64 - mean * mean) / n as f64).sqrt();
        println!("E(n·v={cv}, r={r}): quadrature {q:.5}, Monte Carlo {mean:.5} ± {se:.5}");
        assert!(
            (q - mean).abs() <= 4.0 * se + 1e-3,
            "E(n·v={cv}, r={r}): quadrature {q} against Monte Carlo {mean} ± {se}"
        );
    }
}

/// Energy: with the albedo scaling, a white sheen over a white diffuse base reflects at most
/// what comes in (the specification's reason for the scaling), and without it more: checked by
/// f64 quadrature of the twin over the hemisphere.
#[test]
fn sheen_albedo_scaling_conserves_energy() {
    let n = [0.0f32, 0.0, 1.0];
    for &(cv, sr) in &[(0.1f64, 0.5f32), (0.5, 1.0), (0.9, 0.3), (0.3, 1.0)] {
        let v = dir(cv, 0.0);
        let s = GltfSurface {
            base: [1.0; 3],
            metallic: 0.0,
            roughness: 1.0,
            specular: 0.0,
            f0: [0.0; 3],
            sheen: [1.0; 3],
            sheen_roughness: sr,
            t: [1.0, 0.0, 0.0],
            anisotropy: 0.0,
            transmission: 0.0,
            ..GltfSurface::core([0.0; 3], 0.0, 0.0)
        };
        let e = |c: f64| weft::reference::shading::sheen_albedo(c, sr, 24) as f32;
        let e_v = e(cv);
        let (mut scaled, mut unscaled) = (0.0f64, 0.0f64);
        let (nt, np) = (96, 192);
        for i in 0..nt {
            let cl = (i as f64 + 0.5) / nt as f64;
            for j in 0..np {
                let phi = (j as f64 + 0.5) / np as f64 * std::f64::consts::TAU;
                let l = dir(cl, phi);
                let w = (1.0 / nt as f64) * (std::f64::consts::TAU / np as f64);
                scaled += gltf_brdf_cos(n, v, l, &s, [e_v, e(cl)], 1.0)[0] as f64 * w;
                let mut plain = s;
                plain.sheen = [0.0; 3];
                unscaled += (gltf_brdf_cos(n, v, l, &plain, [0.0; 2], 1.0)[0]
                    + sheen_brdf_cos(
                        cl as f32,
                        cv as f32,
                        {
                            let h = unit([
                                (v[0] + l[0]) as f64,
                                (v[1] + l[1]) as f64,
                                (v[2] + l[2]) as f64,
                            ]);
                            h[2]
                        },
                        sr,
                    )) as f64
                    * w;
            }
        }
        println!("n·v={cv} sheen r={sr}: albedo with scaling {scaled:.4}, without {unscaled:.4}");
        assert!(
            scaled <= 1.0 + 5e-3,
            "with the albedo scaling the white sheen reflects {scaled} > 1"
        );
        assert!(
            unscaled > scaled,
            "the scaling must remove energy ({unscaled} <= {scaled})"
        );
    }
}

/// Energy with KHR_materials_clearcoat: a white coat (factor 1) over a white Lambert base
/// reflects at most what comes in (the coat takes Fc of the light from the base and reflects
/// at most that much), at every view angle and coat roughness; and the coat adds a lobe (more
/// than the base alone at grazing view, where Fc is large). f64 quadrature of the twin over the
/// hemisphere.
#[test]
fn a_clearcoat_over_a_white_base_conserves_energy() {
    let n = [0.0f32, 0.0, 1.0];
    let base = GltfSurface {
        base: [1.0; 3],
        metallic: 0.0,
        roughness: 1.0,
        specular: 0.0,
        f0: [0.0; 3],
        sheen: [0.0; 3],
        sheen_roughness: 0.0,
        t: [1.0, 0.0, 0.0],
        anisotropy: 0.0,
        transmission: 0.0,
        ..GltfSurface::core([0.0; 3], 0.0, 0.0)
    };
    for &cv in &[0.05f64, 0.3, 0.7, 1.0] {
        for &cr in &[0.05f32, 0.3, 0.7, 1.0] {
            let v = dir(cv, 0.0);
            let (nt, np) = (256, 256);
            let (mut coated, mut plain) = (0.0f64, 0.0f64);
            for i in 0..nt {
                // Denser near the mirror direction's cosine: a uniform grid in cos θ.
                let cl = (i as f64 + 0.5) / nt as f64;
                for j in 0..np {
                    let phi = (j as f64 + 0.5) / np as f64 * std::f64::consts::TAU;
                    let l = dir(cl, phi);
                    let w = (1.0 / nt as f64) * (std::f64::consts::TAU / np as f64);
                    let b = gltf_brdf_cos(n, v, l, &base, [0.0; 2], 1.0);
                    plain += b[0] as f64 * w;
                    coated += sh::clearcoat_brdf_cos(b, n, v, l, 1.0, cr)[0] as f64 * w;
                }
            }
            println!("n·v={cv} coat roughness {cr}: albedo {coated:.4} (base alone {plain:.4})");
            // The grid resolves lobes of roughness 0.3 and more (the worst case, 0.3 at n·v 0.7,
            // reads 1.0007); a sharp lobe (0.05) falls between its cells and reads low, so there
            // the check only bounds the base's share. 3e-3 of quadrature slack.
            let slack = 3e-3;
            assert!(
                coated <= 1.0 + slack,
                "n·v={cv}, coat roughness {cr}: the coated white base reflects {coated}"
            );
        }
    }
}
