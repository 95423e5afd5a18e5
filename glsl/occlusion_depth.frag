#version 460
// The occlusion pass, step 1 of 3: the G-buffer's depth at half resolution, the top-left pixel of
// each 2 x 2 block (where occlusion.frag makes its estimate), as one 32-bit float a texel. The
// estimates' 24 depth samples each read this instead of the full-resolution depth-stencil image:
// a quarter of the texels, and on lavapipe an R32F texel is 4 bytes where D32_SFLOAT_S8_UINT is 8.
// The same depth goes to a half-resolution depth attachment, which steps 2 and 3 are drawn against
// at the far plane with depth test LESS: they run where a surface is (llvmpipe skips every 4 x 4
// block that fails the test everywhere, where an early return in the shader would skip nothing).
// With BOUNCE (`--occlusion gtao`), also the block's pixel as an occluder (out_light): its diffuse
// light under the environment, which occlusion.frag reads for the depth samples that set a
// horizon. Made here once per texel, where occlusion.frag made it for each of an estimate's four
// horizons (2026-12-06: the G-buffer reads, the records and the cube look-up were most of the
// bounce's cost on lavapipe).
#include "frame.glsl"
#include "fabric.glsl"
#define WEFT_ENV_SPECULAR_ONLY

// 1: write out_light; 0: out_light is not attached.
layout(constant_id = 2) const uint BOUNCE = 0u;

layout(set = 0, binding = 0, std140) uniform FrameBlock { FrameData frame; };  // the frame uniform (`FrameData`, std140, include/frame.glsl): the environment's rotation and scale (BOUNCE)
layout(set = 0, binding = 1, std430) readonly buffer Materials { Material materials[]; };  // material records (`Material[]`): which pixels are woven (BOUNCE)
layout(set = 0, binding = 2, std430) readonly buffer Fabrics { GpuFabric fabrics[]; };  // fabric records (`GpuFabric[]`): a woven pixel's thread colours (BOUNCE)
layout(set = 0, binding = 14) uniform samplerCube env_specular;  // the GGX-prefiltered specular cube, whose roughness-1 level is the irradiance/π (BOUNCE)
layout(set = 0, binding = 20) uniform sampler2D gb_albedo;  // G-buffer albedo (RGBA8 sRGB): base colour, a: metallic (BOUNCE)
layout(set = 0, binding = 21) uniform usampler2D gb_frame;  // G-buffer normal + tangent (RGBA16_UINT): octahedral normal (xy), frame_encode of include/frame.glsl (BOUNCE)
layout(set = 0, binding = 22) uniform sampler2D gb_surface;  // G-buffer surface (RGBA16F): y the material index (BOUNCE)
layout(set = 0, binding = 23) uniform sampler2D gb_fabric;  // G-buffer fabric coverage (RGBA16F): a woven pixel's c_warp, c_weft, s_warp, s_weft (BOUNCE)
layout(set = 0, binding = 25) uniform sampler2D gb_depth;  // G-buffer depth (D32), fetched per texel
#include "env_cubes.glsl"

layout(location = 0) in vec2 in_uv;
layout(location = 0) out float out_depth;  // the depth of the block's top-left pixel (R32F, half resolution)
// BOUNCE: the block's top-left pixel as an occluder (RGBA32_UINT, occluder_light_pack).
layout(location = 1) out uvec4 out_light;

// An occluder's texel: x, y, z the bits of its diffuse light (an irradiance/π times its diffuse
// colour; for a woven pixel with the coupled diffuse, times its 1 - rs), x's sign bit set where
// that diffuse also falls with the angle toward the receiver (fabric_diffuse_albedo's coupled
// form); w the G-buffer's octahedral normal as it stores it (x low, y high 16 bits).
uvec4 occluder_light_pack(vec3 light, bool coupled, uvec2 normal) {
    uvec3 bits = floatBitsToUint(max(light, vec3(0.0)));
    return uvec4(bits.x | (coupled ? 0x80000000u : 0u), bits.y, bits.z, normal.x | (normal.y << 16u));
}

void main() {
    ivec2 px = min(2 * ivec2(gl_FragCoord.xy), textureSize(gb_depth, 0) - 1);
    out_depth = texelFetch(gb_depth, px, 0).r;
    gl_FragDepth = out_depth;
    if (BOUNCE == 0u) {
        return;
    }
    if (out_depth <= 0.0) {
        out_light = uvec4(0u);
        return;
    }
    uvec4 stored = texelFetch(gb_frame, px, 0);
    vec3 n = oct_decode(frame_decode(stored).xy);
    vec4 alb = texelFetch(gb_albedo, px, 0);
    uint material = min(uint(texelFetch(gb_surface, px, 0).y + 0.5), frame.material_count - 1u);
    uint fabric = uint(materials[material].metallic_roughness.z + 0.5);
    vec3 diffuse = alb.rgb * (1.0 - alb.a);
    bool coupled = false;
    if (fabric > 0u) {
        // The threads' diffuse colour over the coverage (fabric_env_combine's); the diffuse
        // factor towards the receiver (fabric_diffuse_albedo) is occlusion.frag's: its 1 - rs
        // here, its angle there.
        GpuFabric f = fabric_reflecting(fabric_tinted(fabrics[fabric - 1u], alb.rgb));
        coupled = (f.flags & FABRIC_FLAG_COUPLED_DIFFUSE) != 0u;
        diffuse = fabric_albedo(texelFetch(gb_fabric, px, 0), f) * (coupled ? 1.0 - f.rs : 1.0);
    }
    out_light = occluder_light_pack(diffuse * env_prefiltered(n, 1.0), coupled, stored.xy);
}
