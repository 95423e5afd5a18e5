// The transparent pass's fragment shader, compiled as two modules (glsl/forward*.frag, each this
// file after a line or two): forward.frag draws every kind of material, forward_gltf.frag glTF
// materials alone (where no fabric is drawn forward).
// Forward pass, fragment stage (alphaMode BLEND): drawn after the deferred lighting pass, over
// its HDR image, with gbuffer.vert, depth-tested against the opaque surfaces' depth and not
// writing it. Each fragment computes the surface gbuffer.frag would store (surface.glsl) and
// shades it at once as the lighting pass shades a G-buffer pixel (shade.glsl): the same lights,
// environment and shadows. Writes premultiplied radiance and the base colour's alpha, blended
// with ONE, ONE_MINUS_SRC_ALPHA (glTF's BLEND: colour·alpha + behind·(1 - alpha)). Transmissive
// surfaces (KHR_materials_transmission, _volume) are drawn here too: they read the backdrop.
#include "frame.glsl"
#include "pbr.glsl"
#include "fabric.glsl"
#include "weave.glsl"
#include "ibl.glsl"

// gbuffer.vert's and gbuffer.frag's constants keep their ids (the vertex stage reads 2, 3 and 5);
// lighting.frag's others are its id + 10 here.
// Accuracy level (model page §4): 0 nearest, 1 filtered-params, 2 mixture, 3 supersampled.
layout(constant_id = 0) const uint ACCURACY = 2u;
// Where the coverage comes from: 0 the weave texture, 1 the exact coverage of the footprint.
layout(constant_id = 1) const uint WEAVE_SOURCE = 0u;
// How fabric is shaded (SHADING_* in frame.glsl).
layout(constant_id = 2) const uint SHADING = 0u;
// Light types the scene has (bit 0 directional, 1 point, 2 spot).
layout(constant_id = 3) const uint LIGHT_TYPES = 7u;
// The pixel footprint: at most this many pieces per side (gbuffer.frag's FOOTPRINT_PIECES).
layout(constant_id = 4) const uint FOOTPRINT_PIECES = 2u;
// 1: the vertex colour multiplies the base colour and alpha (gbuffer.frag's VERTEX_COLORS).
layout(constant_id = 5) const uint VERTEX_COLORS = 0u;
// N of supersampled:N.
layout(constant_id = 11) const uint SAMPLES = 1u;
// 1: fabric shaded with the metallic-roughness BRDF.
layout(constant_id = 12) const uint FABRIC_AS_PBR = 0u;
// 1: shadow maps are sampled.
layout(constant_id = 15) const uint SHADOWS = 0u;
// 1: point and spot lights out of range are skipped.
layout(constant_id = 16) const uint RANGE_CULLING = 1u;
// Environment lighting (weft::env::IblLevel): 0 none, 1 approx, 2 fis, 3 mc.
layout(constant_id = 17) const uint IBL = 0u;
// N of fis:N and mc:N.
layout(constant_id = 18) const uint IBL_SAMPLES = 16u;
// 1: some material is unlit.
layout(constant_id = 19) const uint UNLIT = 0u;
// 1: some drawn material is transmissive (KHR_materials_transmission): the backdrop is read.
layout(constant_id = 20) const uint TRANSMISSION = 0u;
// 1: some drawn material has a clear coat (KHR_materials_clearcoat).
layout(constant_id = 21) const uint COAT = 0u;
// 1: some drawn material transmits diffusely (KHR_materials_diffuse_transmission).
layout(constant_id = 22) const uint DIFFUSE_TRANSMISSION = 0u;
// 1: some drawn material is iridescent (KHR_materials_iridescence).
layout(constant_id = 23) const uint IRIDESCENCE = 0u;
// 1: some drawn material disperses (KHR_materials_dispersion): three refracted rays, not one.
layout(constant_id = 24) const uint DISPERSION = 0u;
// 1: some fabric has thread-by-thread colours (the ThreadColours buffer is read).
layout(constant_id = 25) const uint THREAD_COLOURS = 0u;
// 1: some drawn fabric is a single sheet (WEFT_materials_fabric "transmission"): light through
// its gaps (blended by its thread coverage) and its threads (lit from both sides).
#ifdef FORWARD_GLTF
// (forward_gltf.frag: no fabric is drawn forward, so the woven model is compiled out when the
// module is compiled: lavapipe translates a module's whole SPIR-V for every pipeline, and
// forward.frag's took 157-237 ms.)
const uint FABRIC_SHEETS = 0u;
const uint MATERIAL_KIND = MATERIAL_KIND_GLTF;
const uint PIXEL_KINDS = PIXEL_KIND_GLTF;
#else
layout(constant_id = 26) const uint FABRIC_SHEETS = 0u;
// The transparent pass draws every kind of material with one pipeline.
const uint MATERIAL_KIND = MATERIAL_KIND_ANY;
const uint PIXEL_KINDS = PIXEL_KINDS_ALL;
#endif
// Every texture slot is read.
const uint TEXTURE_SLOTS = TEXTURE_SLOTS_ALL;
const uint GLTF_FEATURES = GLTF_FEATURES_ALL;
// A fragment of a blended surface estimates its fabric lobes alone (a quad's fragments may lie on
// different triangles and layers).
const uint POOL = 0u;

// Set 0: gbuffer.vert's and gbuffer.frag's bindings 0-5, then lighting.frag's shadow and environment bindings (one
// number per resource in every shader).
layout(set = 0, binding = 0, std140) uniform FrameBlock { FrameData frame; };  // the frame uniform (`FrameData`, std140, include/frame.glsl)
layout(set = 0, binding = 1, std430) readonly buffer Materials { Material materials[]; };  // material records (`Material[]`, include/frame.glsl), as gbuffer.frag's binding 1
layout(set = 0, binding = 2, std430) readonly buffer Fabrics { GpuFabric fabrics[]; };  // fabric records (`GpuFabric[]`, include/fabric.glsl), as gbuffer.frag's binding 2
layout(set = 0, binding = 3, std430) readonly buffer Lights { Light lights[]; };  // lights (`Light[]`, include/frame.glsl), as gbuffer.vert's binding 3
// Thread-by-thread colours of the fabrics that have them (weft::fabric::ThreadColourTable; one
// vec4 of zeros when none has).
layout(set = 0, binding = 5, std430) readonly buffer ThreadColours { vec4 thread_colours[]; };  // thread-by-thread colours, as gbuffer.frag's binding 5
layout(set = 0, binding = 10) uniform sampler2DShadow shadow_atlas;  // the shadow atlas, as lighting.frag's binding 10
layout(set = 0, binding = 11, std430) readonly buffer Shadows { Shadow shadows[]; };  // shadow records, as lighting.frag's binding 11
layout(set = 0, binding = 12, std430) readonly buffer TileLights { uint tile_lights[]; };  // per-cluster light lists, as lighting.frag's binding 12
layout(set = 0, binding = 13) uniform samplerCube env_radiance;  // the environment's radiance cube, as lighting.frag's binding 13
layout(set = 0, binding = 14) uniform samplerCube env_specular;  // the GGX-prefiltered specular cube, as lighting.frag's binding 14
layout(set = 0, binding = 15) uniform sampler2D env_dfg;  // the split-sum DFG table, as lighting.frag's binding 15
layout(set = 0, binding = 17, std430) readonly buffer FabricLobeAlbedo { vec2 fabric_lobe_albedo_table[]; };  // the fabric records' lobe albedo tables, as lighting.frag's binding 17
// The backdrop: the lit opaque image (the lighting pass's HDR target before this pass), with box-
// filtered mips; any image when TRANSMISSION = 0.
layout(set = 0, binding = 16) uniform sampler2D backdrop;  // the backdrop: the lighting pass's HDR image copied before the transparent pass draws, with box-filtered mips (linear, clamp); any image when TRANSMISSION = 0

#include "surface.glsl"

// What the surface shows of the backdrop: its pixel where the refracted view ray leaves the
// volume (transmission_exit), blurred by the lobe's roughness (transmission_lod), attenuated
// over the path (volume_attenuation), weighted by what the specular reflection leaves
// (transmission_weight). Nothing transmissive is in the backdrop: a transmissive surface behind
// another is not seen through it.
// The backdrop seen through the volume along the view ray refracted with index ior, attenuated
// over the path (rgb).
vec3 through_volume(vec3 p, vec3 n, vec3 v, float roughness, vec4 transmission, vec3 attenuation, float ior) {
    vec3 exit = transmission_exit(p, n, v, transmission.y, ior);
    vec4 clip = frame.view_proj * vec4(exit, 1.0);
    vec2 uv = clip.w > 0.0 ? clip.xy / clip.w * 0.5 + 0.5 : gl_FragCoord.xy * frame.viewport.zw;
    float lod = transmission_lod(roughness, ior, float(textureSize(backdrop, 0).x));
    return textureLod(backdrop, uv, lod).rgb * volume_attenuation(distance(p, exit), attenuation, transmission.z);
}

vec3 transmitted_light(vec3 p, vec3 n, vec3 v, GltfSurface s, vec4 transmission, vec4 attenuation) {
    float ior = transmission.w;
    vec3 behind;
    if (DISPERSION != 0u && attenuation.w > 0.0 && transmission.y > 0.0) {
        // KHR_materials_dispersion: each colour's ray refracted with its own index.
        vec3 iors = dispersion_iors(ior, attenuation.w);
        behind = vec3(through_volume(p, n, v, s.roughness, transmission, attenuation.rgb, iors.r).r,
                      through_volume(p, n, v, s.roughness, transmission, attenuation.rgb, iors.g).g,
                      through_volume(p, n, v, s.roughness, transmission, attenuation.rgb, iors.b).b);
    } else {
        behind = through_volume(p, n, v, s.roughness, transmission, attenuation.rgb, ior);
    }
    float nv = clamp(dot(n, v), 1e-4, 1.0);
    vec2 ab = textureLod(env_dfg, vec2(nv, s.roughness), 0.0).rg;
    return behind * transmission_weight(s.f0, s.specular, s.base, ab);
}

#include "shade.glsl"

// Blended fabric is lit fragment by fragment, never pooled (POOL is 0): shade.glsl's declaration
// needs a body.
void fabric_pooled_lobe_sums(out vec4 weft, out vec4 warp, out uint pixels) {
    weft = vec4(0.0);
    warp = vec4(0.0);
    pixels = 1u;
}

layout(location = 0) out vec4 out_color;

void main() {
    GSurface s = material_surface();
    if (frame.debug_view != DEBUG_NONE) {
        // The debug views show the G-buffer, which holds only the opaque surfaces.
        discard;
    }
    vec3 v = normalize(frame.eye.xyz - in_world_pos);
    // A fabric sheet covers what is behind it by its threads only (-1: not a sheet); its
    // emission, as all its light, comes from its threads.
    float cover = fabric_sheet_cover(s.surface, s.fabric);
    cover = cover >= 0.0 ? min(cover, 1.0) : (cover == -1.0 ? -1.0 : 0.0);
    vec4 emissive = cover >= 0.0 ? vec4(s.emissive.rgb * cover, s.emissive.a) : s.emissive;
    vec3 radiance = shade_surface(in_world_pos, v, s.albedo, frame_decode(s.frame), s.surface, s.fabric,
                                  emissive, s.specular, s.transmission, s.attenuation, s.coat,
                                  s.coat_normal, s.diffuse_transmission, s.iridescence, vec3(1.0), vec3(0.0));
    radiance = all(lessThan(abs(radiance), vec3(1e30))) ? radiance : vec3(0.0);
    // alphaMode BLEND blends by the base colour's alpha; a transmissive surface that is not BLEND
    // covers what is behind (its transmitted light is in its radiance).
    uint flags = uint(materials[draw.material].extra.w + 0.5);
    bool blended = (flags & MATERIAL_BLEND) != 0u;
    // alphaMode MASK on a transmissive surface: cut out as the G-buffer pass cuts (BLEND carries
    // the MASK flag only for its shadow).
    if (!blended && alpha_cut(materials[draw.material], s.alpha)) {
        discard;
    }
    float alpha = blended ? clamp(s.alpha, 0.0, 1.0) : 1.0;
    // A sheet's radiance is already the coverage-weighted light of its threads (dark gaps), so
    // it is premultiplied by the coverage, and the gaps pass the light behind them (1 − cover).
    if (cover >= 0.0) {
        out_color = vec4(radiance * alpha, cover * alpha);
        return;
    }
    out_color = vec4(radiance * alpha, alpha);
}
