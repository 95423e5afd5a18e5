#version 460
// Edge anti-aliasing of the tone-mapped image (--aa fxaa, the default of renders and the viewer):
// fast approximate anti-aliasing in the manner of Lottes' FXAA 3.11 "quality" preset, written for
// weft. Each pixel finds whether it sits on a luma edge, which way the edge runs, and how far
// along it the edge's ends are; it then samples the image shifted across the edge by how far the
// pixel is from the edge's middle (a pixel near an end of a staircase step moves most), and never
// less than its sub-pixel aliasing (a lone bright or dark pixel is blended with its neighbours).
// The image is an sRGB target: sampling it returns linear colour, and the blend itself is linear.
// Luma is taken from its encoded bytes (the same image viewed as UNORM, as FXAA 3.11 takes luma in
// the display encoding): on lavapipe the sRGB decode of every look-up was half the pass (1080p:
// 99 ms with every look-up decoded, 53 ms with none), and the edge search reads nothing else.
#include "fxaa.glsl"

layout(location = 0) in vec2 in_uv;
layout(location = 0) out vec4 out_color;

// How much sub-pixel aliasing is removed (0: none, 1: all; softer).
const float SUBPIXEL = 0.75;
// The search along an edge: steps (in pixels) of growing length, 12 of them (up to 32 pixels).
const int SEARCH_STEPS = 12;
const float STEP[SEARCH_STEPS] = float[SEARCH_STEPS](1.0, 1.0, 1.0, 1.0, 1.0, 1.5, 2.0, 2.0, 2.0, 2.0, 4.0, 8.0);

void main() {
    ivec2 size = textureSize(image, 0);
    vec2 texel = 1.0 / vec2(size);
    ivec2 p = ivec2(gl_FragCoord.xy);
    vec2 uv = (vec2(p) + 0.5) * texel;
    vec4 centre = texelFetch(image, p, 0);
    FxaaCross c = fxaa_cross(p);
    if (!fxaa_on_edge(c)) {
        out_color = centre;
        return;
    }
    float m = c.m;
    float n = c.n;
    float s = c.s;
    float e = c.e;
    float w = c.w;
    float range = c.range;
    float nw = luma_at(p + ivec2(-1, -1));
    float ne = luma_at(p + ivec2(1, -1));
    float sw = luma_at(p + ivec2(-1, 1));
    float se = luma_at(p + ivec2(1, 1));

    // Which way the edge runs: the larger second difference across it.
    float across_rows = 2.0 * abs(n + s - 2.0 * m) + abs(ne + se - 2.0 * e) + abs(nw + sw - 2.0 * w);
    float across_cols = 2.0 * abs(e + w - 2.0 * m) + abs(ne + nw - 2.0 * n) + abs(se + sw - 2.0 * s);
    bool horizontal = across_rows >= across_cols;

    // The side of the edge with the steeper step; the search runs half a pixel towards it.
    float l_neg = horizontal ? n : w;
    float l_pos = horizontal ? s : e;
    float g_neg = abs(l_neg - m);
    float g_pos = abs(l_pos - m);
    bool towards_neg = g_neg >= g_pos;
    float gradient = 0.25 * max(g_neg, g_pos);
    float step_across = horizontal ? texel.y : texel.x;
    float local = 0.5 * ((towards_neg ? l_neg : l_pos) + m);
    if (towards_neg) {
        step_across = -step_across;
    }
    vec2 on_edge = uv;
    if (horizontal) {
        on_edge.y += 0.5 * step_across;
    } else {
        on_edge.x += 0.5 * step_across;
    }

    // Walk both ways along the edge until the luma there leaves the edge's local average.
    vec2 along = horizontal ? vec2(texel.x, 0.0) : vec2(0.0, texel.y);
    vec2 a = on_edge - along;
    vec2 b = on_edge + along;
    float end_a = luma(textureLod(encoded, a, 0.0).rgb) - local;
    float end_b = luma(textureLod(encoded, b, 0.0).rgb) - local;
    bool done_a = abs(end_a) >= gradient;
    bool done_b = abs(end_b) >= gradient;
    for (int i = 1; i < SEARCH_STEPS && !(done_a && done_b); ++i) {
        if (!done_a) {
            a -= along * STEP[i];
            end_a = luma(textureLod(encoded, a, 0.0).rgb) - local;
            done_a = abs(end_a) >= gradient;
        }
        if (!done_b) {
            b += along * STEP[i];
            end_b = luma(textureLod(encoded, b, 0.0).rgb) - local;
            done_b = abs(end_b) >= gradient;
        }
    }
    float dist_a = horizontal ? uv.x - a.x : uv.y - a.y;
    float dist_b = horizontal ? b.x - uv.x : b.y - uv.y;
    bool nearer_a = dist_a < dist_b;
    float nearest = min(dist_a, dist_b);
    float span = dist_a + dist_b;
    // Move across the edge only at the end where the edge's step is (the end whose luma changes
    // the other way than the centre's does from the local average).
    bool centre_below = m < local;
    float end = nearer_a ? end_a : end_b;
    float shift = ((end < 0.0) != centre_below) ? 0.5 - nearest / span : 0.0;

    // Sub-pixel aliasing: how far the centre is from the 3 x 3 neighbourhood's mean.
    float mean = (2.0 * (n + s + e + w) + nw + ne + sw + se) / 12.0;
    float sub = clamp(abs(mean - m) / range, 0.0, 1.0);
    sub = (-2.0 * sub + 3.0) * sub * sub;
    shift = max(shift, sub * sub * SUBPIXEL);

    vec2 at = uv;
    if (horizontal) {
        at.y += shift * step_across;
    } else {
        at.x += shift * step_across;
    }
    out_color = vec4(textureLod(image, at, 0.0).rgb, centre.a);
}
