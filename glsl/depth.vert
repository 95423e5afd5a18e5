#version 460
// The G-buffer pass's depth pre-pass, vertex stage: the opaque draws' depth alone, before the
// G-buffer's shading draws them again with depth test GREATER_OR_EQUAL, so that each pixel's
// costly G-buffer shading runs once, for its visible surface. Its clip position is gbuffer.vert's
// by the same expression from the same inputs, both `precise` (no contraction into fused
// multiply-adds that one compilation might make and the other not), so the two passes' depths are
// equal bit for bit. (`invariant` says it too, but glslang puts it on the gl_PerVertex member, which
// Mesa's SPIR-V front end warns of.) Pair it with shadow.frag (empty).
#include "frame.glsl"

layout(set = 0, binding = 0, std140) uniform FrameBlock { FrameData frame; };  // the frame uniform (`FrameData`, std140, include/frame.glsl)

layout(push_constant, std430) uniform Draw {
    mat4 world;
    vec4 normal_matrix[3];  // unused here: gbuffer.vert's push block, pushed once for both
    uint material;
    float tangent_sign;
    uint flags;
    uint pad1;
} draw;

layout(location = 0) in vec3 in_position;

precise gl_Position;

void main() {
    vec4 world_pos = draw.world * vec4(in_position, 1.0);
    gl_Position = frame.view_proj * world_pos;
}
