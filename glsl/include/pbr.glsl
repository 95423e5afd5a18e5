// The glTF 2.0 metallic-roughness BRDF (glTF spec, Appendix B): Lambert diffuse plus a GGX
// specular lobe with the height-correlated Smith visibility and Schlick Fresnel.
#ifndef WEFT_PBR_GLSL
#define WEFT_PBR_GLSL

#include "frame.glsl"

float ggx_d(float n_h, float alpha) {
    float a2 = alpha * alpha;
    float d = n_h * n_h * (a2 - 1.0) + 1.0;
    return a2 / (PI * d * d);
}

float smith_v(float n_l, float n_v, float alpha) {
    float a2 = alpha * alpha;
    float gv = n_l * sqrt(n_v * n_v * (1.0 - a2) + a2);
    float gl = n_v * sqrt(n_l * n_l * (1.0 - a2) + a2);
    float s = gv + gl;
    return s > 0.0 ? 0.5 / s : 0.0;
}

// A surface point of the glTF material with its extensions, as the lighting pass decodes it
// from the G-buffer (Rust twin: weft::reference::shading::GltfSurface).
struct GltfSurface {
    vec3 base;
    float metallic;
    float roughness;
    float specular;        // KHR_materials_specular: the dielectric layer's weight
    vec3 f0;               // the dielectric's F0: min(F0(ior) · specular colour, 1)
    vec3 sheen;            // KHR_materials_sheen colour (0: no sheen)
    float sheen_roughness;
    vec3 t;                // KHR_materials_anisotropy: the direction (unit, in the tangent plane)
    float anisotropy;      // and its strength (0: isotropic GGX)
    float transmission;    // KHR_materials_transmission and _diffuse_transmission: the part of the
                           // diffuse lobe that is not reflected (0: opaque), 1 − (1 − t)(1 − dt)
    float iridescence;     // KHR_materials_iridescence: the thin film's weight (0: none),
    float film_ior;        // its index of refraction
    float film_thickness;  // and its thickness in nanometres
};

GltfSurface gltf_surface(vec3 base, float metallic, float roughness) {
    return GltfSurface(base, metallic, roughness, 1.0, vec3(0.04), vec3(0.0), 0.0, vec3(1.0, 0.0, 0.0), 0.0, 0.0,
                       0.0, 1.3, 0.0);
}

// The Charlie sheen distribution (Estevez & Kulla 2017; KHR_materials_sheen), alpha = r².
float charlie_d(float n_h, float roughness) {
    float alpha = max(roughness * roughness, 1e-3);
    float sin2 = max(1.0 - n_h * n_h, 0.0);
    return (2.0 + 1.0 / alpha) * pow(sin2, 0.5 / alpha) / (2.0 * PI);
}

// The fit of the Charlie shadowing exponent (KHR_materials_sheen, "Sheen visibility").
float sheen_l(float x, float alpha) {
    float t = (1.0 - alpha) * (1.0 - alpha);
    float a = mix(21.5473, 25.3245, t);
    float b = mix(3.82987, 3.32435, t);
    float c = mix(0.19823, 0.16801, t);
    float d = mix(-1.97760, -1.27393, t);
    float e = mix(-4.32054, -4.85967, t);
    return a / (1.0 + b * pow(max(x, 0.0), c)) + d * x + e;
}

float sheen_lambda(float cos_theta, float alpha) {
    return cos_theta < 0.5 ? exp(sheen_l(cos_theta, alpha))
                           : exp(2.0 * sheen_l(0.5, alpha) - sheen_l(1.0 - cos_theta, alpha));
}

// The sheen BRDF with colour 1 times n·l: D·V·n·l with the Charlie visibility
// V = 1 / ((1 + Λ(n·v) + Λ(n·l)) · 4 n·v n·l), the n·l cancelled (finite at grazing light).
float sheen_brdf_cos(float n_l, float n_v, float n_h, float roughness) {
    if (n_l <= 0.0 || n_v <= 0.0) {
        return 0.0;
    }
    float alpha = max(roughness * roughness, 1e-3);
    float lambda = sheen_lambda(n_v, alpha) + sheen_lambda(n_l, alpha);
    return charlie_d(n_h, roughness) / ((1.0 + lambda) * 4.0 * n_v);
}

// Anisotropic GGX (KHR_materials_anisotropy) with roughness at along t and ab along b = n × t:
// D with the product written so that neither a small alpha nor a grazing half vector overflows.
float ggx_aniso_d(float t_h, float b_h, float n_h, float at, float ab) {
    float a2 = at * ab;
    vec3 f = vec3(ab * t_h, at * b_h, a2 * n_h);
    float w2 = a2 / dot(f, f);
    return a2 * w2 * w2 / PI;
}

float ggx_aniso_v(float t_v, float b_v, float n_v, float t_l, float b_l, float n_l, float at, float ab) {
    float gv = n_l * length(vec3(at * t_v, ab * b_v, n_v));
    float gl = n_v * length(vec3(at * t_l, ab * b_l, n_l));
    float s = gv + gl;
    return s > 0.0 ? 0.5 / s : 0.0;
}

float max3(vec3 c) {
    return max(c.r, max(c.g, c.b));
}

// Multiple-scattering energy compensation of a GGX lobe (Kulla & Conty 2017, in the single-table
// form of Fdez-Agüera 2019 that Filament uses): a single-scattering lobe of Fresnel F0 reflects
// about F0·Ess(n·v) of a white furnace, where Ess is its directional albedo with F = 1 (A + B of
// the DFG table): the light that scatters more than once between microfacets is lost, most for
// rough surfaces. Scaling the lobe by 1 + F0·(1/Ess - 1) restores it (a white metal reflects 1 at
// every roughness). ess = 1 gives the single-scattering lobe.
vec3 ggx_energy_compensation(vec3 f0, float ess) {
    return 1.0 + f0 * (1.0 / max(ess, 1e-2) - 1.0);
}

// ---- KHR_materials_iridescence: a thin dielectric film over the material ----
// Belcour & Barla 2017 ("A Practical Extension to Microfacet Theory for the Modeling of Varying
// Iridescence") in the form the extension specifies: Schlick's Fresnel at both interfaces of the
// film (air above, the base below), the Airy series of the waves reflected inside it summed to
// its first two orders, each order's spectrum integrated against the CIE 1931 colour matching
// functions in Fourier space (Gaussian fits), in linear Rec. 709. Ground truth: the f64 spectral
// Airy reflectance with the polarised Fresnel equations (tests/iridescence_truth.rs).

// Schlick's F0 between media of index a and b.
float film_f0(float a, float b) {
    float r = (a - b) / (a + b);
    return r * r;
}

// The Fourier transform of the colour matching functions at optical path difference opd (nm)
// and phase shift `shift`, in linear Rec. 709 (the fits of Belcour & Barla's supplemental).
vec3 film_sensitivity(float opd, vec3 shift) {
    float phase = 2.0 * PI * opd * 1e-9;
    const vec3 val = vec3(5.4856e-13, 4.4201e-13, 5.2481e-13);
    const vec3 pos = vec3(1.6810e+06, 1.7953e+06, 2.2084e+06);
    const vec3 var = vec3(4.3278e+09, 9.3046e+09, 6.6121e+09);
    vec3 xyz = val * sqrt(2.0 * PI * var) * cos(pos * phase + shift) * exp(-phase * phase * var);
    xyz.x += 9.7470e-14 * sqrt(2.0 * PI * 4.5282e+09) * cos(2.2399e+06 * phase + shift.x)
           * exp(-4.5282e+09 * phase * phase);
    xyz /= 1.0685e-7;
    return mat3(3.2404542, -0.9692660, 0.0556434,
                -1.5371385, 1.8760108, -0.2040259,
                -0.4985314, 0.0415560, 1.0572252) * xyz;
}

// The Fresnel reflectance (rgb) at cos θ = cos1 (outside, in air) of a film of index film_ior and
// `thickness` nanometres over a base whose Fresnel at normal incidence is base_f0 (a dielectric's
// F0 or a metal's base colour, read as a real index). Replaces Schlick's F in the BRDF.
vec3 iridescence_fresnel(float film_ior, float cos1, float thickness, vec3 base_f0) {
    // A vanishing film is no film: its index goes to the air's.
    float eta = mix(1.0, film_ior, smoothstep(0.0, 0.03, thickness));
    float c1 = clamp(cos1, 0.0, 1.0);
    float cos2_sq = 1.0 - (1.0 - c1 * c1) / (eta * eta);
    if (cos2_sq < 0.0) {
        return vec3(1.0);  // total internal reflection (a film of index below 1)
    }
    float cos2 = sqrt(cos2_sq);
    // Air to film (and back, the same): reflectance, transmittance, phase change on reflection.
    float r12 = film_f0(eta, 1.0);
    r12 += (1.0 - r12) * pow(1.0 - c1, 5.0);
    float t121 = 1.0 - r12;
    float phi21 = eta < 1.0 ? 0.0 : PI;
    // Film to base.
    vec3 sq = sqrt(clamp(base_f0, 0.0, 0.9999));
    vec3 base_ior = (1.0 + sq) / (1.0 - sq);
    vec3 r0 = (base_ior - eta) / (base_ior + eta);
    vec3 r23 = r0 * r0 + (1.0 - r0 * r0) * pow(1.0 - cos2, 5.0);
    vec3 phi23 = vec3(base_ior.r < eta ? PI : 0.0, base_ior.g < eta ? PI : 0.0, base_ior.b < eta ? PI : 0.0);
    // The Airy series: the mean (order 0) and two orders of the interference.
    float opd = 2.0 * eta * thickness * cos2;
    vec3 phi = phi21 + phi23;
    vec3 r123 = clamp(r12 * r23, 1e-5, 0.9999);
    vec3 rs = t121 * t121 * r23 / (1.0 - r123);
    vec3 result = r12 + rs;
    vec3 cm = rs - t121;
    for (int m = 1; m <= 2; ++m) {
        cm *= sqrt(r123);
        result += cm * 2.0 * film_sensitivity(float(m) * opd, float(m) * phi);
    }
    // The fits can leave the gamut below 0.
    return max(result, vec3(0.0));
}

// The glTF BRDF with KHR_materials_specular, _sheen and _anisotropy, times n·l, for light
// direction l and view direction v (both unit, away from the surface): the metal and the
// dielectric (Fresnel-mixed diffuse and specular, weighted by the specular factor) mixed by
// metallic, under the sheen layer, which scales them by its albedo:
// min(1 - max(sheen)·E(n·v), 1 - max(sheen)·E(n·l)). sheen_e = (E(n·v), E(n·l)) for the sheen
// roughness (the directional albedo of the sheen BRDF with colour 1; env_dfg.b on the GPU).
// ess: the GGX lobe's directional albedo Ess(n·v) at the roughness (env_dfg.r + .g), for the
// energy compensation of both specular lobes (1: single scattering).
vec3 gltf_brdf_cos(vec3 n, vec3 v, vec3 l, GltfSurface s, vec2 sheen_e, float ess) {
    float n_l = dot(n, l);
    float n_v = dot(n, v);
    if (n_l <= 0.0 || n_v <= 0.0) {
        return vec3(0.0);
    }
    vec3 h = normalize(l + v);
    float n_h = clamp(dot(n, h), 0.0, 1.0);
    float v_h = clamp(dot(v, h), 0.0, 1.0);
    float alpha = max(s.roughness * s.roughness, 1e-3);
    float dv;
    if (s.anisotropy > 0.0) {
        vec3 b = cross(n, s.t);
        float at = mix(alpha, 1.0, s.anisotropy * s.anisotropy);
        dv = ggx_aniso_d(dot(s.t, h), dot(b, h), n_h, at, alpha)
           * ggx_aniso_v(dot(s.t, v), dot(b, v), n_v, dot(s.t, l), dot(b, l), n_l, at, alpha);
    } else {
        dv = ggx_d(n_h, alpha) * smith_v(n_l, n_v, alpha);
    }
    float w = pow(1.0 - v_h, 5.0);
    vec3 fr = s.f0 + (1.0 - s.f0) * w;
    vec3 fm = s.base + (1.0 - s.base) * w;
    float reflected = max3(fr);
    if (s.iridescence > 0.0) {
        // KHR_materials_iridescence: the film's Fresnel at v·h mixed in by its weight, for the
        // specular lobes and for what the dielectric's diffuse keeps.
        vec3 fd = iridescence_fresnel(s.film_ior, v_h, s.film_thickness, s.f0);
        reflected = mix(reflected, max3(fd), s.iridescence);
        fr = mix(fr, fd, s.iridescence);
        fm = mix(fm, iridescence_fresnel(s.film_ior, v_h, s.film_thickness, s.base), s.iridescence);
    }
    vec3 dielectric = (1.0 - s.specular * reflected) * (1.0 - s.transmission) * s.base / PI
        + s.specular * fr * dv * ggx_energy_compensation(s.f0, ess);
    vec3 metal = fm * dv * ggx_energy_compensation(s.base, ess);
    vec3 f = mix(dielectric, metal, s.metallic) * n_l;
    if (max3(s.sheen) > 0.0) {
        // Clamped at 0: the Charlie lobe's albedo exceeds 1 at grazing angles and low roughness,
        // where the specification's scaling would go negative.
        float scale = max(min(1.0 - max3(s.sheen) * sheen_e.x, 1.0 - max3(s.sheen) * sheen_e.y), 0.0);
        f = f * scale + s.sheen * sheen_brdf_cos(n_l, n_v, n_h, s.sheen_roughness);
    }
    return f;
}

// ---- KHR_materials_transmission and KHR_materials_volume (the Khronos sample viewer's model:
// the lit opaque image behind, the "backdrop", seen along the refracted view ray) ----

// Where the view ray (v: towards the eye, unit), refracted into the surface (n: unit, facing v)
// with index of refraction ior, leaves a volume `thickness` thick: p + thickness · the refracted
// direction (a straight path of the thickness, not a traced one); p itself for a thin wall
// (thickness 0). A grazing ray that cannot refract (never entering a denser medium) goes straight.
vec3 transmission_exit(vec3 p, vec3 n, vec3 v, float thickness, float ior) {
    vec3 r = refract(-v, n, 1.0 / max(ior, 1.0));
    r = dot(r, r) > 0.0 ? normalize(r) : -v;
    return p + r * thickness;
}

// The backdrop's mip level (its level 0 `width` texels wide) for a lobe of roughness r refracted
// through ior: log2(width) · r · clamp(2·ior − 2, 0, 1) (no blur at ior 1, full at 1.5).
float transmission_lod(float roughness, float ior, float width) {
    return log2(max(width, 1.0)) * roughness * clamp(2.0 * ior - 2.0, 0.0, 1.0);
}

// KHR_materials_volume's Beer–Lambert attenuation over a path of length d: the attenuation colour
// to the power d / attenuation distance (distance 0 here: infinite, no attenuation).
vec3 volume_attenuation(float d, vec3 color, float distance) {
    return distance > 0.0 ? pow(max(color, vec3(0.0)), vec3(max(d, 0.0) / distance)) : vec3(1.0);
}

// KHR_materials_dispersion: the indices of refraction of the red, green and blue rays for a
// volume of index ior and dispersion 20/V (V the Abbe number). By the Abbe number's definition
// the blue (Fraunhofer F) and red (C) indices differ by (ior − 1)/V = (ior − 1) · 0.05 · dispersion:
// half of that below ior for red, half above for blue, green at ior.
vec3 dispersion_iors(float ior, float dispersion) {
    float half_spread = (ior - 1.0) * 0.025 * dispersion;
    return vec3(ior - half_spread, ior, ior + half_spread);
}

// The transmitted light's weight: what the dielectric's specular reflection (its split-sum albedo
// F0·A + B, weighted by KHR_materials_specular's weight) leaves, tinted by the base colour.
vec3 transmission_weight(vec3 f0, float specular, vec3 base, vec2 ab) {
    return max(1.0 - specular * (f0 * ab.x + ab.y), vec3(0.0)) * base;
}

// The roughness of the transmitted lobe: the surface's roughness widened by the index as the
// Khronos sample viewer widens it (applyIorToRoughness): alpha = roughness² · clamp(2·ior − 2, 0, 1),
// so no spread at ior 1 and the reflected lobe's at 1.5 and above.
float transmission_alpha(float roughness, float ior) {
    return max(roughness * roughness * clamp(2.0 * ior - 2.0, 0.0, 1.0), 1e-3);
}

// KHR_materials_transmission under a lamp: the BTDF times |n·l| for light l from behind a surface
// seen from the front (n·l < 0 < n·v), in the sample viewer's thin-surface form: l mirrored through
// the surface's plane (l_m = l − 2(n·l)n), the GGX lobe of transmission_alpha about the mirrored
// direction, (1 − specular·F(v·h)) of the base colour. The sample viewer leaves out the cosine;
// here D·V·|n·l| over the lower hemisphere integrates to the lobe's albedo Ess(n·v), as the
// reflected lobe's does (tests/transparency.rs checks it by quadrature). 0 for light in front.
// The caller weighs it by the transmission and (1 − metallic).
vec3 specular_btdf_cos(vec3 n, vec3 v, vec3 l, GltfSurface s, float ior) {
    float n_l = dot(n, l);
    float n_v = dot(n, v);
    if (!(n_l < 0.0) || !(n_v > 0.0)) {
        return vec3(0.0);
    }
    vec3 h = normalize(l - 2.0 * n_l * n + v);
    float n_h = clamp(dot(n, h), 0.0, 1.0);
    float v_h = clamp(dot(v, h), 0.0, 1.0);
    float alpha = transmission_alpha(s.roughness, ior);
    float dv = ggx_d(n_h, alpha) * smith_v(-n_l, n_v, alpha);
    vec3 fr = s.f0 + (1.0 - s.f0) * pow(1.0 - v_h, 5.0);
    return max(1.0 - s.specular * fr, vec3(0.0)) * s.base * (dv * -n_l);
}

// ---- KHR_materials_diffuse_transmission: a thin surface's diffuse lobe partly goes through ----

// The Lambertian BTDF times the cosine for light l from behind a surface seen from the front
// (n·l < 0 < n·v): colour/π·|n·l|, times what the dielectric's specular layer leaves at the view,
// 1 − specular·max(F(n·v)); 0 for light in front (the BRDF's side). The caller weighs it by the
// diffuse transmission and (1 − metallic)(1 − transmission).
vec3 diffuse_btdf_cos(vec3 n, vec3 v, vec3 l, GltfSurface s, vec3 color) {
    float n_l = dot(n, l);
    float n_v = dot(n, v);
    if (!(n_l < 0.0) || !(n_v > 0.0)) {
        return vec3(0.0);
    }
    float w = pow(1.0 - clamp(n_v, 0.0, 1.0), 5.0);
    vec3 fr = s.f0 + (1.0 - s.f0) * w;
    return color * (1.0 - s.specular * max3(fr)) * (-n_l / PI);
}

// ---- KHR_materials_clearcoat: a clear coat (ior 1.5, F0 0.04) over the material ----

// The coat's Fresnel at cos θ (Schlick, F0 0.04).
float clearcoat_fresnel(float cos_theta) {
    return 0.04 + 0.96 * pow(1.0 - clamp(cos_theta, 0.0, 1.0), 5.0);
}

// A lamp's f·cos through the coat (the specification's fresnel_coat): the material's f·cos
// `base_cos` times 1 − coat·Fc(nc·v) (what the coat reflects of the view, as the specification
// and the Khronos sample viewer weigh it), plus the coat's GGX lobe about its normal nc at its
// roughness with its own Fresnel, coat·Fc(v·h)·D(nc·h)·V·(nc·l).
vec3 clearcoat_brdf_cos(vec3 base_cos, vec3 nc, vec3 v, vec3 l, float coat, float roughness) {
    vec3 h = normalize(l + v);
    float fc = clearcoat_fresnel(dot(v, h));
    float n_l = dot(nc, l);
    float n_v = dot(nc, v);
    float layer = 0.0;
    if (n_l > 0.0 && n_v > 0.0) {
        float alpha = max(roughness * roughness, 1e-3);
        layer = ggx_d(clamp(dot(nc, h), 0.0, 1.0), alpha) * smith_v(n_l, n_v, alpha) * n_l;
    }
    return base_cos * (1.0 - coat * clearcoat_fresnel(dot(nc, v))) + vec3(coat * fc * layer);
}

// The core glTF metallic-roughness BRDF (no extensions, single scattering: what the DFG table
// integrates) times n·l.
vec3 pbr_brdf_cos(vec3 n, vec3 v, vec3 l, vec3 base, float metallic, float roughness) {
    return gltf_brdf_cos(n, v, l, gltf_surface(base, metallic, roughness), vec2(0.0), 1.0);
}

#endif
