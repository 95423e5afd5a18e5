#version 460
// G-buffer pass, vertex stage: object space to world and clip space. With SHADING = Gouraud it
// also lights fabric vertices (the Phong reflection model, as fixed-function pipelines did) for
// `weft compare`; the fragment stage adds the interpolated result to the emitted radiance.
#include "frame.glsl"

// How fabric is shaded (SHADING_* in frame.glsl); only Gouraud does work here.
layout(constant_id = 2) const uint SHADING = 0u;
// Light types the scene has, as in lighting.frag.
layout(constant_id = 3) const uint LIGHT_TYPES = 7u;
// 1: the scene has vertex colours (COLOR_0): each vertex's is read from the colour buffer and
// passed on (0: none is read, gbuffer.frag multiplies nothing).
layout(constant_id = 5) const uint VERTEX_COLORS = 0u;
// 1: the scene has the world light (render::world_light, --occlusion gtao): each vertex's is
// read from the world-light buffer where the draw has it (flags bit 1) and passed on.
layout(constant_id = 10) const uint WORLD_LIGHT = 0u;
// Lights out of range are skipped (as lighting.frag's RANGE_CULLING).
const uint RANGE_CULLING = 1u;

#include "fabric.glsl"
#include "lights.glsl"

layout(set = 0, binding = 0, std140) uniform FrameBlock { FrameData frame; };  // the frame uniform (`FrameData`, std140, include/frame.glsl)
layout(set = 0, binding = 1, std430) readonly buffer Materials { Material materials[]; };  // material records (`Material[]`; read only when SHADING = 1, Gouraud)
layout(set = 0, binding = 2, std430) readonly buffer Fabrics { GpuFabric fabrics[]; };  // fabric records (`GpuFabric[]`; read only when SHADING = 1, Gouraud)
layout(set = 0, binding = 3, std430) readonly buffer Lights { Light lights[]; };  // lights (`Light[]`, include/frame.glsl; read only when SHADING = 1, Gouraud)
// COLOR_0, linear RGBA, one per vertex of the vertex buffer (indexed like it, by gl_VertexIndex,
// which includes the draw's vertex offset); white where a mesh has none.
layout(set = 0, binding = 4, std430) readonly buffer Colors { vec4 colors[]; };  // vertex colours (`vec4[]`, linear RGBA, glTF COLOR_0): one per vertex of the vertex buffer, indexed by `gl_VertexIndex` (vertex offset included), white for vertices without; read only when VERTEX_COLORS = 1
// The world light baked per vertex of each draw that takes it (rgb: the scene's surfaces' light
// over its hemisphere, irradiance/π; a: the environment's visibility), from draw.world_base.
layout(set = 0, binding = 6, std430) readonly buffer WorldLight { vec4 world_light[]; };  // the world light (`vec4[]`: rgb bounce irradiance/π, a visibility; render::world_light), one per vertex of each draw that takes it, at `draw.world_base + gl_VertexIndex`; read only when WORLD_LIGHT = 1

layout(push_constant, std430) uniform Draw {
    mat4 world;
    vec4 normal_matrix[3];  // columns of the inverse-transpose of world's 3x3 part
    uint material;
    float tangent_sign;     // -1 where world mirrors (negative determinant), else 1
    uint flags;             // bit 0: the draw receives shadows; bit 1: it has the world light
    uint world_base;        // where its world light begins, less its vertex offset (wrapping)
} draw;

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec4 in_tangent;
layout(location = 3) in vec2 in_uv;
// The UV with a whole number of weave repeats removed per mesh (in f64, at upload), so that huge
// coordinates keep the weave pattern (model page, hard case 8). Equal to in_uv for non-fabric.
layout(location = 4) in vec2 in_weave_uv;
layout(location = 5) in vec2 in_uv1;

layout(location = 0) out vec3 out_world_pos;
layout(location = 1) out vec3 out_normal;
layout(location = 2) out vec4 out_tangent;
layout(location = 3) out vec2 out_uv;
layout(location = 4) out vec2 out_weave_uv;
layout(location = 5) out vec3 out_gouraud;
layout(location = 6) out vec2 out_uv1;
layout(location = 7) out vec4 out_color;
layout(location = 8) out vec4 out_world_light;
// The depth pre-pass (depth.vert) computes the same clip position by the same expression, both
// `precise`: equal bit for bit.
precise gl_Position;

// The Phong reflection model at a fabric vertex: hemispherical ambient and every light, with the
// normal turned towards the viewer (the vertex stage cannot know which face will be drawn).
vec3 gouraud(vec3 p, vec3 n, vec4 tangent, GpuFabric f) {
    vec3 v = normalize(frame.eye.xyz - p);
    if (dot(n, v) < 0.0) {
        n = -n;
    }
    mat3 tbn = fabric_frame(n, tangent.xyz, tangent.w);
    n = tbn[2];
    vec3 k2 = fabric_local(v, tbn);
    vec3 ambient = mix(frame.ambient_ground.rgb, frame.ambient_sky.rgb, n.y * 0.5 + 0.5);
    vec3 radiance = ambient * fabric_mean_rd(f);
    for (uint i = 0u; i < frame.light_count; ++i) {
        vec3 l;
        vec3 e = light_incoming(lights[i], p, l);
        vec3 k1 = fabric_local(l, tbn);
        if (k1.z <= 0.0 || all(equal(e, vec3(0.0)))) {
            continue;
        }
        radiance += e * phong_brdf(k1, k2, f) * k1.z;
    }
    return radiance;
}

void main() {
    vec4 world_pos = draw.world * vec4(in_position, 1.0);
    mat3 nm = mat3(draw.normal_matrix[0].xyz, draw.normal_matrix[1].xyz, draw.normal_matrix[2].xyz);
    out_world_pos = world_pos.xyz;
    out_normal = nm * in_normal;
    out_tangent = vec4(mat3(draw.world) * in_tangent.xyz, in_tangent.w * draw.tangent_sign);
    out_uv = in_uv;
    out_weave_uv = in_weave_uv;
    out_uv1 = in_uv1;
    out_color = VERTEX_COLORS != 0u ? colors[gl_VertexIndex] : vec4(1.0);
    // Without the world light: no bounce, the environment open (what the lighting leaves as is).
    out_world_light = WORLD_LIGHT != 0u && (draw.flags & 2u) != 0u
                    ? world_light[draw.world_base + uint(gl_VertexIndex)] : vec4(0.0, 0.0, 0.0, 1.0);
    out_gouraud = vec3(0.0);
    if (SHADING == SHADING_GOURAUD) {
        uint fabric = uint(materials[draw.material].metallic_roughness.z + 0.5);
        if (fabric > 0u) {
            out_gouraud = gouraud(world_pos.xyz, out_normal, out_tangent, fabrics[fabric - 1u]);
        }
    }
    gl_Position = frame.view_proj * world_pos;
    // glTF POINTS are 1 pixel (the G-buffer's point-list pipeline; ignored for other topologies).
    gl_PointSize = 1.0;
}
