// Screen-space occlusion of the environment (the occlusion pass, glsl/occlusion.frag): the
// formulas of ground-truth ambient occlusion (GTAO; Jimenez, Wu, Pesce, Jarabo 2016, "Practical
// Real-Time Strategies for Accurate Indirect Occlusion"), written for weft. Rust twins:
// weft::reference::ibl_twin (gtao_half_arc, gtao_arc, gtao_multibounce; compared on the GPU by ibl_probe.comp).
#ifndef WEFT_OCCLUSION_GLSL
#define WEFT_OCCLUSION_GLSL

// One side of a slice's cosine-weighted arc: ∫ from 0 to h of cos(θ − n)·|sin θ| dθ (for h < 0,
// from h to 0), θ the angle from the view vector within the slice's plane (positive towards the
// slice's direction), n the angle of the normal projected into the plane. It grows with |h|; the
// part of a side between two horizons a and b is gtao_half_arc(a, n) − gtao_half_arc(b, n).
float gtao_half_arc(float h, float n) {
    return 0.25 * (cos(n) + 2.0 * h * sin(n) - cos(2.0 * h - n));
}

// The cosine-weighted visible arc of one slice of the hemisphere between the horizons
// h0 ≤ 0 ≤ h1 (within n ± π/2): both sides' gtao_half_arc. An unoccluded slice (h0 = n − π/2,
// h1 = n + π/2) gives cos n + n·sin n; weighted by the projected normal's length and averaged
// over the slices' directions, the unoccluded hemisphere gives 1.
float gtao_arc(float h0, float h1, float n) {
    return gtao_half_arc(h0, n) + gtao_half_arc(h1, n);
}

// The light that bounces between occluders and comes back (Jimenez et al. 2016, §5: a cubic fit
// over the visibility v of scenes whose surroundings have the albedo of the surface): v raised
// for bright surfaces, in [v, 1].
float gtao_multibounce(float v, float albedo) {
    float a = 2.0404 * albedo - 0.3324;
    float b = -4.7951 * albedo + 0.6417;
    float c = 2.7552 * albedo + 0.6903;
    return clamp(max(v, ((v * a + b) * v + c) * v), 0.0, 1.0);
}

#endif
