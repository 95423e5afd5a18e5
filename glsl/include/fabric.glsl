// The fabric BRDF (docs/fabric-model.md §1, §3): the Ashikhmin–Shirley lobe, Schlick's Fresnel,
// Lambert and the A–S coupled diffuse, and the two-lobe mixture weighted by the weave coverage.
//
// Twin of src/reference/brdf.rs (module `single`, f32), function for function and line for line;
// tests compare the two on the GPU through glsl/fabric_probe.comp. The only other copy of the BRDF
// is that Rust one: change both together.
//
// Vectors are in the local shading frame: x = k·t, y = k·b, z = k·n (fabric_frame, fabric_local).
// Numerics (model page §5): hn^E from hu², hv² without cancellation (as_power); back-facing gives
// exactly 0; h·k = |k1 + k2|/2, symmetric in k1, k2 and clamped for Fresnel; the lobe's
// denominator is clamped to FABRIC_DENOM_MIN (acts only within 0.08° of grazing).
#ifndef WEFT_FABRIC_GLSL
#define WEFT_FABRIC_GLSL

#define FABRIC_PI 3.14159265358979323846
#define FABRIC_DENOM_MIN 1e-6
#define FABRIC_SERIES_MAX_S 0.25
#define FABRIC_FLAG_COUPLED_DIFFUSE 1u
// The thread colours are multiplied by a texture of the material (WEFT_materials_fabric
// "thread_texture", docs/fabric-model.md §4): its base colour texture, or its sheen colour texture.
#define FABRIC_FLAG_TEXTURE_BASE_COLOR 2u
#define FABRIC_FLAG_TEXTURE_SHEEN_COLOR 4u
// Thread-by-thread colours (surface.glsl's thread_colour): the G-buffer's albedo holds the
// footprint's thread colour, the lighting pass takes it as both threads' albedo.
#define FABRIC_FLAG_THREAD_COLOURS 8u
// A single sheet of cloth (WEFT_materials_fabric "transmission"): the gaps let light straight
// through (the transparent pass blends the cloth over what is behind it by its thread coverage)
// and each thread passes `transmission` of its diffuse light to its other side.
#define FABRIC_FLAG_SHEET 16u

// One material (std430, 80 bytes). Rust twin: weft::fabric::GpuFabric.
struct GpuFabric {
    vec3 rd_warp;          // 0: diffuse albedo of the warp (vertical) thread
    float rs;              // 12: Schlick's reflectance at normal incidence
    vec3 rd_weft;          // 16: diffuse albedo of the weft (horizontal) thread
    float e_along;         // 28: A–S exponent along a thread
    float e_across;        // 32: A–S exponent across a thread
    float cell_per_uv;     // 36: weave cells per texture unit (2/s_p)
    uint flags;            // 40: bit 0 = coupled diffuse, bit 1/2 = thread texture base/sheen colour
    float shadow_strength; // 44: diffuse factor in shadow = 1 - shadow_strength
    uint pattern_lo;       // 48: bit 8j+i = cell (i, j) weft-up, rows 0..3
    uint pattern_hi;       // 52: rows 4..7
    uint cols;             // 56: pattern size in cells along u
    uint rows;             // 60: along v
    float gap;             // 64: s_g/s_p: half the gap, in cells
    float shadow_dist;     // 68: shadow_width/2, in cells
    uint colours;          // 72: with flag bit 3, the thread colours' record in ThreadColours (vec4s)
    float transmission;    // 76: with flag bit 4 (a sheet), the threads' diffuse transmittance τ
};

// Any unit vector perpendicular to unit n (Duff et al. 2017, branchless ONB).
vec3 any_perpendicular(vec3 n) {
    float s = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (s + n.z);
    float b = n.x * n.y * a;
    return vec3(1.0 + s * n.x * n.x * a, s * b, -s * n.x);
}

// The shading frame (columns t, b, n) from a normal and a glTF tangent (t, handedness sign):
// n normalised, t made orthogonal to it, b = sign·cross(n, t). A zero, NaN or infinite normal
// becomes +z; a tangent (nearly) parallel to n, zero or NaN becomes an arbitrary perpendicular;
// a sign that is not negative counts as +1.
mat3 fabric_frame(vec3 n, vec3 t, float sign_) {
    float nn = dot(n, n);
    n = (nn > 1e-30 && nn < 1e30) ? n * inversesqrt(nn) : vec3(0.0, 0.0, 1.0);
    vec3 tp = t - n * dot(n, t);
    float tt = dot(tp, tp);
    t = (tt > 1e-12 && tt < 1e30) ? tp * inversesqrt(tt) : any_perpendicular(n);
    float s = sign_ < 0.0 ? -1.0 : 1.0;
    vec3 b = cross(n, t) * s;
    return mat3(t, b, n);
}

// k in the local frame: (k·t, k·b, k·n).
vec3 fabric_local(vec3 k, mat3 frame) {
    return vec3(dot(k, frame[0]), dot(k, frame[1]), dot(k, frame[2]));
}

// The half vector h = normalize(k1 + k2), and kh = h·k1 = h·k2 = |k1 + k2|/2 clamped to [0, 1].
// k1 = -k2 gives h = n, kh = 0.
vec3 fabric_half(vec3 k1, vec3 k2, out float kh) {
    vec3 hs = k1 + k2;
    float len2 = dot(hs, hs);
    if (!(len2 > 0.0)) {
        kh = 0.0;
        return vec3(0.0, 0.0, 1.0);
    }
    float inv_len = inversesqrt(len2);
    vec3 h = hs * inv_len;
    kh = min(0.5 * len2 * inv_len, 1.0);
    return h;
}

// E(h) = (eu·hu² + ev·hv²)/(hu² + hv²), scaled by max(|hu|, |hv|) first so it cannot underflow;
// h = n exactly (E undefined, hn^E = 1 for any E) gives the mean of the exponents.
float as_exponent(float hu, float hv, float eu, float ev) {
    float m = max(abs(hu), abs(hv));
    if (!(m > 0.0)) {
        return 0.5 * (eu + ev);
    }
    float x = hu / m;
    float y = hv / m;
    return (eu * x * x + ev * y * y) / (x * x + y * y);
}

// hn^E(h) for a unit h = (hu, hv, hn); 0 for hn <= 0. For s = hu² + hv² < 1/4:
// hn^E = (1 - s)^(E/2) = exp(-a/(2 - s)·P(z²)), a = eu·hu² + ev·hv² (= E·s), z = s/(2 - s),
// P the atanh series; else exp(E·log(hn)).
float as_power(float hu, float hv, float hn, float eu, float ev) {
    if (!(hn > 0.0)) {
        return 0.0;
    }
    float hu2 = hu * hu;
    float hv2 = hv * hv;
    float s = hu2 + hv2;
    float a = eu * hu2 + ev * hv2;
    if (s < FABRIC_SERIES_MAX_S) {
        float z = s / (2.0 - s);
        float z2 = z * z;
        float p = 1.0
            + z2 * (1.0 / 3.0
                + z2 * (1.0 / 5.0
                    + z2 * (1.0 / 7.0
                        + z2 * (1.0 / 9.0
                            + z2 * (1.0 / 11.0
                                + z2 * (1.0 / 13.0 + z2 * (1.0 / 15.0 + z2 * (1.0 / 17.0))))))));
        return exp(-(a / (2.0 - s)) * p);
    } else {
        return exp(a / s * log(hn));
    }
}

// The A–S normalisation sqrt((eu+1)(ev+1)), shared by D and the lobe.
float as_norm(float eu, float ev) {
    return sqrt((eu + 1.0) * (ev + 1.0));
}

// The microfacet density (model page eq. 1): sqrt((eu+1)(ev+1))/(2π) · hn^E.
float as_d(vec3 h, float eu, float ev) {
    return as_norm(eu, ev) / (2.0 * FABRIC_PI) * as_power(h.x, h.y, h.z, eu, ev);
}

// Schlick's Fresnel rs + (1 - rs)(1 - c)^5, c clamped to [0, 1].
float schlick(float rs, float c) {
    float x = 1.0 - clamp(c, 0.0, 1.0);
    float x2 = x * x;
    return rs + (1.0 - rs) * x2 * x2 * x;
}

// The Ashikhmin–Shirley lobe without its hn^E: norm/(8π)·F(kh)/max(kh·max(n·k1, n·k2), min),
// for directions above the surface with kh = h·k1. The same for both thread orientations (norm is
// symmetric in eu, ev), so the environment's sampler (lighting.frag) evaluates it once for both.
float as_lobe_factor(float nk1, float nk2, float kh, float eu, float ev, float rs) {
    float denom = max(kh * max(nk1, nk2), FABRIC_DENOM_MIN);
    return as_norm(eu, ev) / (8.0 * FABRIC_PI) * schlick(rs, kh) / denom;
}

// The Ashikhmin–Shirley lobe with exponent eu along t and ev along b; exactly 0 when either
// direction is back-facing or grazing.
float as_lobe(vec3 k1, vec3 k2, float eu, float ev, float rs) {
    float nk1 = k1.z;
    float nk2 = k2.z;
    if (!(nk1 > 0.0 && nk2 > 0.0)) {
        return 0.0;
    }
    float kh;
    vec3 h = fabric_half(k1, k2, kh);
    return as_lobe_factor(nk1, nk2, kh, eu, ev, rs) * as_power(h.x, h.y, h.z, eu, ev);
}

// Lambert's 1/π (times Rd).
float lambert() {
    return 1.0 / FABRIC_PI;
}

// A–S eq. 5 without its Rd: 28/(23π)·(1 - rs)·(1 - (1 - n·k1/2)^5)·(1 - (1 - n·k2/2)^5).
float coupled_diffuse(float rs, float nk1, float nk2) {
    float a = 1.0 - 0.5 * clamp(nk1, 0.0, 1.0);
    float b = 1.0 - 0.5 * clamp(nk2, 0.0, 1.0);
    float a2 = a * a;
    float b2 = b * b;
    return 28.0 / (23.0 * FABRIC_PI) * (1.0 - rs) * ((1.0 - a2 * a2 * a) * (1.0 - b2 * b2 * b));
}

// The material with both threads' colours multiplied by `tint` (the thread texture's filtered
// value at the pixel, rgb in [0, 1]; white without one). The BRDF is linear in the colours, so
// this is the texture multiplied over the diffuse term wherever the model uses them. With
// thread-by-thread colours (flag bit 3) `tint` already holds the footprint's shadow-weighted
// thread colour times the texture, and is both threads' colour: s_warp·t + s_weft·t is then the
// footprint's Σ s·colour exactly.
GpuFabric fabric_tinted(GpuFabric m, vec3 tint) {
    bool threads = (m.flags & FABRIC_FLAG_THREAD_COLOURS) != 0u;
    m.rd_warp = threads ? tint : m.rd_warp * tint;
    m.rd_weft = threads ? tint : m.rd_weft * tint;
    return m;
}

// The diffuse albedo of a coverage (c_warp, c_weft, s_warp, s_weft): each thread's albedo times
// its shadow-weighted area, s_warp·rd_warp + s_weft·rd_weft (linear in the coverage, so the
// footprint average of the weave gives the footprint average of the diffuse term exactly).
vec3 fabric_albedo(vec4 coverage, GpuFabric m) {
    return coverage.z * m.rd_warp + coverage.w * m.rd_weft;
}

// ---- A sheet of cloth (flag bit 4; docs/fabric-model.md §9): light through the weave. ----

// The material whose threads reflect what they do not pass through: a sheet's thread colours
// times 1 − τ (KHR_materials_diffuse_transmission's split of a diffuse lobe), any other cloth
// unchanged. The lobes are the fibres' surface reflection and keep their strength.
GpuFabric fabric_reflecting(GpuFabric m) {
    float keep = (m.flags & FABRIC_FLAG_SHEET) != 0u ? 1.0 - clamp(m.transmission, 0.0, 1.0) : 1.0;
    m.rd_warp *= keep;
    m.rd_weft *= keep;
    return m;
}

// What a sheet's threads pass to their other side of the diffuse light they receive there: τ
// times the threads' albedo of the coverage (fabric_albedo), 0 for a cloth that is not a sheet.
// The ambient and environment light of the far side take it as it is; fabric_btdf is it over π.
vec3 fabric_passed(vec4 coverage, GpuFabric m) {
    if ((m.flags & FABRIC_FLAG_SHEET) == 0u) {
        return vec3(0.0);
    }
    return clamp(m.transmission, 0.0, 1.0) * fabric_albedo(coverage, m);
}

// The light a sheet's threads pass through, for light from k1 on the far side (n·k1 < 0) seen
// from k2 on the near side (n·k2 > 0): τ/π times the threads' albedo of the coverage (each
// thread's colour times its shadow-weighted area, as the diffuse reflection). 0 for light on the
// viewer's side, and for a cloth that is not a sheet. What the gaps pass is not here: it is the
// light behind the sheet, blended by 1 − c_warp − c_weft.
vec3 fabric_btdf(vec3 k1, vec3 k2, vec4 coverage, GpuFabric m) {
    if (!(k1.z < 0.0 && k2.z > 0.0)) {
        return vec3(0.0);
    }
    return fabric_passed(coverage, m) / FABRIC_PI;
}

// The share of a coverage that is thread (c_warp + c_weft, clamped to [0, 1]): a sheet's opacity.
float fabric_thread_cover(vec4 coverage) {
    return clamp(coverage.x + coverage.y, 0.0, 1.0);
}

// The fabric model (§3) at one shading point. coverage = (c_warp, c_weft, s_warp, s_weft): area
// fractions of warp and weft on top, and the same weighted by the diffuse shadow factor (at a
// point: s_warp = s·c_warp). Diffuse = fabric_albedo · the diffuse term; specular = the coverages
// times each orientation's lobe.
vec3 fabric_brdf(vec3 k1, vec3 k2, vec4 coverage, GpuFabric m) {
    float nk1 = k1.z;
    float nk2 = k2.z;
    if (!(nk1 > 0.0 && nk2 > 0.0)) {
        return vec3(0.0);
    }
    float c_warp = coverage.x;
    float c_weft = coverage.y;
    float rho_weft = as_lobe(k1, k2, m.e_along, m.e_across, m.rs);
    float rho_warp = as_lobe(k1, k2, m.e_across, m.e_along, m.rs);
    float diffuse = (m.flags & FABRIC_FLAG_COUPLED_DIFFUSE) != 0u ? coupled_diffuse(m.rs, nk1, nk2) : lambert();
    float spec = c_weft * rho_weft + c_warp * rho_warp;
    return diffuse * fabric_albedo(coverage, m) + spec;
}

// The filtered-params accuracy level (model page §4): ONE lobe whose exponents are the
// coverage-weighted means of the two orientations', times the thread coverage. Cheap and wrong at
// a distance; kept so its error can be measured. Equal to fabric_brdf at a point.
vec3 fabric_brdf_averaged(vec3 k1, vec3 k2, vec4 coverage, GpuFabric m) {
    float nk1 = k1.z;
    float nk2 = k2.z;
    float c_warp = coverage.x;
    float c_weft = coverage.y;
    float c_thread = c_warp + c_weft;
    if (!(nk1 > 0.0 && nk2 > 0.0 && c_thread > 0.0)) {
        return vec3(0.0);
    }
    float t = c_weft / c_thread;
    float eu = t * m.e_along + (1.0 - t) * m.e_across;
    float ev = t * m.e_across + (1.0 - t) * m.e_along;
    float diffuse = (m.flags & FABRIC_FLAG_COUPLED_DIFFUSE) != 0u ? coupled_diffuse(m.rs, nk1, nk2) : lambert();
    float spec = c_thread * as_lobe(k1, k2, eu, ev, m.rs);
    return diffuse * fabric_albedo(coverage, m) + spec;
}

// ---- The comparison models of `weft compare` (paper figs. 1, 2): the same material without its
// weave. Both use the threads' mean albedo and the material's Rs and exponents.

// Mean diffuse albedo of the two threads (a plain weave shows both in equal parts).
vec3 fabric_mean_rd(GpuFabric m) {
    return 0.5 * (m.rd_warp + m.rd_weft);
}

// Exponent of the Phong lobe that stands for the material's A–S lobes: the mean A–S exponent
// over 4 (a lobe around the half vector with exponent E is about as wide as a Phong lobe around
// the mirror direction with exponent E/4).
float fabric_phong_exponent(GpuFabric m) {
    return 0.125 * (m.e_along + m.e_across);
}

// The normalised Phong lobe (e + 2)/(2π)·(r·k2)^e, r = k1 mirrored about n; exactly 0 when
// either direction is back-facing or r·k2 <= 0.
float phong_lobe(vec3 k1, vec3 k2, float e) {
    if (!(k1.z > 0.0 && k2.z > 0.0)) {
        return 0.0;
    }
    float rk = k1.z * k2.z - k1.x * k2.x - k1.y * k2.y;
    if (!(rk > 0.0)) {
        return 0.0;
    }
    return (e + 2.0) / (2.0 * FABRIC_PI) * exp(e * log(min(rk, 1.0)));
}

// The Phong reflection model: Lambert with the mean albedo plus Rs times the Phong lobe.
vec3 phong_brdf(vec3 k1, vec3 k2, GpuFabric m) {
    if (!(k1.z > 0.0 && k2.z > 0.0)) {
        return vec3(0.0);
    }
    return fabric_mean_rd(m) * lambert() + m.rs * phong_lobe(k1, k2, fabric_phong_exponent(m));
}

// Plain (single-lobe) Ashikhmin–Shirley: the mean albedo with the material's diffuse term, and
// one A–S lobe for threads along t everywhere: no weave, no gaps, no thread shadowing.
vec3 plain_as_brdf(vec3 k1, vec3 k2, GpuFabric m) {
    float nk1 = k1.z;
    float nk2 = k2.z;
    if (!(nk1 > 0.0 && nk2 > 0.0)) {
        return vec3(0.0);
    }
    float diffuse = (m.flags & FABRIC_FLAG_COUPLED_DIFFUSE) != 0u ? coupled_diffuse(m.rs, nk1, nk2) : lambert();
    return fabric_mean_rd(m) * diffuse + as_lobe(k1, k2, m.e_along, m.e_across, m.rs);
}

#endif // WEFT_FABRIC_GLSL
