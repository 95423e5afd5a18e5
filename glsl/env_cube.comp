#version 460
// Environment preprocessing, step 1: the equirectangular map (env space, weft::env's convention)
// resampled into level 0 of the radiance cube (RGBA32F, six faces, bilinear from the map). The
// cube's other levels are box-filtered by blits afterwards.
//
// Dispatch ceil(size/8) x ceil(size/8) x 6.
#extension GL_GOOGLE_include_directive : require
#include "cube.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

layout(set = 0, binding = 0, rgba32f) uniform writeonly image2DArray cube_level;  // level 0 of the radiance cube, as a storage image2DArray (layer = face)
layout(set = 0, binding = 1) uniform sampler2D equirect;  // the equirectangular environment map (RGBA16F), linear, REPEAT

layout(push_constant) uniform CubePush {
    uint size;        // this level's face size in texels
    float roughness;  // (unused here)
    float source_size;
    uint samples;
} pc;

void main() {
    uvec3 id = gl_GlobalInvocationID;
    if (id.x >= pc.size || id.y >= pc.size || id.z >= 6u) {
        return;
    }
    vec3 d = cube_texel_dir(id.z, id.xy, pc.size);
    vec2 uv = equirect_uv(d);
    // The u seam: sample with the derivative-free LOD 0 (REPEAT wraps u).
    vec3 c = textureLod(equirect, uv, 0.0).rgb;
    imageStore(cube_level, ivec3(id), vec4(c, 1.0));
}
