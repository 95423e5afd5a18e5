//! The Rust twins of `glsl/include/env_light.glsl` (the environment light's estimators: the
//! fabric's lobes, diffuse and far side, the glTF BRDF's split sum, its anisotropic lobes and its
//! Monte Carlo truth, the sheen's layering) and `glsl/include/shadows.glsl` (percentage-closer
//! filtering of a shadow map), and the records of their probe `glsl/env_probe.comp`.
//!
//! Each function is the GLSL's line for line in f32 (same operations in the same order, same
//! clamps and literals), calling the twins of what the GLSL calls ([`super::ibl_twin`]'s
//! samplers and mip level, [`super::brdf::single`]'s fabric BRDF, [`super::shading`]'s glTF
//! BRDF). What the GLSL reads from textures — the environment's radiance and prefiltered cubes,
//! the DFG table, the shadow atlas's depth comparison — is a parameter here ([`EnvLookup`],
//! `compare`), as it is a function the including shader defines there: the probe gives both
//! sides the same closed-form stand-ins ([`StandIn`]), so what is compared is the estimators'
//! own arithmetic, sample by sample; [`KeptDfg`] is the DFG table as the GPU samples it.

#![allow(clippy::neg_cmp_op_on_partial_ord)] // `!(x > 0.0)` is meant: true for NaN, as in the GLSL.

use super::brdf::single::{
    self as fb, add, as_lobe_factor, as_norm, coupled_diffuse, cross, dot, scale, sub,
    FabricMaterial, Vec3,
};
use super::ibl_twin::{self, formula};
use super::shading::{
    ggx_aniso_d, ggx_aniso_v, ggx_d, ggx_energy_compensation, gltf_brdf_cos, iridescence_fresnel,
    GltfSurface,
};
use crate::fabric::GpuFabric;
use crate::records::GpuShadow;

const PI: f32 = std::f32::consts::PI;

/// What env_light.glsl reads from the environment's textures (the functions its including shader
/// defines): `env_radiance_at`, `env_prefiltered`, `dfg_lookup`, `env_face_size`.
pub trait EnvLookup {
    /// The radiance cube at world direction `dir` and mip level `lod`, times the intensity.
    fn radiance(&self, dir: Vec3, lod: f32) -> Vec3;
    /// The GGX-prefiltered cube at world direction `dir` and `roughness`, times the intensity.
    fn prefiltered(&self, dir: Vec3, roughness: f32) -> Vec3;
    /// The DFG table at (cos θ, roughness): A, B and the sheen albedo E.
    fn dfg(&self, cos_theta: f32, roughness: f32) -> Vec3;
    /// The radiance cube's face size in texels.
    fn face_size(&self) -> f32;
    /// Entry (i, j) of fabric record `table`'s lobe albedo table (`lobe_albedo_texel`): by
    /// default the real table of `f`'s exponents ([`super::lobe_albedo::table`]).
    fn lobe_albedo_texel(&self, f: &GpuFabric, _table: u32, i: u32, j: u32) -> [f32; 2] {
        super::lobe_albedo::table(f.e_along, f.e_across)
            [j as usize * super::lobe_albedo::LOBE_ALBEDO_MU + i as usize]
    }
}

/// The closed-form environment `glsl/env_probe.comp` defines for its leaves: smooth in the
/// direction and the level, positive, with an albedo-like DFG (A + B ≤ 1), so every estimator's
/// arithmetic shows in the result.
#[derive(Clone, Copy, Debug)]
pub struct StandIn {
    pub face_size: f32,
}

impl EnvLookup for StandIn {
    fn radiance(&self, d: Vec3, lod: f32) -> Vec3 {
        scale(
            [
                1.0 + 0.5 * d[0],
                1.0 + 0.5 * d[1] * d[2],
                0.75 + 0.25 * d[2],
            ],
            1.0 + 0.05 * lod,
        )
    }
    fn prefiltered(&self, d: Vec3, roughness: f32) -> Vec3 {
        scale(
            [0.9 + 0.3 * d[1], 0.8 + 0.2 * d[0], 0.7 + 0.1 * d[2]],
            1.0 - 0.2 * roughness,
        )
    }
    fn dfg(&self, c: f32, r: f32) -> Vec3 {
        [
            0.9 - 0.5 * r * (1.0 - c),
            0.05 + 0.05 * r * c,
            0.3 * r * (1.0 - c) + 0.05,
        ]
    }
    fn face_size(&self) -> f32 {
        self.face_size
    }
    fn lobe_albedo_texel(&self, _: &GpuFabric, table: u32, i: u32, j: u32) -> [f32; 2] {
        [
            0.2 + 0.02 * i as f32 - 0.01 * j as f32 + 0.05 * table as f32,
            0.5 + 0.02 * i as f32 + 0.005 * j as f32,
        ]
    }
}

/// The kept DFG table as the GPU samples it ([`super::shading::dfg_lookup`]); no environment
/// (black, face size 1): for the functions that read only the table.
#[derive(Clone, Copy, Debug, Default)]
pub struct KeptDfg;

impl EnvLookup for KeptDfg {
    fn radiance(&self, _: Vec3, _: f32) -> Vec3 {
        [0.0; 3]
    }
    fn prefiltered(&self, _: Vec3, _: f32) -> Vec3 {
        [0.0; 3]
    }
    fn dfg(&self, c: f32, r: f32) -> Vec3 {
        super::shading::dfg_lookup(c, r)
    }
    fn face_size(&self) -> f32 {
        1.0
    }
}

fn mul(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] * b[0], a[1] * b[1], a[2] * b[2]]
}
fn mix3(a: Vec3, b: Vec3, t: f32) -> Vec3 {
    add(scale(a, 1.0 - t), scale(b, t))
}
fn mixf(a: f32, b: f32, t: f32) -> f32 {
    a * (1.0 - t) + b * t
}
fn normalize(a: Vec3) -> Vec3 {
    scale(a, 1.0 / dot(a, a).sqrt())
}
fn max3(c: Vec3) -> f32 {
    c[0].max(c[1]).max(c[2])
}
/// `mat3(t, b, n) * k` of GLSL: `k.x·t + k.y·b + k.z·n`.
fn to_world(tbn: &[Vec3; 3], k: Vec3) -> Vec3 {
    add(
        add(scale(tbn[0], k[0]), scale(tbn[1], k[1])),
        scale(tbn[2], k[2]),
    )
}

/// `pixel_random`: the Monte Carlo level's per-pixel offset in [0, 1)² (an integer hash; exact).
pub fn pixel_random(p: [u32; 2]) -> [f32; 2] {
    let mut h = p[0]
        .wrapping_mul(1973)
        .wrapping_add(p[1].wrapping_mul(9277))
        .wrapping_add(26699);
    h = (h ^ (h >> 16)).wrapping_mul(0x7feb352d);
    h = (h ^ (h >> 15)).wrapping_mul(0x846ca68b);
    h ^= h >> 16;
    let mut g = h.wrapping_mul(0x9e3779b9);
    g = (g ^ (g >> 16)).wrapping_mul(0x7feb352d);
    [(h >> 8) as f32 / 16777216.0, (g >> 8) as f32 / 16777216.0]
}

/// GLSL `fract`.
fn fract(x: f32) -> f32 {
    x - x.floor()
}

/// `ibl_sample`: Hammersley point `i` of `n` shifted by `rotation`, modulo 1.
pub fn ibl_sample(i: u32, n: u32, rotation: [f32; 2]) -> [f32; 2] {
    let h = formula::hammersley::<f32>(i, n);
    [fract(h[0] + rotation[0]), fract(h[1] + rotation[1])]
}

/// `sheen_albedo`: the DFG table's sheen albedo E at (cos θ clamped to [0, 1], roughness).
pub fn sheen_albedo(env: &impl EnvLookup, cos_theta: f32, r: f32) -> f32 {
    env.dfg(cos_theta.clamp(0.0, 1.0), r)[2]
}

/// `ggx_albedo`: the GGX lobe's directional albedo A + B at (cos θ clamped, roughness).
pub fn ggx_albedo(env: &impl EnvLookup, cos_theta: f32, r: f32) -> f32 {
    let ab = env.dfg(cos_theta.clamp(0.0, 1.0), r);
    ab[0] + ab[1]
}

/// `env_irradiance`: irradiance/π about world normal `n`, the prefiltered cube's roughness-1 level.
pub fn env_irradiance(env: &impl EnvLookup, n: Vec3) -> Vec3 {
    env.prefiltered(n, 1.0)
}

/// `aniso_env_specular`: the anisotropic GGX lobes under the environment at fis:`samples`.
pub fn aniso_env_specular(
    env: &impl EnvLookup,
    n: Vec3,
    v: Vec3,
    s: &GltfSurface,
    ess: f32,
    samples: u32,
) -> Vec3 {
    let b = cross(n, s.t);
    let alpha = (s.roughness * s.roughness).max(1e-3);
    let at = mixf(alpha, 1.0, s.anisotropy * s.anisotropy);
    let nv = dot(n, v).max(1e-4);
    let comp_d = scale(ggx_energy_compensation(s.f0, ess), s.specular);
    let comp_m = ggx_energy_compensation(s.base, ess);
    let mut sum = [0.0f32; 3];
    for i in 0..samples {
        let h1 = ibl_twin::ggx_sample_h(ibl_sample(i, samples, [0.0; 2]), 1.0);
        let hl = normalize([at * h1[0], alpha * h1[1], h1[2]]);
        let h = add(add(scale(s.t, hl[0]), scale(b, hl[1])), scale(n, hl[2]));
        let vh = dot(v, h);
        if !(vh > 0.0) || !(hl[2] > 0.0) {
            continue;
        }
        let l = sub(scale(h, 2.0 * vh), v);
        let nl = dot(n, l);
        if !(nl > 0.0) {
            continue;
        }
        let pdf = ggx_aniso_d(hl[0], hl[1], hl[2], at, alpha) * hl[2] / (4.0 * vh);
        let vis = ggx_aniso_v(
            dot(s.t, v),
            dot(b, v),
            nv,
            dot(s.t, l),
            dot(b, l),
            nl,
            at,
            alpha,
        );
        let w = (1.0 - vh).powf(5.0);
        let mut fd = add(s.f0, scale(sub([1.0; 3], s.f0), w));
        let mut fm = add(s.base, scale(sub([1.0; 3], s.base), w));
        if s.iridescence > 0.0 {
            fd = mix3(
                fd,
                iridescence_fresnel(s.film_ior, vh, s.film_thickness, s.f0),
                s.iridescence,
            );
            fm = mix3(
                fm,
                iridescence_fresnel(s.film_ior, vh, s.film_thickness, s.base),
                s.iridescence,
            );
        }
        let f = mix3(mul(fd, comp_d), mul(fm, comp_m), s.metallic);
        let lod = ibl_twin::fis_lod(pdf, samples, env.face_size());
        sum = add(
            sum,
            scale(mul(env.radiance(l, lod), f), 4.0 * vis * nl * vh / hl[2]),
        );
    }
    scale(sum, 1.0 / samples as f32)
}

/// `sheen_layer_diffuse`: what the layers below a sheen keep of a cosine-weighted hemisphere of
/// light, the lamps' min(1 − k·E(n·v), 1 − k·E(n·l)) averaged over t = (n·l)² by a 16-point
/// midpoint rule.
pub fn sheen_layer_diffuse(env: &impl EnvLookup, k: f32, e_v: f32, roughness: f32) -> f32 {
    let mut sum = 0.0f32;
    for i in 0..16 {
        let mu = ((i as f32 + 0.5) / 16.0).sqrt();
        sum += (1.0 - k * e_v).min(1.0 - k * sheen_albedo(env, mu, roughness));
    }
    (sum / 16.0).max(0.0)
}

/// `pbr_env`: the glTF BRDF under the environment at level `mode` (1 approx, 2 fis, 3 mc) with
/// `samples` samples, `rot` the Monte Carlo level's rotation.
#[allow(clippy::too_many_arguments)]
pub fn pbr_env(
    env: &impl EnvLookup,
    n: Vec3,
    v: Vec3,
    s: &GltfSurface,
    ao: f32,
    bounce: Vec3,
    indirect: Vec3,
    e_v: f32,
    mode: u32,
    samples: u32,
    rot: [f32; 2],
) -> Vec3 {
    let base = s.base;
    let metallic = s.metallic;
    let roughness = s.roughness;
    let nv = dot(n, v).clamp(1e-4, 1.0);
    let has_sheen = max3(s.sheen) > 0.0;
    if mode == 3 {
        let tbn = fb::fabric_frame(n, fb::any_perpendicular(n), 1.0);
        let alpha = (roughness * roughness).max(1e-3);
        let ess = ggx_albedo(env, nv, roughness);
        let mut sum = [0.0f32; 3];
        for i in 0..samples {
            let xi = ibl_sample(i, samples, rot);
            let h = to_world(&tbn, ibl_twin::ggx_sample_h(xi, alpha));
            let dirs = [
                sub(scale(h, 2.0 * dot(v, h)), v),
                to_world(&tbn, ibl_twin::cosine_sample(xi)),
            ];
            for l in dirs {
                let nl = dot(n, l);
                if !(nl > 0.0) {
                    continue;
                }
                let hl = normalize(add(l, v));
                let vh = dot(v, hl);
                let nh = dot(n, hl).clamp(0.0, 1.0);
                let p_ggx = if vh > 0.0 {
                    ggx_d(nh, alpha) * nh / (4.0 * vh)
                } else {
                    0.0
                };
                let pdf = 0.5 * p_ggx + 0.5 * nl / PI;
                let e_l = if has_sheen {
                    sheen_albedo(env, nl, s.sheen_roughness)
                } else {
                    0.0
                };
                let f = gltf_brdf_cos(n, v, l, s, [e_v, e_l], ess);
                sum = add(sum, scale(mul(env.radiance(l, 0.0), f), 1.0 / pdf));
            }
        }
        return scale(scale(sum, 1.0 / (2 * samples) as f32), ao);
    }
    let ab = env.dfg(nv, roughness);
    let ess = ab[0] + ab[1];
    let mut dielectric = mul(
        add(scale(s.f0, ab[0]), [ab[1]; 3]),
        ggx_energy_compensation(s.f0, ess),
    );
    let mut metal = mul(
        add(scale(base, ab[0]), [ab[1]; 3]),
        ggx_energy_compensation(base, ess),
    );
    if s.iridescence > 0.0 {
        let fd = iridescence_fresnel(s.film_ior, nv, s.film_thickness, s.f0);
        dielectric = mix3(
            dielectric,
            mul(scale(fd, ess), ggx_energy_compensation(s.f0, ess)),
            s.iridescence,
        );
        metal = mix3(
            metal,
            mul(
                scale(
                    iridescence_fresnel(s.film_ior, nv, s.film_thickness, base),
                    ess,
                ),
                ggx_energy_compensation(base, ess),
            ),
            s.iridescence,
        );
    }
    let spec_albedo = mix3(scale(dielectric, s.specular), metal, metallic);
    let mut bent = n;
    let mut lookup_roughness = roughness;
    if s.anisotropy > 0.0 {
        let b = cross(n, s.t);
        let across = cross(b, v);
        let an = cross(across, b);
        let mut bend = 1.0 - s.anisotropy * (1.0 - roughness);
        bend *= bend;
        let m = mix3(an, n, bend * bend);
        bent = if dot(m, m) > 1e-12 { normalize(m) } else { n };
        let alpha = roughness * roughness;
        let at = mixf(alpha, 1.0, s.anisotropy * s.anisotropy);
        lookup_roughness = (0.5 * (at + alpha)).sqrt();
    }
    // GLSL reflect(-v, bent) = -v - 2·dot(bent, -v)·bent.
    let mv = scale(v, -1.0);
    let reflected = sub(mv, scale(bent, 2.0 * dot(bent, mv)));
    let r = formula::dominant_dir::<f32>(n, reflected, lookup_roughness);
    let prefiltered = env.prefiltered(r, lookup_roughness);
    let irradiance = env_irradiance(env, n);
    let mut diffuse = scale(
        scale(base, 1.0 - metallic),
        (1.0 - s.specular * max3(dielectric)) * (1.0 - s.transmission),
    );
    diffuse = mul(add(mul(scale(irradiance, ao), bounce), indirect), diffuse);
    let mut specular = if mode == 2 && s.anisotropy > 0.0 {
        aniso_env_specular(env, n, v, s, ess, samples)
    } else {
        mul(prefiltered, spec_albedo)
    };
    specular = scale(specular, ibl_twin::specular_occlusion(nv, ao, roughness));
    if !has_sheen {
        return add(diffuse, specular);
    }
    let k = max3(s.sheen);
    add(
        add(
            scale(diffuse, sheen_layer_diffuse(env, k, e_v, s.sheen_roughness)),
            scale(specular, (1.0 - k * e_v).max(0.0)),
        ),
        scale(
            mul(
                s.sheen,
                add(
                    scale(
                        irradiance,
                        ibl_twin::cone_occlusion(nv, ao, s.sheen_roughness),
                    ),
                    indirect,
                ),
            ),
            e_v,
        ),
    )
}

/// `fabric_lobe_albedo`: the exact albedo of the weft lobe (`warp` false) or the warp lobe for
/// view `k2` with Fresnel `rs`, bilinear in fabric record `table`'s table.
pub fn fabric_lobe_albedo(
    env: &impl EnvLookup,
    f: &GpuFabric,
    table: u32,
    k2: Vec3,
    rs: f32,
    warp: bool,
) -> f32 {
    use super::lobe_albedo::{LOBE_ALBEDO_MU, LOBE_ALBEDO_PHI};
    let ax = (if warp { k2[1] } else { k2[0] }).abs();
    let ay = (if warp { k2[0] } else { k2[1] }).abs();
    let phi = ay.atan2(ax.max(1e-20));
    let x = k2[2].clamp(0.0, 1.0) * (LOBE_ALBEDO_MU as u32 - 1) as f32;
    let y = (phi * (2.0 / PI)).clamp(0.0, 1.0) * (LOBE_ALBEDO_PHI as u32 - 1) as f32;
    let i = (x as u32).min(LOBE_ALBEDO_MU as u32 - 2);
    let j = (y as u32).min(LOBE_ALBEDO_PHI as u32 - 2);
    let fx = x - i as f32;
    let fy = y - j as f32;
    let t = |i, j| env.lobe_albedo_texel(f, table, i, j);
    let mix2 = |a: [f32; 2], b: [f32; 2], t: f32| [mixf(a[0], b[0], t), mixf(a[1], b[1], t)];
    let a = mix2(t(i, j), t(i + 1, j), fx);
    let b = mix2(t(i, j + 1), t(i + 1, j + 1), fx);
    let e = mix2(a, b, fy);
    mixf(e[0], e[1], rs)
}

/// `sobol_block` (ibl.glsl): point `i` of block `block` of the 2D Sobol' (0,2)-sequence in
/// blocks of `n` points (point block·n + i: the van der Corput radical inverse, and Sobol's
/// second dimension with direction numbers v_b = v_(b-1) xor v_(b-1)/2 from 1/2).
pub fn sobol_block(i: u32, n: u32, block: u32) -> [f32; 2] {
    let j = block.wrapping_mul(n).wrapping_add(i);
    // The direction numbers are the binomial coefficients mod 2: the second coordinate is the
    // bit-reversed index times that matrix, five shifted xors (no loop over the index's bits;
    // `sobol_direction_numbers` in the tests below builds it from the direction numbers).
    let mut y = j.reverse_bits();
    y ^= y << 16;
    y ^= (y & 0x00FF_00FF) << 8;
    y ^= (y & 0x0F0F_0F0F) << 4;
    y ^= (y & 0x3333_3333) << 2;
    y ^= (y & 0x5555_5555) << 1;
    let scale = 2.328_306_4e-10f32;
    [j.reverse_bits() as f32 * scale, y as f32 * scale]
}

/// `rgb9e5_pack`: three non-negative values under one exponent (E5B9G9R9: nine-bit mantissas,
/// rounded to nearest, above 65408 clamped, NaN read as 0).
pub fn rgb9e5_pack(c: Vec3) -> u32 {
    // GLSL's max(x, 0) is 0 for NaN; f32::max returns the other operand, as it does.
    let c = c.map(|x| x.max(0.0).min(65408.0));
    let m = c[0].max(c[1]).max(c[2]);
    // frexp's exponent: m = mantissa · 2^e2 with the mantissa in [0.5, 1).
    let e2 = if m > 0.0 {
        ((m.to_bits() >> 23) & 0xff) as i32 - 126
    } else {
        0
    };
    let mut e = if m > 0.0 { (e2 + 15).max(0) } else { 0 };
    let mut scale = (2.0f32).powi(24 - e);
    if (m * scale + 0.5).floor() >= 512.0 {
        e += 1;
        scale *= 0.5;
    }
    let q = c.map(|x| (x * scale + 0.5).floor() as u32);
    q[0] | (q[1] << 9) | (q[2] << 18) | ((e as u32) << 27)
}

/// `rgb9e5_unpack`.
pub fn rgb9e5_unpack(p: u32) -> Vec3 {
    let scale = (2.0f32).powi((p >> 27) as i32 - 24);
    [
        (p & 511) as f32 * scale,
        ((p >> 9) & 511) as f32 * scale,
        ((p >> 18) & 511) as f32 * scale,
    ]
}

/// `bf16x2_pack`: two non-negative values as the top 16 bits of their f32, rounded (NaN and
/// negatives 0, at most 3e38).
pub fn bf16x2_pack(v: [f32; 2]) -> u32 {
    let b = v.map(|x| (x.max(0.0).min(3.0e38).to_bits().wrapping_add(0x8000)) >> 16);
    b[0] | (b[1] << 16)
}

/// `bf16x2_unpack`.
pub fn bf16x2_unpack(p: u32) -> [f32; 2] {
    [f32::from_bits(p << 16), f32::from_bits(p & 0xffff_0000)]
}

/// `fabric_lobe_pack`: one pixel's lobe sums over `samples` samples as fabric_lobes.frag writes
/// them: per lobe the weighted mean radiance (rgb9e5) and the weight per sample (bf16x2), and
/// the mask of the pixels that pool with it.
pub fn fabric_lobe_pack(weft: [f32; 4], warp: [f32; 4], samples: u32, mask: u32) -> [u32; 4] {
    let mean = |s: [f32; 4]| {
        if s[3] > 0.0 {
            [s[0] / s[3], s[1] / s[3], s[2] / s[3]]
        } else {
            [0.0; 3]
        }
    };
    let weights = [weft[3] / samples as f32, warp[3] / samples as f32];
    [
        rgb9e5_pack(mean(weft)),
        rgb9e5_pack(mean(warp)),
        bf16x2_pack(weights),
        mask,
    ]
}

/// `fabric_lobe_unpack`: a packed texel back as sums per sample, per lobe (mean · weight, weight).
pub fn fabric_lobe_unpack(texel: [u32; 4]) -> ([f32; 4], [f32; 4]) {
    let [wa, wb] = bf16x2_unpack(texel[2]);
    let (a, b) = (rgb9e5_unpack(texel[0]), rgb9e5_unpack(texel[1]));
    (
        [a[0] * wa, a[1] * wa, a[2] * wa, wa],
        [b[0] * wb, b[1] * wb, b[2] * wb, wb],
    )
}

/// `fabric_lobe_weft_weight`: the weft lobe's share of the mixture the samples draw from (its
/// thread coverage's share within [0.05, 0.95]; 0.5 where no thread covers).
pub fn fabric_lobe_weft_weight(coverage: [f32; 4]) -> f32 {
    let c_thread = coverage[0] + coverage[1];
    if c_thread > 0.0 {
        (coverage[1] / c_thread).clamp(0.05, 0.95)
    } else {
        0.5
    }
}

/// `fabric_env_lobe_sample`: one sample of the lobes' mixture at the unit square's point `xi`,
/// added to each lobe's (Σ w·L, Σ w).
#[allow(clippy::too_many_arguments)]
pub fn fabric_env_lobe_sample(
    env: &impl EnvLookup,
    tbn: &[Vec3; 3],
    k2: Vec3,
    f: &GpuFabric,
    w_weft: f32,
    mode: u32,
    mut xi: [f32; 2],
    lod_samples: u32,
    weft: &mut [f32; 4],
    warp: &mut [f32; 4],
) {
    let pick_weft = xi[0] < w_weft;
    xi[0] = if pick_weft {
        xi[0] / w_weft
    } else {
        (xi[0] - w_weft) / (1.0 - w_weft)
    };
    xi[0] = xi[0].min(0.99999994);
    let (eu, ev) = if pick_weft {
        (f.e_along, f.e_across)
    } else {
        (f.e_across, f.e_along)
    };
    let (h, e, log_cos) = ibl_twin::as_sample_h_log(xi, eu, ev);
    let kh = dot(k2, h);
    if !(kh > 0.0) {
        return;
    }
    let k1 = sub(scale(h, 2.0 * kh), k2);
    if !(k1[2] > 0.0) {
        return;
    }
    let e_other = f.e_along + f.e_across - e;
    let (e_weft, e_warp) = if pick_weft {
        (e, e_other)
    } else {
        (e_other, e)
    };
    let p_weft = (e_weft * log_cos).exp2();
    let p_warp = (e_warp * log_cos).exp2();
    let mixed = w_weft * p_weft + (1.0 - w_weft) * p_warp;
    if !(mixed > 0.0) {
        return;
    }
    let pdf = as_norm(f.e_along, f.e_across) / (2.0 * PI) * mixed / (4.0 * kh);
    let factor = as_lobe_factor(k1[2], k2[2], kh.min(1.0), f.e_along, f.e_across, f.rs);
    let common_w = factor * k1[2] / pdf;
    let lod = if mode == 3 {
        0.0
    } else {
        ibl_twin::fis_lod(pdf, lod_samples, env.face_size())
    };
    let l = scale(env.radiance(to_world(tbn, k1), lod), common_w);
    for (sum, p) in [(weft, p_weft), (warp, p_warp)] {
        for c in 0..3 {
            sum[c] += l[c] * p;
        }
        sum[3] += common_w * p;
    }
}

/// `fabric_env_lobe_sums`: per lobe (Σ w·L, Σ w) over `samples` samples of the lobes' mixture:
/// `block` 0 the Hammersley set shifted by `rot`, b ≥ 1 block b − 1 of the Sobol' sequence; fis's
/// mip level chosen for `lod_samples` samples, mc's unfiltered.
#[allow(clippy::too_many_arguments)]
pub fn fabric_env_lobe_sums(
    env: &impl EnvLookup,
    tbn: &[Vec3; 3],
    k2: Vec3,
    coverage: [f32; 4],
    f: &GpuFabric,
    mode: u32,
    samples: u32,
    rot: [f32; 2],
    block: u32,
    lod_samples: u32,
) -> ([f32; 4], [f32; 4]) {
    let mut weft = [0.0f32; 4];
    let mut warp = [0.0f32; 4];
    if !(k2[2] > 0.0) {
        return (weft, warp);
    }
    let w_weft = fabric_lobe_weft_weight(coverage);
    for i in 0..samples {
        let xi = if block == 0 {
            ibl_sample(i, samples, rot)
        } else {
            sobol_block(i, samples, block - 1)
        };
        fabric_env_lobe_sample(
            env,
            tbn,
            k2,
            f,
            w_weft,
            mode,
            xi,
            lod_samples,
            &mut weft,
            &mut warp,
        );
    }
    (weft, warp)
}

/// `fabric_lobe_passes` (env_light.glsl): how many times its base count of fis samples a woven
/// pixel takes: 0.6 times its Schlick Fresnel at n·k2 over the cloth's rs (at least 0.02),
/// 1 to 7 (the lobes' error is where they are bright, at grazing views).
pub fn fabric_lobe_passes(nk2: f32, rs: f32) -> u32 {
    let x = 1.0 - nk2.clamp(0.0, 1.0);
    let x2 = x * x;
    let fresnel = rs + (1.0 - rs) * (x2 * x2 * x);
    // GLSL's uint() of a float truncates toward zero, as `as u32` does (NaN: clamp makes 1).
    ((0.6 * fresnel / rs.max(0.02) + 0.5) as u32).clamp(1, 7)
}

/// `fabric_pixel_lobe_sums`: one woven pixel's lobe sums as fabric_lobes.frag takes them at fis:
/// alone (`block` 0) the Hammersley set of `samples` · passes; pooled (`block` b ≥ 1 of a
/// `window`) `passes` blocks of samples / 2 of the Sobol' sequence (b, b + window, ...), the mip
/// level for `pixels` pixels' samples.
#[allow(clippy::too_many_arguments)]
pub fn fabric_pixel_lobe_sums(
    env: &impl EnvLookup,
    tbn: &[Vec3; 3],
    k2: Vec3,
    coverage: [f32; 4],
    f: &GpuFabric,
    samples: u32,
    block: u32,
    window: u32,
    pixels: u32,
) -> ([f32; 4], [f32; 4]) {
    let passes = fabric_lobe_passes(k2[2], f.rs);
    let pooled = block != 0;
    let unit = if pooled {
        (samples / 2).max(1)
    } else {
        samples * passes
    };
    let lod_samples = if pooled { unit * passes * pixels } else { unit };
    let mut weft = [0.0f32; 4];
    let mut warp = [0.0f32; 4];
    if !(k2[2] > 0.0) {
        return (weft, warp);
    }
    let w_weft = fabric_lobe_weft_weight(coverage);
    // One loop over every sample (the shader's: no loop of passes around a loop of samples).
    for n in 0..(if pooled { unit * passes } else { unit }) {
        let k = n / unit;
        let xi = if pooled {
            sobol_block(n - k * unit, unit, block - 1 + window * k)
        } else {
            ibl_sample(n, unit, [0.0, 0.0])
        };
        fabric_env_lobe_sample(
            env,
            tbn,
            k2,
            f,
            w_weft,
            2,
            xi,
            lod_samples,
            &mut weft,
            &mut warp,
        );
    }
    (weft, warp)
}

/// `fabric_env_lobes_resolve`: the lobes' radiance from their sums over `samples` samples: fis
/// a ratio estimator times the exact albedo of fabric record `table` ([`fabric_lobe_albedo`]),
/// mc the plain estimate.
#[allow(clippy::too_many_arguments)]
pub fn fabric_env_lobes_resolve(
    env: &impl EnvLookup,
    weft: [f32; 4],
    warp: [f32; 4],
    k2: Vec3,
    f: &GpuFabric,
    table: u32,
    mode: u32,
    samples: u32,
) -> (Vec3, Vec3) {
    if mode == 2 {
        let ratio = |sum: [f32; 4], warp: bool| {
            if sum[3] > 1e-6 * samples as f32 {
                scale(
                    scale([sum[0], sum[1], sum[2]], 1.0 / sum[3]),
                    fabric_lobe_albedo(env, f, table, k2, f.rs, warp),
                )
            } else {
                [0.0; 3]
            }
        };
        return (ratio(weft, false), ratio(warp, true));
    }
    let n = 1.0 / samples as f32;
    (
        [weft[0] * n, weft[1] * n, weft[2] * n],
        [warp[0] * n, warp[1] * n, warp[2] * n],
    )
}

/// `fabric_env_lobes`: the fabric's two specular lobes under the environment, each without its
/// coverage: (weft lobe, warp lobe); approx one look-up times the exact albedo, fis and mc
/// [`fabric_env_lobe_sums`] and [`fabric_env_lobes_resolve`] for one pixel alone.
#[allow(clippy::too_many_arguments)]
pub fn fabric_env_lobes(
    env: &impl EnvLookup,
    tbn: &[Vec3; 3],
    k2: Vec3,
    coverage: [f32; 4],
    f: &GpuFabric,
    table: u32,
    mode: u32,
    samples: u32,
    rot: [f32; 2],
) -> (Vec3, Vec3) {
    if !(k2[2] > 0.0) {
        return ([0.0; 3], [0.0; 3]);
    }
    if mode == 1 {
        let r = to_world(tbn, [-k2[0], -k2[1], k2[2]]);
        let peak = ((f.e_along + 1.0) * (f.e_across + 1.0)).sqrt() / (8.0 * PI);
        let lod = ibl_twin::fis_lod(peak, 1, env.face_size()) + 1.0;
        let l = env.radiance(r, lod);
        return (
            scale(l, fabric_lobe_albedo(env, f, table, k2, f.rs, false)),
            scale(l, fabric_lobe_albedo(env, f, table, k2, f.rs, true)),
        );
    }
    let (weft, warp) =
        fabric_env_lobe_sums(env, tbn, k2, coverage, f, mode, samples, rot, 0, samples);
    fabric_env_lobes_resolve(env, weft, warp, k2, f, table, mode, samples)
}

/// `fabric_env_diffuse`: the fabric's diffuse under the environment, without its coverage.
pub fn fabric_env_diffuse(
    env: &impl EnvLookup,
    tbn: &[Vec3; 3],
    k2: Vec3,
    f: &GpuFabric,
    mode: u32,
    samples: u32,
    rot: [f32; 2],
) -> Vec3 {
    if mode == 3 {
        let mut sum = [0.0f32; 3];
        for i in 0..samples {
            let k1 = ibl_twin::cosine_sample(ibl_sample(i, samples, rot));
            let factor = if f.flags & crate::fabric::FLAG_COUPLED_DIFFUSE != 0 {
                coupled_diffuse(f.rs, k1[2], k2[2]) * PI
            } else {
                1.0
            };
            sum = add(sum, scale(env.radiance(to_world(tbn, k1), 0.0), factor));
        }
        return scale(sum, 1.0 / samples as f32);
    }
    scale(
        env_irradiance(env, tbn[2]),
        ibl_twin::fabric_diffuse_albedo(f, k2[2]),
    )
}

/// `fabric_env_back`: the irradiance/π on a sheet's far side.
pub fn fabric_env_back(
    env: &impl EnvLookup,
    tbn: &[Vec3; 3],
    mode: u32,
    samples: u32,
    rot: [f32; 2],
) -> Vec3 {
    if mode == 3 {
        let mut sum = [0.0f32; 3];
        for i in 0..samples {
            let k = ibl_twin::cosine_sample(ibl_sample(i, samples, rot));
            sum = add(sum, env.radiance(to_world(tbn, [k[0], k[1], -k[2]]), 0.0));
        }
        return scale(sum, 1.0 / samples as f32);
    }
    env_irradiance(env, scale(tbn[2], -1.0))
}

/// `fabric_env_combine`: the fabric's environment light for one coverage.
#[allow(clippy::too_many_arguments)]
pub fn fabric_env_combine(
    coverage: [f32; 4],
    f: &GpuFabric,
    diffuse: Vec3,
    weft: Vec3,
    warp: Vec3,
    back: Vec3,
    ao: f32,
    bounce: Vec3,
    indirect: Vec3,
    nv: f32,
    sheets: bool,
) -> Vec3 {
    let m = FabricMaterial::from_gpu(f);
    let rd = fb::fabric_albedo(
        coverage,
        &if sheets { fb::fabric_reflecting(&m) } else { m },
    );
    let lobes = add(scale(weft, coverage[1]), scale(warp, coverage[0]));
    let mut radiance = add(
        mul(
            rd,
            add(
                mul(scale(diffuse, ao), bounce),
                scale(indirect, ibl_twin::fabric_diffuse_albedo(f, nv)),
            ),
        ),
        scale(lobes, ibl_twin::specular_occlusion(nv, ao, 0.5)),
    );
    if sheets {
        radiance = add(radiance, mul(back, fb::fabric_passed(coverage, &m)));
    }
    radiance
}

/// `shadow_pcf` of shadows.glsl: how much of the light at `light_pos` reaches world point `p`
/// with normal `n` through the shadow map `s`, `compare` the atlas's depth comparison at
/// (u, v, depth).
pub fn shadow_pcf(
    s: &GpuShadow,
    light_pos: Vec3,
    p: Vec3,
    n: Vec3,
    compare: impl Fn([f32; 3]) -> f32,
) -> f32 {
    let mut offset = s.params[0];
    if s.params[1] > 0.5 {
        offset *= dot(sub(light_pos, p), sub(light_pos, p)).sqrt();
    }
    let q = add(p, scale(n, offset));
    let m = &s.clip_from_world;
    // Column-major: clip = Σ_c column c · q[c], plus column 3.
    let clip: [f32; 4] =
        std::array::from_fn(|r| m[0][r] * q[0] + m[1][r] * q[1] + m[2][r] * q[2] + m[3][r]);
    if !(clip[3] > 0.0) {
        return 1.0;
    }
    let mut ndc = [clip[0] / clip[3], clip[1] / clip[3], clip[2] / clip[3]];
    if ndc[0].abs() > 1.0 || ndc[1].abs() > 1.0 || ndc[2] > 1.0 {
        return 1.0;
    }
    ndc[2] = ndc[2].max(0.0);
    let uv = [
        s.tile[0] + (ndc[0] * 0.5 + 0.5) * s.tile[2],
        s.tile[1] + (ndc[1] * 0.5 + 0.5) * s.tile[3],
    ];
    let texel = s.params[3];
    let lo = [s.tile[0] + texel, s.tile[1] + texel];
    let hi = [s.tile[0] + s.tile[2] - texel, s.tile[1] + s.tile[3] - texel];
    // GLSL clamp(x, lo, hi) = min(max(x, lo), hi) (no panic where lo > hi).
    let clamp2 = |x: [f32; 2]| [x[0].max(lo[0]).min(hi[0]), x[1].max(lo[1]).min(hi[1])];
    let radius = s.params[2];
    if radius <= 0.0 {
        let c = clamp2(uv);
        return compare([c[0], c[1], ndc[2]]);
    }
    let mut sum = 0.0f32;
    for j in -1i32..=1 {
        for i in -1i32..=1 {
            let w = ((2 - i.abs()) * (2 - j.abs())) as f32;
            let c = clamp2([
                uv[0] + i as f32 * radius * texel,
                uv[1] + j as f32 * radius * texel,
            ]);
            sum += w * compare([c[0], c[1], ndc[2]]);
        }
    }
    sum / 16.0
}

/// The depth comparison `glsl/env_probe.comp` defines for shadows.glsl's leaf: a smooth ramp in
/// (u, v, depth), 1 lit to 0 shadowed.
pub fn stand_in_compare(uvz: [f32; 3]) -> f32 {
    (8.0 * (uvz[0] - 0.5 * uvz[1]) - uvz[2] * 2.0 + 0.5).clamp(0.0, 1.0)
}

/// One input of `glsl/env_probe.comp` (std430, 480 bytes; `EnvProbeInput` there, whose comments
/// say what each field feeds).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct EnvProbeInput {
    pub n: [f32; 4],
    pub v: [f32; 4],
    pub base_metallic: [f32; 4],
    pub f0_specular: [f32; 4],
    pub sheen: [f32; 4],
    pub t_anisotropy: [f32; 4],
    pub surface: [f32; 4],
    pub film: [f32; 4],
    pub bounce: [f32; 4],
    pub frame_t: [f32; 4],
    pub frame_n: [f32; 4],
    pub k2: [f32; 4],
    pub coverage: [f32; 4],
    pub rot: [f32; 4],
    pub mode: [u32; 4],
    pub fabric: GpuFabric,
    pub shadow: GpuShadow,
    pub light_pos: [f32; 4],
    pub p: [f32; 4],
    pub pn: [f32; 4],
    pub indirect: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<EnvProbeInput>() == 480);

/// One output of `glsl/env_probe.comp` (std430, 112 bytes; `EnvProbeOutput` there).
///
/// | field | rgb | w |
/// |---|---|---|
/// | `pbr` | `pbr_env` | `sheen_layer_diffuse` |
/// | `aniso` | `aniso_env_specular` | `shadow_pcf` |
/// | `weft` | `fabric_env_lobes`' weft lobe | `pixel_random` x |
/// | `warp` | its warp lobe | `pixel_random` y |
/// | `diffuse` | `fabric_env_diffuse` | `ibl_sample(samples − 1)` x |
/// | `back` | `fabric_env_back` | `ibl_sample` y |
/// | `combined` | `fabric_env_combine` | `ggx_albedo(n·v, roughness)` |
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct EnvProbeOutput {
    pub pbr: [f32; 4],
    pub aniso: [f32; 4],
    pub weft: [f32; 4],
    pub warp: [f32; 4],
    pub diffuse: [f32; 4],
    pub back: [f32; 4],
    pub combined: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<EnvProbeOutput>() == 112);

impl EnvProbeOutput {
    /// The 28 values in record order.
    pub fn to_array(&self) -> [f32; 28] {
        let mut out = [0.0; 28];
        for (k, v) in [
            self.pbr,
            self.aniso,
            self.weft,
            self.warp,
            self.diffuse,
            self.back,
            self.combined,
        ]
        .iter()
        .enumerate()
        {
            out[4 * k..4 * k + 4].copy_from_slice(v);
        }
        out
    }
}

/// The names of [`EnvProbeOutput::to_array`]'s values.
pub const ENV_PROBE_OUTPUT_NAMES: [&str; 28] = [
    "pbr_env.r",
    "pbr_env.g",
    "pbr_env.b",
    "sheen_layer_diffuse",
    "aniso_env_specular.r",
    "aniso_env_specular.g",
    "aniso_env_specular.b",
    "shadow_pcf",
    "lobes.weft.r",
    "lobes.weft.g",
    "lobes.weft.b",
    "pixel_random.x",
    "lobes.warp.r",
    "lobes.warp.g",
    "lobes.warp.b",
    "pixel_random.y",
    "fabric_env_diffuse.r",
    "fabric_env_diffuse.g",
    "fabric_env_diffuse.b",
    "ibl_sample.x",
    "fabric_env_back.r",
    "fabric_env_back.g",
    "fabric_env_back.b",
    "ibl_sample.y",
    "fabric_env_combine.r",
    "fabric_env_combine.g",
    "fabric_env_combine.b",
    "ggx_albedo",
];

fn xyz(a: [f32; 4]) -> Vec3 {
    [a[0], a[1], a[2]]
}

/// What `glsl/env_probe.comp` computes, by the twins, over `env` (the probe's is [`StandIn`]
/// with the input's face size) and `compare` (the probe's: [`stand_in_compare`]).
pub fn env_probe_eval(
    inp: &EnvProbeInput,
    env: &impl EnvLookup,
    compare: impl Fn([f32; 3]) -> f32,
) -> EnvProbeOutput {
    let s = GltfSurface {
        base: xyz(inp.base_metallic),
        metallic: inp.base_metallic[3],
        roughness: inp.surface[0],
        specular: inp.f0_specular[3],
        f0: xyz(inp.f0_specular),
        sheen: xyz(inp.sheen),
        sheen_roughness: inp.sheen[3],
        t: xyz(inp.t_anisotropy),
        anisotropy: inp.t_anisotropy[3],
        transmission: inp.surface[1],
        iridescence: inp.film[0],
        film_ior: inp.film[1],
        film_thickness: inp.film[2],
    };
    let (mode, samples) = (inp.mode[0], inp.mode[1]);
    let rot = [inp.rot[0], inp.rot[1]];
    let (n, v) = (xyz(inp.n), xyz(inp.v));
    let w = |a: Vec3, x: f32| [a[0], a[1], a[2], x];
    let pbr = pbr_env(
        env,
        n,
        v,
        &s,
        inp.n[3],
        xyz(inp.bounce),
        xyz(inp.indirect),
        inp.v[3],
        mode,
        samples,
        rot,
    );
    let layer = sheen_layer_diffuse(env, inp.rot[2], inp.rot[3], inp.sheen[3]);
    let aniso = aniso_env_specular(env, n, v, &s, inp.surface[2], samples);
    let shadow = shadow_pcf(
        &inp.shadow,
        xyz(inp.light_pos),
        xyz(inp.p),
        xyz(inp.pn),
        compare,
    );
    let tbn = fb::fabric_frame(xyz(inp.frame_n), xyz(inp.frame_t), inp.frame_t[3]);
    let k2 = xyz(inp.k2);
    let lane = (inp.mode[3] / 3) % 4;
    let (weft, warp) = if mode == 2 && lane != 0 {
        // A woven pixel as fabric_lobes.frag takes its samples: lane 1 alone, 2 and 3 pooled
        // (block lane − 1 of a 3 x 3 window, the mip level of `lane` pixels' samples), through
        // the packed texel lighting.frag reads, resolved as if they were all its own.
        let (weft, warp) = fabric_pixel_lobe_sums(
            env,
            &tbn,
            k2,
            inp.coverage,
            &inp.fabric,
            samples,
            lane - 1,
            9,
            lane,
        );
        let (weft, warp) = fabric_lobe_unpack(fabric_lobe_pack(weft, warp, samples, 0));
        fabric_env_lobes_resolve(env, weft, warp, k2, &inp.fabric, inp.mode[3] % 3, mode, 1)
    } else {
        fabric_env_lobes(
            env,
            &tbn,
            k2,
            inp.coverage,
            &inp.fabric,
            inp.mode[3] % 3,
            mode,
            samples,
            rot,
        )
    };
    let pr = pixel_random([inp.mode[2], inp.mode[3]]);
    let diffuse = fabric_env_diffuse(env, &tbn, k2, &inp.fabric, mode, samples, rot);
    let back = fabric_env_back(env, &tbn, mode, samples, rot);
    let last = ibl_sample(samples.wrapping_sub(1), samples, rot);
    let combined = fabric_env_combine(
        inp.coverage,
        &inp.fabric,
        diffuse,
        weft,
        warp,
        back,
        inp.frame_n[3],
        xyz(inp.bounce),
        xyz(inp.indirect),
        inp.bounce[3],
        inp.light_pos[3] > 0.5,
    );
    EnvProbeOutput {
        pbr: w(pbr, layer),
        aniso: w(aniso, shadow),
        weft: w(weft, pr[0]),
        warp: w(warp, pr[1]),
        diffuse: w(diffuse, last[0]),
        back: w(back, last[1]),
        combined: w(combined, ggx_albedo(env, dot(n, v), inp.surface[0])),
    }
}

/// [`env_probe_eval`] with the probe's own stand-ins: the CPU side of `glsl/env_probe.comp`.
pub fn env_probe_cpu(inp: &EnvProbeInput) -> EnvProbeOutput {
    env_probe_eval(
        inp,
        &StandIn {
            face_size: inp.surface[3],
        },
        stand_in_compare,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pixel_random_is_in_the_unit_square_and_varies() {
        let mut seen = std::collections::HashSet::new();
        for y in 0..32 {
            for x in 0..32 {
                let r = pixel_random([x, y]);
                assert!((0.0..1.0).contains(&r[0]) && (0.0..1.0).contains(&r[1]));
                seen.insert((r[0].to_bits(), r[1].to_bits()));
            }
        }
        assert_eq!(seen.len(), 1024, "every pixel its own rotation");
    }

    // sobol_block's second coordinate by its definition: Sobol's second dimension, the direction
    // numbers v_1 = 1/2, v_b = v_(b-1) xor v_(b-1)/2, xored for each set bit of the index.
    fn sobol_direction_numbers(j: u32) -> u32 {
        let (mut y, mut v) = (0u32, 0x8000_0000u32);
        for b in 0..32 {
            if (j >> b) & 1 == 1 {
                y ^= v;
            }
            v ^= v >> 1;
        }
        y
    }

    #[test]
    fn sobol_block_matches_the_direction_numbers() {
        let scale = 2.328_306_4e-10f32;
        let check = |j: u32| {
            let got = sobol_block(j, 1, 0);
            assert_eq!(
                got[1],
                sobol_direction_numbers(j) as f32 * scale,
                "index {j}"
            );
            assert_eq!(got[0], j.reverse_bits() as f32 * scale, "index {j}");
        };
        (0..1u32 << 16).for_each(check);
        let mut x = 0x9E37_79B9u32;
        for _ in 0..10_000 {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            check(x);
        }
        // Blocks: point i of block b is point b·n + i.
        assert_eq!(sobol_block(3, 8, 5), sobol_block(43, 1, 0));
    }

    #[test]
    fn lobe_passes_grow_toward_grazing_within_one_to_seven() {
        // The default cloth (rs 0.04): its base count facing the view, more toward grazing
        // (Schlick: 0.6·F/rs is 1.05 at n·k2 0.5, 2.3 at 0.35, 4.0 at 0.25 and 11.7 at 0.05).
        assert_eq!(fabric_lobe_passes(1.0, 0.04), 1);
        assert_eq!(fabric_lobe_passes(0.5, 0.04), 1);
        assert_eq!(fabric_lobe_passes(0.35, 0.04), 2);
        assert_eq!(fabric_lobe_passes(0.25, 0.04), 4);
        assert_eq!(fabric_lobe_passes(0.05, 0.04), 7);
        let mut last = 0;
        for i in 0..=100 {
            let p = fabric_lobe_passes(1.0 - i as f32 / 100.0, 0.04);
            assert!(p >= last && (1..=7).contains(&p), "monotone within 1..=7");
            last = p;
        }
        // rs = 0 (issue 31 item 2) and rs = 1 stay in range; so do NaN and out-of-range cosines.
        assert_eq!(fabric_lobe_passes(1.0, 0.0), 1);
        assert_eq!(fabric_lobe_passes(0.0, 0.0), 7);
        assert_eq!(fabric_lobe_passes(0.0, 1.0), 1);
        for c in [f32::NAN, -1.0, 2.0, f32::INFINITY] {
            assert!((1..=7).contains(&fabric_lobe_passes(c, 0.04)));
        }
    }

    #[test]
    fn rgb9e5_keeps_nine_bits_of_the_largest_channel() {
        for c in [
            [1.0, 0.5, 0.25],
            [65408.0, 1.0, 0.0],
            [1e-3, 2e-3, 3e-3],
            [511.5, 0.0, 0.0],
            [0.0, 0.0, 0.0],
        ] {
            let d = rgb9e5_unpack(rgb9e5_pack(c));
            let m = c[0].max(c[1]).max(c[2]);
            for k in 0..3 {
                assert!((d[k] - c[k]).abs() <= m / 512.0 + 1e-30, "{c:?} -> {d:?}");
            }
        }
        // Beyond the format's largest value, negative and NaN: clamped, 0.
        assert_eq!(
            rgb9e5_unpack(rgb9e5_pack([1e9, -1.0, f32::NAN])),
            [65408.0, 0.0, 0.0]
        );
    }

    #[test]
    fn bf16_keeps_eight_bits_and_the_range() {
        for v in [[1.0, 3.0e-20], [0.123_456, 7.5e6], [0.0, 1.0]] {
            let d = bf16x2_unpack(bf16x2_pack(v));
            for k in 0..2 {
                assert!((d[k] - v[k]).abs() <= v[k] / 256.0, "{v:?} -> {d:?}");
            }
        }
        assert_eq!(bf16x2_unpack(bf16x2_pack([f32::NAN, -2.0])), [0.0, 0.0]);
        assert!(bf16x2_unpack(bf16x2_pack([f32::INFINITY, f32::MAX]))[0].is_finite());
    }

    #[test]
    fn ibl_sample_wraps_into_the_unit_square() {
        let s = ibl_sample(3, 8, [0.9, 0.75]);
        let h = formula::hammersley::<f32>(3, 8);
        assert_eq!(s, [fract(h[0] + 0.9), fract(h[1] + 0.75)]);
        assert!(s.iter().all(|x| (0.0..1.0).contains(x)));
    }

    /// A white furnace of the estimators: a constant environment of radiance 1 with the kept DFG
    /// table. The fabric's lobes at mc:4096 against the f64 white-furnace albedo of the same lobes.
    #[test]
    fn fabric_lobes_under_a_white_environment_match_the_lobes_albedo() {
        struct White;
        impl EnvLookup for White {
            fn radiance(&self, _: Vec3, _: f32) -> Vec3 {
                [1.0; 3]
            }
            fn prefiltered(&self, _: Vec3, _: f32) -> Vec3 {
                [1.0; 3]
            }
            fn dfg(&self, c: f32, r: f32) -> Vec3 {
                KeptDfg.dfg(c, r)
            }
            fn face_size(&self) -> f32 {
                256.0
            }
        }
        let f = GpuFabric {
            rs: 0.04,
            e_along: 200.0,
            e_across: 10.0,
            ..Default::default()
        };
        let tbn = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let k2 = normalize([0.3, 0.2, 0.9]);
        // Only the weft lobe (coverage (0, 1)): its albedo ∫ ρ_weft cos dω by the f64 sampler of
        // the reference (brdf::sampling), not the estimator's.
        let (weft, _) = fabric_env_lobes(
            &White,
            &tbn,
            k2,
            [0.0, 1.0, 0.0, 1.0],
            &f,
            0,
            3,
            4096,
            [0.37, 0.61],
        );
        let k2d = [k2[0] as f64, k2[1] as f64, k2[2] as f64];
        let truth = super::super::furnace::lobe_albedo(k2d, 200.0, 10.0, 0.04, 512);
        // fis:8 takes the albedo from the table: under white each lobe is its exact albedo,
        // whatever the mixture's weights (an even mixture's eight samples alone estimated the
        // weft lobe over half too low: examples/ibl_lobe_estimators.rs).
        let truth_warp = super::super::furnace::lobe_albedo(k2d, 10.0, 200.0, 0.04, 512);
        for cov in [
            [0.0, 1.0, 0.0, 1.0],
            [0.5, 0.5, 0.5, 0.5],
            [0.9, 0.1, 0.9, 0.1],
        ] {
            let (w, v) = fabric_env_lobes(&White, &tbn, k2, cov, &f, 0, 2, 8, [0.0; 2]);
            for (got, t) in [(w[0], truth), (v[0], truth_warp)] {
                assert!(
                    ((got as f64) - t).abs() < 0.01 * t + 1e-4,
                    "fis:8 under white, coverage {cov:?}: {got} against the albedo {t}"
                );
            }
        }
        assert!(
            ((weft[0] as f64) - truth).abs() < 0.01 * truth.max(1e-3) + 2e-3,
            "weft lobe under white: {} against the albedo {truth}",
            weft[0]
        );
    }
}
