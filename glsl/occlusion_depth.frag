#version 460
// The occlusion pass, step 1 of 3: the G-buffer's depth at half resolution, the top-left pixel of
// each 2 x 2 block (where occlusion.frag makes its estimate), as one 32-bit float a texel. The
// estimates' 24 depth samples each read this instead of the full-resolution depth-stencil image:
// a quarter of the texels, and on lavapipe an R32F texel is 4 bytes where D32_SFLOAT_S8_UINT is 8.
// The same depth goes to a half-resolution depth attachment, which steps 2 and 3 are drawn against
// at the far plane with depth test LESS: they run where a surface is (llvmpipe skips every 4 x 4
// block that fails the test everywhere, where an early return in the shader would skip nothing).
layout(set = 0, binding = 25) uniform sampler2D gb_depth;  // G-buffer depth (D32), fetched per texel

layout(location = 0) in vec2 in_uv;
layout(location = 0) out float out_depth;  // the depth of the block's top-left pixel (R32F, half resolution)

void main() {
    ivec2 px = min(2 * ivec2(gl_FragCoord.xy), textureSize(gb_depth, 0) - 1);
    out_depth = texelFetch(gb_depth, px, 0).r;
    gl_FragDepth = out_depth;
}
