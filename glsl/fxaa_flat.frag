#version 460
// The anti-aliasing pass's first draw where the G-buffer's depth has a stencil: every pixel off
// an edge (fxaa_on_edge, include/fxaa.glsl: the test fxaa.frag makes first) is copied from the
// tone-mapped image as fxaa.frag would leave it, and its stencil marked by the pipeline; a pixel
// on an edge is discarded. fxaa.frag is then drawn where no mark is: llvmpipe skips every 4 x 4
// block without a pixel on an edge, where it would run the whole edge search under an empty
// mask (its branches do not jump).
#include "fxaa.glsl"

layout(location = 0) in vec2 in_uv;
layout(location = 0) out vec4 out_color;

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    if (fxaa_on_edge(fxaa_cross(p))) {
        discard;
    }
    out_color = texelFetch(image, p, 0);
}
