// Shading one surface point from its G-buffer values (surface.glsl's GSurface, decoded): every
// light of its tile, the environment and the shadows, with the fabric model or the glTF BRDF. The
// deferred lighting pass (lighting.frag) calls it for each pixel from the targets; the forward
// pass (forward.frag, alphaMode BLEND) for each fragment, so both light a surface alike. The
// including shader declares `frame`, `lights`, `materials`, `fabrics`, `shadow_atlas`, `shadows`,
// `tile_lights`, `env_radiance`, `env_specular`, `env_dfg`, `fabric_lobe_albedo_table` and the specialization constants
// ACCURACY, SAMPLES, FABRIC_AS_PBR, LIGHT_TYPES, SHADING, SHADOWS, RANGE_CULLING, IBL,
// IBL_SAMPLES, UNLIT, TRANSMISSION, COAT, DIFFUSE_TRANSMISSION, IRIDESCENCE, FABRIC_SHEETS,
// PIXEL_KINDS, GLTF_FEATURES and POOL, and defines `transmitted_light` and `fabric_pooled_lobe_sums` (forward.frag: from
// the backdrop; lighting.frag, whose TRANSMISSION is 0: nothing).

// The light seen through a transmissive surface (KHR_materials_transmission and _volume) at p
// with normal n towards v: transmission = (factor, thickness, attenuation distance, ior),
// attenuation: the attenuation colour. Defined by the including shader.
vec3 transmitted_light(vec3 p, vec3 n, vec3 v, GltfSurface s, vec4 transmission, vec4 attenuation);

#include "lights.glsl"

// The light list of world point p's cluster (its pixel's 16 x 16 tile and, when the frame has
// depth slices, its slice of view distance; frame.clusters, weft::render::tiles): (offset into
// tile_lights, count).
uvec2 tile_list(vec3 p) {
    uvec2 t = uvec2(gl_FragCoord.xy) / 16u;
    uint slice = 0u;
    if (RANGE_CULLING == 2u && frame.clusters.x > 1.5) {
        float d = -(frame.view * vec4(p, 1.0)).z;
        float s = floor(log2(max(d, frame.clusters.y) / frame.clusters.y) * frame.clusters.z);
        slice = uint(clamp(s, 0.0, frame.clusters.x - 1.0));
    }
    uint index = (slice * uint(frame.clusters.w + 0.5) + t.y) * frame.tile_columns + t.x;
    return uvec2(tile_lights[2u * index], tile_lights[2u * index + 1u]);
}

// Light j of a cluster's list (tile_list(p)): its index i into `lights`, the unit direction l towards
// it and the illuminance it brings to p (light_incoming: 0 where its range cannot reach p).
vec3 tile_light(uvec2 list, uint j, vec3 p, out uint i, out vec3 l) {
    i = tile_lights[list.x + j];
    return light_incoming(lights[i], p, l);
}


// The atlas's bilinear depth comparison (shadows.glsl's leaf).
float shadow_compare(vec3 uvz) {
    return texture(shadow_atlas, uvz);
}

#include "shadows.glsl"

// How much of light `light` reaches world point p with normal n (1 lit, 0 shadowed): shadow_pcf
// of its shadow map; 1 for lights without one and surfaces that do not receive.
float shadow_factor(Light light, vec3 p, vec3 n, float receives) {
    if (SHADOWS == 0u) {
        return 1.0;
    }
    int index = int(light.spot.z + 0.5) - 1;
    if (index < 0 || receives < 0.5) {
        return 1.0;
    }
    return shadow_pcf(shadows[index], light.position_range.xyz, p, n);
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
    uvec2 list = tile_list(p);
    for (uint j = 0u; j < list.y; ++j) {
        uint i;
        vec3 l;
        vec3 e = tile_light(list, j, p, i, l);
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
    uvec2 list = tile_list(p);
    for (uint j = 0u; j < list.y; ++j) {
        uint i;
        vec3 l;
        vec3 e = tile_light(list, j, p, i, l);
        vec3 k1 = fabric_local(l, tbn);
        if (k1.z <= 0.0 || all(equal(e, vec3(0.0)))) {
            continue;
        }
        vec3 brdf = SHADING == SHADING_PHONG ? phong_brdf(k1, k2, f) : plain_as_brdf(k1, k2, f);
        radiance += e * brdf * (k1.z * shadow_factor(lights[i], p, tbn[2], receives));
    }
    return radiance;
}


// ---- Environment lighting (docs/fabric-model.md §6; the estimators in env_light.glsl) ----

#include "env_cubes.glsl"
#include "env_light.glsl"

vec2 lobe_albedo_texel(uint table, uint i, uint j) {
    return fabric_lobe_albedo_table[table * (LOBE_ALBEDO_MU * LOBE_ALBEDO_PHI) + j * LOBE_ALBEDO_MU + i];
}

// The Monte Carlo level's per-pixel rotation (0 at the other levels).
vec2 ibl_rotation() {
    return IBL == 3u ? pixel_random(uvec2(gl_FragCoord.xy)) : vec2(0.0);
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

// The fabric lobes' sums pooled over the pixel's neighbourhood (lighting.frag: fabric_lobes.frag's
// sums of the pixels around it whose surface agrees; forward.frag, which never pools: unused):
// per lobe the sum of fabric_lobe_unpack over `pixels` pixels.
void fabric_pooled_lobe_sums(out vec4 weft, out vec4 warp, out uint pixels);

// The radiance leaving world point p towards v (unit, towards the eye) from the surface with
// G-buffer values albedo, fr (frame_decode of the frame target), surface, fabric_texel,
// emissive_ao and specular; may be any value, the caller keeps NaN and Inf out of the image.
// transmission, attenuation, coat_params, coat_n, dtrans, iridescence: surface.glsl's GSurface
// fields (no transmission, coat, diffuse transmission or film from the G-buffer, which holds none).
// bounce: per channel, what the occlusion pass's coloured multi-bounce makes of emissive_ao.a
// for diffuse light (its ratio to the grey bounce in ao; 1 without the pass); indirect: the light
// the occluders send back (irradiance/π; pbr_env; 0 without the pass's bounce).
vec3 shade_surface(vec3 p, vec3 v, vec4 albedo, vec4 fr, vec4 surface, vec4 fabric_texel,
                   vec4 emissive_ao, vec4 specular, vec4 transmission, vec4 attenuation,
                   vec4 coat_params, vec3 coat_n, vec4 dtrans, vec4 iridescence, vec3 bounce,
                   vec3 indirect) {
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

    // The woven model or the glTF BRDF; a pipeline made for one kind of pixel (PIXEL_KINDS) has
    // only that kind's code.
    bool woven = (PIXEL_KINDS & PIXEL_KIND_GLTF) == 0u ? true
               : (PIXEL_KINDS & PIXEL_KIND_WOVEN) == 0u ? false
               : fabric > 0u && FABRIC_AS_PBR == 0u;
    if (woven) {
        // The fabric model (docs/fabric-model.md §3) with the weave coverages of the pixel's
        // footprint (filtered by the G-buffer pass), or, supersampled, the analytic weave at
        // N x N points of the footprint.
        // The thread texture (gbuffer.frag writes its value to the albedo target) over the
        // thread colours.
        GpuFabric f = fabric_tinted(fabrics[max(fabric, 1u) - 1u], base);
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
            env_diffuse = fabric_env_diffuse(tbn, k2, f, IBL, IBL_SAMPLES, ibl_rotation());
            if (POOL != 0u && IBL == 2u) {
                // fis, the deferred pass: the lobes' samples of the pixels around this one whose
                // surface agrees (fabric_lobes.frag took them, each pixel its own block).
                vec4 weft_sum;
                vec4 warp_sum;
                uint pixels;
                fabric_pooled_lobe_sums(weft_sum, warp_sum, pixels);
                fabric_env_lobes_resolve(weft_sum, warp_sum, k2, f, max(fabric, 1u) - 1u, IBL, pixels,
                                         env_weft, env_warp);
            } else {
                fabric_env_lobes(tbn, k2, mean_cov, f, max(fabric, 1u) - 1u, IBL, IBL_SAMPLES, ibl_rotation(), env_weft, env_warp);
            }
            if (FABRIC_SHEETS != 0u && (f.flags & FABRIC_FLAG_SHEET) != 0u) {
                env_back = fabric_env_back(tbn, IBL, IBL_SAMPLES, ibl_rotation());
            }
        }
        float nv = clamp(k2.z, 0.0, 1.0);
        if (SHADING == SHADING_GOURAUD) {
            // Lit per vertex by gbuffer.vert: the emissive target already holds it.
        } else if (SHADING != SHADING_FABRIC) {
            radiance += classic_radiance(p, ambient, tbn, k2, f, receives);
            if (IBL != 0u) {
                // The comparison models take only the environment's diffuse light.
                radiance += fabric_mean_rd(f) * (fabric_env_diffuse(tbn, k2, f, IBL, IBL_SAMPLES, ibl_rotation()) * ao * bounce + indirect);
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
                        sum += fabric_env_combine(c, f, env_diffuse, env_weft, env_warp, env_back, ao, bounce, indirect, nv, FABRIC_SHEETS != 0u);
                    }
                }
            }
            radiance += sum / float(SAMPLES * SAMPLES);
        } else {
            radiance += fabric_radiance(p, ambient, ambient_back, tbn, k2, g, f, receives);
            if (IBL != 0u) {
                radiance += fabric_env_combine(g, f, env_diffuse, env_weft, env_warp, env_back, ao, bounce, indirect, nv, FABRIC_SHEETS != 0u);
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
        // Sheen and anisotropy only where the scene has them (GLTF_FEATURES): as constant zeros
        // their code folds away.
        vec3 sheen = (GLTF_FEATURES & GLTF_FEATURE_SHEEN) != 0u ? sh.rgb : vec3(0.0);
        float anisotropy = (GLTF_FEATURES & GLTF_FEATURE_ANISOTROPY) != 0u ? surface.z : 0.0;
        GltfSurface s = GltfSurface(base, metallic, roughness, sp.a, sp.rgb, sheen, sh.a, ta, anisotropy,
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
            under += pbr_env(n, v, s, ao, bounce, indirect, e_v, IBL, IBL_SAMPLES, ibl_rotation());
        } else {
            // Hemispherical ambient, so surfaces facing away from every light are not pure black.
            under += ambient * base * (1.0 - metallic) * (1.0 - s.transmission) + ambient * mix(vec3(0.04), base, metallic) * (1.0 - roughness) * 0.5;
        }
        uvec2 list = tile_list(p);
        for (uint j = 0u; j < list.y; ++j) {
            uint i;
            vec3 l;
            vec3 e = tile_light(list, j, p, i, l);
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
            vec2 ab = dfg_lookup(nv, roughness).rg;
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
            vec2 ab = dfg_lookup(cv, coat_r).rg;
            vec3 coat_light = ambient;
            if (IBL != 0u) {
                vec3 r = dominant_dir(coat_n, reflect(-v, coat_n), coat_r);
                coat_light = env_prefiltered(r, coat_r) * specular_occlusion(cv, ao, coat_r);
            }
            under = under * (1.0 - coat * clearcoat_fresnel(cv)) + coat * (0.04 * ab.x + ab.y) * coat_light;
        }
        radiance += under;
    }
    return radiance;
}
