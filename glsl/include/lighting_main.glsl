// The deferred lighting pass's shader, compiled as four modules (glsl/lighting*.frag, each this
// file after a line or two): lighting.frag shades every kind of pixel its PIXEL_KINDS constant
// names; lighting_background.frag, lighting_woven.frag and lighting_gltf.frag one kind each.
// One fullscreen triangle: reads the G-buffer, sums every light's contribution with the
// material's BRDF, and writes linear HDR radiance.
#include "frame.glsl"
#include "pbr.glsl"
#include "fabric.glsl"
#include "weave.glsl"
#include "ibl.glsl"
#include "occlusion.glsl"

// Accuracy level (model page §4): 0 nearest, 1 filtered-params, 2 mixture, 3 supersampled.
layout(constant_id = 0) const uint ACCURACY = 2u;
// N of supersampled:N (N x N footprint samples).
layout(constant_id = 1) const uint SAMPLES = 1u;
// 1: shade fabric pixels with the metallic-roughness BRDF (to measure what the fabric model costs).
layout(constant_id = 2) const uint FABRIC_AS_PBR = 0u;
// Light types the scene has (bit 0 directional, 1 point, 2 spot): the code for the others is
// compiled out (the plan sets this from the scene).
layout(constant_id = 3) const uint LIGHT_TYPES = 7u;
// How fabric is shaded (SHADING_* in frame.glsl): the fabric model (default), or for
// `weft compare` Gouraud (lit per vertex by gbuffer.vert, carried in the emissive target), Phong,
// or plain single-lobe Ashikhmin–Shirley.
layout(constant_id = 4) const uint SHADING = 0u;
// 1: shadow maps are sampled (some light casts, something casts and something receives); 0: the
// shadow code is compiled out.
layout(constant_id = 5) const uint SHADOWS = 0u;
// 1: a point or spot light whose range cannot reach the pixel is skipped before its falloff and
// BRDF (the default), and the pixel loops over its 16 x 16-pixel tile's lights; 2: as 1, and the
// light lists may also be sliced by view distance (frame.clusters; the plan's choice when the
// scene has many lights); 0: every light is evaluated everywhere (to show the culling changes
// nothing).
layout(constant_id = 6) const uint RANGE_CULLING = 1u;
// Environment lighting (weft::env::IblLevel): 0 none (the fixed hemispherical ambient), 1 approx,
// 2 filtered importance sampling, 3 brute-force Monte Carlo (the ground truth).
layout(constant_id = 7) const uint IBL = 0u;
// N of fis:N and mc:N.
layout(constant_id = 8) const uint IBL_SAMPLES = 16u;
// 1: some material is unlit (KHR_materials_unlit, MATERIAL_UNLIT): its pixels show the base colour
// from the albedo target as their radiance, unlit; 0: the check is compiled out.
layout(constant_id = 9) const uint UNLIT = 0u;
// Bits. Any set: the occlusion pass ran (an environment lights the scene): its visibility,
// raised for light bounced between occluders (a fit), multiplies the material's occlusion
// texture in the environment's light (1 alone: --occlusion gtao-nobounce). Bit 1 (2): where the
// occluders' light the pass measured on screen exceeds what the fit gives back, the excess is
// added to the diffuse and sheen light (--occlusion gtao-screen). Bit 2 (4: --occlusion gtao,
// where the plan bakes the world light): the world light (render::world_light) from the G-buffer's
// specular target: the lesser of the screen's visibility and the world's, the greater of the two
// bounces (KHR_materials_specular's data then the material's F0, weight 1); 4 without bit 1 where
// the world light carries the occluders' light alone (every receiving triangle small beside the
// occlusion radius: the screen's bounce adds nothing the vertices do not hold). 0: none of it is
// read. (Tested with `&`, which spirq evaluates where it does not evaluate `||` of two
// comparisons.)
layout(constant_id = 10) const uint OCCLUSION = 0u;
// 1: a debug view (frame.debug_view) may show a G-buffer target instead of the lit image; 0: that
// code is compiled out.
layout(constant_id = 11) const uint DEBUG_VIEWS = 1u;
// The kinds of pixel this pipeline shades (PIXEL_KIND_* bits, frame.glsl): the background, the
// woven model, glTF materials. One pipeline of every kind the scene has, or (where the G-buffer's
// stencil says what each pixel is, weft::render::passes::lighting) one per kind, each drawn over
// its own pixels only: the other kinds' code is compiled out.
#ifdef LIGHTING_KINDS
// (lighting_background.frag, lighting_woven.frag, lighting_gltf.frag: one kind, fixed when the
// module is compiled, so the other kinds' code is not in its SPIR-V at all. Lavapipe translates a
// module's whole SPIR-V for every pipeline before specialization removes anything: the full
// module took 30-50 ms per pipeline on two cores, the background's alone 1 ms.)
const uint PIXEL_KINDS = LIGHTING_KINDS;
#else
layout(constant_id = 12) const uint PIXEL_KINDS = 7u;
#endif
// The glTF extensions some deferred material of the scene has (GLTF_FEATURE_* bits): the others'
// code is compiled out.
layout(constant_id = 13) const uint GLTF_FEATURES = 3u;
// R ≥ 1: at fis, the woven model's lobe samples are pooled over the (2R + 1) x (2R + 1) pixels
// around each pixel whose surface agrees with its own (fabric_pool_agrees: the same material,
// normals and tangents within a quarter of the lobe's narrow width), from the sums
// fabric_lobes.frag wrote at binding 28 with the same R; 0 (default): each pixel estimates its
// lobes alone.
layout(constant_id = 14) const uint POOL = 0u;
// 0: the pass writes linear HDR radiance (the tonemap pass follows, or the HDR image is read:
// --exr, the transparent pass's blending); c + 1: nothing reads the HDR image, and the pass
// writes the 8-bit target itself: each pixel through tone curve c of include/tonemap.glsl
// (CURVE_PASSTHROUGH for a debug view) after the exposure frame.ambient_sky.a, as the tonemap
// pass would, which then does not run.
layout(constant_id = 15) const uint TONE_CURVE = 0u;
// Fabric sheets are drawn by the transparent pass (forward.frag), never deferred.
const uint FABRIC_SHEETS = 0u;


// Set 0 numbers every resource as gbuffer.vert, gbuffer.frag and forward.frag do (one number per
// resource in every shader): 0-5 the scene's buffers, 10-16 shadows and environment, 20-26 the
// G-buffer this pass reads.
layout(set = 0, binding = 0, std140) uniform FrameBlock { FrameData frame; };  // the frame uniform (`FrameData`, std140, include/frame.glsl)
layout(set = 0, binding = 1, std430) readonly buffer Materials { Material materials[]; };  // material records (`Material[]`)
layout(set = 0, binding = 2, std430) readonly buffer Fabrics { GpuFabric fabrics[]; };  // fabric records (`GpuFabric[]`)
layout(set = 0, binding = 3, std430) readonly buffer Lights { Light lights[]; };  // lights (`Light[]`, include/frame.glsl), with each shadow caster's map index in `spot.z`
// The shadow atlas (D32, one square tile per shadow-casting light) and its tiles.
layout(set = 0, binding = 10) uniform sampler2DShadow shadow_atlas;  // the shadow atlas (D32) with a comparison sampler (GREATER_OR_EQUAL, linear, clamp); any depth image when SHADOWS = 0
layout(set = 0, binding = 11, std430) readonly buffer Shadows { Shadow shadows[]; };  // shadow records (`Shadow[]`, include/frame.glsl), indexed by `Light.spot.z - 1`
// Per cluster (a 16 x 16-pixel tile and a slice of view distance, frame.clusters): (offset,
// count) of its light list, then the lists' light indices (src/render/tiles.rs): the lights
// whose range can reach the cluster.
layout(set = 0, binding = 12, std430) readonly buffer TileLights { uint tile_lights[]; };  // per-cluster light lists (uint[]): for each cluster (slice·rows + y)·`frame.tile_columns` + x of 16 x 16-pixel tiles (x, y) and depth slices (`frame.clusters`: slices, near distance, slices per doubling of the view distance, tile rows), (offset, count) of its list, then the lists of light indices; with `frame.clusters.x` = 1, a list per tile (every tile listing every light works)
// The environment (env space; 1 x 1 black cubes when there is none): radiance with box-filtered
// mips, the GGX-prefiltered specular levels of the split sum, and the DFG table (n·v, roughness).
layout(set = 0, binding = 13) uniform samplerCube env_radiance;  // the environment's radiance cube (RGBA16F, env space, box-filtered mips: env_cube.comp); any cube when IBL = 0
layout(set = 0, binding = 14) uniform samplerCube env_specular;  // the GGX-prefiltered specular cube (level i: roughness i/(levels-1); env_prefilter.comp); any cube when IBL = 0
layout(set = 0, binding = 15) uniform sampler2D env_dfg;  // the split-sum DFG table (x: n·v, y: roughness; rg = A, B, b = the sheen albedo E; weft::env::dfg_table), linear, clamp
layout(set = 0, binding = 17, std430) readonly buffer FabricLobeAlbedo { vec2 fabric_lobe_albedo_table[]; };  // the fabric records' lobe albedo tables (`vec2[]`, weft::reference::lobe_albedo: record k's at k·LOBE_ALBEDO_MU·LOBE_ALBEDO_PHI, n·k2 fastest; albedo at rs 0, at rs 1); one zeroed table when the frame has no fabric under an environment
// The G-buffer (gbuffer.frag's outputs at the same locations, fetched per pixel).
layout(set = 0, binding = 20) uniform sampler2D gb_albedo;  // G-buffer albedo (RGBA8 sRGB): base colour, a: metallic
layout(set = 0, binding = 21) uniform usampler2D gb_frame;  // G-buffer normal + tangent (RGBA16_UINT): octahedral normal (xy), tangent (zw), frame_encode of include/frame.glsl
layout(set = 0, binding = 22) uniform sampler2D gb_surface;  // G-buffer surface (RGBA16F): roughness, material index, tangent sign, 1 if it receives shadows
layout(set = 0, binding = 23) uniform sampler2D gb_fabric;  // G-buffer fabric coverage (RGBA16F): c_warp, c_weft and each shadow-weighted (s_warp, s_weft)
layout(set = 0, binding = 24) uniform sampler2D gb_emissive;  // G-buffer emissive (RGBA16F): emitted radiance, a: ambient occlusion
layout(set = 0, binding = 25) uniform sampler2D gb_depth;  // G-buffer depth (D32)
layout(set = 0, binding = 26) uniform sampler2D gb_specular;  // G-buffer specular (KHR_materials_specular: rgb F0, a weight)
layout(set = 0, binding = 27) uniform sampler2D screen_occlusion;  // the occlusion pass's visibility of the environment and view distance per 2 x 2 pixels (RG16F, half resolution, occlusion_blur.frag); any image when OCCLUSION = 0
layout(set = 0, binding = 29) uniform sampler2D screen_bounce;  // the occlusion pass's bounced light from the occluders per 2 x 2 pixels (RGBA16F: rgb irradiance/π, half resolution, occlusion_blur.frag); any image without OCCLUSION's bit 1
layout(set = 0, binding = 28) uniform usampler2D fabric_lobe_sums;  // fabric_lobes.frag's lobe sums per pixel (RGBA32_UINT, fabric_lobe_pack of include/env_light.glsl) when POOL ≥ 1; any unsigned-integer image otherwise

layout(location = 0) in vec2 in_uv;
layout(location = 0) out vec4 out_color;

// The G-buffer holds no transmissive surface (the transparent pass draws them).
const uint TRANSMISSION = 0u;
const uint COAT = 0u;
const uint DIFFUSE_TRANSMISSION = 0u;
const uint IRIDESCENCE = 0u;
vec3 transmitted_light(vec3 p, vec3 n, vec3 v, GltfSurface s, vec4 transmission, vec4 attenuation) {
    return vec3(0.0);
}

#include "shade.glsl"
#include "pool.glsl"
#include "tonemap.glsl"

// shade.glsl's fabric_pooled_lobe_sums: this pixel's lobe sums (fabric_lobes.frag's, at
// binding 28) and those of the pixels its mask names (within POOL of it, their surface agreeing
// with its own); the pixels pooled in `pixels`.
void fabric_pooled_lobe_sums(out vec4 weft, out vec4 warp, out uint pixels) {
    ivec2 px = ivec2(gl_FragCoord.xy);
    uvec4 own = texelFetch(fabric_lobe_sums, px, 0);
    fabric_lobe_unpack(own, weft, warp);
    pixels = 1u;
    // A loop over the mask's bits, not the window: llvmpipe leaves a loop as soon as no lane of
    // a vector has a turn left, where it would run every fetch of an `if` under a mask.
    uint mask = own.w;
    while (mask != 0u) {
        int bit = findLSB(mask);
        mask &= mask - 1u;
        vec4 a;
        vec4 b;
        fabric_lobe_unpack(texelFetch(fabric_lobe_sums, px + fabric_pool_offset(bit, POOL), 0), a, b);
        weft += a;
        warp += b;
        pixels += 1u;
    }
}

// The occlusion pass's visibility at pixel px, whose view distance is `dist`: the half-resolution
// estimates around it (each made at the top-left pixel of its 2 x 2 block), bilinearly, each
// weighted by how close its distance is to the pixel's (an edge does not take the visibility of
// what is behind it); 1 where no estimate lies on the pixel's surface. `bounced`: the occluders'
// light (OCCLUSION's bit 1) with the same weights; 0 where no estimate lies on the surface.
float screen_visibility(ivec2 px, float dist, out vec3 bounced) {
    ivec2 size = textureSize(screen_occlusion, 0);
    ivec2 c = px / 2;
    vec2 f = vec2(px & 1) * 0.5;
    float sum = 0.0;
    vec3 bounce_sum = vec3(0.0);
    float weights = 0.0;
    for (int y = 0; y < 2; ++y) {
        for (int x = 0; x < 2; ++x) {
            float bilinear = (x == 0 ? 1.0 - f.x : f.x) * (y == 0 ? 1.0 - f.y : f.y);
            if (bilinear <= 0.0) {
                continue;
            }
            vec2 s = texelFetch(screen_occlusion, min(c + ivec2(x, y), size - 1), 0).rg;
            float w = s.y > 0.0 ? bilinear * clamp(1.0 - abs(s.y - dist) / (0.05 * dist), 0.0, 1.0) : 0.0;
            sum += w * s.x;
            if ((OCCLUSION & 2u) != 0u) {
                bounce_sum += w * texelFetch(screen_bounce, min(c + ivec2(x, y), size - 1), 0).rgb;
            }
            weights += w;
        }
    }
    bounced = weights > 1e-6 ? bounce_sum / weights : vec3(0.0);
    return weights > 1e-6 ? sum / weights : 1.0;
}

// The world light (render::world_light; `world`: the G-buffer's specular target, rgb the scene's
// surfaces' light over the vertex's hemisphere as irradiance/π, a the environment's visibility)
// with the screen's: the world sees the occluders the screen hides, the screen the detail
// between vertices, so the visibility is the lesser (returned: what the world sees hidden beyond
// the screen's `screen`) and the occluders' light `bounced` the greater of the two, per channel.
float world_hidden(float screen, inout vec3 bounced, vec4 world) {
    bounced = max(bounced, world.rgb);
    return max(screen - world.a, 0.0);
}

// The view distance occlusion.frag measures: from the eye, or along the view axis when
// orthographic.
float view_distance(vec3 p) {
    return frame.proj[2][3] == 0.0 ? -(frame.view * vec4(p, 1.0)).z : length(p - frame.eye.xyz);
}

vec3 debug_color(uint view, ivec2 px, float depth) {
    vec4 albedo = texelFetch(gb_albedo, px, 0);
    vec4 fr = frame_decode(texelFetch(gb_frame, px, 0));
    vec4 surface = texelFetch(gb_surface, px, 0);
    bool is_fabric = materials[min(uint(surface.y + 0.5), frame.material_count - 1u)].metallic_roughness.z > 0.5;
    vec4 fabric = is_fabric ? texelFetch(gb_fabric, px, 0) : vec4(0.0);
    if (view == DEBUG_ALBEDO) return albedo.rgb;
    if (view == DEBUG_NORMALS) return oct_decode(fr.xy) * 0.5 + 0.5;
    if (view == DEBUG_TANGENTS) return oct_decode(fr.zw) * 0.5 + 0.5;
    if (view == DEBUG_ROUGHNESS_METALLIC) return vec3(surface.x, albedo.a, 0.0);
    // Non-fabric surfaces show dark grey in the two fabric views.
    if (view == DEBUG_COVERAGE) return is_fabric ? vec3(fabric.x, fabric.y, 1.0 - fabric.x - fabric.y) : vec3(0.1);
    if (view == DEBUG_THREAD_DIR) {
        if (!is_fabric) return vec3(0.1);
        // The dominant thread direction in screen colours: the tangent (weft) or bitangent (warp)
        // of the thread on top, weighted by coverage, encoded as 0.5 + 0.5 * direction.
        vec3 t = oct_decode(fr.zw);
        vec3 n = oct_decode(fr.xy);
        vec3 b = (surface.z < 0.0 ? -1.0 : 1.0) * cross(n, t);
        vec3 dir = fabric.y * t + fabric.x * b;
        return dot(dir, dir) > 0.0 ? normalize(dir) * 0.5 + 0.5 : vec3(0.0);
    }
    if (view == DEBUG_OCCLUSION) {
        // The environment's visibility: the occlusion pass's (when it ran) times the material's
        // occlusion texture, before the multi-bounce correction.
        vec2 ndc = (vec2(px) + 0.5) * frame.viewport.zw * 2.0 - 1.0;
        vec4 hp = frame.inv_view_proj * vec4(ndc, depth, 1.0);
        vec3 bounced;
        float screen = OCCLUSION != 0u ? screen_visibility(px, view_distance(hp.xyz / hp.w), bounced) : 1.0;
        if ((OCCLUSION & 4u) != 0u) {
            screen -= world_hidden(screen, bounced, texelFetch(gb_specular, px, 0));
        }
        return vec3(screen * texelFetch(gb_emissive, px, 0).a);
    }
    if (view == DEBUG_DEPTH) {
        vec2 ndc = (vec2(px) + 0.5) * frame.viewport.zw * 2.0 - 1.0;
        vec4 p = frame.inv_view_proj * vec4(ndc, depth, 1.0);
        float dist = length(p.xyz / p.w - frame.eye.xyz);
        return vec3(fract(dist));
    }
    return vec3(1.0, 0.0, 1.0);
}

// The pixel's linear radiance and coverage into out_color.
void shade_pixel() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    float depth = texelFetch(gb_depth, px, 0).r;
    if ((PIXEL_KINDS & PIXEL_KIND_BACKGROUND) != 0u && depth <= 0.0) {
        // Empty pixel: the background (the environment seen along the view ray, a colour, or
        // transparent); debug views show black.
        if (DEBUG_VIEWS != 0u && frame.debug_view != DEBUG_NONE) {
            out_color = vec4(0.0, 0.0, 0.0, 1.0);
        } else if (IBL != 0u && frame.env_background.x == 0.0) {
            vec2 ndc = (vec2(px) + 0.5) * frame.viewport.zw * 2.0 - 1.0;
            vec4 far = frame.inv_view_proj * vec4(ndc, 1e-7, 1.0);
            vec3 ray = normalize(far.xyz / far.w - frame.eye.xyz);
            out_color = vec4(env_radiance_at(ray, frame.env_background.y), 1.0);
        } else if (frame.env_background.x == 2.0) {
            out_color = vec4(0.0);
        } else {
            out_color = vec4(frame.background.rgb, 1.0);
        }
        return;
    }
    if ((PIXEL_KINDS & (PIXEL_KIND_WOVEN | PIXEL_KIND_GLTF)) == 0u) {
        // The background's pipeline: the stencil leaves it nothing else.
        out_color = vec4(0.0);
        return;
    }
    if (DEBUG_VIEWS != 0u && frame.debug_view != DEBUG_NONE) {
        out_color = vec4(debug_color(frame.debug_view, px, depth), 1.0);
        return;
    }

    vec2 ndc = (vec2(px) + 0.5) * frame.viewport.zw * 2.0 - 1.0;
    vec4 hp = frame.inv_view_proj * vec4(ndc, depth, 1.0);
    vec3 p = hp.xyz / hp.w;
    vec3 v = normalize(frame.eye.xyz - p);

    vec4 albedo = texelFetch(gb_albedo, px, 0);
    vec4 fr = frame_decode(texelFetch(gb_frame, px, 0));
    vec4 surface = texelFetch(gb_surface, px, 0);
    vec4 emissive_ao = texelFetch(gb_emissive, px, 0);
    vec3 bounce = vec3(1.0);
    vec3 indirect = vec3(0.0);
    if (OCCLUSION != 0u) {
        // Light bounced between occluders takes their colour (the fit takes the surroundings'
        // albedo to be the surface's): the diffuse light gets each channel's own multi-bounce,
        // the specular occlusion the grey one of the albedo's luminance.
        vec3 bounced;
        float visibility = screen_visibility(px, view_distance(p), bounced);
        // The sky the world light sees hidden and the screen does not (OCCLUSION's bit 2): taken
        // away from the fit's result as it is (no bounce of it credited but the measured one),
        // so the fit gives back multiple bounces only for the occluders the screen shows, whose
        // colour it takes to be the surface's; the world light knows the hidden ones' colour.
        float hidden = (OCCLUSION & 4u) != 0u ? world_hidden(visibility, bounced, texelFetch(gb_specular, px, 0)) : 0.0;
        float grey = gtao_multibounce(visibility, dot(albedo.rgb, vec3(0.2126, 0.7152, 0.0722))) - hidden;
        vec3 coloured = vec3(gtao_multibounce(visibility, albedo.r), gtao_multibounce(visibility, albedo.g),
                             gtao_multibounce(visibility, albedo.b)) - hidden;
        visibility -= hidden;
        if ((OCCLUSION & 6u) != 0u) {
            // The occluders' own light that the screen shows (occlusion.frag: one bounce of the
            // environment's off them), and the world light's, where it exceeds what the fit
            // gives back: per channel, the diffuse light is the larger of the fit's and the
            // visible environment's plus the measured bounce (the fit knows the bounces the
            // screen cannot show; the screen and the world, the occluders' real colour and
            // light). Both under the material's occlusion texture.
            vec3 e = env_irradiance(oct_decode(fr.xy));
            indirect = max(bounced - e * (coloured - visibility), vec3(0.0)) * emissive_ao.a;
        }
        emissive_ao.a *= grey;
        bounce = grey > 1e-4 ? coloured / grey : vec3(1.0);
    }
    // With the world light in the specular target, the material's own dielectric layer: F0 from
    // its index of refraction, weight 1 (the plan leaves the world light out where a material has
    // KHR_materials_specular's data; surface.glsl writes the same for the others).
    vec4 specular = (OCCLUSION & 4u) != 0u
        ? vec4(vec3(min(materials[min(uint(surface.y + 0.5), frame.material_count - 1u)].extra.x, 1.0)), 1.0)
        : texelFetch(gb_specular, px, 0);
    vec3 radiance = shade_surface(p, v, albedo, fr, surface, texelFetch(gb_fabric, px, 0),
                                  emissive_ao, specular,
                                  vec4(0.0), vec4(1.0), vec4(0.0), vec3(0.0, 0.0, 1.0), vec4(0.0),
                                  vec4(0.0), bounce, indirect);
    // Never NaN or Inf into the image.
    out_color = vec4(all(lessThan(abs(radiance), vec3(1e30))) ? radiance : vec3(0.0), 1.0);
}

void main() {
    shade_pixel();
    if (TONE_CURVE != 0u) {
        out_color = tone_map_texel(out_color, TONE_CURVE - 1u, frame.ambient_sky.a);
    }
}
