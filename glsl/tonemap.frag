#version 460
// Exposure and tone mapping of the HDR target (--tonemap: Khronos PBR Neutral by default, three.js'
// ACES fit, AgX, or none: include/tonemap.glsl); the sRGB encoding is done by the RGBA8_SRGB
// output target. Debug views pass through unmapped. Where nothing reads the HDR image, the
// lighting pass applies the same curve itself and this pass does not run (lighting_main.glsl's
// TONE_CURVE).
#include "tonemap.glsl"

layout(set = 0, binding = 0) uniform sampler2D hdr;  // the HDR image from lighting.frag

// The tone curve (tonemap.glsl's codes; CURVE_PASSTHROUGH for a debug view): a specialization
// constant, one pipeline per curve in use, because llvmpipe runs every side of a branch on a
// uniform value (the three curves a push constant chose between cost 32 ms at 1080p, the one in
// use 15 ms).
layout(constant_id = 0) const uint CURVE = 0u;

layout(push_constant, std430) uniform Tonemap {
    float exposure;   // linear scale, 2^EV
} tm;

layout(location = 0) in vec2 in_uv;
layout(location = 0) out vec4 out_color;

void main() {
    out_color = tone_map_texel(texelFetch(hdr, ivec2(gl_FragCoord.xy), 0), CURVE, tm.exposure);
}
