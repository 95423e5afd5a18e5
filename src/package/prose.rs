//! The package's hand-written prose: what each module is for ([`MODULE_NOTES`]) and what each
//! specialization constant means ([`SPEC_MEANINGS`]). Everything else in the manifest is reflected.

/// What each module is for and how to call it (Markdown, for README.md), by module name.
pub const MODULE_NOTES: &[(&str, &str)] = &[
    (
        "env_cube.comp",
        "Environment preprocessing, step 1: resamples an equirectangular RGBA16F map (row 0 up, \
         centre column -z; `include/cube.glsl`) into level 0 of an RGBA16F cube. Bind the cube's \
         level 0 as a storage `image2DArray` (layer = face) and the map with a linear sampler \
         (REPEAT); push the 16-byte `CubePush` (`uint size`, `float roughness` unused, \
         `float source_size`, `uint samples`); dispatch `ceil(size/8)` x `ceil(size/8)` x 6. \
         Then box-filter the other levels (blits). Rust side: \
         `weft::render::environment::EnvPasses::build`.",
    ),
    (
        "env_prefilter.comp",
        "Environment preprocessing, step 2: one level of the GGX-prefiltered specular cube of \
         the split sum, by filtered importance sampling of the radiance cube (Krivanek & Colbert \
         2008); at roughness 1 (the irradiance level) an exact cosine-weighted sum over the \
         radiance cube's 32² level instead (`samples` ignored; its level 0 where the cube is smaller). \
         Bind the level as a storage `image2DArray` and the radiance cube (with mips) as a \
         `samplerCube`; push `CubePush` with this level's `size`, its `roughness` \
         (level/(levels-1)), the radiance cube's level-0 `source_size` and `samples` (32·2^(level-1)); \
         dispatch `ceil(size/8)` x `ceil(size/8)` x 6 per level.",
    ),
    (
        "fabric_probe.comp",
        "Evaluates every function of the fabric BRDF (`include/fabric.glsl`) and of the weave \
         (`include/weave.glsl`) on a batch of inputs, one invocation per input: the way to check \
         that a driver computes the BRDF as weft's CPU reference does. Bind a buffer of `count` \
         208-byte `ProbeInput` records (std430: `vec4 n, t, k1, k2, point, footprint, coverage, \
         tint` then the 80-byte `GpuFabric` of `include/fabric.glsl`; `t.w` is the tangent's \
         handedness, `k1`/`k2` the unit directions to the light and the viewer, `tint.rgb` the \
         thread texture's value) and a buffer for `count` 208-byte `ProbeOutput` records (thirteen \
         `vec4`: `lobe`, `expo`, `diffuse`, `f`, `point`, `footprint`, `f_point`, `f_avg`, \
         `phong`, `plain_as`, `f_tint`, `sheet`, `f_sheet`). Push the `uint count`; dispatch \
         `ceil(count / 64)` groups. weft's Rust twins and error bounds: \
         `weft::reference::probe`.",
    ),
    (
        "fullscreen.vert",
        "One triangle covering the viewport, with no vertex input: draw 3 vertices, no vertex \
         buffer. Writes the screen UV (0..1, y down) at location 0 for `lighting.frag` and \
         `tonemap.frag`.",
    ),
    (
        "gbuffer.frag",
        "G-buffer pass, fragment stage: samples the material's textures (and, for fabric, the \
         weave texture built by `weave.comp`, with derivatives, so the mip level follows the \
         pixel footprint) and writes six colour targets: albedo (RGBA8 sRGB; for fabric the \
         thread texture's value, which the lighting pass multiplies over the thread colours), normal+tangent \
         (RGBA16_UINT, octahedral, explicitly rounded: `frame_encode` in include/frame.glsl), surface (RGBA16F), fabric coverage (RGBA16F; for other materials \
         the KHR_materials_sheen colour and roughness), emissive (RGBA16F), specular (RGBA16F: \
         KHR_materials_specular's dielectric F0 and weight). Each texture slot has its own UV set \
         (TEXCOORD_0 or _1) and affine transform (`Material.uv`). Render with a D32 depth target. The record layouts are in `include/frame.glsl` and \
         `include/fabric.glsl`.",
    ),
    (
        "forward_gltf.frag",
        "`forward.frag` where no fabric is drawn forward (`include/forward_main.glsl` with the \
         woven model compiled out: MATERIAL_KIND glTF, no fabric sheets): the same blending, \
         backdrop and records; its bindings are a subset of forward.frag's at the same numbers, \
         and weft binds it with forward.frag's set layouts.",
    ),
    (
        "gbuffer_gltf.frag",
        "`gbuffer.frag` for glTF materials alone (`include/gbuffer_main.glsl` with MATERIAL_KIND \
         fixed at 2 when compiled, so the weave's code is not in the module): the same targets \
         and records; its bindings are a subset of gbuffer.frag's at the same numbers, and weft \
         binds it with gbuffer.frag's set layouts, so one material set serves both.",
    ),
    (
        "gbuffer.vert",
        "G-buffer pass, vertex stage: one interleaved vertex buffer with position (location 0, \
         vec3), normal (1, vec3), tangent (2, vec4, w = handedness), uv (3, vec2) and weave uv (4, \
         vec2: the uv with whole weave repeats removed per mesh) and uv1 (5, vec2: TEXCOORD_1), and, \
         for SHADING = 1 (Gouraud), per-vertex lighting of fabric at output location 5 for \
         gbuffer.frag; the vertex colour (COLOR_0, from a storage buffer, white unless \
         VERTEX_COLORS = 1) at output location 7; the world light (from a storage buffer, \
         (0, 0, 0, 1) unless WORLD_LIGHT = 1 and the draw's flags bit 1 is set) at output \
         location 8. Push constants per draw: `mat4 world`, `vec4 normal_matrix[3]`, `uint \
         material`, `float tangent_sign`, `uint flags` (bit 0 receives shadows, bit 1 has the \
         world light), `uint world_base` (128 bytes, visible to the vertex and fragment stages). glTF winding: counter-clockwise \
         front faces; the projection flips y. Its clip position is `precise`, computed as \
         depth.vert computes it.",
    ),
    (
        "depth.vert",
        "G-buffer pass, depth pre-pass, vertex stage: the opaque draws' depth alone, before \
         gbuffer.vert/.frag draw them again with depth test GREATER_OR_EQUAL (reversed-Z), so that \
         the G-buffer's shading runs once per pixel. Reads position (location 0) of gbuffer.vert's \
         vertex buffer, the frame uniform (set 0 binding 0) and gbuffer.vert's push block (128 \
         bytes); its clip position is gbuffer.vert's by the same `precise` expression, equal bit \
         for bit. Pair it with `shadow.frag`; weft runs it where the frame has at least 4 pixels \
         per opaque triangle (`weft plan`'s depth line).",
    ),
    (
        "env_probe.comp",
        "Evaluates the environment light's estimators of `include/env_light.glsl` (`pbr_env`, \
         `aniso_env_specular`, `sheen_layer_diffuse`, `fabric_env_lobes`, `fabric_env_diffuse`, \
         `fabric_env_back`, `fabric_env_combine`, `pixel_random`, `ibl_sample`, `ggx_albedo`) and \
         the shadow maps' PCF of `include/shadows.glsl` (`shadow_pcf`) on a batch of inputs, one \
         invocation per input, with closed-form stand-ins for the textures they read (written in \
         the shader and in `weft::reference::env_light::StandIn`): the way to check that a driver \
         computes the estimators as weft's Rust twins do. Bind a buffer of `count` 464-byte \
         `EnvProbeInput` records (std430: fourteen `vec4` — `n`, `v`, `base_metallic`, \
         `f0_specular`, `sheen`, `t_anisotropy`, `surface`, `film`, `bounce`, `frame_t`, \
         `frame_n`, `k2`, `coverage`, `rot` —, `uvec4 mode` (level, samples, pixel; pixel y mod 3 is \
         also the lobe albedo table `fabric_env_lobes` reads, and at fis (y / 3) mod 4 a pooled \
         quad's lane whose shifted sample set `fabric_env_lobe_sums` evaluates), the 80-byte \
         `GpuFabric` of `include/fabric.glsl`, the 96-byte `Shadow` of `include/frame.glsl`, then \
         `vec4 light_pos, p, pn`) and a buffer for `count` 112-byte `EnvProbeOutput` records \
         (seven `vec4`: `pbr`, `aniso`, `weft`, `warp`, `diffuse`, `back`, `combined`; the \
         shader's comments say which function fills each component). Push the `uint count`; \
         dispatch `ceil(count / 64)` groups. weft's Rust twins: `weft::reference::env_light`.",
    ),
    (
        "ibl_probe.comp",
        "Evaluates every function of image-based lighting (`include/ibl.glsl`: `env_dir`, \
         `sh_irradiance`, `hammersley`, `ggx_sample_h`, `as_sample_h`, `cosine_sample`, `fis_lod`, \
         `specular_occlusion`, `dominant_dir`, `fabric_diffuse_albedo`), of `include/cube.glsl` \
         (`cube_texel_dir`, `equirect_uv`) and of `include/occlusion.glsl` (`gtao_arc`, \
         `gtao_multibounce`) on a batch of inputs, one invocation per input: the way \
         to check that a driver computes them as weft's Rust twins do. Bind a buffer of `count` \
         432-byte `IblProbeInput` records (std430: `vec4 world, rot[3], normal, sh[9], xi, lobe, \
         lod, misc`, `uvec4 counts, cube`, `vec4 dir`, the 80-byte `GpuFabric` of \
         `include/fabric.glsl`, then `vec4 arc`) and a buffer for `count` 160-byte `IblProbeOutput` \
         records (ten `vec4`: `env_dir`, `irradiance`, `ggx`, `as_h`, `cosine`, `cube`, `uv` \
         (hammersley xy, equirect uv), `scalars` (fis_lod, specular_occlusion, \
         fabric_diffuse_albedo), `occlusion` (gtao_arc, gtao_multibounce), `dominant` (dominant_dir of the normal, the \
         direction and the roughness)). Push the \
         `uint count`; dispatch `ceil(count / 64)` groups. weft's Rust twins and the interval \
         bound of each output under the Vulkan precision rules: `weft::reference::ibl_twin`.",
    ),
    (
        "pbr_probe.comp",
        "Evaluates the glTF BRDF of `include/pbr.glsl` (`gltf_brdf_cos` with \
         KHR_materials_specular, _sheen, _anisotropy and _transmission, and its terms `charlie_d`, \
         `sheen_brdf_cos`, `ggx_aniso_d`, `sheen_lambda`), the transmission functions \
         (`transmission_exit`, `transmission_lod`, `volume_attenuation`, `transmission_weight`) \
         the clearcoat's (`clearcoat_brdf_cos`, `clearcoat_fresnel`), the diffuse \
         transmission's (`diffuse_btdf_cos`), a lamp's transmitted lobe (`specular_btdf_cos`, \
         `transmission_alpha`) and the thin film's (`iridescence_fresnel`, \
         KHR_materials_iridescence, also inside `gltf_brdf_cos`) on \
         a batch of inputs, one invocation per input. Bind a buffer of `count` 208-byte \
         `PbrProbeInput` records (thirteen `vec4`: `n`, `v`, \
         `l`, `base_metallic`, `f0_specular`, `sheen`, `t_anisotropy`, `params` (roughness, \
         E(n·v), E(n·l), Ess(n·v) of the energy compensation), `terms_in` (n·h, n·l, n·v, sheen \
         roughness), `volume` (thickness, ior, attenuation distance, backdrop width), \
         `attenuation` (colour, transmission factor), `coat` (factor, roughness), `film` \
         (iridescence factor, film ior, film thickness in nm, and KHR_materials_dispersion's \
         dispersion)) and a buffer for \
         `count` 144-byte outputs (`vec4 brdf`, `vec4 terms`, `vec4 exit_lod`, `vec4 transmitted`, \
         `vec4 coated`, `vec4 through`: the BTDF at −l with the attenuation colour, `vec4 film`: \
         the film's Fresnel at n·v over F0, `vec4 dispersed`: `dispersion_iors` of the volume's ior, \
         `vec4 lamp_through`: `specular_btdf_cos` at −l with the volume's ior and \
         `transmission_alpha`). Push the \
         `uint count`; dispatch `ceil(count / 64)` groups. The Rust twins: \
         `weft::reference::shading::gltf_brdf_cos`, `transmission_exit`, `transmission_lod`, \
         `volume_attenuation`, `transmission_weight`, `clearcoat_brdf_cos`, `clearcoat_fresnel`, `diffuse_btdf_cos`, `specular_btdf_cos`, `transmission_alpha`, `iridescence_fresnel`, `dispersion_iors`.",
    ),
    (
        "lighting.frag",
        "Deferred lighting, one fullscreen triangle (`fullscreen.vert`): reads the G-buffer \
         targets and depth written by the G-buffer pass, sums every light with the glTF \
         metallic-roughness BRDF (with KHR_materials_specular, _sheen and _anisotropy) or the \
         fabric BRDF per material, and writes linear HDR radiance \
         to one RGBA16F target. No push constants.",
    ),
    (
        "lighting_background.frag",
        "`lighting.frag` for the empty pixels alone (`include/lighting_main.glsl` with \
         PIXEL_KINDS fixed at 1 when compiled, so the other kinds' code is not in the module): \
         the environment seen along the view ray, a colour, or transparent. weft draws it over \
         the pixels whose G-buffer stencil is 0; its set holds the bindings it keeps, at \
         lighting.frag's numbers. No push constants.",
    ),
    (
        "lighting_woven.frag",
        "`lighting.frag` for the woven model's pixels alone (`include/lighting_main.glsl` with \
         PIXEL_KINDS fixed at 2): drawn over the pixels whose G-buffer stencil is 1, after \
         `fabric_lobes.frag` where the lobe samples are pooled; its set holds the bindings it \
         keeps, at lighting.frag's numbers. No push constants.",
    ),
    (
        "lighting_gltf.frag",
        "`lighting.frag` for the glTF materials' pixels alone (`include/lighting_main.glsl` \
         with PIXEL_KINDS fixed at 4): drawn over the pixels whose G-buffer stencil is 2; its \
         set holds the bindings it keeps, at lighting.frag's numbers. No push constants.",
    ),
    (
        "fabric_lobes.frag",
        "The woven model's environment lobe samples for `lighting.frag` to pool, one fullscreen \
         triangle (`fullscreen.vert`) drawn before lighting.frag with the same set and \
         constants, over the fabric pixels (a stencil test, or every pixel: the others write \
         zeros). Reads the G-buffer's frame, surface, fabric and depth targets and the radiance \
         cube; writes per pixel its two lobes' weighted mean radiance (RGB9E5), their weights \
         (bfloat16) and which pixels around it pool with it (`include/env_light.glsl`'s \
         fabric_lobe_pack) to one RGBA32_UINT target, which lighting.frag reads at binding 28. No push constants.",
    ),
    (
        "forward.frag",
        "Forward pass for alphaMode BLEND surfaces, fragment stage; pair it with `gbuffer.vert` \
         (same vertex buffer and 128-byte push constants) and draw after the lighting pass into \
         its RGBA16F target, with the G-buffer depth attached for testing (GREATER, reversed Z) \
         but not written, back to front. Computes the surface gbuffer.frag would store \
         (`include/surface.glsl`) and lights it as lighting.frag lights a pixel \
         (`include/shade.glsl`); writes premultiplied radiance and alpha: blend with ONE, \
         ONE_MINUS_SRC_ALPHA for colour and alpha. Set 0 holds gbuffer.vert's bindings 0-5 and \
         lighting.frag's shadow and environment bindings 10-15 (one number per resource in every \
         shader), the backdrop at 16; set 1 a material's textures as \
         gbuffer.frag's. Rust side: `weft::render::passes::transparent`.",
    ),
    (
        "shadow.frag",
        "Depth-only passes, fragment stage: empty; pair it with `shadow.vert` (the shadow maps) or \
         `depth.vert` (the G-buffer's depth pre-pass).",
    ),
    (
        "shadow_mask.frag",
        "Shadow pass for alphaMode MASK casters, fragment stage: discards where the base colour's \
         alpha (`Material.base_color.a` x the base colour texture's alpha through the slot's UV \
         set and map x the vertex colour alpha) is below the material's cutoff \
         (`Material.alpha.x`, flag 8 in `Material.extra.w`), so cut-outs cast cut-out shadows. \
         Pair it with `shadow_mask.vert`; set 0 binding 1 the material records (gbuffer.frag's number), set 1 binding 0 \
         the caster material's base colour texture.",
    ),
    (
        "shadow_mask.vert",
        "Shadow pass for alphaMode MASK casters, vertex stage: as `shadow.vert`, with the G-buffer \
         pass's vertex buffer read at position (location 0, offset 0), uv (1, offset 40) and uv1 \
         (2, offset 56), and each vertex's colour alpha from set 0 binding 4 (gbuffer.vert's number) when \
         VERTEX_COLORS = 1. Push `mat4 clip_from_object`, `uint material` and three pad words (80 bytes, vertex \
         and fragment stages) per draw. weft makes this pipeline only for a frame with a shadow \
         map and a MASK material that casts.",
    ),
    (
        "shadow.vert",
        "Shadow pass, vertex stage: depth-only rendering of shadow casters into one light's tile of \
         a D32 shadow atlas (reversed-Z: clear to 0, depth compare GREATER, nearest to the light \
         is 1). The G-buffer pass's vertex buffer (position at location 0, the other attributes \
         ignored); push `mat4 clip_from_object` (the light's projection x view x the draw's world \
         matrix, 64 bytes, vertex stage) per draw, viewport and scissor on the light's tile, no \
         culling. `lighting.frag` samples the atlas with a comparison sampler (GREATER_OR_EQUAL, \
         linear, clamp) through the `Shadow` records of `include/frame.glsl`.",
    ),
    (
        "occlusion_depth.frag",
        "Screen-space occlusion of the environment, step 1 of 3: the G-buffer depth (set 0 \
         binding 25, fetched per texel) of each 2 x 2 block's top-left pixel, into an \
         `R32_SFLOAT` target of half the size (rounded up) that `occlusion.frag` gathers from; \
         with BOUNCE also the same pixel as an occluder into an `R32G32B32A32_UINT` target \
         (location 1: its diffuse light under the environment as three f32 bit patterns, x's \
         sign bit set for a woven pixel with the coupled diffuse, and w its octahedral normal \
         as the G-buffer stores it), from the frame uniform (set 0 binding 0), the material and \
         fabric records (1, 2), the prefiltered environment cube (14) and the G-buffer albedo \
         (20), normal (21), surface (22) and fabric coverage (23). Drawn with `fullscreen.vert` \
         after the G-buffer pass; no push constants.",
    ),
    (
        "occlusion.frag",
        "Screen-space occlusion of the environment, step 2 of 3 (ground-truth ambient occlusion, \
         GTAO, `include/occlusion.glsl`), drawn with `fullscreen.vert` after \
         `occlusion_depth.frag`: at half resolution (one estimate per 2 x 2 pixels, at its \
         top-left pixel; draw it into a target of half the size, rounded up), SLICES planes \
         through the view vector turned by a 4 x 4 pattern of estimates, the \
         highest horizon on each side among STEPS depth samples out to a world radius, and the \
         cosine-weighted visible arc between them. Reads the frame uniform (set 0 binding 0), the \
         G-buffer normal (21) and the half-resolution depth of step 1 (26), and with BOUNCE \
         step 1's occluder light (30), at the texel nearest the sample that set each horizon; push `mat4 view_from_clip` (the inverse projection) \
         and `vec4 params` (radius, falloff scale and offset; 80 bytes, fragment stage); writes \
         visibility and view distance to an `R16G16_SFLOAT` target (location 0) and the \
         occluders' bounced light (rgb, 0 without BOUNCE) to an `R16G16B16A16_SFLOAT` target \
         (location 1) for `occlusion_blur.frag`.",
    ),
    (
        "occlusion_blur.frag",
        "Screen-space occlusion of the environment, step 3 of 3, at half resolution: the mean \
         of the 4 x 4 estimates of `occlusion.frag` (set 0 binding 28) around each, weighted by \
         how close their view distances lie to its surface so that edges stay sharp, into an \
         `R16G16_SFLOAT` target (visibility, view distance) that `lighting.frag` reads at binding \
         27 when OCCLUSION ≥ 1, bringing it to full resolution, and with BOUNCE the same mean of \
         the bounced light (binding 29) into an `R16G16B16A16_SFLOAT` target (location 1) that \
         `lighting.frag` reads at binding 29 when OCCLUSION = 2. Drawn with `fullscreen.vert`; no \
         push constants.",
    ),
    (
        "fxaa.frag",
        "Edge anti-aliasing of a tone-mapped 8-bit image (FXAA in the manner of Lottes' 3.11 \
         quality preset): finds luma edges, their direction and their ends along a search of up to \
         32 pixels, and samples across the edge by how far the pixel is from its middle, or by its \
         sub-pixel aliasing. Binding 0 samples the tone-mapped `R8G8B8A8_SRGB` image (colour, \
         blended linearly), binding 1 the same image through an `R8G8B8A8_UNORM` view (create it \
         `MUTABLE_FORMAT` with both formats listed): luma from the encoded bytes, without an sRGB \
         decode per look-up. Drawn with `fullscreen.vert` after `tonemap.frag`, into the output \
         target; no push constants, no specialization constants.",
    ),
    (
        "fxaa_flat.frag",
        "The first of edge anti-aliasing's two draws over a stencil (`fxaa.frag`'s bindings 0 and \
         1): every pixel off a luma edge (the test `fxaa.frag` makes first) is copied from the \
         tone-mapped image, a pixel on an edge is discarded. Draw it with a pipeline that writes \
         a stencil bit where a fragment is kept, then `fxaa.frag` where that bit is clear: \
         together they write every pixel as `fxaa.frag` alone would, and a GPU that skips \
         blocks by their stencil runs the edge search only where there are edges. Drawn with \
         `fullscreen.vert`; no push constants, no specialization constants.",
    ),
    (
        "tonemap.frag",
        "Exposure and tone mapping (Khronos PBR Neutral by default: constant 0) of the HDR target, drawn with \
         `fullscreen.vert`; write to an `R8G8B8A8_SRGB` target, which does the sRGB encoding. \
         Push `float exposure` (linear scale, 2^EV); the curve is specialization constant 0. \
         Where nothing reads the HDR image, `lighting.frag` can apply the same curve itself \
         (its constant 15) and this pass is not needed.",
    ),
    (
        "weave.comp",
        "Builds one mip level of a weave coverage texture: one full pattern repeat (so it tiles \
         with REPEAT addressing), each texel `(c_warp, c_weft, s_warp, s_weft)`: the exact area \
         fractions of warp and weft on top, and each weighted by the diffuse shadow factor, of the \
         texel's footprint. \
         Every level is computed directly (not downsampled), so filtering stays a correct \
         footprint average. Create an `R16G16B16A16_SFLOAT` image with STORAGE and SAMPLED usage \
         (32 texels per weave cell at level 0, full mip chain); per level, bind a one-level image \
         view in GENERAL layout, push the 36-byte `WeavePush` (`uint pattern_lo, pattern_hi` \
         (bit 8j+i = cell (i, j) weft-up), `uint cols, rows` (1..8), `float gap` (s_g/s_p), \
         `float shadow_dist`, `float shadow_strength`, `uint width, height` (this level's size)) \
         and dispatch `ceil(width / 8) × ceil(height / 8)` groups. weft's Rust twins: \
         `weft::fabric::WeavePush`, `weft::fabric::weave_texels_cpu`.",
    ),
    (
        "skin.comp",
        "Deforms one draw's vertices for an animation pose: morph targets (weighted position,          normal and tangent deltas), then linear blend skinning with up to four joints per vertex;          normals by the cofactor matrix, tangents by the matrix then made orthogonal to the normal,          the handedness flipped where the skin mirrors. Reads the rest vertices at `src` and writes          the posed copy at `dst` of the same vertex buffer (16 floats per vertex: position, normal,          tangent, uv, weave uv, uv1). Push the 48-byte `SkinPush` (`uint src, dst, count, skin`          (0xffffffff: not skinned), `joint, joint_count, morph, target_count, weight`, 3 pad) and          dispatch `ceil(count / 64)` groups. weft's Rust twins: `weft::render::deform::SkinPush`,          `weft::scene::animation::deform_vertex`.",
    ),
];

/// Modules whose specialization constants are another module's (by id): the one-kind modules
/// are gbuffer.frag compiled with MATERIAL_KIND fixed and lighting.frag with PIXEL_KINDS fixed,
/// keeping the constants their code still reads. weft's glTF G-buffer pipelines give
/// gbuffer_gltf.frag gbuffer.frag's set layouts (its bindings are a subset of them).
pub const SPEC_MEANINGS_OF: &[(&str, &str)] = &[
    ("forward_gltf.frag", "forward.frag"),
    ("gbuffer_gltf.frag", "gbuffer.frag"),
    ("lighting_background.frag", "lighting.frag"),
    ("lighting_woven.frag", "lighting.frag"),
    ("lighting_gltf.frag", "lighting.frag"),
];

/// What each specialization constant means: (module, constant id, meaning).
pub const SPEC_MEANINGS: &[(&str, u32, &str)] = &[
    (
        "gbuffer.frag",
        0,
        "ACCURACY: 0 nearest (one level-0 texel), 1 filtered-params, 2 mixture (default), 3 supersampled (writes the footprint, st and half-extent, instead of coverages)",
    ),
    ("gbuffer.frag", 1, "WEAVE_SOURCE: 0 the weave texture (default), 1 the exact coverage of the footprint computed in the shader"),
    ("gbuffer.frag", 4, "FOOTPRINT_PIECES: how the weave is filtered over the pixel's footprint (the parallelogram of the UV derivatives): 0 its bounding box, N >= 1 an oblique footprint within 4 cells cut into up to N pieces along its longer edge, each filtered by its bounding box shrunk to its area (default 2)"),
    ("gbuffer.frag", 2, "SHADING: how fabric is shaded, as gbuffer.vert's and lighting.frag's; 1 (Gouraud) adds the vertex stage's lighting to the emissive target"),
    ("gbuffer.vert", 2, "SHADING: how fabric is shaded: 0 the fabric model (default), 1 Gouraud (the Phong reflection model per vertex, written for gbuffer.frag), 2 Phong, 3 plain Ashikhmin-Shirley; only 1 does work in this stage"),
    ("gbuffer.vert", 3, "LIGHT_TYPES: as lighting.frag's, for the per-vertex lighting of SHADING = 1 (default 7, all)"),
    ("gbuffer.vert", 5, "VERTEX_COLORS: 1 reads each vertex's colour (set 0, binding 4) and writes it to output location 7 for gbuffer.frag; 0 (default) reads none and writes white"),
    ("gbuffer.frag", 5, "VERTEX_COLORS: 1 multiplies the vertex colour (input location 7) into the base colour and alpha, and for fabric into the thread texture's value; 0 (default) compiles that out"),
    ("gbuffer.frag", 6, "ALPHA_MASK: 1 discards pixels of alphaMode MASK materials (`Material.extra.w` flag 8) whose base colour alpha (factor x texture x vertex colour) is below the cutoff `Material.alpha.x`, after every target is written; 0 (default) compiles the discard out"),
    ("gbuffer.frag", 8, "MATERIAL_KIND: what the pipeline draws: 0 (default) any material; 1 only fabric (materials whose `metallic_roughness.z` names a fabric record), the glTF extensions compiled out; 2 only glTF materials, the weave's code compiled out"),
    ("gbuffer.frag", 9, "TEXTURE_SLOTS: bit mask of the material texture slots (set 1 bindings 0-19 as `SLOT_*` of frame.glsl: bit 0 base colour, 2 normal, ...) that are sampled; a slot whose bit is clear reads the stand-in value (flat normal (128/255, 128/255, 1, 1) for the normal and clearcoat-normal slots, white otherwise) without sampling (default 0x7FFFF, all)"),
    ("gbuffer.vert", 10, "WORLD_LIGHT: 1 reads each vertex's world light (set 0, binding 6, `vec4[]`: rgb the scene's surfaces' light over its hemisphere as irradiance/pi, a the environment's cosine-weighted visibility) at `world_base + gl_VertexIndex` for draws whose flags bit 1 is set, and writes it to output location 8 ((0, 0, 0, 1) otherwise); 0 (default) reads none"),
    ("gbuffer.frag", 10, "WORLD_LIGHT: 1 writes the interpolated world light (input location 8; (0, 0, 0, 1) on back faces) to the specular target instead of KHR_materials_specular's F0 and weight; 0 (default) writes those"),
    ("gbuffer.frag", 7, "THREAD_COLOURS: 1 reads fabrics' thread-by-thread colours (`GpuFabric.flags` bit 3) from the `ThreadColours` buffer (set 0 binding 5) into the albedo target; 0 (default) compiles that out (the buffer may then hold one zero vec4)"),
    ("forward.frag", 0, "ACCURACY: as gbuffer.frag's and lighting.frag's"),
    ("forward.frag", 1, "WEAVE_SOURCE: as gbuffer.frag's"),
    ("forward.frag", 2, "SHADING: as gbuffer.vert's, gbuffer.frag's and lighting.frag's (its id 4)"),
    ("forward.frag", 3, "LIGHT_TYPES: as lighting.frag's (gbuffer.vert reads the same id)"),
    ("forward.frag", 4, "FOOTPRINT_PIECES: as gbuffer.frag's"),
    ("forward.frag", 5, "VERTEX_COLORS: as gbuffer.frag's (gbuffer.vert reads the same id)"),
    ("forward.frag", 11, "SAMPLES: lighting.frag's constant 1"),
    ("forward.frag", 12, "FABRIC_AS_PBR: lighting.frag's constant 2"),
    ("forward.frag", 15, "SHADOWS: lighting.frag's constant 5"),
    ("forward.frag", 16, "RANGE_CULLING: lighting.frag's constant 6"),
    ("forward.frag", 17, "IBL: lighting.frag's constant 7"),
    ("forward.frag", 18, "IBL_SAMPLES: lighting.frag's constant 8"),
    ("forward.frag", 19, "UNLIT: lighting.frag's constant 9"),
    ("forward.frag", 24, "DISPERSION: 1 reads the backdrop along three refracted rays for KHR_materials_dispersion volumes (`Material.dispersion.x` > 0); 0 (default) compiles that out"),
    ("forward.frag", 25, "THREAD_COLOURS: as gbuffer.frag's 7"),
    ("forward.frag", 26, "FABRIC_SHEETS: 1 draws fabric sheets (`GpuFabric.flags` bit 4, WEFT_materials_fabric `transmission`): opacity = their thread coverage, so the gaps let the light behind through, and their threads lit from both sides by `transmission` of their diffuse light; 0 (default) compiles that out"),
    ("forward.frag", 23, "IRIDESCENCE: 1 shades KHR_materials_iridescence surfaces (`Material.extra.w` flag 256) with their thin film's Fresnel; 0 (default) compiles that out"),
    ("forward.frag", 22, "DIFFUSE_TRANSMISSION: 1 lights KHR_materials_diffuse_transmission surfaces (`Material.extra.w` flag 128) from behind too; 0 (default) compiles that out"),
    ("forward.frag", 21, "COAT: 1 shades KHR_materials_clearcoat surfaces (`Material.extra.w` flag 64) with their coat; 0 (default) compiles that out"),
    ("forward.frag", 20, "TRANSMISSION: 1 reads the backdrop for KHR_materials_transmission surfaces (`Material.extra.w` flag 32); 0 (default) compiles that out"),
    ("shadow_mask.vert", 0, "VERTEX_COLORS: 1 reads each vertex's colour alpha (set 0, binding 4) for shadow_mask.frag; 0 (default) reads none (alpha 1)"),
    ("lighting.frag", 10, "OCCLUSION, bits: any bit set multiplies the environment's light by the occlusion pass's visibility (binding 27, raised for light bounced between occluders by the surface's albedo) times the material's occlusion texture (1 alone: that only); bit 1 (2) also adds the occluders' bounced light the screen shows (binding 29) where it exceeds that; bit 2 (4) takes the world light from the G-buffer's specular target (binding 26, written by gbuffer.frag with WORLD_LIGHT = 1): the lesser of the two visibilities, the fit credited only for the screen's, and the greater of the two bounces (the world's alone without bit 1), the dielectric's F0 then from `Material.extra.x` with weight 1; 0 (default) uses the texture alone and reads nothing at bindings 27 and 29"),
    ("occlusion.frag", 0, "SLICES: slices per pixel (default 2; the blur averages 16 x SLICES directions)"),
    ("occlusion.frag", 1, "STEPS: depth samples per side of a slice (default 6)"),
    ("occlusion_depth.frag", 2, "BOUNCE: 1 also writes each texel's pixel as an occluder (location 1); 0 (default) writes depth alone and reads nothing at bindings 0, 1, 2, 14, 20, 21, 22 and 23"),
    ("occlusion.frag", 2, "BOUNCE: 1 also measures the occluders' bounced light (location 1) from occlusion_depth.frag's occluder light (binding 30); 0 (default) writes 0 there and reads nothing at binding 30"),
    ("occlusion_blur.frag", 2, "BOUNCE: 1 also blurs the bounced light (binding 29, location 1); 0 (default) writes 0 there"),
    ("lighting.frag", 11, "DEBUG_VIEWS: 1 (default) shows the G-buffer target `FrameData.debug_view` names instead of the lit image when it is not 0; 0 compiles the debug views out"),
    ("lighting.frag", 12, "PIXEL_KINDS: bit mask of the kinds of pixel shaded: 1 empty pixels (the background), 2 fabric by the woven model, 4 glTF materials (and fabric with FABRIC_AS_PBR); the other kinds' code is compiled out, for pipelines each drawn over its own pixels (by a stencil test, say). A pipeline without 4 shades every surface pixel as fabric, one without 2 as glTF (default 7, all)"),
    ("lighting.frag", 13, "GLTF_FEATURES: bit mask of the glTF extensions whose lighting is compiled in: 1 KHR_materials_sheen (the G-buffer's fabric target holds its colour and roughness), 2 KHR_materials_anisotropy (the surface target's z its strength); a clear bit reads that extension as absent (default 3, both)"),
    ("lighting.frag", 14, "POOL: R >= 1 pools the woven model's environment lobe samples at fis (IBL 2) over the (2R + 1) x (2R + 1) pixels around each pixel that show the same material with normals and tangents within a quarter of the lobe's narrow width, from `fabric_lobes.frag`'s sums at binding 28 (drawn first with the same constants); 0 (default) estimates each pixel's lobes alone and reads nothing at binding 28"),
    ("lighting.frag", 15, "TONE_CURVE: 0 (default) writes linear HDR radiance (render into `R16G16B16A16_SFLOAT` and tone-map with `tonemap.frag`); c + 1 applies tonemap.frag's curve c itself (4 pass-through for debug views), after the exposure `FrameData.ambient_sky.a` (linear, 2^EV), writing the 8-bit image into an `R8G8B8A8_SRGB` target as `tonemap.frag` would (to within a step of the 8 bits: the curve takes the shader's f32, not the HDR target's half floats): for a frame in which nothing reads the HDR image"),
    ("tonemap.frag", 0, "CURVE: the tone curve, 0 Khronos PBR Neutral (default), 1 none (clamp), 2 three.js' ACES fit with the 1/2.2 display gamma, 3 AgX, 4 pass-through (no exposure, no curve: debug views); only that curve is compiled in"),
    ("fabric_lobes.frag", 0, "ACCURACY: as lighting.frag's (3, supersampled, weighs the two lobes' sampling evenly; otherwise the pixel's coverage does)"),
    ("fabric_lobes.frag", 8, "IBL_SAMPLES: N of fis:N, as lighting.frag's: the base count of each pixel's samples; a pixel alone takes N times include/env_light.glsl's fabric_lobe_passes (1 to 7, more toward grazing views, where the lobes are bright), a pixel that pools N / 2 times that"),
    ("fabric_lobes.frag", 14, "POOL: the pooling radius R (>= 1), as lighting.frag's: a pixel that pools takes blocks b, b + (2R + 1)^2, b + 2(2R + 1)^2, ... of the Sobol' (0,2)-sequence (include/ibl.glsl's sobol_block), b = (x mod (2R + 1)) + (2R + 1)(y mod (2R + 1)), so that no two pixels of a window lighting.frag pools share a block (default 1)"),
    ("lighting.frag", 9, "UNLIT: 1 shows the pixels of KHR_materials_unlit materials (`Material.extra.w` flag 4) with the albedo target's base colour as their radiance, unlit; 0 (default) compiles the check out"),
    (
        "lighting.frag",
        0,
        "ACCURACY: 0 nearest and 1 filtered-params evaluate one lobe with coverage-averaged exponents, 2 mixture (default) and 3 supersampled the two-lobe mixture; must match gbuffer.frag's",
    ),
    ("lighting.frag", 1, "SAMPLES: N of supersampled:N, the footprint is sampled at N x N points (default 1)"),
    ("lighting.frag", 2, "FABRIC_AS_PBR: 1 shades fabric pixels with the metallic-roughness BRDF, for cost comparisons (default 0)"),
    ("lighting.frag", 3, "LIGHT_TYPES: bit mask of the light types whose code is compiled in: 1 directional, 2 point, 4 spot (default 7, all)"),
    ("lighting.frag", 5, "SHADOWS: 1 samples the shadow atlas for lights with a shadow record (Light.spot.z > 0) on pixels that receive (G-buffer surface.w = 1); 0 (default) compiles the shadow code out"),
    ("lighting.frag", 6, "RANGE_CULLING: 1 (default) skips point and spot lights whose range cannot reach the pixel before their falloff and BRDF; 2 as 1, with the light lists of binding 12 also sliced by view distance when `FrameData.clusters.x` > 1; 0 evaluates every light everywhere (same image)"),
    ("lighting.frag", 7, "IBL: environment lighting: 0 none (default; a fixed hemispherical ambient), 1 approx, 2 filtered importance sampling (fis:N), 3 brute-force Monte Carlo (mc:N, the ground truth)"),
    ("lighting.frag", 8, "IBL_SAMPLES: N of fis:N and mc:N (default 16)"),
    ("lighting.frag", 4, "SHADING: how fabric pixels are shaded: 0 the fabric model (default), 1 Gouraud (the G-buffer's emissive already holds the per-vertex lighting), 2 the Phong reflection model, 3 one Ashikhmin-Shirley lobe without the weave (the models of `weft compare`)"),
];

/// The hand-written notes of a module, if any.
pub fn module_notes(name: &str) -> Option<&'static str> {
    MODULE_NOTES
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, t)| *t)
}
