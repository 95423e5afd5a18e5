// Frame-wide data shared by the G-buffer and lighting passes: the camera and frame uniform, the
// light and material records, and the G-buffer packing. Mirrored in Rust by src/records.rs
// (same field order; std140 for the uniform, std430 for the storage buffers).
#ifndef WEFT_FRAME_GLSL
#define WEFT_FRAME_GLSL

const float PI = 3.14159265358979323846;

// Debug views (frame.debug_view); 0 is the lit image.
const uint DEBUG_NONE = 0u;
const uint DEBUG_ALBEDO = 1u;
const uint DEBUG_NORMALS = 2u;
const uint DEBUG_TANGENTS = 3u;
const uint DEBUG_ROUGHNESS_METALLIC = 4u;
const uint DEBUG_COVERAGE = 5u;
const uint DEBUG_THREAD_DIR = 6u;
const uint DEBUG_DEPTH = 7u;
const uint DEBUG_UV = 8u;
const uint DEBUG_OCCLUSION = 9u;

// How fabric materials are shaded (the SHADING specialization constant; `weft compare`).
const uint SHADING_FABRIC = 0u;    // the fabric model (the default)
const uint SHADING_GOURAUD = 1u;   // the Phong reflection model per vertex, interpolated
const uint SHADING_PHONG = 2u;     // the Phong reflection model per pixel
const uint SHADING_PLAIN_AS = 3u;  // one Ashikhmin–Shirley lobe per pixel, no weave

struct FrameData {
    mat4 view;
    mat4 proj;
    mat4 view_proj;
    mat4 inv_view_proj;
    vec4 eye;            // xyz: camera position in world space
    vec4 viewport;       // width, height, 1/width, 1/height
    vec4 ambient_sky;    // rgb: ambient radiance from above; a: the exposure (linear, 2^EV), which the
                         // lighting pass applies where it tone-maps (lighting_main.glsl's TONE_CURVE)
    vec4 ambient_ground; // rgb: ambient radiance from below
    vec4 background;     // rgb: radiance of empty pixels
    uint light_count;
    uint debug_view;
    uint material_count;
    uint tile_columns;   // 16 x 16-pixel tiles across (lighting.frag's light lists)
    // Environment lighting (weft::env; zeros when the scene has none).
    vec4 env_rot0;       // rows of env_from_world (--env-rotation about +y); w unused
    vec4 env_rot1;
    vec4 env_rot2;
    vec4 env_params;     // x: intensity, y: the specular cube's last level (roughness 1),
                         // z: the radiance cube's face size, w: its last level
    vec4 env_background; // x: 0 environment, 1 colour (background.rgb), 2 transparent;
                         // y: the environment background's blur, in radiance-cube levels
    vec4 sh[9];          // irradiance/π as order-2 SH in env space (weft::env::Environment::sh9); weft's shading reads env_irradiance (the specular cube's roughness-1 level) instead
    vec4 clusters;       // the light clusters (weft::render::tiles): x: depth slices S (1: the
                         // 16 x 16 tiles alone), y: the near distance d0, z: slices per doubling
                         // of the view distance k (view distance d is in slice
                         // clamp(floor(log2(max(d, d0)/d0)·k), 0, S − 1)), w: tile rows
};

const uint LIGHT_DIRECTIONAL = 0u;
const uint LIGHT_POINT = 1u;
const uint LIGHT_SPOT = 2u;

struct Light {
    vec4 position_range;   // xyz world position; w: range (0 = infinite)
    vec4 direction_type;   // xyz: direction the light travels; w: LIGHT_* as float
    vec4 color_intensity;  // rgb colour, a: intensity (lux for directional, candela otherwise)
    vec4 spot;             // x: angle scale, y: angle offset (KHR_lights_punctual spot falloff),
                           // z: index + 1 of the light's Shadow record (0 = casts none)
};

// One light's shadow map: a square tile of the shadow atlas (std430, 96 bytes).
struct Shadow {
    mat4 clip_from_world;  // the light's projection x view (reversed-Z)
    vec4 tile;             // xy: the tile's origin in atlas uv, zw: its size in atlas uv
    vec4 params;           // x: normal offset (world units per unit of distance to the light for
                           // spot lights, world units for directional), y: 1 spot (perspective),
                           // z: PCF radius in tile texels, w: one tile texel in atlas uv
};

// Texture slots (weft::scene::TextureSlot): the index of a slot's UV map in Material.uv.
// What one G-buffer pipeline draws (gbuffer.frag's MATERIAL_KIND, weft::render::passes::gbuffer):
// any material, or only fabric (the woven model's code) or only glTF materials (none of it).
const uint MATERIAL_KIND_ANY = 0u;
const uint MATERIAL_KIND_WOVEN = 1u;
const uint MATERIAL_KIND_GLTF = 2u;
// Every texture slot (TEXTURE_SLOTS: one bit per SLOT_*).
const uint TEXTURE_SLOTS_ALL = 0x7FFFFu;
// What one lighting pipeline shades (lighting.frag's PIXEL_KINDS, a bit each): empty pixels (the
// background), fabric by the woven model, glTF materials (and fabric shaded as one).
const uint PIXEL_KIND_BACKGROUND = 1u;
const uint PIXEL_KIND_WOVEN = 2u;
const uint PIXEL_KIND_GLTF = 4u;
const uint PIXEL_KINDS_ALL = 7u;
// glTF extensions the lighting compiles in (GLTF_FEATURES, a bit each): KHR_materials_sheen,
// KHR_materials_anisotropy.
const uint GLTF_FEATURE_SHEEN = 1u;
const uint GLTF_FEATURE_ANISOTROPY = 2u;
const uint GLTF_FEATURES_ALL = 3u;

const uint SLOT_BASE_COLOR = 0u;
const uint SLOT_METALLIC_ROUGHNESS = 1u;
const uint SLOT_NORMAL = 2u;
const uint SLOT_EMISSIVE = 3u;
const uint SLOT_OCCLUSION = 4u;
const uint SLOT_SHEEN_COLOR = 5u;
const uint SLOT_SHEEN_ROUGHNESS = 6u;
const uint SLOT_SPECULAR = 7u;
const uint SLOT_SPECULAR_COLOR = 8u;
const uint SLOT_ANISOTROPY = 9u;
const uint SLOT_TRANSMISSION = 10u;
const uint SLOT_THICKNESS = 11u;
const uint SLOT_CLEARCOAT = 12u;
const uint SLOT_CLEARCOAT_ROUGHNESS = 13u;
const uint SLOT_CLEARCOAT_NORMAL = 14u;
const uint SLOT_DIFFUSE_TRANSMISSION = 15u;
const uint SLOT_DIFFUSE_TRANSMISSION_COLOR = 16u;
const uint SLOT_IRIDESCENCE = 17u;
const uint SLOT_IRIDESCENCE_THICKNESS = 18u;

// Material.extra.w flags.
const uint MATERIAL_ANISOTROPY = 1u;
const uint MATERIAL_ANISOTROPY_TEXTURE = 2u;
const uint MATERIAL_UNLIT = 4u;  // KHR_materials_unlit
const uint MATERIAL_MASK = 8u;   // alphaMode MASK: alpha.x is the cutoff
const uint MATERIAL_BLEND = 16u;  // alphaMode BLEND: the transparent pass blends by its alpha
const uint MATERIAL_TRANSMISSION = 32u;  // KHR_materials_transmission: alpha.yzw, volume
const uint MATERIAL_CLEARCOAT = 64u;  // KHR_materials_clearcoat: coat
const uint MATERIAL_DIFFUSE_TRANSMISSION = 128u;  // KHR_materials_diffuse_transmission
const uint MATERIAL_IRIDESCENCE = 256u;  // KHR_materials_iridescence: iridescence
const uint MATERIAL_SPEC_GLOSS = 512u;  // KHR_materials_pbrSpecularGlossiness: metallic_roughness.y is
                                        // the glossiness, the metallic-roughness slot's A its texture

struct Material {
    vec4 base_color;          // linear rgba factor
    vec4 emissive_normal;     // rgb emissive factor, a: normal scale
    vec4 metallic_roughness;  // x metallic, y roughness, z: fabric record index + 1 (0 = none),
                              // w: occlusion strength
    vec4 sheen;               // KHR_materials_sheen: rgb colour factor (0: no sheen), a: roughness
    vec4 specular;            // KHR_materials_specular: rgb colour factor, a: specular factor
    vec4 extra;               // x: the dielectric's F0 from KHR_materials_ior, y: anisotropy
                              // strength, z: anisotropy rotation (radians), w: MATERIAL_* flags (a whole number)
    vec4 uv[38];              // per texture slot s: rows uv[2s], uv[2s+1] of its affine UV map
                              // (xyz), uv[2s].w: the UV set (0 or 1)
    vec4 alpha;               // x: alphaCutoff of an alphaMode MASK material (flag MATERIAL_MASK);
                              // KHR_materials_transmission and _volume: y the transmission factor,
                              // z the thickness factor (object space), w the attenuation distance
                              // (0: infinite)
    vec4 volume;              // rgb: the attenuation colour (linear), a: the index of refraction
    vec4 coat;                // KHR_materials_clearcoat: x factor, y roughness, z the coat normal
                              // texture's scale (0: none), w unused
    vec4 diffuse_transmission;  // KHR_materials_diffuse_transmission: x factor, yzw colour
    vec4 iridescence;         // KHR_materials_iridescence: x factor, y the film's ior, z and w its
                              // thickness (nm) at the thickness texture's 0 and 1
    vec4 dispersion;          // KHR_materials_dispersion: x 20 / the Abbe number (0: none)
};

// alphaMode MASK: the base colour's alpha (factor x texture x vertex colour) below the cutoff is
// cut out. No antialiasing of the edge (one sample per pixel, as the cutoff defines it).
bool alpha_cut(Material m, float alpha) {
    return (uint(m.extra.w + 0.5) & MATERIAL_MASK) != 0u && alpha < m.alpha.x;
}

// Octahedral encoding of unit vectors (Cigolle et al. 2014): two values in [-1, 1].
vec2 oct_encode(vec3 n) {
    n /= (abs(n.x) + abs(n.y) + abs(n.z));
    vec2 p = n.xy;
    if (n.z < 0.0) {
        p = (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
    }
    return p;
}

vec3 oct_decode(vec2 p) {
    vec3 n = vec3(p, 1.0 - abs(p.x) - abs(p.y));
    float t = max(-n.z, 0.0);
    n.x += n.x >= 0.0 ? -t : t;
    n.y += n.y >= 0.0 ? -t : t;
    return normalize(n);
}

// The G-buffer's normal + tangent target (RGBA16_UINT): each octahedral coordinate in [-1, 1]
// rounded explicitly to the nearest of 2·32767 + 1 levels, so the stored frame carries no bias
// from how a driver rounds floats into a narrower target (lavapipe's RGBA16F stores rounded
// toward zero, which leaned normals ≈4e-4 rad towards +z). Step 1/32767 (3e-5), 0 exact.
uvec4 frame_encode(vec2 n_oct, vec2 t_oct) {
    vec4 p = clamp(vec4(n_oct, t_oct), -1.0, 1.0);
    return uvec4(ivec4(round(p * 32767.0)) + 32768);
}

vec4 frame_decode(uvec4 stored) {
    return (vec4(stored) - 32768.0) / 32767.0;
}

// A unit vector orthogonal to n, for when a tangent is missing or degenerate.
vec3 any_tangent(vec3 n) {
    vec3 a = abs(n.x) < 0.9 ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 1.0, 0.0);
    return normalize(cross(a, n));
}

#endif
