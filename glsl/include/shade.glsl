// Shading one surface point from its G-buffer values (surface.glsl's GSurface, decoded): every
// light of its tile, the environment and the shadows, with the fabric model or the glTF BRDF. The
// deferred lighting pass (lighting.frag) calls it for each pixel from the targets; the forward
// pass (forward.frag, alphaMode BLEND) for each fragment, so both light a surface alike. The
// including shader declares `frame`, `lights`, `materials`, `fabrics`, `shadow_atlas`, `shadows`,
// `tile_lights`, `env_radiance`, `env_specular`, `env_dfg` and the specialization constants
// ACCURACY, SAMPLES, FABRIC_AS_PBR, LIGHT_TYPES, SHADING, SHADOWS, RANGE_CULLING, IBL,
// IBL_SAMPLES, UNLIT, TRANSMISSION, COAT, DIFFUSE_TRANSMISSION, IRIDESCENCE and FABRIC_SHEETS, and defines `transmitted_light` (forward.frag: from the
// backdrop; lighting.frag, whose TRANSMISSION is 0: nothing).

// The light seen through a transmissive surface (KHR_materials_transmission and _volume) at p
// with normal n towards v: transmission = (factor, thickness, attenuation distance, ior),
// attenuation: the attenuation colour. Defined by the including shader.
vec3 transmitted_light(vec3 p, vec3 n, vec3 v, GltfSurface s, vec4 transmission, vec4 attenuation);

#include "lights.glsl"

// The pixel's tile's light list: (offset into tile_lights, count).
uvec2 tile_list() {
    uvec2 t = uvec2(gl_FragCoord.xy) / 16u;
    uint index = t.y * frame.tile_columns + t.x;
    return uvec2(tile_lights[2u * index], tile_lights[2u * index + 1u]);
}


// How much of light `light` reaches world point p with normal n (1 lit, 0 shadowed), from its
// shadow map with PCF: 3 x 3 bilinear depth comparisons `radius` tile texels apart, tent-weighted.
// 1 for lights without a shadow map, surfaces that do not receive, and points outside the map.
float shadow_factor(Light light, vec3 p, vec3 n, float receives) {
    if (SHADOWS == 0u) {
        return 1.0;
    }
    int index = int(light.spot.z + 0.5) - 1;
    if (index < 0 || receives < 0.5) {
        return 1.0;
    }
    Shadow s = shadows[index];
    // Normal offset: move the look-up point off the surface by about a texel's footprint, so a
    // lit surface does not shadow itself (acne), scaled with the distance for a perspective map.
    float offset = s.params.x;
    if (s.params.y > 0.5) {
        offset *= length(light.position_range.xyz - p);
    }
    vec4 clip = s.clip_from_world * vec4(p + n * offset, 1.0);
    if (!(clip.w > 0.0)) {
        return 1.0;
    }
    vec3 ndc = clip.xyz / clip.w;
    if (any(greaterThan(abs(ndc.xy), vec2(1.0))) || ndc.z > 1.0) {
        return 1.0;
    }
    // Beyond the map's far plane (a receiver behind every caster, such as a ground that casts
    // nothing): in shadow wherever the map holds any caster, so compare with depth 0.
    ndc.z = max(ndc.z, 0.0);
    vec2 uv = s.tile.xy + (ndc.xy * 0.5 + 0.5) * s.tile.zw;
    float texel = s.params.w;
    // Keep every bilinear footprint inside the tile.
    vec2 lo = s.tile.xy + vec2(texel);
    vec2 hi = s.tile.xy + s.tile.zw - vec2(texel);
    float radius = s.params.z;
    if (radius <= 0.0) {
        return texture(shadow_atlas, vec3(clamp(uv, lo, hi), ndc.z));
    }
    float sum = 0.0;
    for (int j = -1; j <= 1; ++j) {
        for (int i = -1; i <= 1; ++i) {
            float w = float((2 - abs(i)) * (2 - abs(j)));
            vec2 q = clamp(uv + vec2(float(i), float(j)) * radius * texel, lo, hi);
            sum += w * texture(shadow_atlas, vec3(q, ndc.z));
        }
    }
    return sum / 16.0;
}

// One fabric BRDF evaluation at the chosen accuracy: nearest and filtered-params evaluate one lobe
// with coverage-averaged exponents (at a point that is the thread on top's own lobe), mixture and
// supersampled the two-lobe mixture.
vec3 fabric_eval(vec3 k1, vec3 k2, vec4 coverage, GpuFabric f) {
    if (ACCURACY <= 1u) {
        return fabric_brdf_averaged(k1, k2, coverage, f);
    }
    return fabric_brdf(k1, k2, coverage, f);
}

// Ambient plus every light reflected by the fabric with the given coverage; a sheet's threads
// also pass on the ambient and the lights behind it (ambient_back: the ambient on its far side).
vec3 fabric_radiance(vec3 p, vec3 ambient, vec3 ambient_back, mat3 tbn, vec3 k2, vec4 coverage, GpuFabric f, float receives) {
    // A sheet's threads reflect the 1 − τ of their diffuse light that they do not pass through.
    GpuFabric fr = FABRIC_SHEETS != 0u ? fabric_reflecting(f) : f;
    // Ambient: the threads' diffuse albedo under the hemispherical ambient.
    vec3 radiance = ambient * fabric_albedo(coverage, fr);
    bool sheet = FABRIC_SHEETS != 0u && (f.flags & FABRIC_FLAG_SHEET) != 0u;
    if (sheet) {
        radiance += ambient_back * fabric_passed(coverage, f);
    }
    uvec2 list = tile_list();
    for (uint j = 0u; j < list.y; ++j) {
        uint i = tile_lights[list.x + j];
        vec3 l;
        vec3 e = light_incoming(lights[i], p, l);
        vec3 k1 = fabric_local(l, tbn);
        if (all(equal(e, vec3(0.0)))) {
            continue;
        }
        if (k1.z > 0.0) {
            radiance += e * (fabric_eval(k1, k2, coverage, fr) * k1.z * shadow_factor(lights[i], p, tbn[2], receives));
        } else if (sheet && k1.z < 0.0) {
            // A lamp behind the sheet, through its threads (its shadow map looked up from the
            // far side).
            radiance += e * (fabric_btdf(k1, k2, coverage, f) * -k1.z * shadow_factor(lights[i], p, -tbn[2], receives));
        }
    }
    return radiance;
}

// Ambient plus every light reflected by one of the comparison models (Phong or plain A–S).
vec3 classic_radiance(vec3 p, vec3 ambient, mat3 tbn, vec3 k2, GpuFabric f, float receives) {
    vec3 radiance = ambient * fabric_mean_rd(f);
    uvec2 list = tile_list();
    for (uint j = 0u; j < list.y; ++j) {
        uint i = tile_lights[list.x + j];
        vec3 l;
        vec3 e = light_incoming(lights[i], p, l);
        vec3 k1 = fabric_local(l, tbn);
        if (k1.z <= 0.0 || all(equal(e, vec3(0.0)))) {
            continue;
        }
        vec3 brdf = SHADING == SHADING_PHONG ? phong_brdf(k1, k2, f) : plain_as_brdf(k1, k2, f);
        radiance += e * brdf * (k1.z * shadow_factor(lights[i], p, tbn[2], receives));
    }
    return radiance;
}


// ---- Environment lighting (docs/fabric-model.md §6) ----

vec3 env_radiance_at(vec3 world_dir, float lod) {
    vec3 d = env_dir(world_dir, frame.env_rot0, frame.env_rot1, frame.env_rot2);
    return textureLod(env_radiance, d, lod).rgb * frame.env_params.x;
}

// A per-pixel offset in [0, 1)² for the Monte Carlo level (Cranley–Patterson rotation): makes its
// error noise, not structured bias.
vec2 pixel_random() {
    uvec2 p = uvec2(gl_FragCoord.xy);
    uint h = p.x * 1973u + p.y * 9277u + 26699u;
    h = (h ^ (h >> 16)) * 0x7feb352du;
    h = (h ^ (h >> 15)) * 0x846ca68bu;
    h = h ^ (h >> 16);
    uint g = h * 0x9e3779b9u;
    g = (g ^ (g >> 16)) * 0x7feb352du;
    return vec2(float(h >> 8), float(g >> 8)) / 16777216.0;
}

vec2 ibl_sample(uint i, uint n, vec2 rotation) {
    return fract(hammersley(i, n) + rotation);
}

// The directional albedo E(cos θ) of the sheen BRDF with colour 1 at sheen roughness r: the DFG
// table's third channel (weft::env::dfg_table).
float sheen_albedo(float cos_theta, float r) {
    return textureLod(env_dfg, vec2(clamp(cos_theta, 0.0, 1.0), r), 0.0).b;
}

// The GGX lobe's directional albedo Ess(cos θ) = A + B at roughness r (the DFG table's first two
// channels), for ggx_energy_compensation.
float ggx_albedo(float cos_theta, float r) {
    vec2 ab = textureLod(env_dfg, vec2(clamp(cos_theta, 0.0, 1.0), r), 0.0).rg;
    return ab.x + ab.y;
}

// Irradiance/π from the environment at world normal n (times the intensity): the specular cube's
// roughness-1 level. GGX at α = 1 has D = 1/π, so with n = v its reflected directions are uniform
// over the sphere and the prefilter's n·l weight makes that level exactly the cosine-weighted mean
// of the radiance, 16² per face from 512 filtered samples. The order-2 SH it replaces is
// band-limited: on a contrasted map (lightroom_14b) it was 14 % off in some directions.
vec3 env_irradiance(vec3 n) {
    vec3 d = env_dir(n, frame.env_rot0, frame.env_rot1, frame.env_rot2);
    return textureLod(env_specular, d, frame.env_params.y).rgb * frame.env_params.x;
}

// The anisotropic GGX lobes (KHR_materials_anisotropy) under the environment at fis:N (issue 28:
// the split sum's bent normal left anisotropic metals nearly matte): N half vectors from the lobe's
// own distribution (the isotropic sampler at alpha 1 with its slopes stretched by (at, ab): GGX
// is stretch-invariant, so the pdf is D_aniso(h)·(n·h)), each direction's radiance filtered to the
// solid angle its pdf gives it (fis_lod, as for the fabric's lobes), weighted by the BRDF over
// the pdf, 4·Vis·F·(n·l)(v·h)/(n·h), both lobes with their energy compensation.
vec3 aniso_env_specular(vec3 n, vec3 v, GltfSurface s, float ess) {
    vec3 b = cross(n, s.t);
    float alpha = max(s.roughness * s.roughness, 1e-3);
    float at = mix(alpha, 1.0, s.anisotropy * s.anisotropy);
    float nv = max(dot(n, v), 1e-4);
    vec3 comp_d = s.specular * ggx_energy_compensation(s.f0, ess);
    vec3 comp_m = ggx_energy_compensation(s.base, ess);
    vec3 sum = vec3(0.0);
    for (uint i = 0u; i < IBL_SAMPLES; ++i) {
        vec3 h1 = ggx_sample_h(ibl_sample(i, IBL_SAMPLES, vec2(0.0)), 1.0);
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
        sum += env_radiance_at(l, fis_lod(pdf, IBL_SAMPLES, frame.env_params.z)) * f
             * (4.0 * vis * nl * vh / hl.z);
    }
    return sum / float(IBL_SAMPLES);
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

// The glTF BRDF (with its extensions) under the environment: SH irradiance for the diffuse, the
// split sum for the specular and the sheen (approx and fis), or Monte Carlo (mc). ao: the
// occlusion texture. Anisotropy bends the look-up normal (McAuley's bent reflection vector, as
// Filament and the glTF Sample Viewer do); the sheen takes the SH irradiance times its albedo,
// and scales the layers below it (sheen_layer_diffuse for the diffuse, 1 - max(sheen)·E(n·v)
// for the specular).
// e_v: the sheen's albedo E(n·v) (0 without sheen), which the lamps' loop shares.
vec3 pbr_env(vec3 n, vec3 v, GltfSurface s, float ao, vec3 bounce, float e_v) {
    vec3 base = s.base;
    float metallic = s.metallic;
    float roughness = s.roughness;
    float nv = clamp(dot(n, v), 1e-4, 1.0);
    bool has_sheen = max3(s.sheen) > 0.0;
    if (IBL == 3u) {
        // Ground truth: the glTF BRDF itself (pbr_brdf_cos) over the unfiltered environment, each
        // sample pair one GGX-sampled and one cosine-sampled direction, weighted by the balance
        // heuristic (the mixture pdf of the two samplers).
        mat3 tbn = fabric_frame(n, any_perpendicular(n), 1.0);
        float alpha = max(roughness * roughness, 1e-3);
        float ess = ggx_albedo(nv, roughness);
        vec2 rot = pixel_random();
        vec3 sum = vec3(0.0);
        for (uint i = 0u; i < IBL_SAMPLES; ++i) {
            vec2 xi = ibl_sample(i, IBL_SAMPLES, rot);
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
        return sum / float(2u * IBL_SAMPLES) * ao;
    }
    vec2 ab = textureLod(env_dfg, vec2(nv, roughness), 0.0).rg;
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
    vec3 d = env_dir(r, frame.env_rot0, frame.env_rot1, frame.env_rot2);
    vec3 prefiltered = textureLod(env_specular, d, lookup_roughness * frame.env_params.y).rgb * frame.env_params.x;
    vec3 irradiance = env_irradiance(n);
    vec3 diffuse = irradiance * base * (1.0 - metallic) * (1.0 - s.specular * max3(dielectric))
                 * (1.0 - s.transmission);
    // fis: an anisotropic lobe is sampled (the bent normal above stays approx's).
    vec3 specular = IBL == 2u && s.anisotropy > 0.0 ? aniso_env_specular(n, v, s, ess)
                                                    : prefiltered * spec_albedo;
    specular *= specular_occlusion(nv, ao, roughness);
    diffuse *= ao * bounce;
    if (!has_sheen) {
        return diffuse + specular;
    }
    // Under a sheen the specular's light comes from about the mirror direction (n·l ≈ n·v): scaled
    // by 1 - k·E(n·v); the diffuse's from the whole hemisphere: sheen_layer_diffuse. The Charlie
    // lobe is broad and lives near the horizon: its light is closer to the cosine-weighted mean
    // (the SH irradiance / π) than to any prefiltered GGX look-up. Sampling it instead (uniform
    // directions weighted by the lobe, normalised, in v's frame) measured worse at 8 samples
    // (velvet 4.7 % against 4.0 %) and little better at 64 (3.8 %): the rest is the SH's.
    float k = max3(s.sheen);
    return diffuse * sheen_layer_diffuse(k, e_v, s.sheen_roughness)
         + specular * max(1.0 - k * e_v, 0.0) + s.sheen * e_v * irradiance * ao;
}

// The fabric's two specular lobes under the environment, each without its coverage:
// (weft lobe, warp lobe) radiance. approx: the radiance in the mirror direction blurred to the
// lobe's width times Fresnel; fis / mc: importance sampling of the coverage-weighted mixture of
// the two lobes' A–S samplers (one-sample MIS, so both estimates use every sample).
void fabric_env_lobes(mat3 tbn, vec3 k2, vec4 coverage, GpuFabric f, out vec3 weft, out vec3 warp) {
    weft = vec3(0.0);
    warp = vec3(0.0);
    // rs = 0 keeps its lobes: Schlick's Fresnel is (1 - c)^5 there, not 0 (as for the lamps).
    if (!(k2.z > 0.0)) {
        return;
    }
    if (IBL == 1u) {
        vec3 r = tbn * vec3(-k2.x, -k2.y, k2.z);
        float peak = sqrt((f.e_along + 1.0) * (f.e_across + 1.0)) / (8.0 * FABRIC_PI);
        // One sample at the mirror direction, blurred to the lobe's peak solid angle (+1 level:
        // the box mips blur less than the lobe's tails reach).
        vec3 l = env_radiance_at(r, fis_lod(peak, 1u, frame.env_params.z) + 1.0) * schlick(f.rs, k2.z);
        weft = l;
        warp = l;
        return;
    }
    float c_thread = coverage.x + coverage.y;
    float w_weft = c_thread > 0.0 ? clamp(coverage.y / c_thread, 0.05, 0.95) : 0.5;
    vec2 rot = IBL == 3u ? pixel_random() : vec2(0.0);
    for (uint i = 0u; i < IBL_SAMPLES; ++i) {
        vec2 xi = ibl_sample(i, IBL_SAMPLES, rot);
        bool pick_weft = xi.x < w_weft;
        xi.x = pick_weft ? xi.x / w_weft : (xi.x - w_weft) / (1.0 - w_weft);
        xi.x = min(xi.x, 0.99999994);
        vec3 h = pick_weft ? as_sample_h(xi, f.e_along, f.e_across) : as_sample_h(xi, f.e_across, f.e_along);
        float kh = dot(k2, h);
        if (!(kh > 0.0)) {
            continue;
        }
        vec3 k1 = 2.0 * kh * h - k2;
        if (!(k1.z > 0.0)) {
            continue;
        }
        // Each lobe's estimate f·cos/pdf with pdf the mixture of the two samplers: a lobe is
        // as_lobe_factor·hn^E and its sampler's pdf as_norm/(2π)·hn^E/(4 kh) (fabric.glsl), so
        // hn^E of each orientation (as_power) is computed once and shared by both.
        float p_weft = as_power(h.x, h.y, h.z, f.e_along, f.e_across);
        float p_warp = as_power(h.x, h.y, h.z, f.e_across, f.e_along);
        float mixed = w_weft * p_weft + (1.0 - w_weft) * p_warp;
        if (!(mixed > 0.0)) {
            continue;
        }
        float pdf = as_norm(f.e_along, f.e_across) / (2.0 * FABRIC_PI) * mixed / (4.0 * kh);
        float factor = as_lobe_factor(k1.z, k2.z, min(kh, 1.0), f.e_along, f.e_across, f.rs);
        float common_w = factor * k1.z / pdf;
        float lod = IBL == 3u ? 0.0 : fis_lod(pdf, IBL_SAMPLES, frame.env_params.z);
        vec3 l = env_radiance_at(tbn * k1, lod) * common_w;
        weft += l * p_weft;
        warp += l * p_warp;
    }
    weft /= float(IBL_SAMPLES);
    warp /= float(IBL_SAMPLES);
}

// The fabric's diffuse under the environment, without its coverage: irradiance/π times the
// diffuse factor (SH; mc: cosine-sampled, unfiltered).
vec3 fabric_env_diffuse(mat3 tbn, vec3 k2, GpuFabric f) {
    if (IBL == 3u) {
        vec2 rot = pixel_random();
        vec3 sum = vec3(0.0);
        for (uint i = 0u; i < IBL_SAMPLES; ++i) {
            vec3 k1 = cosine_sample(ibl_sample(i, IBL_SAMPLES, rot));
            float factor = (f.flags & FABRIC_FLAG_COUPLED_DIFFUSE) != 0u ? coupled_diffuse(f.rs, k1.z, k2.z) * FABRIC_PI : 1.0;
            sum += env_radiance_at(tbn * k1, 0.0) * factor;
        }
        return sum / float(IBL_SAMPLES);
    }
    vec3 n = tbn[2];
    return env_irradiance(n)
        * fabric_diffuse_albedo(f, k2.z);
}

// The irradiance/π on a sheet's far side from the environment (SH; mc: cosine-sampled over the
// far hemisphere, unfiltered): what its threads pass through, times τ and their albedo.
vec3 fabric_env_back(mat3 tbn) {
    if (IBL == 3u) {
        vec2 rot = pixel_random();
        vec3 sum = vec3(0.0);
        for (uint i = 0u; i < IBL_SAMPLES; ++i) {
            vec3 k = cosine_sample(ibl_sample(i, IBL_SAMPLES, rot));
            sum += env_radiance_at(tbn * vec3(k.xy, -k.z), 0.0);
        }
        return sum / float(IBL_SAMPLES);
    }
    return env_irradiance(-tbn[2]);
}

// The fabric's environment light for one coverage: the diffuse with the threads' albedo and the
// thread shadowing (as for lamps), each lobe weighted by its thread's coverage, and for a sheet
// the light its threads pass from its far side (back: fabric_env_back; 0 for any other cloth).
vec3 fabric_env_combine(vec4 coverage, GpuFabric f, vec3 diffuse, vec3 weft, vec3 warp, vec3 back, float ao, vec3 bounce, float nv) {
    vec3 rd = fabric_albedo(coverage, FABRIC_SHEETS != 0u ? fabric_reflecting(f) : f);
    // (Every accuracy level uses the two lobes here: the environment integral of one lobe with
    // averaged exponents would need a sampler of its own.)
    vec3 radiance = rd * diffuse * ao * bounce + (coverage.y * weft + coverage.x * warp) * specular_occlusion(nv, ao, 0.5);
    if (FABRIC_SHEETS != 0u) {
        radiance += back * fabric_passed(coverage, f);
    }
    return radiance;
}

// A fabric sheet's thread coverage over the pixel (its opacity: the gaps let the light behind it
// straight through), or -1 when the surface is not a sheet shaded by the woven model. surface and
// fabric_texel as shade_surface takes them.
float fabric_sheet_cover(vec4 surface, vec4 fabric_texel) {
    if (FABRIC_SHEETS == 0u || FABRIC_AS_PBR != 0u || SHADING != SHADING_FABRIC) {
        return -1.0;
    }
    uint material = uint(surface.y + 0.5);
    uint fabric = uint(materials[min(material, frame.material_count - 1u)].metallic_roughness.z + 0.5);
    if (fabric == 0u || (fabrics[fabric - 1u].flags & FABRIC_FLAG_SHEET) == 0u) {
        return -1.0;
    }
    if (ACCURACY == 3u) {
        // Supersampled: the same N x N points of the footprint as the shading.
        GpuFabric f = fabrics[fabric - 1u];
        Weave w = weave_from_fabric(f);
        vec2 cells = vec2(float(max(f.cols, 1u)), float(max(f.rows, 1u)));
        float sum = 0.0;
        for (uint j = 0u; j < SAMPLES; ++j) {
            for (uint i = 0u; i < SAMPLES; ++i) {
                vec2 o = (vec2(float(i), float(j)) + 0.5) / float(SAMPLES) * 2.0 - 1.0;
                vec2 st = (fabric_texel.xy + o * fabric_texel.zw) * cells;
                sum += fabric_thread_cover(weave_point(w, st.x, st.y));
            }
        }
        return sum / float(SAMPLES * SAMPLES);
    }
    return fabric_thread_cover(fabric_texel);
}

// The radiance leaving world point p towards v (unit, towards the eye) from the surface with
// G-buffer values albedo, fr (frame_decode of the frame target), surface, fabric_texel,
// emissive_ao and specular; may be any value, the caller keeps NaN and Inf out of the image.
// transmission, attenuation, coat_params, coat_n, dtrans, iridescence: surface.glsl's GSurface
// fields (no transmission, coat, diffuse transmission or film from the G-buffer, which holds none).
// bounce: per channel, what the occlusion pass's coloured multi-bounce makes of emissive_ao.a
// for diffuse light (its ratio to the grey bounce in ao; 1 without the pass).
vec3 shade_surface(vec3 p, vec3 v, vec4 albedo, vec4 fr, vec4 surface, vec4 fabric_texel,
                   vec4 emissive_ao, vec4 specular, vec4 transmission, vec4 attenuation,
                   vec4 coat_params, vec3 coat_n, vec4 dtrans, vec4 iridescence, vec3 bounce) {
    vec3 n = oct_decode(fr.xy);
    vec3 base = albedo.rgb;
    float metallic = albedo.a;
    float roughness = surface.x;
    float receives = surface.w;

    vec3 radiance = emissive_ao.rgb;
    float ao = emissive_ao.a;
    // Without an environment: a fixed hemispherical ambient, so surfaces facing away from every
    // light are not pure black. With one, the environment replaces it.
    vec3 ambient = IBL != 0u ? vec3(0.0) : mix(frame.ambient_ground.rgb, frame.ambient_sky.rgb, n.y * 0.5 + 0.5);
    // On the far side (what a fabric sheet's threads pass through).
    vec3 ambient_back = IBL != 0u ? vec3(0.0) : mix(frame.ambient_ground.rgb, frame.ambient_sky.rgb, -n.y * 0.5 + 0.5);
    uint material = uint(surface.y + 0.5);
    uint fabric = uint(materials[min(material, frame.material_count - 1u)].metallic_roughness.z + 0.5);
    if (UNLIT != 0u && (uint(materials[min(material, frame.material_count - 1u)].extra.w + 0.5) & MATERIAL_UNLIT) != 0u) {
        // KHR_materials_unlit: the base colour (factor × texture × vertex colour) is the radiance.
        return base;
    }

    if (fabric > 0u && FABRIC_AS_PBR == 0u) {
        // The fabric model (docs/fabric-model.md §3) with the weave coverages of the pixel's
        // footprint (filtered by the G-buffer pass), or, supersampled, the analytic weave at
        // N x N points of the footprint.
        // The thread texture (gbuffer.frag writes its value to the albedo target) over the
        // thread colours.
        GpuFabric f = fabric_tinted(fabrics[fabric - 1u], base);
        mat3 tbn = fabric_frame(n, oct_decode(fr.zw), surface.z);
        vec3 k2 = fabric_local(v, tbn);
        vec4 g = fabric_texel;
        // Environment light: the lobes are integrated once per pixel (with the pixel's mean
        // coverage as the mixture's sampling weights) and combined with each coverage below.
        vec3 env_diffuse = vec3(0.0);
        vec3 env_weft = vec3(0.0);
        vec3 env_warp = vec3(0.0);
        vec3 env_back = vec3(0.0);
        if (IBL != 0u && SHADING == SHADING_FABRIC) {
            vec4 mean_cov = ACCURACY == 3u ? vec4(0.5, 0.5, 0.5, 0.5) : g;
            env_diffuse = fabric_env_diffuse(tbn, k2, f);
            fabric_env_lobes(tbn, k2, mean_cov, f, env_weft, env_warp);
            if (FABRIC_SHEETS != 0u && (f.flags & FABRIC_FLAG_SHEET) != 0u) {
                env_back = fabric_env_back(tbn);
            }
        }
        float nv = clamp(k2.z, 0.0, 1.0);
        if (SHADING == SHADING_GOURAUD) {
            // Lit per vertex by gbuffer.vert: the emissive target already holds it.
        } else if (SHADING != SHADING_FABRIC) {
            radiance += classic_radiance(p, ambient, tbn, k2, f, receives);
            if (IBL != 0u) {
                // The comparison models take only the environment's diffuse light.
                radiance += fabric_mean_rd(f) * fabric_env_diffuse(tbn, k2, f) * ao * bounce;
            }
        } else if (ACCURACY == 3u) {
            Weave w = weave_from_fabric(f);
            vec2 cells = vec2(float(max(f.cols, 1u)), float(max(f.rows, 1u)));
            vec3 sum = vec3(0.0);
            for (uint j = 0u; j < SAMPLES; ++j) {
                for (uint i = 0u; i < SAMPLES; ++i) {
                    vec2 o = (vec2(float(i), float(j)) + 0.5) / float(SAMPLES) * 2.0 - 1.0;
                    vec2 s = (g.xy + o * g.zw) * cells;
                    vec4 c = weave_point(w, s.x, s.y);
                    sum += fabric_radiance(p, ambient, ambient_back, tbn, k2, c, f, receives);
                    if (IBL != 0u) {
                        sum += fabric_env_combine(c, f, env_diffuse, env_weft, env_warp, env_back, ao, bounce, nv);
                    }
                }
            }
            radiance += sum / float(SAMPLES * SAMPLES);
        } else {
            radiance += fabric_radiance(p, ambient, ambient_back, tbn, k2, g, f, receives);
            if (IBL != 0u) {
                radiance += fabric_env_combine(g, f, env_diffuse, env_weft, env_warp, env_back, ao, bounce, nv);
            }
        }
    } else {
        // The glTF material with its extensions (gb_fabric: sheen; gb_specular: the dielectric
        // layer; the tangent: the anisotropy direction, surface.z its strength).
        vec4 sp = specular;
        vec4 sh = fabric_texel;
        vec3 ta = oct_decode(fr.zw);
        ta -= n * dot(n, ta);
        ta = dot(ta, ta) > 1e-12 ? normalize(ta) : any_tangent(n);
        // The diffuse lobe's parts: transmitted specularly (KHR_materials_transmission, through
        // the backdrop), transmitted diffusely (of the rest; KHR_materials_diffuse_transmission),
        // reflected (what remains).
        float t_spec = TRANSMISSION != 0u ? transmission.x : 0.0;
        float t_diff = DIFFUSE_TRANSMISSION != 0u ? dtrans.x : 0.0;
        GltfSurface s = GltfSurface(base, metallic, roughness, sp.a, sp.rgb, sh.rgb, sh.a, ta, surface.z,
                                    1.0 - (1.0 - t_spec) * (1.0 - t_diff),
                                    IRIDESCENCE != 0u ? iridescence.x : 0.0, iridescence.y, iridescence.z);
        float diffuse_through = (1.0 - metallic) * (1.0 - t_spec) * t_diff;
        bool has_sheen = max3(s.sheen) > 0.0;
        float e_v = has_sheen ? sheen_albedo(dot(n, v), s.sheen_roughness) : 0.0;
        float ess = ggx_albedo(dot(n, v), roughness);
        // KHR_materials_clearcoat (forward pass only): its weight and roughness, and its normal.
        float coat = COAT != 0u ? coat_params.x : 0.0;
        float coat_r = coat_params.y;
        // What the coat covers besides the lamps (each lamp's is coated in the loop): the
        // environment or ambient, the transmitted light, and the emission.
        vec3 under = emissive_ao.rgb;
        radiance -= emissive_ao.rgb;
        if (IBL != 0u) {
            under += pbr_env(n, v, s, ao, bounce, e_v);
        } else {
            // Hemispherical ambient, so surfaces facing away from every light are not pure black.
            under += ambient * base * (1.0 - metallic) * (1.0 - s.transmission) + ambient * mix(vec3(0.04), base, metallic) * (1.0 - roughness) * 0.5;
        }
        uvec2 list = tile_list();
    for (uint j = 0u; j < list.y; ++j) {
        uint i = tile_lights[list.x + j];
            vec3 l;
            vec3 e = light_incoming(lights[i], p, l);
            if (TRANSMISSION != 0u && t_spec > 0.0) {
                // KHR_materials_transmission: a lamp behind, seen through the surface (the
                // sample viewer's model: its light as seen from where the refracted view ray
                // leaves the volume, attenuated over that path; its shadow looked up there from
                // the back side).
                vec3 q = transmission_exit(p, n, v, transmission.y, transmission.w);
                vec3 lq;
                vec3 eq = light_incoming(lights[i], q, lq);
                vec3 through = (1.0 - metallic) * t_spec * specular_btdf_cos(n, v, lq, s, transmission.w);
                if (any(greaterThan(eq * through, vec3(0.0)))) {
                    through *= volume_attenuation(distance(p, q), attenuation.rgb, transmission.z);
                    if (COAT != 0u && coat > 0.0) {
                        through *= 1.0 - coat * clearcoat_fresnel(dot(coat_n, v));
                    }
                    radiance += eq * through * shadow_factor(lights[i], q, -n, receives);
                }
            }
            if (all(equal(e, vec3(0.0)))) {
                continue;
            }
            float e_l = has_sheen ? sheen_albedo(dot(n, l), s.sheen_roughness) : 0.0;
            vec3 c = gltf_brdf_cos(n, v, l, s, vec2(e_v, e_l), ess);
            if (COAT != 0u && coat > 0.0) {
                c = clearcoat_brdf_cos(c, coat_n, v, l, coat, coat_r);
            }
            if (DIFFUSE_TRANSMISSION != 0u && diffuse_through > 0.0 && dot(n, l) < 0.0) {
                // Light from behind, through the sheet: its shadow is looked up from the back
                // side (the normal offset away from the light, as for a front-lit surface).
                vec3 through = diffuse_through * diffuse_btdf_cos(n, v, l, s, dtrans.yzw);
                if (COAT != 0u && coat > 0.0) {
                    through *= 1.0 - coat * clearcoat_fresnel(dot(coat_n, v));
                }
                radiance += e * through * shadow_factor(lights[i], p, -n, receives);
                continue;
            }
            if (all(equal(c, vec3(0.0)))) {
                continue;
            }
            radiance += e * c * shadow_factor(lights[i], p, n, receives);
        }
        if (TRANSMISSION != 0u && t_spec > 0.0) {
            // The dielectric's transmitted part replaces that much of its diffuse lobe (above).
            under += (1.0 - metallic) * t_spec * transmitted_light(p, n, v, s, transmission, attenuation);
        }
        if (DIFFUSE_TRANSMISSION != 0u && diffuse_through > 0.0) {
            // The environment or ambient from behind, through the sheet: the irradiance about −n
            // through the Lambertian BTDF, as the reflected diffuse takes it about n.
            float nv = clamp(dot(n, v), 1e-4, 1.0);
            vec2 ab = textureLod(env_dfg, vec2(nv, roughness), 0.0).rg;
            vec3 behind = IBL != 0u
                ? env_irradiance(-n)
                : mix(frame.ambient_ground.rgb, frame.ambient_sky.rgb, -n.y * 0.5 + 0.5);
            under += diffuse_through * dtrans.yzw * behind * ao * bounce
                   * (1.0 - s.specular * max3(s.f0 * ab.x + ab.y));
        }
        if (COAT != 0u && coat > 0.0) {
            // The coat reflects Fc(nc·v) of what would leave the layers below, and adds its own
            // split-sum specular (F0 0.04) of the environment about its normal.
            float cv = clamp(dot(coat_n, v), 1e-4, 1.0);
            vec2 ab = textureLod(env_dfg, vec2(cv, coat_r), 0.0).rg;
            vec3 coat_light = ambient;
            if (IBL != 0u) {
                vec3 r = dominant_dir(coat_n, reflect(-v, coat_n), coat_r);
                vec3 d = env_dir(r, frame.env_rot0, frame.env_rot1, frame.env_rot2);
                coat_light = textureLod(env_specular, d, coat_r * frame.env_params.y).rgb * frame.env_params.x
                           * specular_occlusion(cv, ao, coat_r);
            }
            under = under * (1.0 - coat * clearcoat_fresnel(cv)) + coat * (0.04 * ab.x + ab.y) * coat_light;
        }
        radiance += under;
    }
    return radiance;
}
