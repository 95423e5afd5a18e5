#version 460
// Evaluates the environment light's estimators of include/env_light.glsl (pbr_env,
// aniso_env_specular, sheen_layer_diffuse, fabric_env_lobes (and a woven pixel's fabric_pixel_lobe_sums,
// fabric_env_lobes_resolve), fabric_env_diffuse, fabric_env_back,
// fabric_env_combine, pixel_random, ibl_sample, ggx_albedo) and the shadow maps' PCF of
// include/shadows.glsl (shadow_pcf) on a batch of inputs, so tests can compare the GPU with the
// Rust twins (weft::reference::env_light). The textures those functions read are replaced by the
// closed-form stand-ins below, which weft::reference::env_light::StandIn and stand_in_compare
// repeat: what is compared is the estimators' arithmetic. One invocation per input.
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"
#include "fabric.glsl"
#include "pbr.glsl"
#include "ibl.glsl"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

// Rust twin: weft::reference::env_light::EnvProbeInput (480 bytes).
struct EnvProbeInput {
    vec4 n;              // pbr_env: normal (unit, xyz); w: ao
    vec4 v;              // pbr_env: view direction (unit, xyz); w: the sheen's E(n·v)
    vec4 base_metallic;  // GltfSurface: base colour (rgb), metallic
    vec4 f0_specular;    // GltfSurface: dielectric F0 (rgb), specular weight
    vec4 sheen;          // GltfSurface: sheen colour (rgb), sheen roughness
    vec4 t_anisotropy;   // GltfSurface: anisotropy direction (unit, ⟂ n), strength
    vec4 surface;        // x: roughness, y: transmission, z: Ess (aniso_env_specular), w: the cube's face size
    vec4 film;           // GltfSurface: iridescence factor, film ior, film thickness (nm)
    vec4 bounce;         // pbr_env and fabric_env_combine: bounce (rgb); w: n·v (fabric_env_combine)
    vec4 frame_t;        // the fabric's frame: fabric_frame(frame_n, frame_t, w = sign)
    vec4 frame_n;        // the fabric's normal (xyz); w: ao (fabric_env_combine)
    vec4 k2;             // the view in the fabric's frame (unit, xyz)
    vec4 coverage;       // the weave coverage (c_warp, c_weft, s_warp, s_weft)
    vec4 rot;            // xy: the Monte Carlo rotation; zw: sheen_layer_diffuse's k and E(n·v)
    uvec4 mode;          // x: the level (1 approx, 2 fis, 3 mc), y: samples, zw: pixel_random's pixel; w % 3: the lobe table, at fis w / 3 % 4: a lane (0: fabric_env_lobes, 1: fabric_pixel_lobe_sums alone, 2 and 3: pooled, block lane - 1 of 9, lane pixels)
    GpuFabric fabric;    // the fabric material
    Shadow shadow;       // shadow_pcf: the shadow record
    vec4 light_pos;      // shadow_pcf: the light's position (xyz); w > 0.5: fabric sheets (fabric_env_combine)
    vec4 p;              // shadow_pcf: the point (xyz)
    vec4 pn;             // shadow_pcf: its normal (xyz)
    vec4 indirect;       // pbr_env and fabric_env_combine: the occluders' bounced light (rgb)
};

// Rust twin: weft::reference::env_light::EnvProbeOutput (112 bytes).
struct EnvProbeOutput {
    vec4 pbr;       // pbr_env (rgb), sheen_layer_diffuse
    vec4 aniso;     // aniso_env_specular at mode.y samples (rgb), shadow_pcf
    vec4 weft;      // fabric_env_lobes: the weft lobe (rgb), pixel_random x
    vec4 warp;      // fabric_env_lobes: the warp lobe (rgb), pixel_random y
    vec4 diffuse;   // fabric_env_diffuse (rgb), ibl_sample(samples - 1, samples, rot) x
    vec4 back;      // fabric_env_back (rgb), ibl_sample y
    vec4 combined;  // fabric_env_combine of the three above (rgb), ggx_albedo(n·v, roughness)
};

// set 0, binding 0: the inputs.
layout(std430, set = 0, binding = 0) readonly buffer EnvProbeInputs {
    EnvProbeInput inputs[];  // the inputs: `EnvProbeInput[count]`
};

// set 0, binding 1: the outputs, one per input.
layout(std430, set = 0, binding = 1) writeonly buffer EnvProbeOutputs {
    EnvProbeOutput outputs[];  // the outputs: `EnvProbeOutput[count]`, written by the shader
};

layout(push_constant) uniform EnvProbePush {
    uint count;      // number of inputs
} pc;

// The leaves, closed-form (weft::reference::env_light::StandIn, stand_in_compare).
float g_face_size = 256.0;

vec3 env_radiance_at(vec3 d, float lod) {
    return vec3(1.0 + 0.5 * d.x, 1.0 + 0.5 * d.y * d.z, 0.75 + 0.25 * d.z) * (1.0 + 0.05 * lod);
}

vec3 env_prefiltered(vec3 d, float roughness) {
    return vec3(0.9 + 0.3 * d.y, 0.8 + 0.2 * d.x, 0.7 + 0.1 * d.z) * (1.0 - 0.2 * roughness);
}

vec3 dfg_lookup(float c, float r) {
    return vec3(0.9 - 0.5 * r * (1.0 - c), 0.05 + 0.05 * r * c, 0.3 * r * (1.0 - c) + 0.05);
}

float env_face_size() {
    return g_face_size;
}

vec2 lobe_albedo_texel(uint table, uint i, uint j) {
    return vec2(0.2 + 0.02 * float(i) - 0.01 * float(j) + 0.05 * float(table), 0.5 + 0.02 * float(i) + 0.005 * float(j));
}

float shadow_compare(vec3 uvz) {
    return clamp(8.0 * (uvz.x - 0.5 * uvz.y) - uvz.z * 2.0 + 0.5, 0.0, 1.0);
}

#include "env_light.glsl"
#include "shadows.glsl"

void main() {
    uint id = gl_GlobalInvocationID.x;
    if (id >= pc.count) {
        return;
    }
    EnvProbeInput p = inputs[id];
    g_face_size = p.surface.w;
    GltfSurface s = GltfSurface(p.base_metallic.rgb, p.base_metallic.a, p.surface.x, p.f0_specular.a,
                                p.f0_specular.rgb, p.sheen.rgb, p.sheen.a, p.t_anisotropy.xyz,
                                p.t_anisotropy.w, p.surface.y, p.film.x, p.film.y, p.film.z);
    uint mode = p.mode.x;
    uint samples = p.mode.y;
    vec2 rot = p.rot.xy;
    EnvProbeOutput o;
    o.pbr = vec4(pbr_env(p.n.xyz, p.v.xyz, s, p.n.w, p.bounce.rgb, p.indirect.rgb, p.v.w, mode, samples, rot),
                 sheen_layer_diffuse(p.rot.z, p.rot.w, p.sheen.a));
    o.aniso = vec4(aniso_env_specular(p.n.xyz, p.v.xyz, s, p.surface.z, samples),
                   shadow_pcf(p.shadow, p.light_pos.xyz, p.p.xyz, p.pn.xyz));
    mat3 tbn = fabric_frame(p.frame_n.xyz, p.frame_t.xyz, p.frame_t.w);
    vec3 weft;
    vec3 warp;
    uint lane = (p.mode.w / 3u) % 4u;
    if (mode == 2u && lane != 0u) {
        // A woven pixel as fabric_lobes.frag takes its samples (fabric_pixel_lobe_sums): lane 1
        // alone, lanes 2 and 3 pooled (block lane - 1 of a 3 x 3 window, the mip level of `lane`
        // pixels' samples), through fabric_lobe_pack as lighting.frag reads it, resolved as if
        // they were all its own.
        uint block = lane - 1u;
        vec4 weft_sum;
        vec4 warp_sum;
        fabric_pixel_lobe_sums(tbn, p.k2.xyz, p.coverage, p.fabric, samples, block, 9u, lane,
                               weft_sum, warp_sum);
        fabric_lobe_unpack(fabric_lobe_pack(weft_sum, warp_sum, samples, 0u), weft_sum, warp_sum);
        fabric_env_lobes_resolve(weft_sum, warp_sum, p.k2.xyz, p.fabric, p.mode.w % 3u, mode, 1u,
                                 weft, warp);
    } else {
        fabric_env_lobes(tbn, p.k2.xyz, p.coverage, p.fabric, p.mode.w % 3u, mode, samples, rot, weft, warp);
    }
    vec2 pr = pixel_random(p.mode.zw);
    o.weft = vec4(weft, pr.x);
    o.warp = vec4(warp, pr.y);
    vec3 diffuse = fabric_env_diffuse(tbn, p.k2.xyz, p.fabric, mode, samples, rot);
    vec3 back = fabric_env_back(tbn, mode, samples, rot);
    vec2 last = ibl_sample(samples - 1u, samples, rot);
    o.diffuse = vec4(diffuse, last.x);
    o.back = vec4(back, last.y);
    o.combined = vec4(fabric_env_combine(p.coverage, p.fabric, diffuse, weft, warp, back, p.frame_n.w,
                                         p.bounce.rgb, p.indirect.rgb, p.bounce.w, p.light_pos.w > 0.5),
                      ggx_albedo(dot(p.n.xyz, p.v.xyz), p.surface.x));
    outputs[id] = o;
}
