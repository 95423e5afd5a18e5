//! A scene on the GPU: geometry, vertex colours, material, fabric and thread-colour records,
//! lights, textures with their samplers, and the weave textures (the weave pass, at upload).

use glam::Mat4;

use crate::fabric::{FabricParams, GpuFabric};
use crate::scene::{ColorSpace, Scene, Texture, TextureSlot};
use crate::vk::{
    Buffer, BufferUsageFlags, Context, Format, Image, ImageDesc, ImageUsageFlags, Sampler,
    Topology, Usage, VertexLayout,
};
use crate::Error;

use super::frame::Renderer;
use super::gpu::{GpuLight, GpuMaterial};
use super::passes;
use super::plan::weave_key;

/// Floats per vertex in the G-buffer pass's vertex buffer: position, normal, tangent, uv, weave uv.
pub(crate) const VERTEX_FLOATS: usize = 16;

/// gbuffer.vert's vertex inputs: position, normal, tangent, uv, weave uv, uv1.
pub(crate) fn gbuffer_vertex_layout() -> VertexLayout {
    VertexLayout {
        stride: (VERTEX_FLOATS * 4) as u32,
        attributes: vec![
            (0, Format::R32G32B32_SFLOAT, 0),
            (1, Format::R32G32B32_SFLOAT, 12),
            (2, Format::R32G32B32A32_SFLOAT, 24),
            (3, Format::R32G32_SFLOAT, 40),
            (4, Format::R32G32_SFLOAT, 48),
            (5, Format::R32G32_SFLOAT, 56),
        ],
    }
}

/// The same vertex buffer read at position alone (location 0): the depth-only passes' input
/// (shadow.vert, depth.vert).
pub(crate) fn position_vertex_layout() -> VertexLayout {
    VertexLayout {
        stride: (VERTEX_FLOATS * 4) as u32,
        attributes: vec![(0, Format::R32G32B32_SFLOAT, 0)],
    }
}

/// One draw: a mesh range in the shared buffers.
pub(crate) struct DrawRange {
    /// Triangles, or (drawn by the G-buffer pass only, casting no shadow) lines or points.
    pub(crate) topology: Topology,
    pub(crate) first_index: u32,
    pub(crate) index_count: u32,
    pub(crate) vertex_offset: i32,
    pub(crate) material: u32,
    pub(crate) world: Mat4,
    pub(crate) double_sided: bool,
    pub(crate) cast_shadows: bool,
    pub(crate) receive_shadows: bool,
    /// The material is alphaMode MASK (the shadow pass casts it with its cut-out pipeline).
    pub(crate) alpha_mask: bool,
    /// The G-buffer cannot hold the material (`Material::needs_forward`): drawn by the
    /// transparent pass instead; `blended`: alphaMode BLEND (else opaque there).
    pub(crate) forward: bool,
    pub(crate) blended: bool,
    /// The material is fabric (the G-buffer pass draws it with its woven-model pipeline).
    pub(crate) woven: bool,
    /// The centre of the mesh's bounds (object space): the transparent pass sorts by it.
    pub(crate) centre: glam::Vec3,
    /// Index into `Scene::draws` (what `update_pose` takes the world matrix from).
    pub(crate) scene_draw: usize,
    /// Shown (KHR_node_visibility; `update_pose` takes it from the scene): a hidden draw is in
    /// no pass.
    pub(crate) visible: bool,
}

impl DrawRange {
    /// Whether the world transform mirrors the mesh (negative determinant): its front faces wind
    /// clockwise (glTF 2.0, "Instantiation").
    pub(crate) fn mirrored(&self) -> bool {
        self.world.determinant() < 0.0
    }
}

/// A scene's data on the GPU.
/// A scene's baked world light on the device (render::world_light).
pub(crate) struct WorldLightGpu {
    /// The environment it was baked under: its content hash, rotation and intensity.
    pub(crate) key: ([u8; 32], u32, u32),
    /// `vec4` per receiving vertex (rgb bounce irradiance/π, a visibility).
    pub(crate) buffer: Buffer,
    /// Per scene draw, where its vertices' entries begin.
    pub(crate) base: Vec<Option<u32>>,
}

pub struct GpuScene {
    pub(crate) vertices: Buffer,
    /// COLOR_0 of every vertex of `vertices` (linear RGBA, white where a mesh has none), or one
    /// white entry when no mesh has vertex colours (the G-buffer pass then reads none).
    pub(crate) colors: Buffer,
    /// Whether `colors` holds one entry per vertex (some mesh has COLOR_0), and how many
    /// vertices `vertices` holds (posed copies included).
    pub(crate) has_colors: bool,
    pub(crate) vertex_count: usize,
    pub(crate) indices: Buffer,
    pub(crate) materials: Buffer,
    /// One GpuFabric record per fabric material (a zeroed one when there is none).
    pub(crate) fabrics: Buffer,
    /// The same records on the CPU, and their lobes' exact albedo tables (weft::reference::lobe_albedo;
    /// made by the first frame at the approx or a fis level of environment light, binding 17 of the lighting
    /// and transparent passes).
    pub(crate) fabric_records: Vec<GpuFabric>,
    pub(crate) lobe_albedo: std::sync::OnceLock<Buffer>,
    /// The world light baked for the environment of its key, made by the first frame that
    /// plans it (render::world_light; replaced when a frame's environment differs).
    pub(crate) world_light: std::sync::Mutex<Option<std::sync::Arc<WorldLightGpu>>>,
    /// The world light's rays as traced for this scene (render::world_light::Traced), kept so
    /// that another sky (a viewer turning the environment) shades them again without tracing:
    /// at most `world_light::MAX_RAYS` hits of 8 bytes, with the BVH.
    pub(crate) world_traced: std::sync::Mutex<Option<std::sync::Arc<super::world_light::Traced>>>,
    /// The scene's part of the world light's key on disk (`world_light::scene_hash`), hashed
    /// once: every sky's key starts with it.
    pub(crate) world_scene_hash: std::sync::OnceLock<[u8; 32]>,
    /// Thread-by-thread colours (set 0 binding 5 of the G-buffer and transparent passes).
    pub(crate) thread_colours: Buffer,
    /// One weave texture per distinct weave (RGBA16F mip chains, built by the weave pass for
    /// the first frame that reads them: a frame of the default precision reads the summed-area
    /// tables instead and never needs them; the RGBA8 copies likewise), and per material the
    /// weave it uses.
    pub(crate) weaves: std::sync::OnceLock<Vec<Image>>,
    pub(crate) weaves8: std::sync::OnceLock<Vec<Image>>,
    /// The summed-area tables of the weaves (made by the first frame that asks for them).
    pub(crate) weaves_sat: std::sync::OnceLock<Vec<Image>>,
    /// The fabric parameters each weave was built from.
    pub(crate) weave_params: Vec<FabricParams>,
    pub(crate) material_weave: Vec<Option<usize>>,
    pub(crate) lights: Buffer,
    /// The light records as uploaded (no shadow maps): a frame with shadows uploads a copy with
    /// each caster's shadow index.
    pub(crate) light_records: Vec<GpuLight>,
    pub(crate) light_count: u32,
    pub(crate) material_count: u32,
    /// Per material: base colour, metallic-roughness, normal, emissive and occlusion textures
    /// (indices into `textures`, None = a default).
    pub(crate) material_textures: Vec<[Option<usize>; TextureSlot::COUNT]>,
    /// Per material and slot: the index into `samplers` of the slot's glTF sampler.
    pub(crate) material_samplers: Vec<[usize; TextureSlot::COUNT]>,
    /// The distinct samplers the materials' texture slots use (wrap modes and filters).
    pub(crate) samplers: Vec<Sampler>,
    /// Per material: alphaMode MASK.
    pub(crate) material_mask: Vec<bool>,
    pub(crate) textures: Vec<Image>,
    pub(crate) draws: Vec<DrawRange>,
    pub(crate) triangles: usize,
    /// Skinning and morph targets (None when nothing deforms; see render::deform).
    pub(crate) deform: Option<super::deform::GpuDeform>,
}

impl Renderer {
    /// Uploads a scene: geometry, materials, lights and textures (with mip chains).
    pub fn upload(&self, scene: &Scene) -> crate::Result<GpuScene> {
        let ctx = &self.ctx;
        let mut vertices = Vec::new();
        let mut indices = Vec::new();
        let mut mesh_ranges = Vec::new();
        for mesh in &scene.meshes {
            mesh_ranges.push((
                indices.len() as u32,
                mesh.indices.len() as u32,
                vertices.len() as i32,
            ));
            let fabric = scene.mesh_material(mesh).and_then(|m| m.fabric.as_ref());
            let weave_offset = fabric.map(|f| weave_uv_offset(f, mesh)).unwrap_or([0.0; 2]);
            vertices.extend(mesh.vertices.iter().map(|v| {
                let mut w = [0f32; VERTEX_FLOATS];
                w[0..3].copy_from_slice(&v.position);
                w[3..6].copy_from_slice(&v.normal);
                w[6..10].copy_from_slice(&v.tangent);
                w[10..12].copy_from_slice(&v.uv);
                w[12] = (v.uv[0] as f64 - weave_offset[0]) as f32;
                w[13] = (v.uv[1] as f64 - weave_offset[1]) as f32;
                w[14..16].copy_from_slice(&v.uv1);
                w
            }));
            indices.extend_from_slice(&mesh.indices);
        }
        let mut draws = Vec::new();
        let mut triangles = 0;
        for (scene_draw, d) in scene.draws.iter().enumerate() {
            let mesh = &scene.meshes[d.mesh];
            let (first_index, index_count, vertex_offset) = mesh_ranges[d.mesh];
            if index_count == 0 {
                continue;
            }
            let topology = match mesh.topology {
                crate::scene::Topology::Triangles => Topology::Triangles,
                crate::scene::Topology::Lines => Topology::Lines,
                crate::scene::Topology::Points => Topology::Points,
            };
            if topology == Topology::Triangles {
                triangles += index_count as usize / 3;
            }
            // What the GPU reads for the draw (the index clamped to the last material).
            let material = scene.mesh_material(mesh);
            draws.push(DrawRange {
                topology,
                first_index,
                index_count,
                vertex_offset,
                material: mesh.material as u32,
                world: d.world,
                double_sided: material.is_some_and(|m| m.double_sided),
                // Points and lines cover no area a shadow map could hold.
                cast_shadows: d.cast_shadows && topology == Topology::Triangles,
                receive_shadows: d.receive_shadows,
                alpha_mask: material.is_some_and(|m| m.alpha_cutoff.is_some() || m.blend),
                // Points and lines are the G-buffer pass's whatever their material (the loader
                // says so).
                forward: topology == Topology::Triangles
                    && material.is_some_and(|m| m.needs_forward()),
                blended: material.is_some_and(|m| m.blended()),
                woven: material.is_some_and(|m| m.fabric.is_some()),
                centre: passes::transparent::bounds_centre(
                    mesh.vertices.iter().map(|v| v.position),
                ),
                scene_draw,
                visible: d.visible,
            });
        }
        // Skinned and morphed draws get posed copies of their vertices, which the skinning pass
        // writes (render::deform).
        let deform = super::deform::upload(ctx, scene, &mut vertices, &mesh_ranges, &mut draws)?;
        let vertex_count = vertices.len();
        let colors = vertex_colors(scene, vertex_count, &mesh_ranges, &draws);
        let has_colors = scene.meshes.iter().any(|m| !m.colors.is_empty());
        let colors =
            ctx.create_buffer_with("vertex colours", BufferUsageFlags::STORAGE_BUFFER, &colors)?;
        let vertices = ctx.create_buffer_with(
            "vertices",
            BufferUsageFlags::VERTEX_BUFFER | BufferUsageFlags::STORAGE_BUFFER,
            &vertices,
        )?;
        let indices =
            ctx.create_buffer_with("indices", BufferUsageFlags::INDEX_BUFFER, &indices)?;
        // Fabric records, and one weave texture per distinct weave (materials that differ only in
        // colour or exponents share one).
        let (fabric_bytes, materials, thread_colours) = material_records(scene)?;
        let mut weave_keys: Vec<[u32; 7]> = Vec::new();
        let mut weave_params: Vec<FabricParams> = Vec::new();
        let mut material_weave = Vec::new();
        for m in &scene.materials {
            material_weave.push(m.fabric.as_ref().map(|f| {
                let key = weave_key(f);
                weave_keys
                    .iter()
                    .position(|k| *k == key)
                    .unwrap_or_else(|| {
                        weave_keys.push(key);
                        weave_params.push(f.clone());
                        weave_keys.len() - 1
                    })
            }));
        }
        let fabrics =
            ctx.create_buffer_with("fabrics", BufferUsageFlags::STORAGE_BUFFER, &fabric_bytes)?;
        let thread_colours = ctx.create_buffer_with(
            "thread colours",
            BufferUsageFlags::STORAGE_BUFFER,
            &thread_colours,
        )?;
        let material_textures = scene.materials.iter().map(|m| m.textures()).collect();
        let (material_samplers, samplers) = texture_samplers(ctx, scene)?;
        let material_mask = scene
            .materials
            .iter()
            .map(|m| m.alpha_cutoff.is_some() || m.blend)
            .collect();
        let material_count = materials.len() as u32;
        let materials =
            ctx.create_buffer_with("materials", BufferUsageFlags::STORAGE_BUFFER, &materials)?;
        let mut lights: Vec<GpuLight> = scene.lights.iter().map(GpuLight::new).collect();
        let light_count = lights.len() as u32;
        if lights.is_empty() {
            lights.push(bytemuck::Zeroable::zeroed()); // a storage buffer cannot be empty
        }
        let light_records = lights.clone();
        let lights = ctx.create_buffer_with("lights", BufferUsageFlags::STORAGE_BUFFER, &lights)?;
        let textures = scene
            .textures
            .iter()
            .map(|t| upload_texture(ctx, t))
            .collect::<crate::Result<Vec<_>>>()?;
        let mut gpu = GpuScene {
            vertices,
            colors,
            has_colors,
            vertex_count,
            indices,
            materials,
            fabric_records: bytemuck::pod_collect_to_vec(&fabric_bytes),
            fabrics,
            lobe_albedo: std::sync::OnceLock::new(),
            world_light: std::sync::Mutex::new(None),
            world_traced: std::sync::Mutex::new(None),
            world_scene_hash: std::sync::OnceLock::new(),
            thread_colours,
            weaves: std::sync::OnceLock::new(),
            weaves8: std::sync::OnceLock::new(),
            weaves_sat: std::sync::OnceLock::new(),
            weave_params,
            material_weave,
            lights,
            light_records,
            light_count,
            material_count,
            material_textures,
            material_samplers,
            samplers,
            material_mask,
            textures,
            draws,
            triangles,
            deform,
        };
        if gpu.deform.is_some() {
            self.update_pose(&mut gpu, scene)?;
        }
        Ok(gpu)
    }

    /// Rewrites the material and fabric records of an uploaded scene from `scene` (colours,
    /// exponents, roughness...: `weft view`'s live parameters), without touching geometry,
    /// textures or weave textures. Only for changes that keep every material's weave (its
    /// `weave_key`) and repeat: anything else needs [`Renderer::upload`] again.
    pub fn update_material_records(&self, scene: &Scene, gpu: &mut GpuScene) -> crate::Result<()> {
        let (fabric_bytes, materials, thread_colours) = material_records(scene)?;
        if materials.len() as u32 != gpu.material_count {
            return Err(Error::input(
                "update_material_records: the scene has a different number of materials than was uploaded",
            ));
        }
        let ctx = &self.ctx;
        // Fabric records that changed (a `weft view` edit) need their buffer and, for new
        // exponents, new albedo tables (the next frame that reads them makes them). A pose that
        // drives only glTF materials (KHR_animation_pointer, every frame of a sequence) leaves
        // them, and the tables are not made again.
        let uploaded: &[u8] = bytemuck::cast_slice(&gpu.fabric_records);
        if uploaded != fabric_bytes.as_slice() {
            gpu.fabrics =
                ctx.create_buffer_with("fabrics", BufferUsageFlags::STORAGE_BUFFER, &fabric_bytes)?;
            gpu.fabric_records = bytemuck::pod_collect_to_vec(&fabric_bytes);
            gpu.lobe_albedo = std::sync::OnceLock::new();
        }
        gpu.thread_colours = ctx.create_buffer_with(
            "thread colours",
            BufferUsageFlags::STORAGE_BUFFER,
            &thread_colours,
        )?;
        gpu.materials =
            ctx.create_buffer_with("materials", BufferUsageFlags::STORAGE_BUFFER, &materials)?;
        // The world light's bake reads the materials' colours (its rays, kept, are checked
        // against the cut-outs when next used): shaded again by the next frame that plans it.
        gpu.world_light = std::sync::Mutex::new(None);
        gpu.world_scene_hash = std::sync::OnceLock::new();
        Ok(())
    }
}

pub(crate) fn solid(name: &str, rgba: [u8; 4], color_space: ColorSpace) -> Texture {
    Texture {
        name: name.into(),
        width: 1,
        height: 1,
        color_space,
        rgba8: rgba.to_vec(),
        bc7: None,
    }
}

/// Uploads a texture: its BC7 mip chain as is where it has one and the device samples BC7
/// ([`Context::samples_bc7`]), else its RGBA8 level 0 with a mip chain built by linear blits.
pub(crate) fn upload_texture(ctx: &Context, texture: &Texture) -> crate::Result<Image> {
    if let (Some(levels), true) = (&texture.bc7, ctx.samples_bc7()) {
        return upload_bc7(ctx, texture, levels);
    }
    let format = match texture.color_space {
        ColorSpace::Srgb => Format::R8G8B8A8_SRGB,
        ColorSpace::Linear => Format::R8G8B8A8_UNORM,
    };
    let expected = texture.width as usize * texture.height as usize * 4;
    if texture.rgba8.len() != expected {
        return Err(Error::input(format!(
            "texture '{}' has {} bytes of pixels, expected {expected} for {}x{} RGBA8",
            texture.name,
            texture.rgba8.len(),
            texture.width,
            texture.height
        )));
    }
    let image = ctx.create_image(
        &ImageDesc::new_2d(texture.name.clone(), format, texture.width, texture.height)
            .usage(
                ImageUsageFlags::SAMPLED
                    | ImageUsageFlags::TRANSFER_DST
                    | ImageUsageFlags::TRANSFER_SRC,
            )
            .full_mips(),
    )?;
    let staging = ctx.create_buffer_with(
        "texture staging",
        BufferUsageFlags::TRANSFER_SRC,
        &texture.rgba8,
    )?;
    ctx.submit(|cmd| {
        cmd.transition(&image, Usage::Undefined, Usage::TransferDst, None);
        cmd.copy_buffer_to_image(&staging, &image);
        cmd.generate_mips(&image, Usage::FragmentRead);
    })?;
    Ok(image)
}

/// Uploads `levels` (a full BC7 mip chain of `texture`) level by level.
fn upload_bc7(ctx: &Context, texture: &Texture, levels: &[Vec<u8>]) -> crate::Result<Image> {
    let format = match texture.color_space {
        ColorSpace::Srgb => Format::BC7_SRGB_BLOCK,
        ColorSpace::Linear => Format::BC7_UNORM_BLOCK,
    };
    let desc = ImageDesc::new_2d(texture.name.clone(), format, texture.width, texture.height)
        .usage(ImageUsageFlags::SAMPLED | ImageUsageFlags::TRANSFER_DST)
        .full_mips();
    for (level, bytes) in levels.iter().enumerate() {
        let (w, h) = (
            (texture.width >> level).max(1),
            (texture.height >> level).max(1),
        );
        let expected = w.div_ceil(4) as usize * h.div_ceil(4) as usize * 16;
        if levels.len() != desc.mip_levels as usize || bytes.len() != expected {
            return Err(Error::input(format!(
                "texture '{}' has {} BC7 mip levels, level {level} of {} bytes; a {}x{} texture needs {} levels and {expected} bytes there",
                texture.name,
                levels.len(),
                bytes.len(),
                texture.width,
                texture.height,
                desc.mip_levels
            )));
        }
    }
    let image = ctx.create_image(&desc)?;
    ctx.fill_image_levels(&image, levels, "BC7 texture staging")?;
    Ok(image)
}

/// The vertex colour buffer: one RGBA per vertex of the uploaded vertex buffer (`vertex_count`,
/// posed copies included: a deforming draw's copy gets its mesh's colours), white where a mesh
/// has none; a single white entry when no mesh has COLOR_0 (a storage buffer cannot be empty).
fn vertex_colors(
    scene: &Scene,
    vertex_count: usize,
    mesh_ranges: &[(u32, u32, i32)],
    draws: &[DrawRange],
) -> Vec<[f32; 4]> {
    if scene.meshes.iter().all(|m| m.colors.is_empty()) {
        return vec![[1.0; 4]];
    }
    let mut colors = vec![[1.0f32; 4]; vertex_count];
    let mut copy = |mesh: &crate::scene::Mesh, at: usize| {
        if let Some(dst) = colors.get_mut(at..) {
            for (d, c) in dst
                .iter_mut()
                .zip(mesh.colors.iter().take(mesh.vertices.len()))
            {
                *d = *c;
            }
        }
    };
    for (mesh, range) in scene.meshes.iter().zip(mesh_ranges) {
        copy(mesh, range.2.max(0) as usize);
    }
    for d in draws {
        let Some(mesh) = scene
            .draws
            .get(d.scene_draw)
            .and_then(|sd| scene.meshes.get(sd.mesh))
        else {
            continue;
        };
        copy(mesh, d.vertex_offset.max(0) as usize);
    }
    colors
}

/// A scene's fabric records (80 bytes each; one zero record when there are none: a storage
/// buffer cannot be empty) and the material records, which index them (one default material when
/// the scene has none). And the thread-colour buffer (`ThreadColours` of gbuffer.frag and forward.frag): each
/// fabric's [`crate::fabric::ThreadColourTable`] record where it has colour sequences, its fabric
/// record pointing at it; one zero vec4 when none has.
#[allow(clippy::type_complexity)]
fn material_records(scene: &Scene) -> crate::Result<(Vec<u8>, Vec<GpuMaterial>, Vec<[f32; 4]>)> {
    let mut fabric_bytes: Vec<u8> = Vec::new();
    let mut fabric_index = Vec::new();
    let mut thread_colours: Vec<[f32; 4]> = vec![[0.0; 4]];
    for m in &scene.materials {
        let index = match &m.fabric {
            None => None,
            Some(f) => {
                let mut g = f.to_gpu();
                if let Some(t) = crate::fabric::ThreadColourTable::new(f)
                    .map_err(|e| Error::input(format!("material '{}': {e}", m.name)))?
                {
                    g.colours = thread_colours.len() as u32;
                    thread_colours.extend(t.record());
                }
                fabric_bytes.extend_from_slice(&g.to_bytes());
                Some(fabric_bytes.len() / 80 - 1)
            }
        };
        fabric_index.push(index);
    }
    if fabric_bytes.is_empty() {
        fabric_bytes = vec![0; 80];
    }
    let materials = if scene.materials.is_empty() {
        vec![GpuMaterial::new(&Default::default(), None)]
    } else {
        scene
            .materials
            .iter()
            .zip(&fabric_index)
            .map(|(m, f)| GpuMaterial::new(m, *f))
            .collect()
    };
    Ok((fabric_bytes, materials, thread_colours))
}

/// The whole number of weave repeats to take off a fabric mesh's UVs, per axis, computed in f64
/// so that huge coordinates keep the pattern once they are f32 again (model page, hard case 8).
fn weave_uv_offset(fabric: &FabricParams, mesh: &crate::scene::Mesh) -> [f64; 2] {
    // Whole repeats of the weave, or of its thread colours where they repeat more slowly (the
    // thread index must survive the offset).
    let mut repeat = fabric.repeat_uv();
    if fabric.has_thread_colours() {
        let cells = crate::fabric::ThreadColourTable::repeat_cells(&fabric.sanitized());
        repeat[0] *= cells[0] as f64 / fabric.pattern.cols() as f64;
        repeat[1] *= cells[1] as f64 / fabric.pattern.rows() as f64;
    }
    let mut min = [f64::INFINITY; 2];
    for v in &mesh.vertices {
        for a in 0..2 {
            if v.uv[a].is_finite() {
                min[a] = min[a].min(v.uv[a] as f64);
            }
        }
    }
    let mut offset = [0.0; 2];
    for a in 0..2 {
        if min[a].is_finite() && repeat[a] > 0.0 {
            offset[a] = (min[a] / repeat[a]).floor() * repeat[a];
        }
    }
    offset
}

/// The distinct samplers of the scene's material texture slots, and per material and slot the
/// index of its own (glTF: a texture's sampler sets its wrap modes and filters).
fn texture_samplers(
    ctx: &Context,
    scene: &Scene,
) -> crate::Result<(Vec<[usize; TextureSlot::COUNT]>, Vec<Sampler>)> {
    use crate::scene::{MipFilter, TexelFilter, Wrap};
    use crate::vk::{Address, TextureSamplerDesc};
    let address = |w: Wrap| match w {
        Wrap::Repeat => Address::Repeat,
        Wrap::ClampToEdge => Address::ClampToEdge,
        Wrap::MirroredRepeat => Address::MirroredRepeat,
    };
    let mut keys: Vec<crate::scene::TextureSampler> = Vec::new();
    let mut samplers = Vec::new();
    let mut per_material = Vec::with_capacity(scene.materials.len());
    for m in &scene.materials {
        let mut slots = [0usize; TextureSlot::COUNT];
        let textures = m.textures();
        for (slot, s) in m.samplers.iter().enumerate().take(10) {
            if textures[slot].is_none() {
                continue;
            }
            slots[slot] = match keys.iter().position(|k| k == s) {
                Some(i) => i,
                None => {
                    samplers.push(ctx.create_texture_sampler(TextureSamplerDesc {
                        address_u: address(s.wrap_s),
                        address_v: address(s.wrap_t),
                        mag_linear: s.mag == TexelFilter::Linear,
                        min_linear: s.min == TexelFilter::Linear,
                        mip_linear: match s.mip {
                            MipFilter::None => None,
                            MipFilter::Nearest => Some(false),
                            MipFilter::Linear => Some(true),
                        },
                    })?);
                    keys.push(*s);
                    keys.len() - 1
                }
            };
        }
        per_material.push(slots);
    }
    Ok((per_material, samplers))
}
