// Image-based lighting (docs/fabric-model.md §6): environment look-ups, the spherical-harmonic
// irradiance, low-discrepancy samples, the GGX and Ashikhmin–Shirley half-vector samplers, and
// the filtered-importance-sampling mip level (Křivánek & Colbert 2008).
//
// Rust twins: weft::env (sh_eval, hammersley, env_from_world, the equirect convention) and
// weft::reference::ibl_twin (the samplers, fis_lod, specular_occlusion, f32; compared on the GPU
// by tests/ibl_probe_gpu.rs). Cube faces are in env space: a world direction w is looked up at
// env_dir(w).
#ifndef WEFT_IBL_GLSL
#define WEFT_IBL_GLSL

#include "fabric.glsl"

#define IBL_PI 3.14159265358979323846

// The environment direction of world direction w: rows of env_from_world (--env-rotation).
vec3 env_dir(vec3 w, vec4 r0, vec4 r1, vec4 r2) {
    return vec3(dot(r0.xyz, w), dot(r1.xyz, w), dot(r2.xyz, w));
}

// Irradiance/π at env-space normal n from the SH9 coefficients (weft::env::sh_eval), >= 0.
vec3 sh_irradiance(vec4 sh[9], vec3 n) {
    float x = n.x;
    float y = n.y;
    float z = n.z;
    vec3 e = sh[0].rgb * 0.2820948
        + sh[1].rgb * (0.4886025 * y)
        + sh[2].rgb * (0.4886025 * z)
        + sh[3].rgb * (0.4886025 * x)
        + sh[4].rgb * (1.0925484 * x * y)
        + sh[5].rgb * (1.0925484 * y * z)
        + sh[6].rgb * (0.3153916 * (3.0 * z * z - 1.0))
        + sh[7].rgb * (1.0925484 * x * z)
        + sh[8].rgb * (0.5462742 * (x * x - y * y));
    return max(e, vec3(0.0));
}

// The Hammersley point i of n: (i/n, radical inverse of i).
vec2 hammersley(uint i, uint n) {
    return vec2(float(i) / float(n), float(bitfieldReverse(i)) * 2.3283064365386963e-10);
}

// Point i of block `block` of the 2D Sobol' (0,2)-sequence in blocks of n points (n a power of
// two): point block·n + i, its first coordinate the van der Corput radical inverse, its second
// Sobol's second dimension (the direction numbers v_b = v_(b-1) xor v_(b-1)/2 from 1/2). Each
// block alone is a (0,m,2)-net of n points (as stratified as the Hammersley set), and the first
// 2^k blocks together are one of 2^k·n points: pixels that pool their samples take different
// blocks and together sample as well as one pixel taking them all.
// The second coordinate without a loop over j's bits (a loop llvmpipe runs for the longest
// index of a vector of pixels, and once more): the direction numbers are the binomial
// coefficients mod 2, so the coordinate is the bit-reversed j times that matrix, five shifted
// xors (Rust twin checked against the direction numbers: weft::reference::env_light).
vec2 sobol_block(uint i, uint n, uint block) {
    uint j = block * n + i;
    uint y = bitfieldReverse(j);
    y ^= y << 16u;
    y ^= (y & 0x00FF00FFu) << 8u;
    y ^= (y & 0x0F0F0F0Fu) << 4u;
    y ^= (y & 0x33333333u) << 2u;
    y ^= (y & 0x55555555u) << 1u;
    return vec2(float(bitfieldReverse(j)), float(y)) * 2.3283064365386963e-10;
}

// A GGX half vector in the local frame (z = n) with pdf D(h)·h.z, alpha = roughness².
// cos²θ = (1 - y)/((1 - y) + a²y) and sin²θ = a²y/((1 - y) + a²y), each without cancellation
// (1 - cos²θ loses half its digits when the lobe is narrow).
vec3 ggx_sample_h(vec2 xi, float alpha) {
    float a2 = alpha * alpha;
    float phi = 2.0 * IBL_PI * xi.x;
    float den = (1.0 - xi.y) + a2 * xi.y;
    float cos_t = sqrt((1.0 - xi.y) / den);
    float sin_t = sqrt(a2 * xi.y / den);
    return vec3(sin_t * cos(phi), sin_t * sin(phi), cos_t);
}

// An A–S half vector in the local frame with pdf as_d(h, eu, ev) (weft::reference::brdf::sampling
// ::sample_h): φ0 = atan(k·tan(πr/2)), k = sqrt((eu+1)/(ev+1)), mirrored to the quadrant
// floor(4·xi.x); cos θ = xi.y^(1/(eu cos²φ + ev sin²φ + 1)). (cos φ0, sin φ0) is taken as the
// direction of (cos x, k·sin x), x = πr/2: no tan (unbounded error near π/2 under Vulkan's
// precision rules), no atan, no trigonometry of φ afterwards.
// Also gives the exponent E = eu cos²φ + ev sin²φ at the sample and log2 cos θ =
// log2(xi.y)/(E + 1), from which hn^E' = exp2(E'·log2 cos θ) for any exponent E' at the same φ
// (as_power's value, from xi.y itself: nothing cancels where cos θ rounds to 1).
vec3 as_sample_h_log(vec2 xi, float eu, float ev, out float e, out float log_cos) {
    float q = clamp(floor(4.0 * xi.x), 0.0, 3.0);
    float r = 4.0 * xi.x - q;
    float x = 0.5 * IBL_PI * min(r, 0.9999999);
    float k = sqrt((eu + 1.0) / (ev + 1.0));
    vec2 d = vec2(max(cos(x), 0.0), k * sin(x));
    d = d / sqrt(max(dot(d, d), 1e-30));
    float cp = (q == 1.0 || q == 2.0) ? -d.x : d.x;
    float sp = q >= 2.0 ? -d.y : d.y;
    e = eu * cp * cp + ev * sp * sp;
    log_cos = log2(max(xi.y, 1e-30)) * (1.0 / (e + 1.0));
    float cos_t = exp2(log_cos);
    float sin_t = sqrt(max(1.0 - cos_t * cos_t, 0.0));
    return vec3(sin_t * cp, sin_t * sp, cos_t);
}

vec3 as_sample_h(vec2 xi, float eu, float ev) {
    float e;
    float log_cos;
    return as_sample_h_log(xi, eu, ev, e, log_cos);
}

// A cosine-distributed direction in the local frame (pdf z/π).
vec3 cosine_sample(vec2 xi) {
    float r = sqrt(xi.x);
    float phi = 2.0 * IBL_PI * xi.y;
    return vec3(r * cos(phi), r * sin(phi), sqrt(max(1.0 - xi.x, 0.0)));
}

// The mip level of filtered importance sampling: half the log2 ratio of the solid angle a sample
// stands for, 1/(n·pdf), to a texel's of the level-0 cube face of `size` (4π/(6 size²)); pdf per
// unit solid angle. Without Křivánek & Colbert's +1 bias: measured on the cloth (weft bench --ibl),
// the bias blurred the anisotropic A–S lobes too much (fis:16 close-up 12 % against 9 % without).
float fis_lod(float pdf, uint n, float size) {
    float omega_s = 1.0 / (float(n) * max(pdf, 1e-30));
    float omega_p = 4.0 * IBL_PI / (6.0 * size * size);
    return max(0.5 * log2(omega_s / omega_p), 0.0);
}

// Lagarde & de Rousiers 2014 (Moving Frostbite to PBR, eq. 46): the specular occlusion of a
// surface with ambient occlusion ao, seen at n·v, with roughness r.
float specular_occlusion(float nv, float ao, float roughness) {
    return clamp(pow(max(nv + ao, 0.0), exp2(-16.0 * roughness - 1.0)) - 1.0 + ao, 0.0, 1.0);
}

// acos on [0, 1] by Abramowitz & Stegun 4.4.45 (|error| ≤ 6.7e-5 rad): only a square root and
// products, so the GPU and the Rust twin agree to their rounding, where Vulkan lets acos err by
// 4096 ulp (inherited from atan2: the twins of cone_occlusion were 0.1 % apart with it).
float acos01(float x) {
    return sqrt(1.0 - x) * (1.5707288 + x * (-0.2121144 + x * (0.0742610 - 0.0187293 * x)));
}

// How much of the smaller of two spherical caps (half-angles a1, a2, axes d apart) lies in the
// larger: 1 while inside (d ≤ |a1 - a2|), 0 once they part (d ≥ a1 + a2), a smoothstep between
// (Oat & Sander 2007, "Ambient aperture lighting", the approximation Jimenez et al. 2016 take for
// specular occlusion). The overlap's solid angle is this times 2π(1 - cos min(a1, a2)).
float cap_overlap(float a1, float a2, float d) {
    float lo = max(a1, a2) - min(a1, a2);
    float x = clamp((a1 + a2 - d) / max(a1 + a2 - lo, 1e-6), 0.0, 1.0);
    return x * x * (3.0 - 2.0 * x);
}

// The share of a lobe's environment light that an occlusion ao leaves, from cones (Jimenez et al.
// 2016, §5): the visible directions as a cone about n whose cosine-weighted visibility is ao
// (sin² of its half-angle), the lobe as a cone about the mirror direction (n·v from n) whose
// cosine is 10^(-α), α = roughness² (a GGX lobe's spread, as Filament's cone occlusion takes
// it); their overlap over the lobe's overlap with the open hemisphere, so an open surface keeps
// all (the split sum's albedo already has the horizon).
// Used for the sheen's light: a rough Charlie lobe lives near the horizon, which occlusion takes
// first, so ao alone lit the inside of folds (measured against the path tracers:
// docs/fidelity.md). Rust twin: weft::reference::ibl_twin::cone_occlusion.
float cone_occlusion(float nv, float ao, float roughness) {
    float cos_visible = sqrt(clamp(1.0 - ao, 0.0, 1.0));
    float alpha = roughness * roughness;
    float cos_lobe = clamp(exp2(-3.321928 * alpha), 0.0, 1.0);
    float d = acos01(clamp(nv, 0.0, 1.0));
    float visible = acos01(cos_visible);
    float lobe = acos01(cos_lobe);
    // The smaller cap's 1 - cos over the lobe's (the lobe is never wider than the hemisphere).
    float caps = min((1.0 - cos_visible) / max(1.0 - cos_lobe, 1e-7), 1.0);
    // The open hemisphere is the visibility cone of ao = 1, its angle by the same acos01, so the
    // share tends to 1 as ao does; at ao = 1 it is 1 exactly (also for a mirror lobe at the
    // horizon, where both overlaps vanish).
    float open = acos01(0.0);
    float share = caps * cap_overlap(visible, lobe, d) / max(cap_overlap(open, lobe, d), 1e-6);
    return ao >= 1.0 ? 1.0 : clamp(share, 0.0, 1.0);
}

// The split sum's look-up direction for roughness r about normal n: the mirror direction bent
// towards the normal as the lobe widens (Lagarde & de Rousiers 2014, "dominant direction"): a
// rough lobe's mass is nearer n.
vec3 dominant_dir(vec3 n, vec3 r, float roughness) {
    float a = roughness * roughness;
    return normalize(mix(n, r, (1.0 - a) * (sqrt(1.0 - a) + a)));
}

// The diffuse factor of the fabric's diffuse term under a uniform-in-cosine environment: 1 for
// Lambert, (1 - rs)(1 - (1 - n·k2/2)^5) for the A–S coupled diffuse (its hemispherical
// integral, which its 28/(23π) normalises to exactly that).
// The same from the record's rs and flags alone (the twin's `formula::fabric_diffuse_albedo`).
float fabric_diffuse_factor(float rs, uint flags, float nk2) {
    if ((flags & FABRIC_FLAG_COUPLED_DIFFUSE) == 0u) {
        return 1.0;
    }
    float b = 1.0 - 0.5 * clamp(nk2, 0.0, 1.0);
    float b2 = b * b;
    return (1.0 - rs) * (1.0 - b2 * b2 * b);
}

float fabric_diffuse_albedo(GpuFabric f, float nk2) {
    return fabric_diffuse_factor(f.rs, f.flags, nk2);
}

#endif
