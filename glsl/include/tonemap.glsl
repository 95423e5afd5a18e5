// The tone curves and the 8-bit target's texel from a linear HDR one (tonemap.frag, and the
// lighting pass where it writes the 8-bit image itself: include/lighting_main.glsl's
// TONE_CURVE). The sRGB encoding is done by the RGBA8_SRGB target. Rust twins:
// weft::reference::shading::{pbr_neutral, aces_three, agx}.
#ifndef WEFT_TONEMAP_GLSL
#define WEFT_TONEMAP_GLSL

// The curves' codes (weft::reference::shading::ToneCurve::code: 0 Khronos PBR Neutral, 1 none
// (clamp), 2 three.js' ACES fit with its 1/2.2 display gamma, 3 AgX), and 4 for a debug view (no
// exposure, no curve).
const uint CURVE_PASSTHROUGH = 4u;

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

// three.js' ACES filmic fit (Stephen Hill's RRT+ODT fit with its input and output matrices), with
// three.js' exposure scale 1/0.6, then the display encoding of the Khronos render-fidelity goldens
// (gamma 1/2.2): returned as the linear value whose sRGB encoding is that, since the target encodes
// with the sRGB curve.
vec3 aces_three(vec3 c) {
    const mat3 m_in = mat3(0.59719, 0.07600, 0.02840, 0.35458, 0.90834, 0.13383, 0.04823, 0.01566, 0.83777);
    const mat3 m_out = mat3(1.60475, -0.10208, -0.00327, -0.53108, 1.10813, -0.07276, -0.07367, -0.00605, 1.07602);
    vec3 v = m_in * (c / 0.6);
    v = (v * (v + 0.0245786) - 0.000090537) / (v * (0.983729 * v + 0.4329510) + 0.238081);
    v = clamp(m_out * v, 0.0, 0.9999);
    vec3 g = pow(v, vec3(1.0 / 2.2));
    // sRGB decode of the gamma-encoded value.
    return mix(g / 12.92, pow((g + 0.055) / 1.055, vec3(2.4)), step(vec3(0.04045), g));
}

// AgX (Troy Sobotka's, in Benjamin Wrensch's minimal form): the inset matrix, a log2 encoding from
// -12.47393 to 4.026069 EV, the default contrast as a 7th-order polynomial, the outset matrix
// (the inset's inverse) and the 2.2 display EOTF back to linear.
vec3 agx(vec3 c) {
    const mat3 inset = mat3(0.842479062253094, 0.0423282422610123, 0.0423756549057051,
                            0.0784335999999992, 0.878468636469772, 0.0784336,
                            0.0792237451477643, 0.0791661274605434, 0.879142973793104);
    const mat3 outset = mat3(1.19687900512017, -0.0528968517574562, -0.0529716355144438,
                             -0.0980208811401368, 1.15190312990417, -0.0980434501171241,
                             -0.0990297440797205, -0.0989611768448433, 1.15107367264116);
    const float min_ev = -12.47393;
    const float max_ev = 4.026069;
    vec3 v = inset * c;
    v = clamp(log2(max(v, vec3(1e-10))), min_ev, max_ev);
    v = (v - min_ev) / (max_ev - min_ev);
    vec3 x2 = v * v;
    vec3 x4 = x2 * x2;
    v = -17.86 * x4 * x2 * v + 78.01 * x4 * x2 - 126.7 * x4 * v + 92.06 * x4 - 28.72 * x2 * v
        + 4.361 * x2 - 0.1718 * v + 0.002857;
    v = outset * v;
    return pow(max(v, vec3(0.0)), vec3(2.2));
}

// The 8-bit target's texel (linear, before the target's sRGB encoding) from the HDR texel
// `texel` (rgb radiance, a coverage) by tone curve `curve` (a constant where it is called, so
// only that curve is compiled in: llvmpipe runs every side of a branch on a uniform value) after
// `exposure` (linear, 2^EV).
vec4 tone_map_texel(vec4 texel, uint curve, float exposure) {
    vec3 c = texel.rgb;
    // A NaN or Inf here is a bug upstream (the frame reports it); never let it reach the image.
    if (any(isnan(c)) || any(isinf(c))) {
        c = vec3(0.0);
    }
    c = max(c, vec3(0.0));
    // Coverage: 1 wherever something opaque or a background was drawn; over a transparent
    // background (--background none) 0 where nothing was, and a blended surface's alpha where
    // only blended surfaces were. Those are premultiplied (the transparent pass blends ONE,
    // ONE_MINUS_SRC_ALPHA): the curve is applied to the colour itself and the PNG gets straight
    // alpha, as it defines it.
    float coverage = clamp(texel.a, 0.0, 1.0);
    if (coverage > 0.0 && coverage < 1.0) {
        c /= coverage;
    }
    if (curve != CURVE_PASSTHROUGH) {
        c *= exposure;
        if (curve == 0u) {
            c = pbr_neutral(c);
        } else if (curve == 2u) {
            c = aces_three(c);
        } else if (curve == 3u) {
            c = agx(c);
        }
    }
    return vec4(clamp(c, 0.0, 1.0), coverage);
}

#endif
