#version 460
// Evaluates the glTF BRDF of include/pbr.glsl (the core material and KHR_materials_specular,
// _sheen and _anisotropy) on a batch of inputs, so tests can compare the GPU with the Rust twin
// (weft::reference::shading::gltf_brdf_cos and its terms; with KHR_materials_iridescence's film). One invocation per input.
#extension GL_GOOGLE_include_directive : require
#include "pbr.glsl"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

// Rust twin: tests/pbr_probe_gpu.rs PbrProbeInput (208 bytes).
struct PbrProbeInput {
    vec4 n;              // xyz: normal (unit)
    vec4 v;              // xyz: view direction (unit)
    vec4 l;              // xyz: light direction (unit)
    vec4 base_metallic;  // rgb base colour, a metallic
    vec4 f0_specular;    // rgb dielectric F0, a specular weight
    vec4 sheen;          // rgb sheen colour, a sheen roughness
    vec4 t_anisotropy;   // xyz anisotropy direction (unit, ⟂ n), w strength
    vec4 params;         // x roughness, y E(n·v), z E(n·l), w Ess(n·v) (energy compensation)
    vec4 terms_in;       // x n·h, y n·l, z n·v (inputs of the scalar terms), w sheen roughness
    vec4 volume;         // transmission: x thickness, y ior, z attenuation distance, w backdrop width
    vec4 attenuation;    // rgb attenuation colour, w the transmission factor (GltfSurface)
    vec4 coat;           // clearcoat: x factor, y roughness (its normal: n)
    vec4 film;           // iridescence: x factor, y the film's ior, z its thickness (nm) (GltfSurface);
                         // w: KHR_materials_dispersion's dispersion (with volume.y's ior)
};

// Rust twin: PbrProbeOutput (144 bytes).
struct PbrProbeOutput {
    vec4 brdf;   // gltf_brdf_cos (rgb), 0
    vec4 terms;  // charlie_d, sheen_brdf_cos, ggx_aniso_d (t·h = b·h from n·h), sheen_lambda(n·v)
    vec4 exit_lod;     // transmission_exit(l, n, v, thickness, ior), transmission_lod(roughness, ior, width)
    vec4 transmitted;  // volume_attenuation(thickness, colour, distance) · transmission_weight(f0,
                       // specular, base, (E(n·v), E(n·l))) (rgb), 0
    vec4 coated;       // clearcoat_brdf_cos(brdf, n, v, l, coat, coat roughness) (rgb),
                       // clearcoat_fresnel(n·v)
    vec4 through;      // diffuse_btdf_cos(n, v, −l, surface, attenuation colour) (rgb), 0
    vec4 film;         // iridescence_fresnel(film ior, n·v, thickness, f0) (rgb), 0
    vec4 dispersed;    // dispersion_iors(volume ior, dispersion) (rgb), 0
    vec4 lamp_through; // specular_btdf_cos(n, v, −l, surface, volume ior) (rgb),
                       // transmission_alpha(roughness, volume ior)
};

layout(std430, set = 0, binding = 0) readonly buffer PbrProbeInputs {
    PbrProbeInput inputs[];  // the inputs: `PbrProbeInput[count]`
};

layout(std430, set = 0, binding = 1) writeonly buffer PbrProbeOutputs {
    PbrProbeOutput outputs[];  // the outputs: `PbrProbeOutput[count]`, written by the shader
};

layout(push_constant) uniform PbrProbePush {
    uint count;
} pc;

void main() {
    uint id = gl_GlobalInvocationID.x;
    if (id >= pc.count) {
        return;
    }
    PbrProbeInput p = inputs[id];
    GltfSurface s = GltfSurface(p.base_metallic.rgb, p.base_metallic.a, p.params.x, p.f0_specular.a,
                                p.f0_specular.rgb, p.sheen.rgb, p.sheen.a, p.t_anisotropy.xyz,
                                p.t_anisotropy.w, p.attenuation.w, p.film.x, p.film.y, p.film.z);
    vec3 brdf = gltf_brdf_cos(p.n.xyz, p.v.xyz, p.l.xyz, s, p.params.yz, p.params.w);
    float nh = p.terms_in.x;
    float sr = p.terms_in.w;
    float th = sqrt(max(1.0 - nh * nh, 0.0) * 0.5);
    float alpha = max(p.params.x * p.params.x, 1e-3);
    outputs[id].brdf = vec4(brdf, 0.0);
    outputs[id].lamp_through = vec4(specular_btdf_cos(p.n.xyz, p.v.xyz, -p.l.xyz, s, p.volume.y),
                                    transmission_alpha(p.params.x, p.volume.y));
    outputs[id].dispersed = vec4(dispersion_iors(p.volume.y, p.film.w), 0.0);
    outputs[id].film = vec4(iridescence_fresnel(p.film.y, dot(p.n.xyz, p.v.xyz), p.film.z, p.f0_specular.rgb), 0.0);
    outputs[id].through = vec4(diffuse_btdf_cos(p.n.xyz, p.v.xyz, -p.l.xyz, s, p.attenuation.rgb), 0.0);
    outputs[id].coated = vec4(clearcoat_brdf_cos(brdf, p.n.xyz, p.v.xyz, p.l.xyz, p.coat.x, p.coat.y),
                              clearcoat_fresnel(dot(p.n.xyz, p.v.xyz)));
    outputs[id].exit_lod = vec4(transmission_exit(p.l.xyz, p.n.xyz, p.v.xyz, p.volume.x, p.volume.y),
                                transmission_lod(p.params.x, p.volume.y, p.volume.w));
    outputs[id].transmitted = vec4(volume_attenuation(p.volume.x, p.attenuation.rgb, p.volume.z)
        * transmission_weight(p.f0_specular.rgb, p.f0_specular.a, p.base_metallic.rgb, p.params.yz), 0.0);
    outputs[id].terms = vec4(charlie_d(nh, sr), sheen_brdf_cos(p.terms_in.y, p.terms_in.z, nh, sr),
                             ggx_aniso_d(th, th, nh, mix(alpha, 1.0, 0.5), alpha),
                             sheen_lambda(p.terms_in.z, max(sr * sr, 1e-3)));
}
