#version 460
// Evaluates every function of ibl.glsl and cube.glsl on a batch of inputs, so tests can compare
// the GPU with the Rust twins (weft::reference::ibl_twin, which also bounds the error each output
// may have under Vulkan's precision rules). One invocation per input; main() mirrors
// weft::reference::ibl_twin::ibl_probe_cpu.
#extension GL_GOOGLE_include_directive : require
#include "cube.glsl"
#include "ibl.glsl"
#include "occlusion.glsl"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

// Rust twin: weft::reference::ibl_twin::IblProbeInput (432 bytes).
struct IblProbeInput {
    vec4 world;      // env_dir: world direction (xyz)
    vec4 rot[3];     // env_dir: rows of env_from_world (xyz)
    vec4 normal;     // sh_irradiance: env-space normal (xyz); dominant_dir: n
    vec4 sh[9];      // sh_irradiance: the SH9 coefficients (rgb)
    vec4 xi;         // xy: the xi of ggx_sample_h, as_sample_h and cosine_sample
    vec4 lobe;       // x: GGX alpha, y: A–S eu, z: A–S ev
    vec4 lod;        // x: pdf, y: face size (fis_lod); z: n·v, w: ao (specular_occlusion)
    vec4 misc;       // x: roughness (specular_occlusion, dominant_dir), y: n·k2 (fabric_diffuse_albedo),
                     // z: visibility, w: albedo (gtao_multibounce)
    uvec4 counts;    // x: hammersley i, y: hammersley n, z: fis_lod n
    uvec4 cube;      // cube_texel_dir: face, texel x, texel y, size
    vec4 dir;        // equirect_uv: direction (xyz); dominant_dir: the mirror direction r
    GpuFabric fabric; // fabric_diffuse_albedo: the material (rs, flags)
    vec4 arc;        // gtao_arc: h0, h1, n
};

// Rust twin: weft::reference::ibl_twin::IblProbeOutput (160 bytes).
struct IblProbeOutput {
    vec4 env_dir;    // env_dir (xyz), 0
    vec4 irradiance; // sh_irradiance (rgb), 0
    vec4 ggx;        // ggx_sample_h (xyz), 0
    vec4 as_h;       // as_sample_h (xyz), 0
    vec4 cosine;     // cosine_sample (xyz), 0
    vec4 cube;       // cube_texel_dir (xyz), 0
    vec4 uv;         // hammersley (xy), equirect_uv (zw)
    vec4 scalars;    // fis_lod, specular_occlusion, fabric_diffuse_albedo, cone_occlusion
    vec4 occlusion;  // gtao_arc, gtao_multibounce, gtao_half_arc(h0, n), 0
    vec4 dominant;   // dominant_dir(normal, dir, misc.x) (xyz), 0
};

// set 0, binding 0: the inputs.
layout(std430, set = 0, binding = 0) readonly buffer IblProbeInputs {
    IblProbeInput inputs[];  // the inputs: `IblProbeInput[count]`
};

// set 0, binding 1: the outputs, one per input.
layout(std430, set = 0, binding = 1) writeonly buffer IblProbeOutputs {
    IblProbeOutput outputs[];  // the outputs: `IblProbeOutput[count]`, written by the shader
};

layout(push_constant) uniform IblProbePush {
    uint count;      // number of inputs
} pc;

void main() {
    uint id = gl_GlobalInvocationID.x;
    if (id >= pc.count) {
        return;
    }
    IblProbeInput inp = inputs[id];
    vec4 sh[9];
    for (int k = 0; k < 9; ++k) {
        sh[k] = inp.sh[k];
    }

    IblProbeOutput o;
    o.env_dir = vec4(env_dir(inp.world.xyz, inp.rot[0], inp.rot[1], inp.rot[2]), 0.0);
    o.irradiance = vec4(sh_irradiance(sh, inp.normal.xyz), 0.0);
    o.ggx = vec4(ggx_sample_h(inp.xi.xy, inp.lobe.x), 0.0);
    o.as_h = vec4(as_sample_h(inp.xi.xy, inp.lobe.y, inp.lobe.z), 0.0);
    o.cosine = vec4(cosine_sample(inp.xi.xy), 0.0);
    o.cube = vec4(cube_texel_dir(inp.cube.x, inp.cube.yz, inp.cube.w), 0.0);
    o.uv = vec4(hammersley(inp.counts.x, inp.counts.y), equirect_uv(inp.dir.xyz));
    o.scalars = vec4(
        fis_lod(inp.lod.x, inp.counts.z, inp.lod.y),
        specular_occlusion(inp.lod.z, inp.lod.w, inp.misc.x),
        fabric_diffuse_albedo(inp.fabric, inp.misc.y),
        cone_occlusion(inp.lod.z, inp.lod.w, inp.misc.x));
    o.occlusion = vec4(gtao_arc(inp.arc.x, inp.arc.y, inp.arc.z), gtao_multibounce(inp.misc.z, inp.misc.w),
                       gtao_half_arc(inp.arc.x, inp.arc.z), 0.0);
    o.dominant = vec4(dominant_dir(inp.normal.xyz, inp.dir.xyz, inp.misc.x), 0.0);
    outputs[id] = o;
}
