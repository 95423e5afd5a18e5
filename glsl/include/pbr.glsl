// The glTF 2.0 metallic-roughness BRDF (glTF spec, Appendix B): Lambert diffuse plus a GGX
// specular lobe with the height-correlated Smith visibility and Schlick Fresnel.
#ifndef WEFT_PBR_GLSL
#define WEFT_PBR_GLSL

#include "frame.glsl"

float ggx_d(float n_h, float alpha) {
    float a2 = alpha * alpha;
    float d = n_h * n_h * (a2 - 1.0) + 1.0;
    return a2 / (PI * d * d);
}

float smith_v(float n_l, float n_v, float alpha) {
    float a2 = alpha * alpha;
    float gv = n_l * sqrt(n_v * n_v * (1.0 - a2) + a2);
    float gl = n_v * sqrt(n_l * n_l * (1.0 - a2) + a2);
    float s = gv + gl;
    return s > 0.0 ? 0.5 / s : 0.0;
}

// BRDF times n.l for light direction l and view direction v (both unit, away from the surface).
vec3 pbr_brdf_cos(vec3 n, vec3 v, vec3 l, vec3 base, float metallic, float roughness) {
    float n_l = dot(n, l);
    float n_v = dot(n, v);
    if (n_l <= 0.0 || n_v <= 0.0) {
        return vec3(0.0);
    }
    vec3 h = normalize(l + v);
    float n_h = clamp(dot(n, h), 0.0, 1.0);
    float v_h = clamp(dot(v, h), 0.0, 1.0);
    float alpha = max(roughness * roughness, 1e-3);
    vec3 f0 = mix(vec3(0.04), base, metallic);
    vec3 f = f0 + (1.0 - f0) * pow(1.0 - v_h, 5.0);
    vec3 diffuse = (1.0 - f) * (1.0 - metallic) * base / PI;
    vec3 specular = f * ggx_d(n_h, alpha) * smith_v(n_l, n_v, alpha);
    return (diffuse + specular) * n_l;
}

#endif
