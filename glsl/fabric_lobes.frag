#version 460
// The fabric lobes' environment samples, for the deferred lighting to pool (issue 31 item 1): one
// fullscreen triangle over the woven pixels (where the G-buffer's stencil says what each pixel
// is; over every pixel otherwise, the others writing zeros) before lighting.frag. Each pixel
// finds which pixels within POOL of it agree with it (fabric_pool_agrees), takes samples of its
// A–S lobes at fis (fabric_pixel_lobe_sums: blocks of the Sobol' (0,2)-sequence from its place
// fabric_pool_block where any does, the Hammersley set otherwise, as a pixel alone; more of them
// the more grazing its view, fabric_lobe_passes), the mip level chosen for all the samples
// pooled, and writes them with the mask of those pixels (fabric_lobe_pack); lighting.frag then
// sums the masked pixels' with its own, so a window of agreeing pixels samples its lobe with
// (2·POOL + 1)² pixels' samples.
#include "frame.glsl"
#include "fabric.glsl"
#include "ibl.glsl"

// As lighting.frag's constants of the same ids: the accuracy level (2 mixture: the pixel's
// coverage weighs the lobes' sampling; 3 supersampled: even weights), N of fis:N, and the
// pooling radius (≥ 1).
layout(constant_id = 0) const uint ACCURACY = 2u;
layout(constant_id = 8) const uint IBL_SAMPLES = 8u;
layout(constant_id = 14) const uint POOL = 1u;

// Set 0 as lighting.frag numbers it (the same resources, one set for both draws).
layout(set = 0, binding = 0, std140) uniform FrameBlock { FrameData frame; };  // the frame uniform (`FrameData`, std140, include/frame.glsl)
layout(set = 0, binding = 1, std430) readonly buffer Materials { Material materials[]; };  // material records (`Material[]`)
layout(set = 0, binding = 2, std430) readonly buffer Fabrics { GpuFabric fabrics[]; };  // fabric records (`GpuFabric[]`)
layout(set = 0, binding = 13) uniform samplerCube env_radiance;  // the environment's radiance cube (RGBA16F, env space, box-filtered mips: env_cube.comp)
layout(set = 0, binding = 14) uniform samplerCube env_specular;  // the GGX-prefiltered specular cube (not read here; env_cubes.glsl declares its look-up)
layout(set = 0, binding = 15) uniform sampler2D env_dfg;  // the split-sum DFG table (not read here; env_cubes.glsl declares its look-up)
layout(set = 0, binding = 21) uniform usampler2D gb_frame;  // G-buffer normal + tangent (RGBA16_UINT): octahedral normal (xy), tangent (zw), frame_encode of include/frame.glsl
layout(set = 0, binding = 22) uniform sampler2D gb_surface;  // G-buffer surface (RGBA16F): roughness, material index, tangent sign, 1 if it receives shadows
layout(set = 0, binding = 23) uniform sampler2D gb_fabric;  // G-buffer fabric coverage (RGBA16F): c_warp, c_weft and each shadow-weighted (s_warp, s_weft)
layout(set = 0, binding = 25) uniform sampler2D gb_depth;  // G-buffer depth (D32)

layout(location = 0) in vec2 in_uv;
layout(location = 0) out uvec4 out_sums;

#include "env_cubes.glsl"
#include "env_light.glsl"
#include "pool.glsl"

void main() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    float depth = texelFetch(gb_depth, px, 0).r;
    vec4 fr = frame_decode(texelFetch(gb_frame, px, 0));
    vec4 surface = texelFetch(gb_surface, px, 0);
    uint material = uint(surface.y + 0.5);
    uint fabric = uint(materials[min(material, frame.material_count - 1u)].metallic_roughness.z + 0.5);
    bool woven = depth > 0.0 && fabric > 0u;
    GpuFabric f = fabrics[max(fabric, 1u) - 1u];
    vec3 n = oct_decode(fr.xy);
    vec3 t = oct_decode(fr.zw);
    float near = fabric_pool_near(f);
    // Whether a neighbour in the pixel's 2 x 2 quad agrees with it (fine derivatives, before any
    // pixel returns): where none does, the cloth turns too fast here for its neighbourhood to
    // pool, and the pixel looks no further (mid and far away, most pixels: llvmpipe skips the
    // search loop below for a block of pixels that all have no turn in it).
    vec4 key = vec4(n, woven ? surface.y : -1.0);
    float sx = (px.x & 1) == 0 ? 1.0 : -1.0;
    float sy = (px.y & 1) == 0 ? 1.0 : -1.0;
    vec4 kx = key + sx * dFdxFine(key);
    vec3 tx = t + sx * dFdxFine(t);
    vec4 ky = key + sy * dFdyFine(key);
    vec3 ty = t + sy * dFdyFine(t);
    bool quad = fabric_pool_agrees(n, t, key.w, kx.xyz, tx, kx.w, near)
             || fabric_pool_agrees(n, t, key.w, ky.xyz, ty, ky.w, near);
    if (!woven) {
        out_sums = uvec4(0u);
        return;
    }
    // Which pixels within POOL agree with this one: the lighting pools exactly these, so the
    // samples' mip level is chosen for all of them.
    ivec2 size = textureSize(gb_frame, 0);
    uint mask = 0u;
    uint pixels = 1u;
    // One loop over the window's other pixels by their bits, not a loop of rows around a loop
    // of columns: llvmpipe runs a loop's body once more under an empty mask after every lane has
    // left, and an inner loop once more per outer turn (13 turns for 8 pixels).
    int others = quad ? (2 * int(POOL) + 1) * (2 * int(POOL) + 1) - 1 : 0;
    for (int bit = 0; bit < others; ++bit) {
        ivec2 q = px + fabric_pool_offset(bit, POOL);
        if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size))) {
            continue;
        }
        vec4 fq = frame_decode(texelFetch(gb_frame, q, 0));
        if (fabric_pool_agrees(n, t, surface.y, oct_decode(fq.xy), oct_decode(fq.zw),
                               texelFetch(gb_surface, q, 0).y, near)) {
            mask |= 1u << uint(bit);
            pixels += 1u;
        }
    }
    vec2 ndc = (vec2(px) + 0.5) * frame.viewport.zw * 2.0 - 1.0;
    vec4 hp = frame.inv_view_proj * vec4(ndc, depth, 1.0);
    vec3 v = normalize(frame.eye.xyz - hp.xyz / hp.w);
    mat3 tbn = fabric_frame(n, t, surface.z);
    vec3 k2 = fabric_local(v, tbn);
    vec4 coverage = ACCURACY == 3u ? vec4(0.5) : texelFetch(gb_fabric, px, 0);
    // A pixel that pools takes its blocks of the Sobol' sequence; one alone the Hammersley set,
    // each as many times its base count as its view needs (fabric_lobe_passes).
    uint window = (2u * POOL + 1u) * (2u * POOL + 1u);
    uint block = pixels > 1u ? fabric_pool_block(px, POOL) + 1u : 0u;
    vec4 weft;
    vec4 warp;
    fabric_pixel_lobe_sums(tbn, k2, coverage, f, IBL_SAMPLES, block, window, pixels, weft, warp);
    out_sums = fabric_lobe_pack(weft, warp, IBL_SAMPLES, mask);
}
