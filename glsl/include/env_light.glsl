// Environment light (docs/fabric-model.md §6): the estimators of the light an environment map
// sends the fabric's lobes and the glTF BRDF's, at each level (weft::env::IblLevel: `mode` 1
// approx, 2 fis:N, 3 mc:N, with N = `samples`), and the sheen's layering. shade.glsl calls them
// for every pixel with an environment; glsl/env_probe.comp on a batch of inputs.
//
// Rust twins: weft::reference::env_light (f32, line for line, over any look-up of the
// environment), compared on the GPU by tests/env_probe_gpu.rs.
//
// The including shader defines the look-ups these read (the leaves: shade.glsl from the
// environment's cubes and the DFG table, env_probe.comp from closed-form stand-ins):
// - `vec3 env_radiance_at(vec3 world_dir, float lod)`: the radiance cube (box-filtered mips) at a
//   world direction and mip level, times the environment's intensity;
// - `vec3 env_prefiltered(vec3 world_dir, float roughness)`: the GGX-prefiltered specular cube at
//   a world direction and roughness (its level roughness · (levels − 1)), times the intensity;
// - `vec3 dfg_lookup(float cos_theta, float roughness)`: the DFG table (weft::env::dfg_table):
//   the split sum's A and B, and the sheen's directional albedo E;
// - `float env_face_size()`: the radiance cube's face size in texels (fis_lod's solid angles);
// - `vec2 lobe_albedo_texel(uint table, uint i, uint j)`: entry (i, j) of fabric record `table`'s
//   lobe albedo table (weft::reference::lobe_albedo: the weft lobe's albedo at rs 0 and at rs 1).
#ifndef WEFT_ENV_LIGHT_GLSL
#define WEFT_ENV_LIGHT_GLSL

#include "fabric.glsl"
#include "ibl.glsl"
#include "pbr.glsl"

vec3 env_radiance_at(vec3 world_dir, float lod);
vec3 env_prefiltered(vec3 world_dir, float roughness);
vec3 dfg_lookup(float cos_theta, float roughness);
float env_face_size();
vec2 lobe_albedo_texel(uint table, uint i, uint j);

// The lobe albedo tables' nodes (weft::reference::lobe_albedo): n·k2 = i/(MU-1), the view's azimuth
// from the lobe's long axis j/(PHI-1)·π/2.
const uint LOBE_ALBEDO_MU = 24u;
const uint LOBE_ALBEDO_PHI = 12u;

// The exact directional albedo ∫ ρs (n·k1) dk1 of the fabric's weft lobe (warp = false) or warp
// lobe (the weft lobe turned by 90°) for the view k2 with Fresnel rs, bilinear in fabric record
// `table`'s table over n·k2 and the view's azimuth folded into the first quadrant.
float fabric_lobe_albedo(uint table, vec3 k2, float rs, bool warp) {
    float ax = abs(warp ? k2.y : k2.x);
    float ay = abs(warp ? k2.x : k2.y);
    float phi = atan(ay, max(ax, 1e-20));
    float x = clamp(k2.z, 0.0, 1.0) * float(LOBE_ALBEDO_MU - 1u);
    float y = clamp(phi * (2.0 / FABRIC_PI), 0.0, 1.0) * float(LOBE_ALBEDO_PHI - 1u);
    uint i = min(uint(x), LOBE_ALBEDO_MU - 2u);
    uint j = min(uint(y), LOBE_ALBEDO_PHI - 2u);
    float fx = x - float(i);
    float fy = y - float(j);
    vec2 a = mix(lobe_albedo_texel(table, i, j), lobe_albedo_texel(table, i + 1u, j), fx);
    vec2 b = mix(lobe_albedo_texel(table, i, j + 1u), lobe_albedo_texel(table, i + 1u, j + 1u), fx);
    vec2 e = mix(a, b, fy);
    return mix(e.x, e.y, rs);
}

// A per-pixel offset in [0, 1)² for the Monte Carlo level (Cranley–Patterson rotation) from the
// pixel's integer coordinates: makes its error noise, not structured bias.
vec2 pixel_random(uvec2 p) {
    uint h = p.x * 1973u + p.y * 9277u + 26699u;
    h = (h ^ (h >> 16)) * 0x7feb352du;
    h = (h ^ (h >> 15)) * 0x846ca68bu;
    h = h ^ (h >> 16);
    uint g = h * 0x9e3779b9u;
    g = (g ^ (g >> 16)) * 0x7feb352du;
    return vec2(float(h >> 8), float(g >> 8)) / 16777216.0;
}

// Sample i of n: the Hammersley point shifted by `rotation` (0 for fis, pixel_random for mc).
vec2 ibl_sample(uint i, uint n, vec2 rotation) {
    return fract(hammersley(i, n) + rotation);
}

// The directional albedo E(cos θ) of the sheen BRDF with colour 1 at sheen roughness r: the DFG
// table's third channel (weft::env::dfg_table).
float sheen_albedo(float cos_theta, float r) {
    return dfg_lookup(clamp(cos_theta, 0.0, 1.0), r).b;
}

// The GGX lobe's directional albedo Ess(cos θ) = A + B at roughness r (the DFG table's first two
// channels), for ggx_energy_compensation.
float ggx_albedo(float cos_theta, float r) {
    vec2 ab = dfg_lookup(clamp(cos_theta, 0.0, 1.0), r).rg;
    return ab.x + ab.y;
}

// Irradiance/π from the environment at world normal n (times the intensity): the specular cube's
// roughness-1 level. GGX at α = 1 has D = 1/π, so with n = v its reflected directions are uniform
// over the sphere and the prefilter's n·l weight makes that level exactly the cosine-weighted mean
// of the radiance, 16² per face, each texel an exact sum over the radiance cube's 32² level
// (env_prefilter.comp; 256 filtered samples aliased with small bright lights, 8.6 % low under
// lightroom_14b straight up). The order-2 SH it replaces is
// band-limited: on a contrasted map (lightroom_14b) it was 14 % off in some directions.
vec3 env_irradiance(vec3 n) {
    return env_prefiltered(n, 1.0);
}

// The anisotropic GGX lobes (KHR_materials_anisotropy) under the environment at fis:N (issue 28:
// the split sum's bent normal left anisotropic metals nearly matte): N half vectors from the lobe's
// own distribution (the isotropic sampler at alpha 1 with its slopes stretched by (at, ab): GGX
// is stretch-invariant, so the pdf is D_aniso(h)·(n·h)), each direction's radiance filtered to the
// solid angle its pdf gives it (fis_lod, as for the fabric's lobes), weighted by the BRDF over
// the pdf, 4·Vis·F·(n·l)(v·h)/(n·h), both lobes with their energy compensation.
vec3 aniso_env_specular(vec3 n, vec3 v, GltfSurface s, float ess, uint samples) {
    vec3 b = cross(n, s.t);
    float alpha = max(s.roughness * s.roughness, 1e-3);
    float at = mix(alpha, 1.0, s.anisotropy * s.anisotropy);
    float nv = max(dot(n, v), 1e-4);
    vec3 comp_d = s.specular * ggx_energy_compensation(s.f0, ess);
    vec3 comp_m = ggx_energy_compensation(s.base, ess);
    vec3 sum = vec3(0.0);
    for (uint i = 0u; i < samples; ++i) {
        vec3 h1 = ggx_sample_h(ibl_sample(i, samples, vec2(0.0)), 1.0);
        vec3 hl = normalize(vec3(at * h1.x, alpha * h1.y, h1.z));
        vec3 h = hl.x * s.t + hl.y * b + hl.z * n;
        float vh = dot(v, h);
        if (!(vh > 0.0) || !(hl.z > 0.0)) {
            continue;
        }
        vec3 l = 2.0 * vh * h - v;
        float nl = dot(n, l);
        if (!(nl > 0.0)) {
            continue;
        }
        float pdf = ggx_aniso_d(hl.x, hl.y, hl.z, at, alpha) * hl.z / (4.0 * vh);
        float vis = ggx_aniso_v(dot(s.t, v), dot(b, v), nv, dot(s.t, l), dot(b, l), nl, at, alpha);
        float w = pow(1.0 - vh, 5.0);
        vec3 fd = s.f0 + (1.0 - s.f0) * w;
        vec3 fm = s.base + (1.0 - s.base) * w;
        if (s.iridescence > 0.0) {
            fd = mix(fd, iridescence_fresnel(s.film_ior, vh, s.film_thickness, s.f0), s.iridescence);
            fm = mix(fm, iridescence_fresnel(s.film_ior, vh, s.film_thickness, s.base), s.iridescence);
        }
        vec3 f = mix(fd * comp_d, fm * comp_m, s.metallic);
        sum += env_radiance_at(l, fis_lod(pdf, samples, env_face_size())) * f
             * (4.0 * vis * nl * vh / hl.z);
    }
    return sum / float(samples);
}

// What the layers below a sheen keep of light from the whole hemisphere, cosine-weighted: the
// lamps' scaling min(1 - k·E(n·v), 1 - k·E(n·l)) (gltf_brdf_cos; k = max(sheen colour)) averaged
// over n·l = μ with weight 2μ, i.e. over t = μ² uniformly, by a 16-point midpoint rule (within
// 0.007 of the integral; 8 points: 0.012). Light from grazing directions, where E is largest, is
// dimmed more than 1 - k·E(n·v) says (up to 0.11 more).
float sheen_layer_diffuse(float k, float e_v, float roughness) {
    float sum = 0.0;
    for (uint i = 0u; i < 16u; ++i) {
        float mu = sqrt((float(i) + 0.5) / 16.0);
        sum += min(1.0 - k * e_v, 1.0 - k * sheen_albedo(mu, roughness));
    }
    return max(sum / 16.0, 0.0);
}

// The glTF BRDF (with its extensions) under the environment: the prefiltered irradiance for the
// diffuse, the split sum for the specular and the sheen (approx and fis), or Monte Carlo (mc,
// `rot` its per-pixel rotation). ao: the occlusion texture (times the occlusion pass's
// visibility); bounce: the pass's coloured multi-bounce for diffuse light; indirect: more light
// from the occluders (irradiance/π: what the occlusion pass measured on screen beyond the
// multi-bounce fit, times the occlusion texture; 0 without it), which the diffuse and the sheen
// take besides the environment's. Anisotropy bends the
// look-up normal (McAuley's bent reflection vector, as Filament and the glTF Sample Viewer do) at
// approx and is sampled at fis; the sheen takes the irradiance times its albedo, and scales the
// layers below it (sheen_layer_diffuse for the diffuse, 1 - max(sheen)·E(n·v) for the specular).
// e_v: the sheen's albedo E(n·v) (0 without sheen), which the lamps' loop shares.
vec3 pbr_env(vec3 n, vec3 v, GltfSurface s, float ao, vec3 bounce, vec3 indirect, float e_v, uint mode, uint samples, vec2 rot) {
    vec3 base = s.base;
    float metallic = s.metallic;
    float roughness = s.roughness;
    float nv = clamp(dot(n, v), 1e-4, 1.0);
    bool has_sheen = max3(s.sheen) > 0.0;
    if (mode == 3u) {
        // Ground truth: the glTF BRDF itself (pbr_brdf_cos) over the unfiltered environment, each
        // sample pair one GGX-sampled and one cosine-sampled direction, weighted by the balance
        // heuristic (the mixture pdf of the two samplers).
        mat3 tbn = fabric_frame(n, any_perpendicular(n), 1.0);
        float alpha = max(roughness * roughness, 1e-3);
        float ess = ggx_albedo(nv, roughness);
        vec3 sum = vec3(0.0);
        for (uint i = 0u; i < samples; ++i) {
            vec2 xi = ibl_sample(i, samples, rot);
            vec3 h = tbn * ggx_sample_h(xi, alpha);
            vec3 dirs[2] = vec3[2](2.0 * dot(v, h) * h - v, tbn * cosine_sample(xi));
            for (uint k = 0u; k < 2u; ++k) {
                vec3 l = dirs[k];
                float nl = dot(n, l);
                if (!(nl > 0.0)) {
                    continue;
                }
                vec3 hl = normalize(l + v);
                float vh = dot(v, hl);
                float p_ggx = vh > 0.0 ? ggx_d(clamp(dot(n, hl), 0.0, 1.0), alpha) * clamp(dot(n, hl), 0.0, 1.0) / (4.0 * vh) : 0.0;
                float pdf = 0.5 * p_ggx + 0.5 * nl / PI;
                float e_l = has_sheen ? sheen_albedo(nl, s.sheen_roughness) : 0.0;
                sum += env_radiance_at(l, 0.0) * gltf_brdf_cos(n, v, l, s, vec2(e_v, e_l), ess) / pdf;
            }
        }
        return sum / float(2u * samples) * ao;
    }
    vec2 ab = dfg_lookup(nv, roughness).rg;
    // Each lobe with its multiple-scattering compensation, as for the lamps (gltf_brdf_cos); the
    // diffuse below takes what the compensated dielectric lobe leaves, so a white dielectric
    // still reflects exactly 1 of a white furnace.
    float ess = ab.x + ab.y;
    vec3 dielectric = (s.f0 * ab.x + ab.y) * ggx_energy_compensation(s.f0, ess);
    vec3 metal = (base * ab.x + ab.y) * ggx_energy_compensation(base, ess);
    if (s.iridescence > 0.0) {
        // KHR_materials_iridescence: the film's Fresnel at n·v times the lobe's albedo Ess
        // stands in for the split sum's F0·A + B (as the sample viewer does), mixed by its weight.
        vec3 fd = iridescence_fresnel(s.film_ior, nv, s.film_thickness, s.f0);
        dielectric = mix(dielectric, fd * ess * ggx_energy_compensation(s.f0, ess), s.iridescence);
        metal = mix(metal, iridescence_fresnel(s.film_ior, nv, s.film_thickness, base) * ess
                               * ggx_energy_compensation(base, ess), s.iridescence);
    }
    vec3 spec_albedo = mix(s.specular * dielectric, metal, metallic);
    vec3 bent = n;
    float lookup_roughness = roughness;
    if (s.anisotropy > 0.0) {
        vec3 b = cross(n, s.t);
        vec3 across = cross(b, v);
        vec3 an = cross(across, b);
        float bend = 1.0 - s.anisotropy * (1.0 - roughness);
        bend *= bend;
        vec3 m = mix(an, n, bend * bend);
        bent = dot(m, m) > 1e-12 ? normalize(m) : n;
        // The stretched lobe is wider than the isotropic one: look up the prefiltered radiance
        // at the roughness of the mean of its two alphas.
        float alpha = roughness * roughness;
        float at = mix(alpha, 1.0, s.anisotropy * s.anisotropy);
        lookup_roughness = sqrt(0.5 * (at + alpha));
    }
    vec3 r = dominant_dir(n, reflect(-v, bent), lookup_roughness);
    vec3 prefiltered = env_prefiltered(r, lookup_roughness);
    vec3 irradiance = env_irradiance(n);
    vec3 diffuse = (irradiance * ao * bounce + indirect) * base * (1.0 - metallic)
                 * (1.0 - s.specular * max3(dielectric)) * (1.0 - s.transmission);
    // fis: an anisotropic lobe is sampled (the bent normal above stays approx's).
    vec3 specular = mode == 2u && s.anisotropy > 0.0 ? aniso_env_specular(n, v, s, ess, samples)
                                                     : prefiltered * spec_albedo;
    specular *= specular_occlusion(nv, ao, roughness);
    if (!has_sheen) {
        return diffuse + specular;
    }
    // Under a sheen the specular's light comes from about the mirror direction (n·l ≈ n·v): scaled
    // by 1 - k·E(n·v); the diffuse's from the whole hemisphere: sheen_layer_diffuse. The Charlie
    // lobe is broad and lives near the horizon: its light is closer to the cosine-weighted mean
    // (the irradiance / π) than to any prefiltered GGX look-up. Sampling it instead (uniform
    // directions weighted by the lobe, normalised, in v's frame) measured worse at 8 samples
    // (velvet 4.7 % against 4.0 %) and little better at 64 (3.8 %).
    float k = max3(s.sheen);
    return diffuse * sheen_layer_diffuse(k, e_v, s.sheen_roughness)
         + specular * max(1.0 - k * e_v, 0.0)
         + s.sheen * e_v * (irradiance * cone_occlusion(nv, ao, s.sheen_roughness) + indirect);
}

// The weft lobe's share of the mixture the samples draw from: its thread coverage's share,
// kept within [0.05, 0.95] so neither lobe goes unsampled (0.5 where no thread covers).
float fabric_lobe_weft_weight(vec4 coverage) {
    float c_thread = coverage.x + coverage.y;
    return c_thread > 0.0 ? clamp(coverage.y / c_thread, 0.05, 0.95) : 0.5;
}

// One sample of fabric_env_lobe_sums at the unit square's point xi (before the lobe choice
// stretches it), added to each lobe's (Σ w·L, Σ w). Rust twin: fabric_env_lobe_sample.
void fabric_env_lobe_sample(mat3 tbn, vec3 k2, GpuFabric f, float w_weft, uint mode, vec2 xi, uint lod_samples, inout vec4 weft, inout vec4 warp) {
    bool pick_weft = xi.x < w_weft;
    xi.x = pick_weft ? xi.x / w_weft : (xi.x - w_weft) / (1.0 - w_weft);
    xi.x = min(xi.x, 0.99999994);
    // One sampler call with the picked lobe's exponents (a choice between two calls would
    // run both where a branch costs every lane).
    float e;
    float log_cos;
    vec3 h = as_sample_h_log(xi, pick_weft ? f.e_along : f.e_across,
                             pick_weft ? f.e_across : f.e_along, e, log_cos);
    float kh = dot(k2, h);
    if (!(kh > 0.0)) {
        return;
    }
    vec3 k1 = 2.0 * kh * h - k2;
    if (!(k1.z > 0.0)) {
        return;
    }
    // Each lobe's estimate f·cos/pdf with pdf the mixture of the two samplers: a lobe is
    // as_lobe_factor·hn^E and its sampler's pdf as_norm/(2π)·hn^E/(4 kh) (fabric.glsl), so
    // hn^E of each orientation is computed once and shared by both: from the sample's
    // log2 cos θ, the two exponents at its φ adding up to e_along + e_across.
    float e_other = f.e_along + f.e_across - e;
    float p_weft = exp2((pick_weft ? e : e_other) * log_cos);
    float p_warp = exp2((pick_weft ? e_other : e) * log_cos);
    float mixed = w_weft * p_weft + (1.0 - w_weft) * p_warp;
    if (!(mixed > 0.0)) {
        return;
    }
    float pdf = as_norm(f.e_along, f.e_across) / (2.0 * FABRIC_PI) * mixed / (4.0 * kh);
    float factor = as_lobe_factor(k1.z, k2.z, min(kh, 1.0), f.e_along, f.e_across, f.rs);
    float common_w = factor * k1.z / pdf;
    float lod = mode == 3u ? 0.0 : fis_lod(pdf, lod_samples, env_face_size());
    vec3 l = env_radiance_at(tbn * k1, lod) * common_w;
    weft += vec4(l, common_w) * p_weft;
    warp += vec4(l, common_w) * p_warp;
}

// The sums of the fabric's lobe estimators (fis and mc): per lobe (Σ w·L, Σ w) over `samples`
// samples of the coverage-weighted mixture of the two lobes' A–S samplers (one-sample MIS, so
// both lobes use every sample). `block` 0: the Hammersley set shifted by `rot` (fis: 0, a pixel
// alone; mc: the pixel's rotation); b ≥ 1: block b − 1 of the Sobol' (0,2)-sequence (sobol_block:
// pixels that pool take different blocks, which together are one well-spread set; alone, a
// block is no better than the Hammersley set, and worse once the lobe choice splits it: the
// bench's lobes mid and far views lost 1.5-2 dB with it). fis's mip level is chosen for
// `lod_samples` samples (all the samples a pixel's neighbourhood pools, or `samples`), mc's
// unfiltered. w is f·cos/pdf times the lobe's hn^E; fabric_env_lobes_resolve turns the sums
// into radiance.
void fabric_env_lobe_sums(mat3 tbn, vec3 k2, vec4 coverage, GpuFabric f, uint mode, uint samples, vec2 rot, uint block, uint lod_samples, out vec4 weft, out vec4 warp) {
    weft = vec4(0.0);
    warp = vec4(0.0);
    if (!(k2.z > 0.0)) {
        return;
    }
    float w_weft = fabric_lobe_weft_weight(coverage);
    for (uint i = 0u; i < samples; ++i) {
        vec2 xi = block == 0u ? ibl_sample(i, samples, rot) : sobol_block(i, samples, block - 1u);
        fabric_env_lobe_sample(tbn, k2, f, w_weft, mode, xi, lod_samples, weft, warp);
    }
}

// How many times its base count of fis samples a woven pixel takes (issue 31 item 1): the
// lobes' error is where they are bright, at grazing views (the Fresnel factor rises from rs
// toward 1, and the samples the horizon cuts off are lost), so a pixel takes 0.6 times its
// Schlick Fresnel at n·k2 over the cloth's rs times the samples, 1 to 7 times (rs at least
// 0.02, so an rs = 0 cloth is not all grazing). Measured (weft bench --ibl, close-up, 480x270):
// half the Fresnel up to 6 took 37.8 -> 40.0 dB close up at about the same lighting-pass time,
// the pooled pixels' base count halved; 0.6 up to 7, once the sample loop was flattened, 40.7 dB
// at 1.4x the time of a pixel alone (docs/performance.md).
uint fabric_lobe_passes(float nk2, float rs) {
    float x = 1.0 - clamp(nk2, 0.0, 1.0);
    float x2 = x * x;
    float fresnel = rs + (1.0 - rs) * (x2 * x2 * x);
    return clamp(uint(0.6 * fresnel / max(rs, 0.02) + 0.5), 1u, 7u);
}

// One woven pixel's lobe sums as fabric_lobes.frag takes them, at fis: `passes`
// (fabric_lobe_passes) times its samples. A pixel alone (`block` 0) takes the Hammersley set of
// samples · passes; a pixel that pools (`block` b ≥ 1: 1 + its place in a window of `window`
// pixels, fabric_pool_block) takes `passes` blocks of samples / 2 of the Sobol' sequence (b,
// b + window, b + 2·window, ...: no two pixels of a window share one) with the mip level for
// `pixels` pixels' samples (a pooled pixel takes half the base count: a window of agreeing
// pixels' samples are more than a pixel alone needs).
void fabric_pixel_lobe_sums(mat3 tbn, vec3 k2, vec4 coverage, GpuFabric f, uint samples, uint block, uint window, uint pixels, out vec4 weft, out vec4 warp) {
    uint passes = fabric_lobe_passes(k2.z, f.rs);
    bool pooled = block != 0u;
    uint unit = pooled ? max(samples / 2u, 1u) : samples * passes;
    uint lod_samples = pooled ? unit * passes * pixels : unit;
    weft = vec4(0.0);
    warp = vec4(0.0);
    if (!(k2.z > 0.0)) {
        return;
    }
    float w_weft = fabric_lobe_weft_weight(coverage);
    // One loop over every sample, for both (llvmpipe runs both sides of an if for a vector of
    // pixels), and not a loop of passes around a loop of samples: llvmpipe runs a loop's body
    // once more under an empty mask after every lane has left, and an inner loop once more per
    // outer turn.
    for (uint n = 0u; n < (pooled ? unit * passes : unit); ++n) {
        uint k = n / unit;
        vec2 xi = pooled ? sobol_block(n - k * unit, unit, block - 1u + window * k) : ibl_sample(n, unit, vec2(0.0));
        fabric_env_lobe_sample(tbn, k2, f, w_weft, 2u, xi, lod_samples, weft, warp);
    }
}

// The lobes' radiance from fabric_env_lobe_sums' sums over `samples` samples (or, as the
// deferred lighting pools them, the sum of `samples` pixels' fabric_lobe_unpack). fis takes from the samples only the lobe's weighted mean radiance (a ratio estimator:
// Σ w L / Σ w, bounded by the brightest sample whatever the weights) and its albedo from fabric
// record `table`'s exact table (fabric_lobe_albedo): eight fixed samples' own estimate of the
// albedo was the larger half of their error (issue 31 item 1; docs/performance.md). A lobe its
// samples together weigh under 1e-6 of one sample's full weight has no sample on it (no sample
// above the horizon, or only the far tails of a sample of the other lobe, whose hn^E underflows
// differently on each device): it stays dark, as the plain estimate leaves it. mc: the plain
// unbiased estimate Σ w L / samples.
void fabric_env_lobes_resolve(vec4 weft_sum, vec4 warp_sum, vec3 k2, GpuFabric f, uint table, uint mode, uint samples, out vec3 weft, out vec3 warp) {
    if (mode == 2u) {
        float w_min = 1e-6 * float(samples);
        weft = weft_sum.w > w_min ? weft_sum.rgb / weft_sum.w * fabric_lobe_albedo(table, k2, f.rs, false) : vec3(0.0);
        warp = warp_sum.w > w_min ? warp_sum.rgb / warp_sum.w * fabric_lobe_albedo(table, k2, f.rs, true) : vec3(0.0);
        return;
    }
    weft = weft_sum.rgb / float(samples);
    warp = warp_sum.rgb / float(samples);
}

// Three non-negative values under one exponent, as VK_FORMAT_E5B9G9R9_UFLOAT_PACK32 holds them
// (nine-bit mantissas, the exponent from the largest, rounded to nearest; values above 65408
// clamped, NaN read as 0).
uint rgb9e5_pack(vec3 c) {
    // max(x, 0) turns NaN into 0 on every device.
    c = min(max(c, vec3(0.0)), vec3(65408.0));
    float m = max(max(c.r, c.g), c.b);
    int e2;
    frexp(m, e2);
    // m = mantissa · 2^e2 with the mantissa in [0.5, 1): floor(log2 m) = e2 − 1; the shared
    // exponent is that + 16 (bias 15, one more for the mantissa's leading bit), at least 0.
    int e = m > 0.0 ? max(e2 + 15, 0) : 0;
    float scale = exp2(float(24 - e));
    if (floor(m * scale + 0.5) >= 512.0) {
        e += 1;
        scale *= 0.5;
    }
    uvec3 q = uvec3(floor(c * scale + 0.5));
    return q.r | (q.g << 9u) | (q.b << 18u) | (uint(e) << 27u);
}

vec3 rgb9e5_unpack(uint p) {
    vec3 q = vec3(float(p & 511u), float((p >> 9u) & 511u), float((p >> 18u) & 511u));
    return q * exp2(float(int(p >> 27u) - 24));
}

// Two non-negative values as the top 16 bits of their f32 (bfloat16: 8 exponent and 7 mantissa
// bits, rounded), in integer arithmetic: packHalf2x16 took lavapipe down with SIGILL at
// LP_NATIVE_VECTOR_WIDTH=128 (Mesa 22.3.6, its CPU caps at SSE4.1).
uint bf16x2_pack(vec2 v) {
    // max(x, 0) turns NaN into 0; the bound keeps the rounding below infinity.
    uvec2 b = floatBitsToUint(min(max(v, vec2(0.0)), vec2(3.0e38)));
    b = (b + 0x8000u) >> 16u;
    return b.x | (b.y << 16u);
}

vec2 bf16x2_unpack(uint p) {
    return uintBitsToFloat(uvec2(p << 16u, p & 0xffff0000u));
}

// One pixel's lobe sums (fabric_env_lobe_sums over `samples` samples) as fabric_lobes.frag
// writes them for the deferred lighting to pool: per lobe its weighted mean radiance
// Σ w·L / Σ w (x: weft, y: warp, rgb9e5_pack) and its weight Σ w / samples (z: both,
// bf16x2_pack; `samples` the base count, the same for every pixel, so that a pixel that took more
// samples weighs more; a weight only weighs one pixel's mean against its neighbours'), and `mask` (w: which
// pixels around it pool with it).
uvec4 fabric_lobe_pack(vec4 weft, vec4 warp, uint samples, uint mask) {
    vec3 weft_mean = weft.w > 0.0 ? weft.rgb / weft.w : vec3(0.0);
    vec3 warp_mean = warp.w > 0.0 ? warp.rgb / warp.w : vec3(0.0);
    vec2 weights = vec2(weft.w, warp.w) / float(samples);
    return uvec4(rgb9e5_pack(weft_mean), rgb9e5_pack(warp_mean), bf16x2_pack(weights), mask);
}

// fabric_lobe_pack's texel back as sums per sample: per lobe (mean · weight, weight).
void fabric_lobe_unpack(uvec4 texel, out vec4 weft, out vec4 warp) {
    vec2 w = bf16x2_unpack(texel.z);
    weft = vec4(rgb9e5_unpack(texel.x) * w.x, w.x);
    warp = vec4(rgb9e5_unpack(texel.y) * w.y, w.y);
}

// The fabric's two specular lobes under the environment, each without its coverage:
// (weft lobe, warp lobe) radiance. approx: the radiance in the mirror direction blurred to the
// lobe's width times the lobe's exact albedo; fis / mc: fabric_env_lobe_sums (mc: rotated by
// `rot`, unfiltered) and fabric_env_lobes_resolve, for one pixel alone (the deferred lighting
// pools a neighbourhood's samples instead: fabric_lobes.frag and lighting.frag).
void fabric_env_lobes(mat3 tbn, vec3 k2, vec4 coverage, GpuFabric f, uint table, uint mode, uint samples, vec2 rot, out vec3 weft, out vec3 warp) {
    weft = vec3(0.0);
    warp = vec3(0.0);
    // rs = 0 keeps its lobes: Schlick's Fresnel is (1 - c)^5 there, not 0 (as for the lamps).
    if (!(k2.z > 0.0)) {
        return;
    }
    if (mode == 1u) {
        vec3 r = tbn * vec3(-k2.x, -k2.y, k2.z);
        float peak = sqrt((f.e_along + 1.0) * (f.e_across + 1.0)) / (8.0 * FABRIC_PI);
        // One sample at the mirror direction, blurred to the lobe's peak solid angle (+1 level:
        // the box mips blur less than the lobe's tails reach), times each lobe's exact albedo
        // (it was Schlick's Fresnel at n·k2: 12 % off the albedo under a white map, +117 % for
        // an rs = 0 cloth's lobes).
        vec3 l = env_radiance_at(r, fis_lod(peak, 1u, env_face_size()) + 1.0);
        weft = l * fabric_lobe_albedo(table, k2, f.rs, false);
        warp = l * fabric_lobe_albedo(table, k2, f.rs, true);
        return;
    }
    vec4 weft_sum;
    vec4 warp_sum;
    fabric_env_lobe_sums(tbn, k2, coverage, f, mode, samples, rot, 0u, samples, weft_sum, warp_sum);
    fabric_env_lobes_resolve(weft_sum, warp_sum, k2, f, table, mode, samples, weft, warp);
}

// The fabric's diffuse under the environment, without its coverage: irradiance/π times the
// diffuse factor (mc: cosine-sampled, unfiltered, rotated by `rot`).
vec3 fabric_env_diffuse(mat3 tbn, vec3 k2, GpuFabric f, uint mode, uint samples, vec2 rot) {
    if (mode == 3u) {
        vec3 sum = vec3(0.0);
        for (uint i = 0u; i < samples; ++i) {
            vec3 k1 = cosine_sample(ibl_sample(i, samples, rot));
            float factor = (f.flags & FABRIC_FLAG_COUPLED_DIFFUSE) != 0u ? coupled_diffuse(f.rs, k1.z, k2.z) * FABRIC_PI : 1.0;
            sum += env_radiance_at(tbn * k1, 0.0) * factor;
        }
        return sum / float(samples);
    }
    vec3 n = tbn[2];
    return env_irradiance(n) * fabric_diffuse_albedo(f, k2.z);
}

// The irradiance/π on a sheet's far side from the environment (mc: cosine-sampled over the far
// hemisphere, unfiltered, rotated by `rot`): what its threads pass through, times τ and their
// albedo.
vec3 fabric_env_back(mat3 tbn, uint mode, uint samples, vec2 rot) {
    if (mode == 3u) {
        vec3 sum = vec3(0.0);
        for (uint i = 0u; i < samples; ++i) {
            vec3 k = cosine_sample(ibl_sample(i, samples, rot));
            sum += env_radiance_at(tbn * vec3(k.xy, -k.z), 0.0);
        }
        return sum / float(samples);
    }
    return env_irradiance(-tbn[2]);
}

// The fabric's environment light for one coverage: the diffuse with the threads' albedo and the
// thread shadowing (as for lamps), each lobe weighted by its thread's coverage, and for a sheet
// (`sheets`: the shader draws fabric sheets) the light its threads pass from its far side (back:
// fabric_env_back; 0 for any other cloth). indirect: as pbr_env's, for the diffuse (times its
// diffuse factor at nv).
vec3 fabric_env_combine(vec4 coverage, GpuFabric f, vec3 diffuse, vec3 weft, vec3 warp, vec3 back, float ao, vec3 bounce, vec3 indirect, float nv, bool sheets) {
    vec3 rd = fabric_albedo(coverage, sheets ? fabric_reflecting(f) : f);
    // (Every accuracy level uses the two lobes here: the environment integral of one lobe with
    // averaged exponents would need a sampler of its own.)
    vec3 radiance = rd * (diffuse * ao * bounce + indirect * fabric_diffuse_albedo(f, nv))
                  + (coverage.y * weft + coverage.x * warp) * specular_occlusion(nv, ao, 0.5);
    if (sheets) {
        radiance += back * fabric_passed(coverage, f);
    }
    return radiance;
}

#endif
