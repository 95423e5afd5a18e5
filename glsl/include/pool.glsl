// Pooling the fabric lobes' environment samples over a pixel's neighbourhood (issue 31 item 1):
// fabric_lobes.frag takes each woven pixel's samples, lighting.frag sums those of the pixels
// around it whose surface agrees with its own. Close up, neighbouring pixels see almost the same
// A–S lobe, so their samples are samples of each other's lobe; pixels whose lobes differ by more
// than a fraction of the lobe's width keep apart.
#ifndef WEFT_POOL_GLSL
#define WEFT_POOL_GLSL

#include "fabric.glsl"
#include "frame.glsl"

// The angle, in units of the fabric's narrow lobe width 1/sqrt(max exponent), within which two
// pixels' normals and tangents must agree to pool their lobe samples: at a quarter the pooled
// lobes' centres differ by half their width at most (the reflection turns twice as fast as the
// normal). Measured (weft bench --ibl): 0.25 keeps the mid and far views' accuracy, where a fixed
// 5.7° pooled across the cloth's curvature and lost 1-2 dB on the lobes.
const float POOL_ANGLE = 0.25;

// The cosine two pixels of fabric f must exceed between their normals and between their
// tangents to pool.
float fabric_pool_near(GpuFabric f) {
    return cos(POOL_ANGLE * inversesqrt(max(max(f.e_along, f.e_across), 1.0)));
}

// Whether a pixel of material `material` with normal n and tangent t pools with a pixel of
// material `mq` with normal nq and tangent tq (`near`: fabric_pool_near). An empty pixel's
// frame target is zero, its normal equal to its tangent, which no fabric pixel's normal and
// tangent both come near.
bool fabric_pool_agrees(vec3 n, vec3 t, float material, vec3 nq, vec3 tq, float mq, float near) {
    return abs(mq - material) < 0.5 && dot(nq, n) > near && dot(tq, t) > near;
}

// The Sobol' block (sobol_block) pixel px takes when pixels pool within `radius` of each other
// (fabric_env_lobe_sums' `block` is this + 1):
// its place in a tiling of the screen by (2·radius + 1)² squares, so that every window the
// lighting pass pools holds each block once and its pooled samples are the first (2·radius + 1)²
// blocks of the sequence.
uint fabric_pool_block(ivec2 px, uint radius) {
    uint w = 2u * radius + 1u;
    uvec2 p = uvec2(px);
    return p.x % w + w * (p.y % w);
}

// The bit of the pixel at offset d (within `radius`, not the centre) in a pixel's pooling mask:
// the window's pixels in rows from the top left, the centre left out.
uint fabric_pool_bit(ivec2 d, uint radius) {
    int w = 2 * int(radius) + 1;
    int i = (d.y + int(radius)) * w + d.x + int(radius);
    int centre = (w * w) / 2;
    return 1u << uint(i < centre ? i : i - 1);
}

// The offset of the pixel whose bit is `bit` (fabric_pool_bit's inverse).
ivec2 fabric_pool_offset(int bit, uint radius) {
    int w = 2 * int(radius) + 1;
    int i = bit < (w * w) / 2 ? bit : bit + 1;
    return ivec2(i % w, i / w) - int(radius);
}

#endif
