// env_light.glsl's leaves from the environment's cubes and the DFG table, for the shaders that
// light from the G-buffer or a fragment (shade.glsl) and fabric_lobes.frag. The including shader
// declares `frame`, `env_radiance`, `env_specular` and `env_dfg`; one that defines
// WEFT_ENV_SPECULAR_ONLY (the occlusion pass's bounce) declares only `frame` and `env_specular` and
// gets env_prefiltered alone.
#ifndef WEFT_ENV_CUBES_GLSL
#define WEFT_ENV_CUBES_GLSL

#include "ibl.glsl"

#ifndef WEFT_ENV_SPECULAR_ONLY
// A world direction is looked up at env_dir (env space).
vec3 env_radiance_at(vec3 world_dir, float lod) {
    vec3 d = env_dir(world_dir, frame.env_rot0, frame.env_rot1, frame.env_rot2);
    return textureLod(env_radiance, d, lod).rgb * frame.env_params.x;
}

#endif

vec3 env_prefiltered(vec3 world_dir, float roughness) {
    vec3 d = env_dir(world_dir, frame.env_rot0, frame.env_rot1, frame.env_rot2);
    return textureLod(env_specular, d, roughness * frame.env_params.y).rgb * frame.env_params.x;
}

#ifndef WEFT_ENV_SPECULAR_ONLY
vec3 dfg_lookup(float cos_theta, float roughness) {
    return textureLod(env_dfg, vec2(cos_theta, roughness), 0.0).rgb;
}

float env_face_size() {
    return frame.env_params.z;
}
#endif

#endif
