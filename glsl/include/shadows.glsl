// Shadow maps: how much of a light reaches a point, from its tile of the shadow atlas with PCF.
// shade.glsl calls it for every lamp with a shadow map; glsl/env_probe.comp on a batch of inputs.
//
// Rust twin: weft::reference::env_light::shadow_pcf (f32, line for line, over any depth
// comparison), compared on the GPU by tests/env_probe_gpu.rs.
//
// The including shader defines the comparison this reads (the leaf: shade.glsl from the shadow
// atlas, env_probe.comp from a closed-form stand-in):
// - `float shadow_compare(vec3 uvz)`: the atlas's bilinear depth comparison at atlas uv `uvz.xy`
//   against depth `uvz.z` (1 lit, 0 shadowed; a `sampler2DShadow` look-up).
#ifndef WEFT_SHADOWS_GLSL
#define WEFT_SHADOWS_GLSL

#include "frame.glsl"

float shadow_compare(vec3 uvz);

// How much of the light at `light_pos` with shadow record `s` reaches world point p with normal
// n (1 lit, 0 shadowed), with PCF: 3 x 3 bilinear depth comparisons `s.params.z` tile texels
// apart, tent-weighted (one comparison at radius 0). 1 for points outside the map.
float shadow_pcf(Shadow s, vec3 light_pos, vec3 p, vec3 n) {
    // Normal offset: move the look-up point off the surface by about a texel's footprint, so a
    // lit surface does not shadow itself (acne), scaled with the distance for a perspective map.
    float offset = s.params.x;
    if (s.params.y > 0.5) {
        offset *= length(light_pos - p);
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
        return shadow_compare(vec3(clamp(uv, lo, hi), ndc.z));
    }
    float sum = 0.0;
    for (int j = -1; j <= 1; ++j) {
        for (int i = -1; i <= 1; ++i) {
            float w = float((2 - abs(i)) * (2 - abs(j)));
            vec2 q = clamp(uv + vec2(float(i), float(j)) * radius * texel, lo, hi);
            sum += w * shadow_compare(vec3(q, ndc.z));
        }
    }
    return sum / 16.0;
}

#endif
