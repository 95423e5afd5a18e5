// The G-buffer pass's fragment shader, compiled as two modules (glsl/gbuffer*.frag, each this
// file after a line or two): gbuffer.frag draws the kind of material its MATERIAL_KIND constant
// names (or any), gbuffer_gltf.frag glTF materials alone. It samples the material's textures and
// writes the surface's attributes; lighting happens later, in the lighting pass, from these
// targets alone.
#include "frame.glsl"
#include "fabric.glsl"
#include "weave.glsl"

// Accuracy level (model page §4): 0 nearest, 1 filtered-params, 2 mixture, 3 supersampled.
layout(constant_id = 0) const uint ACCURACY = 2u;
// Where the coverage comes from: 0 the weave texture, 1 the exact coverage of the footprint box
// evaluated here (no texture).
layout(constant_id = 1) const uint WEAVE_SOURCE = 0u;
// How fabric is shaded (SHADING_* in frame.glsl): Gouraud adds the vertex stage's lighting to
// the emitted radiance; the others change nothing here.
layout(constant_id = 2) const uint SHADING = 0u;
// The pixel footprint (RenderOptions::footprint): at most this many pieces per side of the
// parallelogram spanned by the UV derivatives, each filtered by its bounding box (1: the whole
// footprint's bounding box). Id 3 is gbuffer.vert's.
layout(constant_id = 4) const uint FOOTPRINT_PIECES = 2u;
// 1: multiply the vertex colour (COLOR_0, from gbuffer.vert) into the base colour and alpha, and
// into fabric's thread texture value; 0: the scene has none.
layout(constant_id = 5) const uint VERTEX_COLORS = 0u;
// 1: some drawn material is alphaMode MASK: pixels whose base colour alpha is below the cutoff
// are discarded (at the end, after every derivative); 0: no discard is compiled in, so early
// depth testing stays possible.
layout(constant_id = 6) const uint ALPHA_MASK = 0u;
// 1: some fabric has thread-by-thread colours (the ThreadColours buffer is read).
layout(constant_id = 7) const uint THREAD_COLOURS = 0u;
// The draw's kind of material (MATERIAL_KIND_*, frame.glsl): the pass binds a pipeline per kind,
// so a glTF material runs none of the weave's code and fabric none of the glTF extensions'.
#ifdef GBUFFER_KIND
// (gbuffer_gltf.frag: fixed when the module is compiled, so the weave's code is not in its
// SPIR-V, 18 KB against 175: lavapipe translates a module's whole SPIR-V for every pipeline
// before specialization removes anything. Fabric's pipeline keeps gbuffer.frag: the glTF code
// it would leave out is a few kilobytes.)
const uint MATERIAL_KIND = GBUFFER_KIND;
#else
layout(constant_id = 8) const uint MATERIAL_KIND = 0u;
#endif
// The texture slots some material of the scene has a texture in (bit SLOT_*): the others are
// not sampled (sample_slot, surface.glsl).
layout(constant_id = 9) const uint TEXTURE_SLOTS = 0x7FFFFu;
// 1: the scene has the world light (render::world_light): the specular target carries each
// pixel's, interpolated from its vertices (gbuffer.vert), in place of KHR_materials_specular's
// data, which the plan then knows no material has (the lighting takes F0 from the material).
layout(constant_id = 10) const uint WORLD_LIGHT = 0u;
// The G-buffer draws no clear coat (coated draws go to the transparent pass): surface.glsl's coat
// code is compiled out.
const uint COAT = 0u;

layout(set = 0, binding = 0, std140) uniform FrameBlock { FrameData frame; };
layout(set = 0, binding = 1, std430) readonly buffer Materials { Material materials[]; };  // material records (`Material[]`, include/frame.glsl)
layout(set = 0, binding = 2, std430) readonly buffer Fabrics { GpuFabric fabrics[]; };  // fabric records (`GpuFabric[]`, include/fabric.glsl)
// Thread-by-thread colours of the fabrics that have them (weft::fabric::ThreadColourTable; one
// vec4 of zeros when none has).
layout(set = 0, binding = 5, std430) readonly buffer ThreadColours { vec4 thread_colours[]; };  // thread-by-thread colours (`vec4 thread_colours[]`; weft::fabric::ThreadColourTable records, one per striped fabric, at `GpuFabric.colours`; read only when THREAD_COLOURS = 1)

#include "surface.glsl"

layout(location = 0) out vec4 gb_albedo;    // RGBA8 sRGB: base colour, a: metallic
layout(location = 1) out uvec4 gb_frame;    // RGBA16_UINT: octahedral normal (xy), tangent (zw), frame_encode
layout(location = 2) out vec4 gb_surface;   // RGBA16F: roughness, material index, tangent sign, 1 if it receives shadows
layout(location = 3) out vec4 gb_fabric;    // RGBA16F: c_warp, c_weft and each shadow-weighted (s_warp, s_weft)
layout(location = 4) out vec4 gb_emissive;  // RGBA16F: emitted radiance, a: ambient occlusion
layout(location = 5) out vec4 gb_specular;  // RGBA16F: the dielectric's F0 (rgb), specular weight; with WORLD_LIGHT the world light (rgb bounce irradiance/π, a visibility)

void main() {
    GSurface s = material_surface();
    gb_albedo = s.albedo;
    gb_frame = s.frame;
    gb_surface = s.surface;
    gb_fabric = s.fabric;
    gb_emissive = s.emissive;
    // The world light is its vertices' front hemisphere's: a double-sided surface's back face
    // keeps the screen's occlusion alone.
    gb_specular = WORLD_LIGHT != 0u ? (gl_FrontFacing ? in_world_light : vec4(0.0, 0.0, 0.0, 1.0))
                                    : s.specular;
    if (ALPHA_MASK != 0u && alpha_cut(materials[draw.material], s.alpha)) {
        discard;
    }
}
