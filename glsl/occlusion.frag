#version 460
// The occlusion pass, step 2 of 3 (`--occlusion gtao`, planned when an environment lights the
// scene): how much of each pixel's cosine-weighted hemisphere is open to the environment, by
// ground-truth ambient occlusion (GTAO, include/occlusion.glsl) over the depth buffer, at half
// resolution (one estimate per 2 x 2 pixels, at its top-left pixel, whose depth step 1,
// occlusion_depth.frag, keeps in a half-resolution R32F image that the depth samples read). Per estimate,
// SLICES planes through the view vector at angles that a 4 x 4 pattern of estimates turns (so the
// 4 x 4 blur of step 3, occlusion_blur.frag, averages 16 x SLICES evenly spaced directions); in
// each, the highest horizon on either side among STEPS depth samples out to the world radius,
// falling off to none over its outer 60 %; the visible arc between the horizons, weighted by the
// normal's projection into the plane, over the same with nothing in the way. Written with the
// pixel's view distance for the blur.
// With BOUNCE (`--occlusion gtao`, the default), also the light the occluders send back: the
// part of each side's arc that its horizon hides (gtao_half_arc from the tangent plane to the
// horizon) sees the surface of the depth sample that set the horizon instead of the environment:
// its diffuse light under the environment (the albedo target's base colour times 1 - metallic,
// times the environment's irradiance/π at its normal; a woven occluder's threads' diffuse colour,
// fabric_albedo of its coverage, times the diffuse factor towards this pixel), where its front
// faces this pixel. One bounce, from what the screen shows, one occluder per side and slice (the
// highest: per depth sample, the G-buffer reads and the cube look-up made the pass five times
// slower on lavapipe), its light made once per half-resolution texel by step 1
// (occlusion_depth.frag) and read here at the texel nearest the sample. Weighted and normalised
// as the visibility, so an irradiance/π;
// the lighting pass adds what of it exceeds the multi-bounce fit (lighting.frag's OCCLUSION bit 1).
#include "frame.glsl"
#include "occlusion.glsl"
#include "fabric.glsl"
#include "ibl.glsl"

// Slices per pixel and depth samples per side of a slice.
layout(constant_id = 0) const uint SLICES = 2u;
layout(constant_id = 1) const uint STEPS = 6u;
// 1: the occluders' bounced light too (out_bounce); 0: out_bounce is 0.
layout(constant_id = 2) const uint BOUNCE = 0u;

layout(set = 0, binding = 0, std140) uniform FrameBlock { FrameData frame; };  // the frame uniform (`FrameData`, std140, include/frame.glsl)
layout(set = 0, binding = 21) uniform usampler2D gb_frame;  // G-buffer normal + tangent (RGBA16_UINT): octahedral normal (xy), tangent (zw), frame_encode of include/frame.glsl
layout(set = 0, binding = 26) uniform sampler2D half_depth;  // the G-buffer depth of each 2 x 2 block's top-left pixel (R32F, half resolution; occlusion_depth.frag), gathered
layout(set = 0, binding = 30) uniform usampler2D occluder_light;  // each 2 x 2 block's top-left pixel as an occluder (RGBA32_UINT, half resolution; occlusion_depth.frag's occluder_light_pack): its diffuse light and normal (BOUNCE)

layout(push_constant) uniform OcclusionPush {
    mat4 view_from_clip;  // the inverse of frame.proj (view space from clip space)
    vec4 params;          // x: the radius (world units), y, z: the falloff's scale and offset
                          // (weight = clamp(distance·y + z, 0, 1)), w: unused
} pc;

layout(location = 0) in vec2 in_uv;
layout(location = 0) out vec2 out_occlusion;  // x: visibility (1: open), y: view distance (0: empty); half resolution
layout(location = 1) out vec4 out_bounce;     // rgb: the occluders' bounced light, as an irradiance/π (0 without BOUNCE); a: 0

vec3 view_position(vec2 pixel, float depth) {
    vec2 ndc = pixel * frame.viewport.zw * 2.0 - 1.0;
    vec4 p = pc.view_from_clip * vec4(ndc, depth, 1.0);
    return p.xyz / p.w;
}

void main() {
    // This estimate's pixel of the full-resolution G-buffer, and its place in the pattern.
    ivec2 half_px = ivec2(gl_FragCoord.xy);
    ivec2 px = min(2 * half_px, ivec2(frame.viewport.xy) - 1);
    float depth = texelFetch(half_depth, half_px, 0).r;
    if (depth <= 0.0) {
        out_occlusion = vec2(1.0, 0.0);
        out_bounce = vec4(0.0);
        return;
    }
    vec2 centre = vec2(px) + 0.5;
    vec3 p = view_position(centre, depth);
    bool orthographic = frame.proj[2][3] == 0.0;
    vec3 v = orthographic ? vec3(0.0, 0.0, 1.0) : normalize(-p);
    vec3 n = normalize(mat3(frame.view) * oct_decode(frame_decode(texelFetch(gb_frame, px, 0)).xy));
    // The radius in pixels at this depth (w of the clip position: -z in perspective, 1 otherwise).
    float w = frame.proj[2][3] * p.z + frame.proj[3][3];
    float radius_px = pc.params.x * 0.5 * frame.viewport.y * abs(frame.proj[1][1]) / max(w, 1e-30);
    // The 4 x 4 pattern: the slices' turn in sixteenths, and the steps' offset.
    uint k = uint(half_px.x & 3) + 4u * uint(half_px.y & 3);
    const uint TURN[16] = uint[16](0u, 8u, 2u, 10u, 12u, 4u, 14u, 6u, 3u, 11u, 1u, 9u, 15u, 7u, 13u, 5u);
    float turn = float(TURN[k]) / 16.0;
    float jitter = (float((k * 7u) & 15u) + 0.5) / 16.0;
    vec2 size = frame.viewport.xy;
    // The half-resolution depth's texels lie at the full-resolution pixels 2i + 0.5: samples stay
    // between the first and the last.
    ivec2 half_size = textureSize(half_depth, 0);
    vec2 half_texel = 1.0 / vec2(half_size);
    vec2 q_max = 2.0 * vec2(half_size - 1) + 0.5;

    // The visible arcs, and what they would be with nothing in the way: their ratio is 1 on an
    // open surface whatever the slices' turn (each estimate unbiased on its own, so the blur's
    // unequal weights do not bias the mean).
    float visibility = 0.0;
    float open = 0.0;
    vec3 bounce = vec3(0.0);
    for (uint slice = 0u; slice < SLICES; ++slice) {
        float phi = (float(slice) + turn) / float(SLICES) * PI;
        vec3 dir = vec3(cos(phi), sin(phi), 0.0);
        // The slice's direction on screen (x right, y down, as the projection maps view space).
        vec2 dir_px = vec2(dir.x * frame.proj[0][0] * size.x, dir.y * frame.proj[1][1] * size.y);
        dir_px /= max(length(dir_px), 1e-30);
        vec3 ortho = dir - dot(dir, v) * v;
        vec3 axis = normalize(cross(ortho, v));
        vec3 pn = n - axis * dot(n, axis);
        float pn_len = length(pn);
        if (pn_len < 1e-6) {
            continue;  // the normal is perpendicular to this slice: it adds nothing
        }
        float cos_n = clamp(dot(pn, v) / pn_len, 0.0, 1.0);
        float angle_n = (dot(ortho, pn) < 0.0 ? -1.0 : 1.0) * acos(cos_n);
        // The lowest horizons: the tangent plane's, where nothing occludes.
        float low_pos = cos(angle_n + 0.5 * PI);
        float low_neg = cos(angle_n - 0.5 * PI);
        float horizon_pos = low_pos;
        float horizon_neg = low_neg;
        // Where the sample that set each side's horizon lies (BOUNCE): its pixel and its offset.
        vec2 top_q[2] = vec2[2](vec2(-1.0), vec2(-1.0));
        vec3 top_delta[2] = vec3[2](vec3(0.0), vec3(0.0));
        for (uint step = 0u; step < STEPS; ++step) {
            float s = (float(step) + jitter) / float(STEPS);
            float t = s * s * radius_px + 1.0;
            for (int side = 0; side < 2; ++side) {
                vec2 q = centre + (side == 0 ? t : -t) * dir_px;
                if (any(lessThan(q, vec2(0.5))) || any(greaterThan(q, q_max))) {
                    continue;
                }
                // The depth at q itself, bilinear between the four half-resolution texels around
                // it where they lie on one plane (depth is affine in screen space over a plane, so
                // the point is on the surface and in the slice's plane: a plane seen obliquely
                // does not occlude itself); the nearest texel's, at its pixel, across an edge. On
                // one plane: the two diagonals' sums agree (exactly for an affine depth: a floor
                // seen at a grazing angle, whose depth halves over a few rows near the horizon,
                // passes) within 2 % of the depth, which an edge through one corner fails, and no
                // texel is 1.5 times another's depth, which an edge between two rows fails.
                vec2 tq = (q - 0.5) * 0.5;
                vec2 base = floor(tq);
                vec2 f = tq - base;
                vec4 g = textureGather(half_depth, (base + 1.0) * half_texel, 0);
                float lo = min(min(g.x, g.y), min(g.z, g.w));
                float hi = max(max(g.x, g.y), max(g.z, g.w));
                float d;
                if (lo > 0.0 && abs(g.x + g.z - g.y - g.w) <= 0.02 * lo && hi <= lo * 1.5) {
                    d = mix(mix(g.w, g.z, f.x), mix(g.x, g.y, f.x), f.y);
                } else {
                    // The texel nearest q, which the gather holds (its (0, 1), (1, 1), (1, 0),
                    // (0, 0) texels from base), at its full-resolution pixel. No second fetch
                    // (on lavapipe both sides of this branch run for every pixel).
                    vec2 near = vec2(greaterThanEqual(f, vec2(0.5)));
                    q = 2.0 * (base + near) + 0.5;
                    d = f.y >= 0.5 ? (f.x >= 0.5 ? g.y : g.x) : (f.x >= 0.5 ? g.z : g.w);
                }
                if (d <= 0.0) {
                    continue;  // empty: the environment itself
                }
                vec3 delta = view_position(q, d) - p;
                float dist = length(delta);
                if (dist < 1e-30) {
                    continue;
                }
                float weight = clamp(dist * pc.params.y + pc.params.z, 0.0, 1.0);
                float h = dot(delta / dist, v);
                float raised = mix(side == 0 ? low_pos : low_neg, h, weight);
                if (BOUNCE != 0u && raised > (side == 0 ? horizon_pos : horizon_neg)) {
                    top_q[side] = q;
                    top_delta[side] = delta;
                }
                if (side == 0) {
                    horizon_pos = max(horizon_pos, raised);
                } else {
                    horizon_neg = max(horizon_neg, raised);
                }
            }
        }
        float h0 = -acos(clamp(horizon_neg, -1.0, 1.0));
        float h1 = acos(clamp(horizon_pos, -1.0, 1.0));
        h0 = angle_n + max(h0 - angle_n, -0.5 * PI);
        h1 = angle_n + min(h1 - angle_n, 0.5 * PI);
        visibility += pn_len * gtao_arc(h0, h1, angle_n);
        open += pn_len * gtao_arc(angle_n - 0.5 * PI, angle_n + 0.5 * PI, angle_n);
        if (BOUNCE != 0u) {
            // Each side's hidden arc, from the tangent plane to its horizon, and what hides it.
            float hidden[2] = float[2](gtao_half_arc(angle_n + 0.5 * PI, angle_n) - gtao_half_arc(h1, angle_n),
                                       gtao_half_arc(angle_n - 0.5 * PI, angle_n) - gtao_half_arc(h0, angle_n));
            for (int side = 0; side < 2; ++side) {
                if (!(top_q[side].x >= 0.0 && hidden[side] > 0.0)) {
                    continue;
                }
                // The half-resolution texel nearest the sample (its light made at the texel's
                // pixel by occlusion_depth.frag).
                ivec2 qt = clamp(ivec2(floor((top_q[side] - 0.5) * 0.5 + 0.5)), ivec2(0), half_size - 1);
                uvec4 occluder = texelFetch(occluder_light, qt, 0);
                vec3 ns = oct_decode(frame_decode(uvec4(occluder.w & 0xffffu, occluder.w >> 16u, 0u, 0u)).xy);
                // Its front faces this pixel: the sample's normal (world) against the way back.
                float toward = -dot(mat3(frame.view) * ns, top_delta[side]) / max(length(top_delta[side]), 1e-30);
                // Its diffuse light, for a woven occluder with the coupled diffuse times that
                // diffuse's factor towards this pixel (its 1 - rs already in).
                vec3 diffuse = uintBitsToFloat(occluder.xyz & uvec3(0x7fffffffu, 0xffffffffu, 0xffffffffu))
                             * fabric_diffuse_factor(0.0, (occluder.x >> 31u) != 0u ? FABRIC_FLAG_COUPLED_DIFFUSE : 0u, toward);
                if (toward > 0.0) {
                    bounce += pn_len * hidden[side] * diffuse;
                }
            }
        }
    }
    visibility = open > 0.0 ? visibility / open : 1.0;
    float distance = orthographic ? -p.z : length(p);
    out_occlusion = vec2(clamp(visibility, 0.0, 1.0), max(distance, 1e-30));
    out_bounce = vec4(open > 0.0 ? max(bounce / open, vec3(0.0)) : vec3(0.0), 0.0);
}
