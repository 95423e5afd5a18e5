#version 460
// G-buffer pass, vertex stage: object space to world and clip space.
#include "frame.glsl"

layout(set = 0, binding = 0, std140) uniform FrameBlock { FrameData frame; };

layout(push_constant, std430) uniform Draw {
    mat4 world;
    vec4 normal_matrix[3];  // columns of the inverse-transpose of world's 3x3 part
    uint material;
    float tangent_sign;     // -1 where world mirrors (negative determinant), else 1
    uint pad0;
    uint pad1;
} draw;

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec4 in_tangent;
layout(location = 3) in vec2 in_uv;
// The UV with a whole number of weave repeats removed per mesh (in f64, at upload), so that huge
// coordinates keep the weave pattern (model page, hard case 8). Equal to in_uv for non-fabric.
layout(location = 4) in vec2 in_weave_uv;

layout(location = 0) out vec3 out_world_pos;
layout(location = 1) out vec3 out_normal;
layout(location = 2) out vec4 out_tangent;
layout(location = 3) out vec2 out_uv;
layout(location = 4) out vec2 out_weave_uv;

void main() {
    vec4 world_pos = draw.world * vec4(in_position, 1.0);
    mat3 nm = mat3(draw.normal_matrix[0].xyz, draw.normal_matrix[1].xyz, draw.normal_matrix[2].xyz);
    out_world_pos = world_pos.xyz;
    out_normal = nm * in_normal;
    out_tangent = vec4(mat3(draw.world) * in_tangent.xyz, in_tangent.w * draw.tangent_sign);
    out_uv = in_uv;
    out_weave_uv = in_weave_uv;
    gl_Position = frame.view_proj * world_pos;
}
