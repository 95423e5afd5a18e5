#version 460
// Exposure and tone mapping (Khronos PBR Neutral) of the HDR target; the sRGB encoding is done by
// the RGBA8_SRGB output target. Debug views pass through unmapped.
layout(set = 0, binding = 0) uniform sampler2D hdr;

layout(push_constant, std430) uniform Tonemap {
    float exposure;   // linear scale, 2^EV
    uint passthrough; // 1: no curve (debug views)
} tm;

layout(location = 0) in vec2 in_uv;
layout(location = 0) out vec4 out_color;

vec3 pbr_neutral(vec3 color) {
    const float start_compression = 0.8 - 0.04;
    const float desaturation = 0.15;
    float x = min(color.r, min(color.g, color.b));
    float offset = x < 0.08 ? x - 6.25 * x * x : 0.04;
    color -= offset;
    float peak = max(color.r, max(color.g, color.b));
    if (peak < start_compression) {
        return color;
    }
    const float d = 1.0 - start_compression;
    float new_peak = 1.0 - d * d / (peak + d - start_compression);
    color *= new_peak / peak;
    float g = 1.0 - 1.0 / (desaturation * (peak - new_peak) + 1.0);
    return mix(color, vec3(new_peak), g);
}

void main() {
    vec4 texel = texelFetch(hdr, ivec2(gl_FragCoord.xy), 0);
    vec3 c = texel.rgb;
    // A NaN or Inf here is a bug upstream (the frame reports it); never let it reach the image.
    if (any(isnan(c)) || any(isinf(c))) {
        c = vec3(0.0);
    }
    c = max(c, vec3(0.0));
    if (tm.passthrough == 0u) {
        c = pbr_neutral(c * tm.exposure);
    }
    // Alpha 0 only where the background is transparent (--background none).
    out_color = vec4(clamp(c, 0.0, 1.0), texel.a > 0.5 ? 1.0 : 0.0);
}
