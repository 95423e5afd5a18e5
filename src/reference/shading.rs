//! The CPU twin of the deferred lighting and tonemap passes (`glsl/lighting.frag`,
//! `glsl/include/pbr.glsl`, `glsl/tonemap.frag`): lights (KHR_lights_punctual falloff), the glTF
//! metallic-roughness BRDF, the hemispherical ambient, the fabric branch (which calls the fabric
//! BRDF of [`super::brdf::single`], not a copy) and the tone curve. In f32, line for line, so a test
//! can shade a read-back G-buffer on the CPU and compare it with the lighting pass's output, and the
//! CPU rasterizer can make whole reference images.

use super::brdf::single::{self as fb, Vec3};
use crate::fabric::GpuFabric;
use crate::records::{FrameData, GpuLight, Shading, LIGHT_DIRECTIONAL, LIGHT_SPOT};

const PI: f32 = std::f32::consts::PI;

fn dot(a: Vec3, b: Vec3) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn add(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn sub(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn mul(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] * b[0], a[1] * b[1], a[2] * b[2]]
}
fn scale(a: Vec3, s: f32) -> Vec3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
fn mix(a: Vec3, b: Vec3, t: f32) -> Vec3 {
    add(scale(a, 1.0 - t), scale(b, t))
}
fn normalize(a: Vec3) -> Vec3 {
    scale(a, 1.0 / dot(a, a).sqrt())
}
fn xyz(v: [f32; 4]) -> Vec3 {
    [v[0], v[1], v[2]]
}

/// `oct_decode` of frame.glsl: the unit vector of an octahedral encoding.
pub fn oct_decode(p: [f32; 2]) -> Vec3 {
    let mut n = [p[0], p[1], 1.0 - p[0].abs() - p[1].abs()];
    let t = (-n[2]).max(0.0);
    n[0] += if n[0] >= 0.0 { -t } else { t };
    n[1] += if n[1] >= 0.0 { -t } else { t };
    normalize(n)
}

/// `distance_falloff` of lighting.frag: inverse square, windowed to zero at `range` (0 = none).
pub fn distance_falloff(dist: f32, range: f32) -> f32 {
    let inv_sq = 1.0 / (dist * dist).max(1e-8);
    if range <= 0.0 {
        return inv_sq;
    }
    let r = dist / range;
    let window = (1.0 - r * r * r * r).clamp(0.0, 1.0);
    window * window * inv_sq
}

/// `light_incoming` of lighting.frag: the unit direction to the light and the illuminance it
/// brings at `p`, per channel.
pub fn light_incoming(light: &GpuLight, p: Vec3) -> (Vec3, Vec3) {
    let kind = light.direction_type[3];
    let c = light.color_intensity;
    let color = scale([c[0], c[1], c[2]], c[3]);
    if kind == LIGHT_DIRECTIONAL {
        return (scale(xyz(light.direction_type), -1.0), color);
    }
    let to_light = sub(xyz(light.position_range), p);
    let range = light.position_range[3];
    let dist2 = dot(to_light, to_light);
    if range > 0.0 && dist2 >= range * range {
        return ([0.0, 1.0, 0.0], [0.0; 3]);
    }
    let dist = dist2.sqrt();
    let l = if dist > 0.0 {
        scale(to_light, 1.0 / dist)
    } else {
        [0.0, 1.0, 0.0]
    };
    let mut atten = distance_falloff(dist, light.position_range[3]);
    if kind == LIGHT_SPOT {
        let cd = dot(xyz(light.direction_type), scale(l, -1.0));
        let a = (cd * light.spot[0] + light.spot[1]).clamp(0.0, 1.0);
        atten *= a * a;
    }
    (l, scale(color, atten))
}

/// `ggx_d` of pbr.glsl: the GGX (Trowbridge–Reitz) normal distribution.
pub fn ggx_d(n_h: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let d = n_h * n_h * (a2 - 1.0) + 1.0;
    a2 / (PI * d * d)
}

fn smith_v(n_l: f32, n_v: f32, alpha: f32) -> f32 {
    let a2 = alpha * alpha;
    let gv = n_l * (n_v * n_v * (1.0 - a2) + a2).sqrt();
    let gl = n_v * (n_l * n_l * (1.0 - a2) + a2).sqrt();
    let s = gv + gl;
    if s > 0.0 {
        0.5 / s
    } else {
        0.0
    }
}

fn length(a: Vec3) -> f32 {
    dot(a, a).sqrt()
}
fn max3(c: Vec3) -> f32 {
    c[0].max(c[1]).max(c[2])
}
fn lerp(a: f32, b: f32, t: f32) -> f32 {
    a * (1.0 - t) + b * t
}

/// `GltfSurface` of pbr.glsl: the glTF material with KHR_materials_specular, _sheen and
/// _anisotropy at a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GltfSurface {
    pub base: Vec3,
    pub metallic: f32,
    pub roughness: f32,
    /// The dielectric layer's weight (specularFactor · texture).
    pub specular: f32,
    /// The dielectric's F0: min(F0(ior) · specular colour, 1).
    pub f0: Vec3,
    /// Sheen colour (0: no sheen) and roughness.
    pub sheen: Vec3,
    pub sheen_roughness: f32,
    /// The anisotropy direction (unit, in the tangent plane) and strength (0: isotropic).
    pub t: Vec3,
    pub anisotropy: f32,
    /// KHR_materials_transmission: the part of the dielectric's diffuse lobe transmitted instead
    /// (0: opaque).
    pub transmission: f32,
    /// KHR_materials_iridescence: the thin film's weight (0: none), its index of refraction and
    /// its thickness in nanometres.
    pub iridescence: f32,
    pub film_ior: f32,
    pub film_thickness: f32,
}

impl GltfSurface {
    /// `gltf_surface` of pbr.glsl: the core material (no extensions).
    pub fn core(base: Vec3, metallic: f32, roughness: f32) -> GltfSurface {
        GltfSurface {
            base,
            metallic,
            roughness,
            specular: 1.0,
            f0: [0.04; 3],
            sheen: [0.0; 3],
            sheen_roughness: 0.0,
            t: [1.0, 0.0, 0.0],
            anisotropy: 0.0,
            transmission: 0.0,
            iridescence: 0.0,
            film_ior: 1.3,
            film_thickness: 0.0,
        }
    }
}

/// `transmission_exit` of pbr.glsl: where the view ray `v` refracted into the surface `n` with
/// index of refraction `ior` leaves a volume `thickness` thick (GLSL's `refract` with
/// eta = 1/ior; straight on where it cannot refract).
pub fn transmission_exit(p: Vec3, n: Vec3, v: Vec3, thickness: f32, ior: f32) -> Vec3 {
    let eta = 1.0 / ior.max(1.0);
    let i = scale(v, -1.0);
    let ni = dot(n, i);
    let k = 1.0 - eta * eta * (1.0 - ni * ni);
    let r = if k < 0.0 {
        [0.0; 3]
    } else {
        sub(scale(i, eta), scale(n, eta * ni + k.sqrt()))
    };
    let r = if dot(r, r) > 0.0 { normalize(r) } else { i };
    add(p, scale(r, thickness))
}

/// `diffuse_btdf_cos` of pbr.glsl (KHR_materials_diffuse_transmission): for light from behind
/// (n·l < 0 < n·v), colour/π·|n·l| × (1 − specular·max(F(n·v))); else 0.
pub fn diffuse_btdf_cos(n: Vec3, v: Vec3, l: Vec3, s: &GltfSurface, color: Vec3) -> Vec3 {
    let (n_l, n_v) = (dot(n, l), dot(n, v));
    if !(n_l < 0.0) || !(n_v > 0.0) {
        return [0.0; 3];
    }
    let w = (1.0 - n_v.clamp(0.0, 1.0)).powf(5.0);
    let fr = add(s.f0, scale(sub([1.0; 3], s.f0), w));
    scale(color, (1.0 - s.specular * max3(fr)) * (-n_l / PI))
}

/// `transmission_alpha` of pbr.glsl: the transmitted lobe's GGX alpha, roughness² widened by the
/// index as the Khronos sample viewer does (× clamp(2·ior − 2, 0, 1)), at least 1e-3.
pub fn transmission_alpha(roughness: f32, ior: f32) -> f32 {
    (roughness * roughness * (2.0 * ior - 2.0).clamp(0.0, 1.0)).max(1e-3)
}

/// `specular_btdf_cos` of pbr.glsl (KHR_materials_transmission under a lamp): for light from
/// behind (n·l < 0 < n·v), the GGX lobe about l mirrored through the surface's plane,
/// D·V·|n·l| × (1 − specular·F(v·h)) × base; else 0.
pub fn specular_btdf_cos(n: Vec3, v: Vec3, l: Vec3, s: &GltfSurface, ior: f32) -> Vec3 {
    let (n_l, n_v) = (dot(n, l), dot(n, v));
    if !(n_l < 0.0) || !(n_v > 0.0) {
        return [0.0; 3];
    }
    let h = normalize(add(sub(l, scale(n, 2.0 * n_l)), v));
    let n_h = dot(n, h).clamp(0.0, 1.0);
    let v_h = dot(v, h).clamp(0.0, 1.0);
    let alpha = transmission_alpha(s.roughness, ior);
    let dv = ggx_d(n_h, alpha) * smith_v(-n_l, n_v, alpha);
    let w = (1.0 - v_h).powf(5.0);
    [0, 1, 2].map(|k| {
        let fr = s.f0[k] + (1.0 - s.f0[k]) * w;
        (1.0 - s.specular * fr).max(0.0) * s.base[k] * (dv * -n_l)
    })
}

/// `film_sensitivity` of pbr.glsl: the Fourier transform of the CIE 1931 colour matching
/// functions (Belcour & Barla's Gaussian fits) at optical path difference `opd` (nm) and phase
/// shift, in linear Rec. 709.
pub fn film_sensitivity(opd: f32, shift: Vec3) -> Vec3 {
    let phase = 2.0 * PI * opd * 1e-9;
    let val = [5.4856e-13f32, 4.4201e-13, 5.2481e-13];
    let pos = [1.6810e+06f32, 1.7953e+06, 2.2084e+06];
    let var = [4.3278e+09f32, 9.3046e+09, 6.6121e+09];
    let mut xyz = [0.0f32; 3];
    for i in 0..3 {
        xyz[i] = val[i]
            * (2.0 * PI * var[i]).sqrt()
            * (pos[i] * phase + shift[i]).cos()
            * (-phase * phase * var[i]).exp();
    }
    xyz[0] += 9.7470e-14
        * (2.0 * PI * 4.5282e+09f32).sqrt()
        * (2.2399e+06 * phase + shift[0]).cos()
        * (-4.5282e+09 * phase * phase).exp();
    let xyz = xyz.map(|c| c / 1.0685e-7);
    [
        3.2404542 * xyz[0] - 1.5371385 * xyz[1] - 0.4985314 * xyz[2],
        -0.9692660 * xyz[0] + 1.8760108 * xyz[1] + 0.0415560 * xyz[2],
        0.0556434 * xyz[0] - 0.2040259 * xyz[1] + 1.0572252 * xyz[2],
    ]
}

/// `iridescence_fresnel` of pbr.glsl (KHR_materials_iridescence): the reflectance at cos θ1
/// (in air) of a film of index `film_ior`, `thickness` nanometres thick, over a base of normal
/// Fresnel `base_f0` — Belcour & Barla's Airy sum with Schlick interfaces, two orders.
pub fn iridescence_fresnel(film_ior: f32, cos1: f32, thickness: f32, base_f0: Vec3) -> Vec3 {
    let t = (thickness / 0.03).clamp(0.0, 1.0);
    let eta = lerp(1.0, film_ior, t * t * (3.0 - 2.0 * t));
    let c1 = cos1.clamp(0.0, 1.0);
    let cos2_sq = 1.0 - (1.0 - c1 * c1) / (eta * eta);
    if cos2_sq < 0.0 {
        return [1.0; 3];
    }
    let cos2 = cos2_sq.sqrt();
    let f0_12 = ((eta - 1.0) / (eta + 1.0)).powi(2);
    let r12 = f0_12 + (1.0 - f0_12) * (1.0 - c1).powf(5.0);
    let t121 = 1.0 - r12;
    let phi21 = if eta < 1.0 { 0.0 } else { PI };
    let opd = 2.0 * eta * thickness * cos2;
    let mut out = [0.0f32; 3];
    let mut phi = [0.0f32; 3];
    let mut cm = [0.0f32; 3];
    let mut sr = [0.0f32; 3];
    for i in 0..3 {
        let sq = base_f0[i].clamp(0.0, 0.9999).sqrt();
        let base_ior = (1.0 + sq) / (1.0 - sq);
        let r0 = (base_ior - eta) / (base_ior + eta);
        let r23 = r0 * r0 + (1.0 - r0 * r0) * (1.0 - cos2).powf(5.0);
        phi[i] = phi21 + if base_ior < eta { PI } else { 0.0 };
        let r123 = (r12 * r23).clamp(1e-5, 0.9999);
        let rs = t121 * t121 * r23 / (1.0 - r123);
        out[i] = r12 + rs;
        cm[i] = rs - t121;
        sr[i] = r123.sqrt();
    }
    for m in 1..=2 {
        let s = film_sensitivity(m as f32 * opd, phi.map(|p| m as f32 * p));
        for i in 0..3 {
            cm[i] *= sr[i];
            out[i] += cm[i] * 2.0 * s[i];
        }
    }
    out.map(|c| c.max(0.0))
}

/// `dispersion_iors` of pbr.glsl (KHR_materials_dispersion): the red, green and blue rays'
/// indices of refraction, ior ∓ (ior − 1) · 0.025 · dispersion.
pub fn dispersion_iors(ior: f32, dispersion: f32) -> Vec3 {
    let half_spread = (ior - 1.0) * 0.025 * dispersion;
    [ior - half_spread, ior, ior + half_spread]
}

/// `clearcoat_fresnel` of pbr.glsl: Schlick with F0 0.04.
pub fn clearcoat_fresnel(cos_theta: f32) -> f32 {
    0.04 + 0.96 * (1.0 - cos_theta.clamp(0.0, 1.0)).powf(5.0)
}

/// `clearcoat_brdf_cos` of pbr.glsl: `base_cos` under a coat of weight `coat` (attenuated by
/// the coat's Fresnel at nc·v) and roughness `roughness` about `nc`, plus the coat's GGX lobe
/// with its Fresnel at v·h.
pub fn clearcoat_brdf_cos(
    base_cos: Vec3,
    nc: Vec3,
    v: Vec3,
    l: Vec3,
    coat: f32,
    roughness: f32,
) -> Vec3 {
    let h = normalize(add(l, v));
    let fc = clearcoat_fresnel(dot(v, h));
    let (n_l, n_v) = (dot(nc, l), dot(nc, v));
    let layer = if n_l > 0.0 && n_v > 0.0 {
        let alpha = (roughness * roughness).max(1e-3);
        ggx_d(dot(nc, h).clamp(0.0, 1.0), alpha) * smith_v(n_l, n_v, alpha) * n_l
    } else {
        0.0
    };
    let fv = clearcoat_fresnel(n_v);
    base_cos.map(|b| b * (1.0 - coat * fv) + coat * fc * layer)
}

/// `transmission_lod` of pbr.glsl: the backdrop's mip level for roughness r through ior.
pub fn transmission_lod(roughness: f32, ior: f32, width: f32) -> f32 {
    width.max(1.0).log2() * roughness * (2.0 * ior - 2.0).clamp(0.0, 1.0)
}

/// `volume_attenuation` of pbr.glsl: Beer–Lambert over d (distance 0: infinite).
pub fn volume_attenuation(d: f32, color: Vec3, distance: f32) -> Vec3 {
    if distance > 0.0 {
        color.map(|c| c.max(0.0).powf(d.max(0.0) / distance))
    } else {
        [1.0; 3]
    }
}

/// `transmission_weight` of pbr.glsl: (1 − specular·(F0·A + B)) · base, clamped at 0.
pub fn transmission_weight(f0: Vec3, specular: f32, base: Vec3, ab: [f32; 2]) -> Vec3 {
    [0, 1, 2].map(|k| (1.0 - specular * (f0[k] * ab[0] + ab[1])).max(0.0) * base[k])
}

/// `charlie_d` of pbr.glsl.
pub fn charlie_d(n_h: f32, roughness: f32) -> f32 {
    let alpha = (roughness * roughness).max(1e-3);
    let sin2 = (1.0 - n_h * n_h).max(0.0);
    (2.0 + 1.0 / alpha) * sin2.powf(0.5 / alpha) / (2.0 * PI)
}

fn sheen_l(x: f32, alpha: f32) -> f32 {
    let t = (1.0 - alpha) * (1.0 - alpha);
    let a = lerp(21.5473, 25.3245, t);
    let b = lerp(3.82987, 3.32435, t);
    let c = lerp(0.19823, 0.16801, t);
    let d = lerp(-1.97760, -1.27393, t);
    let e = lerp(-4.32054, -4.85967, t);
    a / (1.0 + b * x.max(0.0).powf(c)) + d * x + e
}

/// `sheen_lambda` of pbr.glsl: the Charlie shadowing term Λ(cos θ) at alpha = r².
pub fn sheen_lambda(cos_theta: f32, alpha: f32) -> f32 {
    if cos_theta < 0.5 {
        sheen_l(cos_theta, alpha).exp()
    } else {
        (2.0 * sheen_l(0.5, alpha) - sheen_l(1.0 - cos_theta, alpha)).exp()
    }
}

/// `sheen_brdf_cos` of pbr.glsl: the sheen BRDF with colour 1 times n·l.
pub fn sheen_brdf_cos(n_l: f32, n_v: f32, n_h: f32, roughness: f32) -> f32 {
    if n_l <= 0.0 || n_v <= 0.0 {
        return 0.0;
    }
    let alpha = (roughness * roughness).max(1e-3);
    let lambda = sheen_lambda(n_v, alpha) + sheen_lambda(n_l, alpha);
    charlie_d(n_h, roughness) / ((1.0 + lambda) * 4.0 * n_v)
}

/// `ggx_aniso_d` of pbr.glsl.
pub fn ggx_aniso_d(t_h: f32, b_h: f32, n_h: f32, at: f32, ab: f32) -> f32 {
    let a2 = at * ab;
    let f = [ab * t_h, at * b_h, a2 * n_h];
    let w2 = a2 / dot(f, f);
    a2 * w2 * w2 / PI
}

/// `ggx_aniso_v` of pbr.glsl.
#[allow(clippy::too_many_arguments)]
pub fn ggx_aniso_v(
    t_v: f32,
    b_v: f32,
    n_v: f32,
    t_l: f32,
    b_l: f32,
    n_l: f32,
    at: f32,
    ab: f32,
) -> f32 {
    let gv = n_l * length([at * t_v, ab * b_v, n_v]);
    let gl = n_v * length([at * t_l, ab * b_l, n_l]);
    let s = gv + gl;
    if s > 0.0 {
        0.5 / s
    } else {
        0.0
    }
}

/// `ggx_energy_compensation` of pbr.glsl: the factor 1 + F0·(1/Ess - 1) that restores a GGX
/// lobe's multiply scattered light (Kulla & Conty; Fdez-Agüera's single-table form), Ess being the
/// lobe's directional albedo with F = 1 at n·v.
pub fn ggx_energy_compensation(f0: Vec3, ess: f32) -> Vec3 {
    let k = 1.0 / ess.max(1e-2) - 1.0;
    f0.map(|c| 1.0 + c * k)
}

/// `gltf_brdf_cos` of pbr.glsl: the glTF BRDF with its extensions times n·l; `sheen_e` =
/// (E(n·v), E(n·l)) at the sheen roughness; `ess` the GGX lobe's directional albedo Ess(n·v) for
/// the energy compensation of both specular lobes (1: single scattering).
pub fn gltf_brdf_cos(
    n: Vec3,
    v: Vec3,
    l: Vec3,
    s: &GltfSurface,
    sheen_e: [f32; 2],
    ess: f32,
) -> Vec3 {
    let n_l = dot(n, l);
    let n_v = dot(n, v);
    if n_l <= 0.0 || n_v <= 0.0 {
        return [0.0; 3];
    }
    let h = normalize(add(l, v));
    let n_h = dot(n, h).clamp(0.0, 1.0);
    let v_h = dot(v, h).clamp(0.0, 1.0);
    let alpha = (s.roughness * s.roughness).max(1e-3);
    let dv = if s.anisotropy > 0.0 {
        let b = fb::cross(n, s.t);
        let at = lerp(alpha, 1.0, s.anisotropy * s.anisotropy);
        ggx_aniso_d(dot(s.t, h), dot(b, h), n_h, at, alpha)
            * ggx_aniso_v(
                dot(s.t, v),
                dot(b, v),
                n_v,
                dot(s.t, l),
                dot(b, l),
                n_l,
                at,
                alpha,
            )
    } else {
        ggx_d(n_h, alpha) * smith_v(n_l, n_v, alpha)
    };
    let w = (1.0 - v_h).powf(5.0);
    let mut fr = add(s.f0, scale(sub([1.0; 3], s.f0), w));
    let mut fm = add(s.base, scale(sub([1.0; 3], s.base), w));
    let mut reflected = max3(fr);
    if s.iridescence > 0.0 {
        let fd = iridescence_fresnel(s.film_ior, v_h, s.film_thickness, s.f0);
        reflected = lerp(reflected, max3(fd), s.iridescence);
        fr = mix(fr, fd, s.iridescence);
        fm = mix(
            fm,
            iridescence_fresnel(s.film_ior, v_h, s.film_thickness, s.base),
            s.iridescence,
        );
    }
    let dielectric = add(
        scale(
            s.base,
            (1.0 - s.specular * reflected) * (1.0 - s.transmission) / PI,
        ),
        mul(
            scale(fr, s.specular * dv),
            ggx_energy_compensation(s.f0, ess),
        ),
    );
    let metal = mul(scale(fm, dv), ggx_energy_compensation(s.base, ess));
    let mut f = scale(mix(dielectric, metal, s.metallic), n_l);
    if max3(s.sheen) > 0.0 {
        let k = max3(s.sheen);
        // Clamped at 0: the Charlie lobe's albedo exceeds 1 at grazing angles and low roughness
        // (1.6 at n·v = 0.02, roughness 0.1), where the specification's scaling would go negative.
        let sc = (1.0 - k * sheen_e[0]).min(1.0 - k * sheen_e[1]).max(0.0);
        f = add(
            scale(f, sc),
            scale(s.sheen, sheen_brdf_cos(n_l, n_v, n_h, s.sheen_roughness)),
        );
    }
    f
}

/// `pbr_brdf_cos` of pbr.glsl: the core glTF BRDF times n·l, single scattering (what the DFG
/// table integrates).
pub fn pbr_brdf_cos(n: Vec3, v: Vec3, l: Vec3, base: Vec3, metallic: f32, roughness: f32) -> Vec3 {
    gltf_brdf_cos(
        n,
        v,
        l,
        &GltfSurface::core(base, metallic, roughness),
        [0.0; 2],
        1.0,
    )
}

/// `sheen_albedo` of env_light.glsl over the kept DFG table as the GPU stores it (f16) and
/// samples it (bilinear, clamp to edge, texel centres at (i + 1/2)/size).
pub fn sheen_albedo_lookup(cos_theta: f32, roughness: f32) -> f32 {
    super::env_light::sheen_albedo(&super::env_light::KeptDfg, cos_theta, roughness)
}

/// `ggx_albedo` of env_light.glsl over the kept DFG table: Ess = A + B as the GPU stores and
/// samples it (the sum of the two bilinear look-ups).
pub fn ggx_albedo_lookup(cos_theta: f32, roughness: f32) -> f32 {
    super::env_light::ggx_albedo(&super::env_light::KeptDfg, cos_theta, roughness)
}

/// `crate::env::dfg_table` at [`DFG_SIZE`], as f16 (A, B, E), kept in the
/// repository (`src/reference/dfg_table.f16`, 6 KiB) because computing it costs ~280 ms of the first
/// picture's time. A test recomputes it and compares; `WEFT_WRITE_DFG=1 cargo test --release --lib
/// kept_dfg_table` rewrites the file after a change of the BRDF.
pub fn dfg_table_kept() -> Vec<[half::f16; 3]> {
    const KEPT: &[u8] = include_bytes!("dfg_table.f16");
    KEPT.chunks_exact(6)
        .map(|c| {
            [0, 1, 2].map(|k| half::f16::from_bits(u16::from_le_bytes([c[2 * k], c[2 * k + 1]])))
        })
        .collect()
}

/// Side of the DFG table (n·v by roughness) the renderer samples.
pub const DFG_SIZE: u32 = 32;

/// The DFG table (A, B, E) at (cos θ, roughness) as the GPU stores it (f16) and samples it
/// (bilinear, clamp to edge, texel centres at (i + 1/2)/size).
pub fn dfg_lookup(cos_theta: f32, roughness: f32) -> [f32; 3] {
    static TABLE: std::sync::OnceLock<Vec<[f32; 3]>> = std::sync::OnceLock::new();
    let table = TABLE.get_or_init(|| {
        dfg_table_kept()
            .iter()
            .map(|t| t.map(|x| x.to_f32()))
            .collect()
    });
    [0, 1, 2].map(|c| bilinear(table, c, cos_theta, roughness))
}

fn bilinear(table: &[[f32; 3]], c: usize, cos_theta: f32, roughness: f32) -> f32 {
    let table = |k: usize| table[k][c];
    let n = DFG_SIZE as i32;
    let at = |i: i32, j: i32| table((j.clamp(0, n - 1) * n + i.clamp(0, n - 1)) as usize);
    let x = cos_theta.clamp(0.0, 1.0) * n as f32 - 0.5;
    let y = roughness.clamp(0.0, 1.0) * n as f32 - 0.5;
    let (i, j) = (x.floor() as i32, y.floor() as i32);
    let (fx, fy) = (x - x.floor(), y - y.floor());
    let top = at(i, j) * (1.0 - fx) + at(i + 1, j) * fx;
    let bottom = at(i, j + 1) * (1.0 - fx) + at(i + 1, j + 1) * fx;
    top * (1.0 - fy) + bottom * fy
}

/// The directional albedo E(cos θ) = ∫ sheen_brdf_cos dω of the sheen BRDF with colour 1 at sheen
/// roughness `roughness`, by a midpoint quadrature in (cos θ_l, φ) with `n` × 4n cells, in f64
/// (what the DFG table's third channel holds; the sheen layer's albedo scaling uses it).
pub fn sheen_albedo(cos_theta: f64, roughness: f32, n: u32) -> f64 {
    let nv = cos_theta.clamp(1e-4, 1.0);
    let v = [(1.0 - nv * nv).max(0.0).sqrt(), 0.0, nv];
    let mut sum = 0.0;
    let (nt, np) = (n, 4 * n);
    for i in 0..nt {
        // Cells in cos θ_l = u², denser towards the horizon where the lobe of a low roughness or
        // a grazing view lives (24 cells: within 3e-4 of a 200-cell quadrature).
        let u0 = i as f64 / nt as f64;
        let u1 = (i + 1) as f64 / nt as f64;
        let um = (u0 + u1) * 0.5;
        let cl = um * um;
        let dcos = u1 * u1 - u0 * u0;
        let sl = (1.0 - cl * cl).max(0.0).sqrt();
        for j in 0..np {
            let phi = (j as f64 + 0.5) / np as f64 * 2.0 * std::f64::consts::PI;
            let l = [sl * phi.cos(), sl * phi.sin(), cl];
            let h = [v[0] + l[0], v[1] + l[1], v[2] + l[2]];
            let hl = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
            let n_h = (h[2] / hl) as f32;
            let f = sheen_brdf_cos(cl as f32, nv as f32, n_h, roughness) as f64;
            sum += f * dcos * (2.0 * std::f64::consts::PI / np as f64);
        }
    }
    sum
}

/// A surface point as the lighting pass sees it (decoded from the G-buffer, or made by the CPU
/// rasterizer).
#[derive(Clone, Copy, Debug)]
pub struct Surface {
    pub position: Vec3,
    pub normal: Vec3,
    pub tangent: Vec3,
    /// Handedness: bitangent = sign · n × t.
    pub sign: f32,
    pub base_color: Vec3,
    pub metallic: f32,
    pub roughness: f32,
    pub emissive: Vec3,
    /// (c_warp, c_weft, s_warp, s_weft), for fabric.
    pub coverage: [f32; 4],
    pub fabric: Option<GpuFabric>,
    /// The glTF material's extensions (non-fabric; None: the core material of `base_color`,
    /// `metallic`, `roughness`). Its `t` is the anisotropy direction.
    pub gltf: Option<GltfSurface>,
}

/// `gouraud` of gbuffer.vert: the Phong reflection model at a fabric vertex (world position `p`,
/// normal `n`, glTF tangent with handedness), ambient and every light, with the normal turned
/// towards the viewer.
pub fn gouraud_vertex(
    frame: &FrameData,
    lights: &[GpuLight],
    p: Vec3,
    n: Vec3,
    tangent: [f32; 4],
    f: &GpuFabric,
) -> Vec3 {
    let m = fb::FabricMaterial::from_gpu(f);
    let v = normalize(sub(xyz(frame.eye), p));
    let n = if dot(n, v) < 0.0 { scale(n, -1.0) } else { n };
    let tbn = fb::fabric_frame(n, xyz(tangent), tangent[3]);
    let n = tbn[2];
    let k2 = fb::fabric_local(v, tbn);
    let ambient = mix(
        xyz(frame.ambient_ground),
        xyz(frame.ambient_sky),
        n[1] * 0.5 + 0.5,
    );
    let mut radiance = mul(ambient, fb::fabric_mean_rd(&m));
    let count = (frame.light_count as usize).min(lights.len());
    for light in &lights[..count] {
        let (l, e) = light_incoming(light, p);
        let k1 = fb::fabric_local(l, tbn);
        if k1[2] <= 0.0 || e == [0.0; 3] {
            continue;
        }
        radiance = add(radiance, scale(mul(e, fb::phong_brdf(k1, k2, &m)), k1[2]));
    }
    radiance
}

/// The main body of lighting.frag for a covered pixel: linear HDR radiance towards the eye.
pub fn shade(frame: &FrameData, lights: &[GpuLight], s: &Surface) -> Vec3 {
    shade_with(frame, lights, s, Shading::Fabric)
}

/// [`shade`] with fabric shaded by `shading` (lighting.frag's SHADING): for Gouraud the surface's
/// emissive must already hold the interpolated [`gouraud_vertex`] lighting, as the G-buffer's does.
pub fn shade_with(frame: &FrameData, lights: &[GpuLight], s: &Surface, shading: Shading) -> Vec3 {
    let n = s.normal;
    let v = normalize(sub(xyz(frame.eye), s.position));
    let mut radiance = s.emissive;
    let ambient = mix(
        xyz(frame.ambient_ground),
        xyz(frame.ambient_sky),
        n[1] * 0.5 + 0.5,
    );
    let count = (frame.light_count as usize).min(lights.len());
    match &s.fabric {
        Some(f) => {
            // The thread texture's value (the G-buffer's albedo of a fabric pixel) over the
            // thread colours.
            let m = fb::fabric_tinted(&fb::FabricMaterial::from_gpu(f), s.base_color);
            let cov = s.coverage;
            let tbn = fb::fabric_frame(n, s.tangent, s.sign);
            let k2 = fb::fabric_local(v, tbn);
            if shading == Shading::Gouraud {
                return radiance;
            }
            if shading != Shading::Fabric {
                radiance = add(radiance, mul(ambient, fb::fabric_mean_rd(&m)));
                for light in &lights[..count] {
                    let (l, e) = light_incoming(light, s.position);
                    let k1 = fb::fabric_local(l, tbn);
                    if k1[2] <= 0.0 || e == [0.0; 3] {
                        continue;
                    }
                    let brdf = if shading == Shading::Phong {
                        fb::phong_brdf(k1, k2, &m)
                    } else {
                        fb::plain_as_brdf(k1, k2, &m)
                    };
                    radiance = add(radiance, scale(mul(e, brdf), k1[2]));
                }
                return radiance;
            }
            // A sheet's threads reflect the 1 − τ they do not pass through (identity otherwise).
            let mr = fb::fabric_reflecting(&m);
            let rd = fb::fabric_albedo(cov, &mr);
            radiance = add(radiance, mul(ambient, rd));
            if m.sheet.is_some() {
                let ambient_back = mix(
                    xyz(frame.ambient_ground),
                    xyz(frame.ambient_sky),
                    -n[1] * 0.5 + 0.5,
                );
                radiance = add(radiance, mul(ambient_back, fb::fabric_passed(cov, &m)));
            }
            for light in &lights[..count] {
                let (l, e) = light_incoming(light, s.position);
                let k1 = fb::fabric_local(l, tbn);
                if e == [0.0; 3] {
                    continue;
                }
                if k1[2] > 0.0 {
                    radiance = add(
                        radiance,
                        scale(mul(e, fb::fabric_brdf(k1, k2, cov, &mr)), k1[2]),
                    );
                } else if m.sheet.is_some() && k1[2] < 0.0 {
                    // A lamp behind the sheet, through its threads.
                    radiance = add(
                        radiance,
                        scale(mul(e, fb::fabric_btdf(k1, k2, cov, &m)), -k1[2]),
                    );
                }
            }
        }
        None => {
            let base = s.base_color;
            let gs = s
                .gltf
                .unwrap_or_else(|| GltfSurface::core(base, s.metallic, s.roughness));
            let albedo = |c: f32| {
                if max3(gs.sheen) > 0.0 {
                    sheen_albedo_lookup(c, gs.sheen_roughness)
                } else {
                    0.0
                }
            };
            let e_v = albedo(dot(n, v));
            let ess = ggx_albedo_lookup(dot(n, v), s.roughness);
            let spec_ambient = scale(mix([0.04; 3], base, s.metallic), (1.0 - s.roughness) * 0.5);
            radiance = add(
                radiance,
                add(
                    scale(mul(ambient, base), 1.0 - s.metallic),
                    mul(ambient, spec_ambient),
                ),
            );
            for light in &lights[..count] {
                let (l, e) = light_incoming(light, s.position);
                if e == [0.0; 3] {
                    continue;
                }
                radiance = add(
                    radiance,
                    mul(
                        e,
                        gltf_brdf_cos(n, v, l, &gs, [e_v, albedo(dot(n, l))], ess),
                    ),
                );
            }
        }
    }
    radiance
}

/// `pbr_neutral` of tonemap.frag (Khronos PBR Neutral).
pub fn pbr_neutral(color: Vec3) -> Vec3 {
    const START_COMPRESSION: f32 = 0.8 - 0.04;
    const DESATURATION: f32 = 0.15;
    let x = color[0].min(color[1]).min(color[2]);
    let offset = if x < 0.08 { x - 6.25 * x * x } else { 0.04 };
    let color = sub(color, [offset; 3]);
    let peak = color[0].max(color[1]).max(color[2]);
    if peak < START_COMPRESSION {
        return color;
    }
    let d = 1.0 - START_COMPRESSION;
    let new_peak = 1.0 - d * d / (peak + d - START_COMPRESSION);
    let color = scale(color, new_peak / peak);
    let g = 1.0 - 1.0 / (DESATURATION * (peak - new_peak) + 1.0);
    mix(color, [new_peak; 3], g)
}

/// The tone curve of tonemap.frag (`--tonemap`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ToneCurve {
    /// Khronos PBR Neutral (the default).
    #[default]
    PbrNeutral,
    /// No curve: exposure, then the clamp to [0, 1].
    None,
    /// three.js' ACES filmic fit with its 1/0.6 exposure scale and the 1/2.2 display gamma of
    /// the Khronos render-fidelity goldens (the comparison's tone mapping).
    Aces,
    /// AgX (Sobotka), Wrensch's minimal form with the default look.
    Agx,
}

impl ToneCurve {
    pub const ALL: [ToneCurve; 4] = [
        ToneCurve::PbrNeutral,
        ToneCurve::None,
        ToneCurve::Aces,
        ToneCurve::Agx,
    ];

    pub fn name(self) -> &'static str {
        match self {
            ToneCurve::PbrNeutral => "pbr-neutral",
            ToneCurve::None => "none",
            ToneCurve::Aces => "aces",
            ToneCurve::Agx => "agx",
        }
    }

    pub fn by_name(name: &str) -> Option<ToneCurve> {
        ToneCurve::ALL.into_iter().find(|c| c.name() == name)
    }

    /// tonemap.frag's `curve`.
    pub fn code(self) -> u32 {
        match self {
            ToneCurve::PbrNeutral => 0,
            ToneCurve::None => 1,
            ToneCurve::Aces => 2,
            ToneCurve::Agx => 3,
        }
    }
}

/// Column-major 3x3 (GLSL's `mat3(c0, c1, c2)`) times a vector.
fn mat3_mul(cols: &[f32; 9], v: Vec3) -> Vec3 {
    [0, 1, 2].map(|r| cols[r] * v[0] + cols[3 + r] * v[1] + cols[6 + r] * v[2])
}

/// `aces_three` of tonemap.frag: three.js' ACES filmic fit, the 1/2.2 display gamma, returned as
/// the linear value whose sRGB encoding is that.
pub fn aces_three(c: Vec3) -> Vec3 {
    const M_IN: [f32; 9] = [
        0.59719, 0.07600, 0.02840, 0.35458, 0.90834, 0.13383, 0.04823, 0.01566, 0.83777,
    ];
    const M_OUT: [f32; 9] = [
        1.60475, -0.10208, -0.00327, -0.53108, 1.10813, -0.07276, -0.07367, -0.00605, 1.07602,
    ];
    let v = mat3_mul(&M_IN, scale(c, 1.0 / 0.6));
    let v = v
        .map(|x| (x * (x + 0.0245786) - 0.000090537) / (x * (0.983729 * x + 0.4329510) + 0.238081));
    mat3_mul(&M_OUT, v).map(|x| srgb_decode(x.clamp(0.0, 0.9999).powf(1.0 / 2.2)))
}

/// `agx` of tonemap.frag: AgX with the default contrast, back to linear by the 2.2 EOTF.
pub fn agx(c: Vec3) -> Vec3 {
    const INSET: [f32; 9] = [
        0.842479062253094,
        0.0423282422610123,
        0.0423756549057051,
        0.0784335999999992,
        0.878468636469772,
        0.0784336,
        0.0792237451477643,
        0.0791661274605434,
        0.879142973793104,
    ];
    const OUTSET: [f32; 9] = [
        1.19687900512017,
        -0.0528968517574562,
        -0.0529716355144438,
        -0.0980208811401368,
        1.15190312990417,
        -0.0980434501171241,
        -0.0990297440797205,
        -0.0989611768448433,
        1.15107367264116,
    ];
    const MIN_EV: f32 = -12.47393;
    const MAX_EV: f32 = 4.026069;
    let v = mat3_mul(&INSET, c).map(|x| {
        let e = x.max(1e-10).log2().clamp(MIN_EV, MAX_EV);
        let v = (e - MIN_EV) / (MAX_EV - MIN_EV);
        let x2 = v * v;
        let x4 = x2 * x2;
        -17.86 * x4 * x2 * v + 78.01 * x4 * x2 - 126.7 * x4 * v + 92.06 * x4 - 28.72 * x2 * v
            + 4.361 * x2
            - 0.1718 * v
            + 0.002857
    });
    mat3_mul(&OUTSET, v).map(|x| x.max(0.0).powf(2.2))
}

/// tonemap.frag: exposure (a linear scale, 2^EV), the curve, and the clamp to [0, 1]. The sRGB
/// encoding after it is the output target's; [`srgb_encode`] is its CPU side.
pub fn tonemap(hdr: Vec3, exposure: f32) -> Vec3 {
    tonemap_with(ToneCurve::PbrNeutral, hdr, exposure)
}

/// [`tonemap`] with any [`ToneCurve`].
pub fn tonemap_with(curve: ToneCurve, hdr: Vec3, exposure: f32) -> Vec3 {
    let c = if hdr.iter().any(|v| !v.is_finite()) {
        [0.0; 3]
    } else {
        hdr
    };
    let c = scale([c[0].max(0.0), c[1].max(0.0), c[2].max(0.0)], exposure);
    let c = match curve {
        ToneCurve::PbrNeutral => pbr_neutral(c),
        ToneCurve::None => c,
        ToneCurve::Aces => aces_three(c),
        ToneCurve::Agx => agx(c),
    };
    [
        c[0].clamp(0.0, 1.0),
        c[1].clamp(0.0, 1.0),
        c[2].clamp(0.0, 1.0),
    ]
}

/// What the output target holds for linear radiance `hdr`: tone-mapped (`exposure` a linear
/// scale) and sRGB-encoded, alpha 255.
pub fn display_rgba8(hdr: Vec3, exposure: f32) -> [u8; 4] {
    display_rgba8_with(ToneCurve::PbrNeutral, hdr, exposure)
}

/// [`display_rgba8`] with any [`ToneCurve`].
pub fn display_rgba8_with(curve: ToneCurve, hdr: Vec3, exposure: f32) -> [u8; 4] {
    let d = tonemap_with(curve, hdr, exposure);
    [srgb_encode(d[0]), srgb_encode(d[1]), srgb_encode(d[2]), 255]
}

pub use crate::color::{srgb_decode, srgb_encode};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn oct_decode_round_trips_axes() {
        assert_eq!(oct_decode([0.0, 0.0]), [0.0, 0.0, 1.0]);
        let n = oct_decode([1.0, 0.0]);
        assert!((n[0] - 1.0).abs() < 1e-6 && n[2].abs() < 1e-6);
    }

    #[test]
    fn falloff_reaches_zero_at_range() {
        assert_eq!(distance_falloff(2.0, 2.0), 0.0);
        assert_eq!(distance_falloff(2.0, 0.0), 0.25);
    }

    #[test]
    fn tonemap_is_identity_for_dark_mid_tones_and_bounded() {
        let c = tonemap([0.3, 0.2, 0.1], 1.0);
        assert!((c[0] - 0.26).abs() < 1e-6, "{c:?}");
        let bright = tonemap([1e6, 1e6, 1e6], 1.0);
        assert!(bright.iter().all(|v| *v <= 1.0 && *v > 0.99));
        assert_eq!(tonemap([f32::NAN, 0.0, 0.0], 1.0), [0.0; 3]);
    }

    /// The sheen layer's diffuse scaling under a cosine-weighted hemisphere of light against its
    /// f64 integral 2∫ min(1 - k·E(n·v), 1 - k·E(μ)) μ dμ (E by its own quadrature, 200 cells in
    /// μ²), and against the scaling 1 - k·E(n·v) the environment used before, which ignored that
    /// grazing light (where E is largest) is dimmed more.
    #[test]
    fn sheen_layer_diffuse_matches_its_integral() {
        let (mut worst, mut worst_old) = (0f64, 0f64);
        for &r in &[0.1f32, 0.4, 0.7, 1.0] {
            let e: Vec<f64> = (0..200)
                .map(|i| sheen_albedo(((i as f64 + 0.5) / 200.0).sqrt(), r, 24))
                .collect();
            for &nv in &[0.1f32, 0.3, 0.6, 0.9] {
                let e_v = sheen_albedo(nv as f64, r, 24);
                for &k in &[0.3f32, 1.0] {
                    let want: f64 = e
                        .iter()
                        .map(|e_l| (1.0 - k as f64 * e_v).min(1.0 - k as f64 * e_l))
                        .sum::<f64>()
                        / 200.0;
                    let got = super::super::env_light::sheen_layer_diffuse(
                        &super::super::env_light::KeptDfg,
                        k,
                        sheen_albedo_lookup(nv, r),
                        r,
                    ) as f64;
                    worst = worst.max((got - want).abs());
                    worst_old = worst_old.max((1.0 - k as f64 * e_v - want).abs());
                }
            }
        }
        println!("sheen layer: twin within {worst:.4}, 1 - k E(n.v) within {worst_old:.4}");
        // Measured 0.0068 (the 16-point rule where min's kink falls between points, and the
        // table's f16 + bilinear E; 8 points gave 0.0119): bound 0.009. The old scaling was off
        // by up to 0.109.
        assert!(worst < 0.009, "{worst}");
        assert!(worst_old > 0.04, "{worst_old}");
    }
}
