// KHR_lights_punctual lights: the incoming direction and illuminance at a point, with the
// spec's range window and spot cone. Shared by lighting.frag (per pixel) and gbuffer.vert (per
// vertex, for Gouraud shading in `weft compare`).
//
// The includer declares `const uint LIGHT_TYPES` (bit 0 directional, 1 point, 2 spot): code for
// the types not in it is compiled out; and `const uint RANGE_CULLING` (1: lights out of range
// return nothing before the falloff; 0: the falloff, which is 0 there too, is always evaluated).
#ifndef WEFT_LIGHTS_GLSL
#define WEFT_LIGHTS_GLSL

#include "frame.glsl"

// Irradiance-style falloff of KHR_lights_punctual: inverse square, windowed to zero at range.
float distance_falloff(float dist, float range) {
    float inv_sq = 1.0 / max(dist * dist, 1e-8);
    if (range <= 0.0) {
        return inv_sq;
    }
    float r = dist / range;
    float window = clamp(1.0 - r * r * r * r, 0.0, 1.0);
    return window * window * inv_sq;
}

// Direction to the light (unit) and the illuminance it brings, per colour channel.
// Zero, without the falloff's work, where a point or spot light's range cannot reach p.
vec3 light_incoming(Light light, vec3 p, out vec3 l) {
    uint type = uint(light.direction_type.w + 0.5);
    vec3 color = light.color_intensity.rgb * light.color_intensity.a;
    if ((LIGHT_TYPES & 1u) != 0u && type == LIGHT_DIRECTIONAL) {
        l = -light.direction_type.xyz;
        return color;
    }
    if ((LIGHT_TYPES & 6u) == 0u) {
        l = vec3(0.0, 1.0, 0.0);
        return vec3(0.0);
    }
    vec3 to_light = light.position_range.xyz - p;
    float range = light.position_range.w;
    float dist2 = dot(to_light, to_light);
    if (RANGE_CULLING != 0u && range > 0.0 && dist2 >= range * range) {
        // Culled: out of range.
        l = vec3(0.0, 1.0, 0.0);
        return vec3(0.0);
    }
    float dist = sqrt(dist2);
    l = dist > 0.0 ? to_light / dist : vec3(0.0, 1.0, 0.0);
    float atten = distance_falloff(dist, light.position_range.w);
    if ((LIGHT_TYPES & 4u) != 0u && type == LIGHT_SPOT) {
        float cd = dot(light.direction_type.xyz, -l);
        float a = clamp(cd * light.spot.x + light.spot.y, 0.0, 1.0);
        atten *= a * a;
    }
    return color * atten;
}

#endif
