#version 460
// Shadow pass for casters with an alphaMode MASK material, fragment stage: discards where the
// base colour's alpha (factor x base colour texture, through its UV set and transform, x vertex
// colour alpha) is below the material's cutoff, exactly as gbuffer.frag does; depth is written
// by the fixed function elsewhere.
#include "frame.glsl"

// Material records, gbuffer.frag's binding 1.
layout(set = 0, binding = 1, std430) readonly buffer Materials { Material materials[]; };  // material records (`Material[]`, include/frame.glsl): the base colour factor, its texture's UV map and the MASK cutoff
// The material's base colour texture (white when it has none).
layout(set = 1, binding = 0) uniform sampler2D base_color_tex;  // the caster material's base colour texture (sRGB; white when none): its alpha

layout(push_constant, std430) uniform ShadowMaskDraw {
    mat4 clip_from_object;
    uint material;
    uint pad0;
    uint pad1;
    uint pad2;
} draw;

layout(location = 0) in vec2 in_uv;
layout(location = 1) in vec2 in_uv1;
layout(location = 2) in float in_alpha;

void main() {
    // Derivatives of the interpolants alone, first (as gbuffer.frag: on lavapipe buffer loads
    // read 0 in helper invocations, so nothing loaded may be differentiated).
    vec2 d[4] = vec2[4](dFdx(in_uv), dFdy(in_uv), dFdx(in_uv1), dFdy(in_uv1));
    Material m = materials[draw.material];
    vec4 r0 = m.uv[2u * SLOT_BASE_COLOR];
    vec4 r1 = m.uv[2u * SLOT_BASE_COLOR + 1u];
    bool set1 = r0.w > 0.5;
    mat2 lin = mat2(r0.x, r1.x, r0.y, r1.y);
    vec2 st = lin * (set1 ? in_uv1 : in_uv) + vec2(r0.z, r1.z);
    vec2 dx = lin * (set1 ? d[2] : d[0]);
    vec2 dy = lin * (set1 ? d[3] : d[1]);
    float alpha = m.base_color.a * textureGrad(base_color_tex, st, dx, dy).a * in_alpha;
    if (alpha_cut(m, alpha)) {
        discard;
    }
}
