#version 460
// Shadow pass, vertex stage: a caster's vertices into one light's shadow map (depth only,
// reversed-Z: nearest to the light is 1). The same vertex buffer as the G-buffer pass; only the
// position is read.

layout(push_constant, std430) uniform ShadowDraw {
    mat4 clip_from_object;  // the light's projection x view x the draw's world matrix
} draw;

layout(location = 0) in vec3 in_position;

void main() {
    gl_Position = draw.clip_from_object * vec4(in_position, 1.0);
}
