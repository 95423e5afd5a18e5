#version 460
// Forward pass, fragment stage (alphaMode BLEND): drawn after the deferred lighting pass, over
// its HDR image, with gbuffer.vert, depth-tested against the opaque surfaces' depth and not
// writing it. Each fragment computes the surface gbuffer.frag would store (surface.glsl) and
// shades it at once as the lighting pass shades a G-buffer pixel (shade.glsl): the same lights,
// environment and shadows. Writes premultiplied radiance and the base colour's alpha, blended
// with ONE, ONE_MINUS_SRC_ALPHA (glTF's BLEND: colour·alpha + behind·(1 - alpha)).
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

// Set 0: gbuffer.vert's bindings 0-4, then lighting.frag's shadow and environment bindings.
layout(set = 0, binding = 0, std140) uniform FrameBlock { FrameData frame; };
layout(set = 0, binding = 1, std430) readonly buffer Materials { Material materials[]; };
layout(set = 0, binding = 2, std430) readonly buffer Fabrics { GpuFabric fabrics[]; };
layout(set = 0, binding = 3, std430) readonly buffer Lights { Light lights[]; };
layout(set = 0, binding = 10) uniform sampler2DShadow shadow_atlas;
layout(set = 0, binding = 11, std430) readonly buffer Shadows { Shadow shadows[]; };
layout(set = 0, binding = 12, std430) readonly buffer TileLights { uint tile_lights[]; };
layout(set = 0, binding = 13) uniform samplerCube env_radiance;
layout(set = 0, binding = 14) uniform samplerCube env_specular;
layout(set = 0, binding = 15) uniform sampler2D env_dfg;

#include "surface.glsl"
#include "shade.glsl"

layout(location = 0) out vec4 out_color;

void main() {
    GSurface s = material_surface();
    if (frame.debug_view != DEBUG_NONE) {
        // The debug views show the G-buffer, which holds only the opaque surfaces.
        discard;
    }
    vec3 v = normalize(frame.eye.xyz - in_world_pos);
    vec3 radiance = shade_surface(in_world_pos, v, s.albedo, frame_decode(s.frame), s.surface, s.fabric,
                                  s.emissive, s.specular);
    radiance = all(lessThan(abs(radiance), vec3(1e30))) ? radiance : vec3(0.0);
    float alpha = clamp(s.alpha, 0.0, 1.0);
    out_color = vec4(radiance * alpha, alpha);
}
