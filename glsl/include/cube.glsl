// Cube-map texel directions (Vulkan face order +x, -x, +y, -y, +z, -z; s right, t down) and the
// equirectangular mapping of weft::env (row 0 up, centre column -z, u towards +x).
// Rust twins: weft::render::environment::cube_texel_dir, weft::env::dir_to_uv.
#ifndef WEFT_CUBE_GLSL
#define WEFT_CUBE_GLSL

vec3 cube_texel_dir(uint face, uvec2 texel, uint size) {
    vec2 st = (vec2(texel) + 0.5) / float(size) * 2.0 - 1.0;
    float s = st.x;
    float t = st.y;
    vec3 d;
    if (face == 0u) d = vec3(1.0, -t, -s);
    else if (face == 1u) d = vec3(-1.0, -t, s);
    else if (face == 2u) d = vec3(s, 1.0, t);
    else if (face == 3u) d = vec3(s, -1.0, -t);
    else if (face == 4u) d = vec3(s, -t, 1.0);
    else d = vec3(-s, -t, -1.0);
    return normalize(d);
}

vec2 equirect_uv(vec3 d) {
    float u = 0.5 + atan(d.x, -d.z) / (2.0 * 3.14159265358979323846);
    float v = acos(clamp(d.y, -1.0, 1.0)) / 3.14159265358979323846;
    return vec2(u, v);
}

#endif
