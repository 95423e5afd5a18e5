#version 460
// Environment preprocessing, step 2: one level of the GGX-prefiltered specular cube of the split
// sum (Karis 2013): for each texel direction R (with n = v = R), the radiance cube convolved with
// the GGX distribution of `roughness`, weighted by n·l, by filtered importance sampling
// (Křivánek & Colbert 2008: each sample reads the radiance cube at the mip level of its pdf);
// roughness 1, the cosine-weighted mean, by an exact sum over the radiance cube's 32² level.
//
// Dispatch ceil(size/8) x ceil(size/8) x 6.
#extension GL_GOOGLE_include_directive : require
#include "cube.glsl"
#include "ibl.glsl"
#include "pbr.glsl"

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

layout(set = 0, binding = 0, rgba32f) uniform writeonly image2DArray cube_level;  // the specular cube's level being written, as a storage image2DArray
layout(set = 0, binding = 1) uniform samplerCube radiance;  // the radiance cube with its mips, linear, clamp

layout(push_constant) uniform CubePush {
    uint size;          // this level's face size in texels
    float roughness;    // of this level
    float source_size;  // the radiance cube's level-0 face size
    uint samples;
} pc;

void main() {
    uvec3 id = gl_GlobalInvocationID;
    if (id.x >= pc.size || id.y >= pc.size || id.z >= 6u) {
        return;
    }
    vec3 n = cube_texel_dir(id.z, id.xy, pc.size);
    if (pc.roughness <= 0.0) {
        imageStore(cube_level, ivec3(id), vec4(textureLod(radiance, n, 0.0).rgb, 1.0));
        return;
    }
    if (pc.roughness >= 1.0) {
        // Roughness 1, the irradiance level (env_irradiance): GGX at α = 1 with n = v reflects
        // uniformly over the sphere, so this level is the cosine-weighted mean of the radiance
        // about n. Summed exactly over every texel of the radiance cube's 32² level (box-filtered
        // from level 0, so every texel's light is in it) with its solid angle, not sampled: 256
        // samples of a map whose lights are small and bright (lightroom_14b: 0.5 % of its pixels
        // hold 30 % of its light) left it 8.6 % low straight up, where Monte Carlo over level 0
        // and the map's own quadrature agree within 0.1 %. Normalised by the same sum's cosine
        // weights, so a uniform environment gives exactly its radiance.
        const uint FACE = 32u;
        float lod = log2(max(pc.source_size / float(FACE), 1.0));
        vec3 total = vec3(0.0);
        float norm = 0.0;
        for (uint face = 0u; face < 6u; ++face) {
            for (uint y = 0u; y < FACE; ++y) {
                for (uint x = 0u; x < FACE; ++x) {
                    vec2 st = (vec2(x, y) + 0.5) / float(FACE) * 2.0 - 1.0;
                    vec3 d = cube_texel_dir(face, uvec2(x, y), FACE);
                    float c = dot(d, n);
                    if (c <= 0.0) {
                        continue;
                    }
                    // The texel's solid angle (its area on the unit cube face over the cube of
                    // its distance), times the cosine.
                    float w = c * inversesqrt(pow(1.0 + dot(st, st), 3.0));
                    total += textureLod(radiance, d, lod).rgb * w;
                    norm += w;
                }
            }
        }
        imageStore(cube_level, ivec3(id), vec4(norm > 0.0 ? total / norm : vec3(0.0), 1.0));
        return;
    }
    mat3 frame = fabric_frame(n, any_perpendicular(n), 1.0);
    float alpha = max(pc.roughness * pc.roughness, 1e-3);
    vec3 sum = vec3(0.0);
    float weight = 0.0;
    for (uint i = 0u; i < pc.samples; ++i) {
        vec3 h = ggx_sample_h(hammersley(i, pc.samples), alpha);
        // v = n = z: l = 2 (n·h) h - n.
        vec3 l = vec3(2.0 * h.z * h.x, 2.0 * h.z * h.y, 2.0 * h.z * h.z - 1.0);
        if (l.z <= 0.0) {
            continue;
        }
        // pdf of l: D(h)·(n·h)/(4 v·h) = D/4 with v = n.
        float pdf = ggx_d(h.z, alpha) * 0.25;
        vec3 w = frame * l;
        sum += textureLod(radiance, w, fis_lod(pdf, pc.samples, pc.source_size)).rgb * l.z;
        weight += l.z;
    }
    imageStore(cube_level, ivec3(id), vec4(weight > 0.0 ? sum / weight : vec3(0.0), 1.0));
}
