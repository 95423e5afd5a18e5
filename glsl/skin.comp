#version 460
// Deforms one draw's vertices before the G-buffer and shadow passes: morph targets (weighted
// position, normal and tangent deltas), then linear blend skinning (the weighted sum of up to four
// joint matrices, each world-from-bind-pose). Reads the mesh's rest vertices at `src` and writes
// the draw's posed copy at `dst` of the same vertex buffer (16 floats per vertex: position,
// normal, tangent with handedness, uv, weave uv, uv1; only the first ten change), so the vertex
// stages of both passes stay as they are and skin once per pose, not once per pass and light.
//
// Normals go through the cofactor matrix (det · inverse transpose: right under non-uniform scale
// and defined for singular matrices), tangents through the matrix itself, then made orthogonal to
// the normal; where the skin mirrors (negative determinant) the handedness w flips, so the
// bitangent w · n × t is the deformed one.
//
// Dispatch ceil(count / 64) groups per draw. CPU twin: weft::scene::animation::deform_vertex.

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

struct VertexSkin {
    uvec4 joints;   // indices into this skin's joint matrices
    vec4 weights;   // normalised at load
};

layout(set = 0, binding = 0, std430) buffer Vertices { float vertices[]; };  // the vertex buffer (16 floats per vertex): rest vertices read at `src`, the posed copy written at `dst`
layout(set = 0, binding = 1, std430) readonly buffer Skins { VertexSkin skins[]; };  // per vertex of the mesh: `uvec4 joints` (indices into this skin's joints) and `vec4 weights` (normalised)
// Per mesh, target-major: (target t, vertex v) at morph + 3 (t count + v): position, normal and
// tangent deltas (w unused).
layout(set = 0, binding = 2, std430) readonly buffer Morphs { vec4 morphs[]; };  // morph deltas, target-major: (target t, vertex v) at `morph + 3 (t count + v)`: position, normal, tangent (w unused)
layout(set = 0, binding = 3, std430) readonly buffer Joints { mat4 joints[]; };  // joint matrices (`mat4`, world from bind pose), the skin's from `joint`
layout(set = 0, binding = 4, std430) readonly buffer Weights { float weights[]; };  // morph weights (`float`), the draw's from `weight`

// Rust twin: weft::render::deform::SkinPush (48 bytes).
layout(push_constant, std430) uniform SkinPush {
    uint src;           // first rest vertex
    uint dst;           // first posed vertex
    uint count;
    uint skin;          // first VertexSkin of the mesh, or 0xffffffff: not skinned
    uint joint;         // first joint matrix of the skin
    uint joint_count;
    uint morph;         // first morph delta of the mesh
    uint target_count;
    uint weight;        // first morph weight of the draw
    uint pad0;
    uint pad1;
    uint pad2;
} push;

const uint STRIDE = 16u;
const uint NONE = 0xffffffffu;

vec3 load3(uint base) {
    return vec3(vertices[base], vertices[base + 1u], vertices[base + 2u]);
}

void store3(uint base, vec3 v) {
    vertices[base] = v.x;
    vertices[base + 1u] = v.y;
    vertices[base + 2u] = v.z;
}

// A unit vector perpendicular to n (glam's Vec3::any_orthonormal_vector).
vec3 any_orthonormal(vec3 n) {
    float sign = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (sign + n.z);
    float b = n.x * n.y * a;
    return vec3(b, sign + n.y * n.y * a, -n.y);
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= push.count) {
        return;
    }
    uint s = (push.src + i) * STRIDE;
    uint d = (push.dst + i) * STRIDE;
    vec3 p = load3(s);
    vec3 n = load3(s + 3u);
    vec3 t = load3(s + 6u);
    float w = vertices[s + 9u];
    for (uint k = 0u; k < push.target_count; ++k) {
        float wk = weights[push.weight + k];
        uint m = push.morph + 3u * (k * push.count + i);
        p += morphs[m].xyz * wk;
        n += morphs[m + 1u].xyz * wk;
        t += morphs[m + 2u].xyz * wk;
    }
    if (push.skin != NONE) {
        VertexSkin vs = skins[push.skin + i];
        mat4 m = mat4(0.0);
        for (uint k = 0u; k < 4u; ++k) {
            if (vs.joints[k] < push.joint_count) {
                m += joints[push.joint + vs.joints[k]] * vs.weights[k];
            }
        }
        p = (m * vec4(p, 1.0)).xyz;
        mat3 m3 = mat3(m);
        mat3 cof = mat3(cross(m3[1], m3[2]), cross(m3[2], m3[0]), cross(m3[0], m3[1]));
        float sign = determinant(m3) < 0.0 ? -1.0 : 1.0;
        n = cof * n * sign;
        t = m3 * t;
        w *= sign;
    }
    float nl = length(n);
    n = nl > 0.0 ? n / nl : vec3(0.0, 0.0, 1.0);
    vec3 tp = t - n * dot(n, t);
    float tl = length(tp);
    t = tl > 0.0 ? tp / tl : any_orthonormal(n);
    store3(d, p);
    store3(d + 3u, n);
    store3(d + 6u, t);
    vertices[d + 9u] = w;
}
