#version 460
// Evaluates every function of fabric.glsl and weave.glsl on a batch of inputs, so tests can
// compare the GPU with the CPU reference (weft::reference::probe, which documents the error
// bounds). One invocation per input. main() mirrors weft::reference::probe::probe_cpu_f32.
#extension GL_GOOGLE_include_directive : require
#include "fabric.glsl"
#include "weave.glsl"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

// Rust twin: weft::reference::probe::ProbeInput (208 bytes).
struct ProbeInput {
    vec4 n;          // world normal (xyz)
    vec4 t;          // world tangent (xyz), w = handedness sign
    vec4 k1;         // world direction to the light (unit)
    vec4 k2;         // world direction to the viewer (unit)
    vec4 point;      // xy: point for weave_point, in cells
    vec4 footprint;  // (x0, y0, x1, y1): box for weave_box, in cells
    vec4 coverage;   // (c_warp, c_weft, s_warp, s_weft) given to fabric_brdf
    vec4 tint;       // rgb: the thread texture's value given to fabric_tinted
    GpuFabric fabric;
};

// Rust twin: weft::reference::probe::ProbeOutput (208 bytes).
struct ProbeOutput {
    vec4 lobe;       // ρs weft-oriented, ρs warp-oriented, D(h) weft-oriented, F(h·k)
    vec4 expo;       // E(h) weft, E(h) warp, h·n, h·k
    vec4 diffuse;    // coupled diffuse (no Rd), n·k1, n·k2, hn^E weft
    vec4 f;          // fabric_brdf with the input coverage (rgb), 0
    vec4 point;      // weave_point (c_warp, c_weft, s_warp, s_weft)
    vec4 footprint;  // weave_box (c_warp, c_weft, s_warp, s_weft)
    vec4 f_point;    // fabric_brdf with the point's coverage (rgb), 0
    vec4 f_avg;      // fabric_brdf_averaged with the input coverage (rgb), 0
    vec4 phong;      // phong_brdf (rgb), phong_lobe with fabric_phong_exponent
    vec4 plain_as;   // plain_as_brdf (rgb), 0
    vec4 f_tint;     // fabric_brdf of fabric_tinted(m, tint) with the input coverage (rgb), 0
    vec4 sheet;      // fabric_btdf with k1 mirrored to the far side (rgb), fabric_thread_cover
    vec4 f_sheet;    // fabric_brdf of fabric_reflecting(m) with the input coverage (rgb), 0
};

// set 0, binding 0: the inputs.
layout(std430, set = 0, binding = 0) readonly buffer ProbeInputs {
    ProbeInput inputs[];  // the inputs: `ProbeInput[count]`
};

// set 0, binding 1: the outputs, one per input.
layout(std430, set = 0, binding = 1) writeonly buffer ProbeOutputs {
    ProbeOutput outputs[];  // the outputs: `ProbeOutput[count]`, written by the shader
};

layout(push_constant) uniform ProbePush {
    uint count;      // number of inputs
} pc;

void main() {
    uint id = gl_GlobalInvocationID.x;
    if (id >= pc.count) {
        return;
    }
    ProbeInput inp = inputs[id];
    GpuFabric m = inp.fabric;
    Weave w = weave_from_fabric(m);
    mat3 frame = fabric_frame(inp.n.xyz, inp.t.xyz, inp.t.w);
    vec3 k1 = fabric_local(inp.k1.xyz, frame);
    vec3 k2 = fabric_local(inp.k2.xyz, frame);
    float kh;
    vec3 h = fabric_half(k1, k2, kh);
    vec4 cov = inp.coverage;
    vec4 p = weave_point(w, inp.point.x, inp.point.y);
    vec4 fp = inp.footprint;
    vec4 b = weave_box(w, fp.x, fp.y, fp.z, fp.w);
    vec3 f = fabric_brdf(k1, k2, cov, m);
    vec3 f_point = fabric_brdf(k1, k2, p, m);
    vec3 f_avg = fabric_brdf_averaged(k1, k2, cov, m);
    vec3 phong = phong_brdf(k1, k2, m);
    vec3 plain_as = plain_as_brdf(k1, k2, m);
    vec3 f_tint = fabric_brdf(k1, k2, cov, fabric_tinted(m, inp.tint.rgb));
    // The sheet's terms, with the light mirrored to the far side.
    vec3 btdf = fabric_btdf(vec3(k1.xy, -k1.z), k2, cov, m);
    vec3 f_sheet = fabric_brdf(k1, k2, cov, fabric_reflecting(m));

    ProbeOutput o;
    o.lobe = vec4(
        as_lobe(k1, k2, m.e_along, m.e_across, m.rs),
        as_lobe(k1, k2, m.e_across, m.e_along, m.rs),
        as_d(h, m.e_along, m.e_across),
        schlick(m.rs, kh));
    o.expo = vec4(
        as_exponent(h.x, h.y, m.e_along, m.e_across),
        as_exponent(h.x, h.y, m.e_across, m.e_along),
        h.z,
        kh);
    o.diffuse = vec4(
        coupled_diffuse(m.rs, k1.z, k2.z),
        k1.z,
        k2.z,
        as_power(h.x, h.y, h.z, m.e_along, m.e_across));
    o.f = vec4(f, 0.0);
    o.point = p;
    o.footprint = b;
    o.f_point = vec4(f_point, 0.0);
    o.f_avg = vec4(f_avg, 0.0);
    o.phong = vec4(phong, phong_lobe(k1, k2, fabric_phong_exponent(m)));
    o.plain_as = vec4(plain_as, 0.0);
    o.f_tint = vec4(f_tint, 0.0);
    o.sheet = vec4(btdf, fabric_thread_cover(cov));
    o.f_sheet = vec4(f_sheet, 0.0);
    outputs[id] = o;
}
