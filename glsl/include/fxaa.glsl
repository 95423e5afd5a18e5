// What the anti-aliasing pass's two shaders share (fxaa.frag, fxaa_flat.frag): the images they
// read, luma, and the test of whether a pixel sits on an edge, so that the pixels fxaa_flat.frag
// copies are exactly those fxaa.frag would leave as they are.
layout(set = 0, binding = 0) uniform sampler2D image;  // the tone-mapped image (an `R8G8B8A8_SRGB` target, linear filtering, clamp to edge)
layout(set = 0, binding = 1) uniform sampler2D encoded;  // the same image viewed as `R8G8B8A8_UNORM`: its sRGB-encoded values, undecoded (linear filtering, clamp to edge)

// Edges below this contrast (of the local maximum, or absolutely) are left alone.
const float EDGE_RELATIVE = 0.125;
const float EDGE_ABSOLUTE = 0.0312;

// Luma of sRGB-encoded colour (Rec. 601 weights on the encoded values).
float luma(vec3 encoded_rgb) {
    return dot(encoded_rgb, vec3(0.299, 0.587, 0.114));
}

float luma_at(ivec2 p) {
    ivec2 size = textureSize(encoded, 0);
    return luma(texelFetch(encoded, clamp(p, ivec2(0), size - 1), 0).rgb);
}

// The luma of a pixel (m) and of its four neighbours, their maximum and their range.
struct FxaaCross {
    float m;
    float n;
    float s;
    float e;
    float w;
    float hi;
    float range;
};

FxaaCross fxaa_cross(ivec2 p) {
    FxaaCross c;
    c.m = luma_at(p);
    c.n = luma_at(p + ivec2(0, -1));
    c.s = luma_at(p + ivec2(0, 1));
    c.e = luma_at(p + ivec2(1, 0));
    c.w = luma_at(p + ivec2(-1, 0));
    float lo = min(c.m, min(min(c.n, c.s), min(c.e, c.w)));
    c.hi = max(c.m, max(max(c.n, c.s), max(c.e, c.w)));
    c.range = c.hi - lo;
    return c;
}

// Whether the pixel sits on an edge FXAA smooths: its neighbourhood's contrast reaches the
// thresholds.
bool fxaa_on_edge(FxaaCross c) {
    return c.range >= max(EDGE_ABSOLUTE, c.hi * EDGE_RELATIVE);
}
