#version 460
// Shadow pass for casters with an alphaMode MASK material, vertex stage: as shadow.vert, and the
// texture coordinates and vertex colour alpha that shadow_mask.frag cuts out with, so cut-outs
// cast cut-out shadows. Only a scene with such a caster and a shadow map makes this pipeline.

// 1: the scene has vertex colours (their alpha is part of the base colour's); 0: none is read.
layout(constant_id = 0) const uint VERTEX_COLORS = 0u;

// COLOR_0 per vertex, gbuffer.vert's binding 4 (indexed by gl_VertexIndex).
layout(set = 0, binding = 4, std430) readonly buffer Colors { vec4 colors[]; };  // vertex colours (`vec4[]`, gbuffer.vert's set 0 binding 4; read only when VERTEX_COLORS = 1)

layout(push_constant, std430) uniform ShadowMaskDraw {
    mat4 clip_from_object;  // the light's projection x view x the draw's world matrix
    uint material;
    uint pad0;
    uint pad1;
    uint pad2;
} draw;

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec2 in_uv;
layout(location = 2) in vec2 in_uv1;

layout(location = 0) out vec2 out_uv;
layout(location = 1) out vec2 out_uv1;
layout(location = 2) out float out_alpha;

void main() {
    out_uv = in_uv;
    out_uv1 = in_uv1;
    out_alpha = VERTEX_COLORS != 0u ? colors[gl_VertexIndex].a : 1.0;
    gl_Position = draw.clip_from_object * vec4(in_position, 1.0);
}
