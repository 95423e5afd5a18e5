//! The frame: scene upload, then the passes the plan lists, each a function whose signature says
//! what it reads and writes, then readback.
//!
//! Each pass is its own submission bracketed by two timestamps: on lavapipe, timestamps around a
//! render pass that follows another in the same command buffer read far too short, so one pass per
//! submit is what gives honest per-pass timings (see docs/architecture.md).

use std::collections::HashMap;
use std::time::Instant;

use glam::Mat4;

use crate::fabric::{weave_level0_size, weave_level_size, weave_mip_count, FabricParams};
use crate::scene::{ColorSpace, Scene, Texture, TextureSlot};
use crate::vk::{
    shaders, Attachment, Binding, BindingKind, Buffer, BufferLocation, BufferUsageFlags, Cmd,
    ComputeDesc, Context, Filter, Format, GraphicsDesc, Image, ImageDesc, ImageUsageFlags,
    Pipeline, Resource, Sampler, SetLayout, Stages, Topology, Usage, VertexLayout,
};
use crate::Error;

use super::gpu::{DrawPush, FrameData, GpuLight, GpuMaterial, GpuShadow, ShadowPush, TonemapPush};
use super::plan::{weave_key, Pass, Plan};
use super::{passes, RenderOptions};

pub const ALBEDO_FORMAT: Format = Format::R8G8B8A8_SRGB;
/// Normal + tangent, octahedral, explicitly rounded 16-bit integers (frame.glsl's frame_encode).
pub const FRAME_FORMAT: Format = Format::R16G16B16A16_UINT;
pub const SURFACE_FORMAT: Format = Format::R16G16B16A16_SFLOAT;
pub const FABRIC_FORMAT: Format = Format::R16G16B16A16_SFLOAT;
pub const EMISSIVE_FORMAT: Format = Format::R16G16B16A16_SFLOAT;
/// The dielectric specular layer (KHR_materials_specular): rgb F0, a: specular weight.
pub const SPECULAR_FORMAT: Format = Format::R16G16B16A16_SFLOAT;
pub const DEPTH_FORMAT: Format = Format::D32_SFLOAT;
pub const HDR_FORMAT: Format = Format::R16G16B16A16_SFLOAT;
pub const LDR_FORMAT: Format = Format::R8G8B8A8_SRGB;
pub const WEAVE_FORMAT: Format = Format::R16G16B16A16_SFLOAT;
/// The weave's summed-area table (`--weave-precision sat`): f32, fetched (never filtered).
pub const WEAVE_SAT_FORMAT: Format = Format::R32G32B32A32_SFLOAT;
pub const WEAVE_FORMAT_8: Format = Format::R8G8B8A8_UNORM;
pub const SHADOW_FORMAT: Format = Format::D32_SFLOAT;

/// Floats per vertex in the G-buffer pass's vertex buffer: position, normal, tangent, uv, weave uv.
const VERTEX_FLOATS: usize = 16;

/// Wall-clock and GPU time of one pass.
#[derive(Clone, Debug)]
pub struct PassTiming {
    pub name: &'static str,
    /// GPU time between the pass's two timestamps, when the device has timestamps.
    pub gpu_ms: Option<f64>,
    /// CPU time from recording to the end of the wait for the GPU.
    pub wall_ms: f64,
}

/// What the frame actually did.
#[derive(Clone, Debug, Default)]
pub struct FrameStats {
    pub passes: Vec<&'static str>,
    pub draws: usize,
    pub triangles: usize,
    pub pipelines: Vec<String>,
    /// Weave textures of the scene (built by the weave pass at upload) and the pass's dispatches.
    pub weave_textures: usize,
    pub weave_dispatches: u32,
    /// Shadow maps rendered, and the caster draws into them.
    pub shadow_maps: usize,
    pub shadow_draws: usize,
    /// alphaMode BLEND draws the transparent pass drew.
    pub blend_draws: usize,
}

/// A rendered frame, read back.
pub struct Frame {
    pub width: u32,
    pub height: u32,
    /// Display-referred RGBA8, sRGB-encoded, rows top to bottom.
    pub ldr: Vec<u8>,
    /// Linear HDR radiance (before exposure), RGBA f32, rows top to bottom.
    pub hdr: Vec<f32>,
    pub timings: Vec<PassTiming>,
    pub stats: FrameStats,
    pub plan: Plan,
}

/// The G-buffer and output targets of one resolution.
pub(crate) struct Targets {
    pub(crate) albedo: Image,
    pub(crate) frame: Image,
    pub(crate) surface: Image,
    pub(crate) fabric: Image,
    pub(crate) emissive: Image,
    pub(crate) specular: Image,
    pub(crate) depth: Image,
    pub(crate) hdr: Image,
    pub(crate) ldr: Image,
    /// The lit opaque image with box-filtered mips, for transmissive surfaces (made by the first
    /// frame that has one).
    pub(crate) backdrop: Option<Image>,
    /// The tone-mapped image before edge anti-aliasing (made by the first frame that plans the
    /// anti-aliasing pass).
    pub(crate) tonemapped: Option<Image>,
}

impl Targets {
    fn new(ctx: &Context, width: u32, height: u32) -> crate::Result<Targets> {
        let color = ImageUsageFlags::COLOR_ATTACHMENT | ImageUsageFlags::SAMPLED;
        let read = ImageUsageFlags::TRANSFER_SRC;
        let t = |name: &str, format: Format, usage: ImageUsageFlags| {
            ctx.create_image(&ImageDesc::new_2d(name, format, width, height).usage(usage))
        };
        Ok(Targets {
            albedo: t("gbuffer albedo", ALBEDO_FORMAT, color | read)?,
            frame: t("gbuffer normal+tangent", FRAME_FORMAT, color | read)?,
            surface: t("gbuffer surface", SURFACE_FORMAT, color | read)?,
            fabric: t("gbuffer fabric coverage", FABRIC_FORMAT, color | read)?,
            emissive: t("gbuffer emissive", EMISSIVE_FORMAT, color | read)?,
            specular: t("gbuffer specular", SPECULAR_FORMAT, color | read)?,
            depth: t(
                "gbuffer depth",
                DEPTH_FORMAT,
                ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT | ImageUsageFlags::SAMPLED | read,
            )?,
            hdr: t("hdr", HDR_FORMAT, color | read)?,
            ldr: t("ldr", LDR_FORMAT, ImageUsageFlags::COLOR_ATTACHMENT | read)?,
            backdrop: None,
            tonemapped: None,
        })
    }

    pub(crate) fn gbuffer_colors(&self) -> [&Image; 6] {
        [
            &self.albedo,
            &self.frame,
            &self.surface,
            &self.fabric,
            &self.emissive,
            &self.specular,
        ]
    }
}

/// Bytes a pixel of the render targets takes on the device (six G-buffer targets, depth, HDR,
/// LDR: 60).
pub const TARGET_BYTES_PER_PIXEL: u64 = 4 + 8 + 8 + 8 + 8 + 8 + 4 + 8 + 4;

/// Bytes a pixel of the readback takes in host memory: the LDR buffer and its copy (4 + 4), and
/// with `read_hdr` the half-float buffer and the f32 image (8 + 16).
pub fn readback_bytes_per_pixel(read_hdr: bool) -> u64 {
    8 + if read_hdr { 24 } else { 0 }
}

/// The memory the host can still give (MemAvailable of /proc/meminfo), where known.
pub fn host_available_bytes() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kib.checked_mul(1024)
}

/// Refuses, before any target is created, a frame size the device cannot hold: a side beyond
/// maxImageDimension2D, render targets beyond the device's largest device-local heap, or, on a
/// CPU device, targets and readback beyond 90 % of the memory the host has available. A CPU device's
/// "device memory" is system memory: its heap size is nominal (lavapipe reports 2 GiB and
/// allocates beyond it), and an allocation too large is met by the kernel's OOM killer rather
/// than an error, so there the host's available memory is the bound.
pub fn check_target_memory(
    info: &crate::vk::DeviceInfo,
    host_available: Option<u64>,
    width: u32,
    height: u32,
    read_hdr: bool,
) -> crate::Result<()> {
    let max = info.max_image_dimension_2d;
    if width > max || height > max {
        return Err(Error::device(format!(
            "--size {width}x{height} is larger than the device '{}' supports ({max} pixels a side): choose a smaller --size",
            info.name
        )));
    }
    let gib = |b: u64| b as f64 / f64::from(1u32 << 30);
    let pixels = u64::from(width) * u64::from(height);
    let targets = pixels * TARGET_BYTES_PER_PIXEL;
    let heap = info.device_local_heap_bytes;
    if !info.is_cpu() && heap > 0 && targets > heap {
        return Err(Error::device(format!(
            "--size {width}x{height} needs {:.1} GiB of device memory for its render targets ({TARGET_BYTES_PER_PIXEL} bytes a pixel); the device '{}' has {:.1} GiB: choose a smaller --size",
            gib(targets),
            info.name,
            gib(heap)
        )));
    }
    if info.is_cpu() {
        if let Some(available) = host_available {
            let total = targets + pixels * readback_bytes_per_pixel(read_hdr);
            // A tenth kept back for what the estimate leaves out: the scene, its textures and
            // buffers, pipelines, the allocator's slack, the rest of the process.
            if total > available / 10 * 9 {
                return Err(Error::device(format!(
                    "--size {width}x{height} needs {:.1} GiB of memory for its render targets and readback on the CPU device '{}'; the system has {:.1} GiB available (weft plans for at most 90 % of it): choose a smaller --size, or close other programs",
                    gib(total),
                    info.name,
                    gib(available)
                )));
            }
        }
    }
    Ok(())
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
    /// The centre of the mesh's bounds (object space): the transparent pass sorts by it.
    pub(crate) centre: glam::Vec3,
    /// Index into `Scene::draws` (what `update_pose` takes the world matrix from).
    pub(crate) scene_draw: usize,
}

/// A scene's data on the GPU.
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
    /// Thread-by-thread colours (set 0 binding 5 of the G-buffer and transparent passes).
    pub(crate) thread_colours: Buffer,
    /// One weave texture per distinct weave (RGBA16F; the RGBA8 copies are made by the first
    /// frame that asks for that precision), and per material the weave it uses.
    pub(crate) weaves: Vec<Image>,
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

pub struct Renderer {
    pub(crate) ctx: Context,
    frame_layout: SetLayout,
    material_layout: SetLayout,
    forward_material_layout: SetLayout,
    lighting_layout: SetLayout,
    tonemap_layout: SetLayout,
    weave_layout: SetLayout,
    weave_pipeline: Pipeline,
    /// Pipeline variants by their specialization constants (Filament-style: one per feature set
    /// a frame asks for, made on first use).
    gbuffer_variants: HashMap<Vec<(u32, u32)>, Pipeline>,
    /// The G-buffer pipeline for line and point lists (scenes with such primitives only).
    gbuffer_primitive_variants: HashMap<(Vec<(u32, u32)>, Topology), Pipeline>,
    lighting_variants: HashMap<Vec<(u32, u32)>, Pipeline>,
    /// The transparent pass's pipelines (gbuffer.vert + forward.frag) and their set 0 layout
    /// (gbuffer.vert's bindings, then lighting.frag's shadow and environment bindings).
    /// By key and blend mode (true: BLEND, blended without depth writes; false: transmissive
    /// draws, opaque, writing depth).
    forward_variants: HashMap<(Vec<(u32, u32)>, bool), Pipeline>,
    forward_layout: SetLayout,
    tonemap_pipeline: Pipeline,
    shadow_pipeline: Pipeline,
    /// The shadow pass's cut-out pipeline for alphaMode MASK casters (shadow_mask.vert/.frag), by
    /// VERTEX_COLORS, made when a frame first needs it; its two set layouts (materials and
    /// vertex colours; the base colour texture).
    shadow_mask_variants: HashMap<u32, Pipeline>,
    shadow_mask_layout: SetLayout,
    shadow_mask_texture_layout: SetLayout,
    linear: Sampler,
    nearest: Sampler,
    shadow_sampler: Sampler,
    white: Image,
    flat_normal: Image,
    /// A 1 x 1 shadow atlas at depth 0 (everything lit), bound when no shadow map is rendered.
    no_shadows: Image,
    /// The shadow atlas of the last frame that had shadows (kept while the size stays).
    shadow_atlas: Option<Image>,
    targets: Option<Targets>,
    /// Environment preprocessing and its fixed resources.
    env: super::environment::EnvPasses,
    /// Preprocessed environments, newest last (a few are kept, found by content hash).
    env_cache: Vec<super::environment::GpuEnvironment>,
    /// The skinning pass (render::deform), made on the first scene that deforms.
    pub(crate) skin_pass: std::sync::OnceLock<super::deform::SkinPass>,
    /// The anti-aliasing pass's pipeline, made by the first frame that plans the pass.
    antialias_pipeline: std::sync::OnceLock<Pipeline>,
    /// Bilinear, clamped: the anti-aliasing pass's reads between texels.
    linear_clamp: Sampler,
}

/// A pipeline variant's specialization constants (id, value): its key among the variants.
type VariantKey = Vec<(u32, u32)>;

/// Preprocessed environments a renderer keeps.
const ENV_CACHE: usize = 2;

/// gbuffer.vert's vertex inputs: position, normal, tangent, uv, weave uv, uv1.
fn gbuffer_vertex_layout() -> VertexLayout {
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

fn sampled(binding: u32, stages: Stages) -> Binding {
    Binding {
        binding,
        kind: BindingKind::SampledImage,
        stages,
    }
}

impl Renderer {
    pub fn new(ctx: Context) -> crate::Result<Renderer> {
        // Frame, materials, fabrics, and lights (the vertex stage reads the last three only when
        // it lights vertices for Gouraud shading), and the vertex colours.
        let frame_layout = ctx.create_set_layout(&[
            Binding {
                binding: 0,
                kind: BindingKind::UniformBuffer,
                stages: Stages::GRAPHICS,
            },
            Binding {
                binding: 1,
                kind: BindingKind::StorageBuffer,
                stages: Stages::GRAPHICS,
            },
            Binding {
                binding: 2,
                kind: BindingKind::StorageBuffer,
                stages: Stages::GRAPHICS,
            },
            Binding {
                binding: 3,
                kind: BindingKind::StorageBuffer,
                stages: Stages::VERTEX,
            },
            // COLOR_0 per vertex (read only when the plan compiles vertex colours in).
            Binding {
                binding: 4,
                kind: BindingKind::StorageBuffer,
                stages: Stages::VERTEX,
            },
            // The fabrics' thread-by-thread colours.
            Binding {
                binding: 5,
                kind: BindingKind::StorageBuffer,
                stages: Stages::FRAGMENT,
            },
        ])?;
        // A material's textures (set 1): its slots in gbuffer.frag's bindings 0-10 (the weave
        // texture at 4); forward.frag adds transmission's, thickness's, the clearcoat's three,
        // diffuse transmission's two and iridescence's two at 11-19.
        let material_layout = ctx.create_set_layout(
            &(0..11)
                .map(|b| sampled(b, Stages::FRAGMENT))
                .collect::<Vec<_>>(),
        )?;
        let forward_material_layout = ctx.create_set_layout(
            &(0..TextureSlot::COUNT as u32 + 1)
                .map(|b| sampled(b, Stages::FRAGMENT))
                .collect::<Vec<_>>(),
        )?;
        let mut lighting_bindings = vec![
            Binding {
                binding: 0,
                kind: BindingKind::UniformBuffer,
                stages: Stages::FRAGMENT,
            },
            Binding {
                binding: 1,
                kind: BindingKind::StorageBuffer,
                stages: Stages::FRAGMENT,
            },
            Binding {
                binding: 2,
                kind: BindingKind::StorageBuffer,
                stages: Stages::FRAGMENT,
            },
        ];
        lighting_bindings.extend((3..9).map(|b| sampled(b, Stages::FRAGMENT)));
        lighting_bindings.push(Binding {
            binding: 9,
            kind: BindingKind::StorageBuffer,
            stages: Stages::FRAGMENT,
        });
        lighting_bindings.push(sampled(10, Stages::FRAGMENT));
        lighting_bindings.push(Binding {
            binding: 11,
            kind: BindingKind::StorageBuffer,
            stages: Stages::FRAGMENT,
        });
        lighting_bindings.push(Binding {
            binding: 12,
            kind: BindingKind::StorageBuffer,
            stages: Stages::FRAGMENT,
        });
        lighting_bindings.extend((13..17).map(|b| sampled(b, Stages::FRAGMENT)));
        let lighting_layout = ctx.create_set_layout(&lighting_bindings)?;
        let tonemap_layout = ctx.create_set_layout(&[sampled(0, Stages::FRAGMENT)])?;
        let storage = |binding: u32, stages: Stages| Binding {
            binding,
            kind: BindingKind::StorageBuffer,
            stages,
        };
        let forward_layout = ctx.create_set_layout(&[
            Binding {
                binding: 0,
                kind: BindingKind::UniformBuffer,
                stages: Stages::GRAPHICS,
            },
            storage(1, Stages::GRAPHICS),
            storage(2, Stages::GRAPHICS),
            storage(3, Stages::GRAPHICS),
            storage(4, Stages::VERTEX),
            storage(5, Stages::FRAGMENT),
            sampled(10, Stages::FRAGMENT),
            storage(11, Stages::FRAGMENT),
            storage(12, Stages::FRAGMENT),
            sampled(13, Stages::FRAGMENT),
            sampled(14, Stages::FRAGMENT),
            sampled(15, Stages::FRAGMENT),
            sampled(16, Stages::FRAGMENT),
        ])?;
        let shadow_mask_layout = ctx.create_set_layout(&[
            Binding {
                binding: 0,
                kind: BindingKind::StorageBuffer,
                stages: Stages::FRAGMENT,
            },
            Binding {
                binding: 1,
                kind: BindingKind::StorageBuffer,
                stages: Stages::VERTEX,
            },
        ])?;
        let shadow_mask_texture_layout = ctx.create_set_layout(&[sampled(0, Stages::FRAGMENT)])?;
        let weave_layout = ctx.create_set_layout(&[Binding {
            binding: 0,
            kind: BindingKind::StorageImage,
            stages: Stages::COMPUTE,
        }])?;
        // The environment's pipelines and DFG table on a thread of their own while the others
        // compile here (drivers compile pipelines on the CPU).
        let (env, rest) = std::thread::scope(|scope| {
            let env = scope.spawn(|| super::environment::EnvPasses::new(&ctx));
            let rest = (|| -> crate::Result<_> {
                let weave_pipeline = ctx.create_compute_pipeline(&ComputeDesc {
                    name: "weave",
                    shader: &shaders::WEAVE_COMP,
                    set_layouts: &[&weave_layout],
                    push_constant_size: std::mem::size_of::<crate::fabric::WeavePush>() as u32,
                    constants: &[],
                })?;

                let tonemap_pipeline = ctx.create_graphics_pipeline(&GraphicsDesc {
                    name: "tonemap",
                    vertex: &shaders::FULLSCREEN_VERT,
                    fragment: &shaders::TONEMAP_FRAG,
                    vertex_layout: None,
                    color_formats: &[LDR_FORMAT],
                    depth_format: None,
                    set_layouts: &[&tonemap_layout],
                    push_constant_size: std::mem::size_of::<TonemapPush>() as u32,
                    push_stages: Stages::FRAGMENT,
                    constants: &[],
                    blend: false,
                    topology: Topology::Triangles,
                })?;
                let shadow_pipeline = ctx.create_graphics_pipeline(&GraphicsDesc {
                    name: "shadow",
                    vertex: &shaders::SHADOW_VERT,
                    fragment: &shaders::SHADOW_FRAG,
                    vertex_layout: Some(VertexLayout {
                        stride: (VERTEX_FLOATS * 4) as u32,
                        attributes: vec![(0, Format::R32G32B32_SFLOAT, 0)],
                    }),
                    color_formats: &[],
                    depth_format: Some(SHADOW_FORMAT),
                    set_layouts: &[],
                    push_constant_size: std::mem::size_of::<ShadowPush>() as u32,
                    push_stages: Stages::VERTEX,
                    constants: &[],
                    blend: false,
                    topology: Topology::Triangles,
                })?;
                let shadow_sampler = ctx.create_sampler(Filter::ShadowCompare)?;
                let no_shadows =
                    ctx.create_image(&ImageDesc::new_2d("no shadows", SHADOW_FORMAT, 1, 1).usage(
                        ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT | ImageUsageFlags::SAMPLED,
                    ))?;
                ctx.submit(|cmd| {
                    cmd.transition(&no_shadows, Usage::Undefined, Usage::DepthAttachment, None);
                    cmd.begin_rendering(
                        &[],
                        Some(Attachment {
                            image: &no_shadows,
                            clear: Some([0.0; 4]),
                        }),
                    );
                    cmd.end_rendering();
                    cmd.transition(
                        &no_shadows,
                        Usage::DepthAttachment,
                        Usage::FragmentRead,
                        None,
                    );
                })?;
                let linear = ctx.create_sampler(Filter::LinearRepeat)?;
                let nearest = ctx.create_sampler(Filter::NearestClamp)?;
                let white = upload_texture(
                    &ctx,
                    &solid("default white", [255, 255, 255, 255], ColorSpace::Srgb),
                )?;
                let flat_normal = upload_texture(
                    &ctx,
                    &solid("default normal", [128, 128, 255, 255], ColorSpace::Linear),
                )?;
                Ok((
                    weave_pipeline,
                    tonemap_pipeline,
                    shadow_pipeline,
                    shadow_sampler,
                    no_shadows,
                    linear,
                    nearest,
                    white,
                    flat_normal,
                ))
            })();
            (
                env.join()
                    .expect("the environment set-up thread does not panic"),
                rest,
            )
        });
        let env = env?;
        let (
            weave_pipeline,
            tonemap_pipeline,
            shadow_pipeline,
            shadow_sampler,
            no_shadows,
            linear,
            nearest,
            white,
            flat_normal,
        ) = rest?;
        let ctx_linear_clamp = ctx.create_sampler(Filter::LinearClamp)?;
        Ok(Renderer {
            env,
            env_cache: Vec::new(),
            ctx,
            frame_layout,
            material_layout,
            forward_material_layout,
            lighting_layout,
            tonemap_layout,
            weave_layout,
            weave_pipeline,
            gbuffer_variants: HashMap::new(),
            gbuffer_primitive_variants: HashMap::new(),
            lighting_variants: HashMap::new(),
            forward_variants: HashMap::new(),
            forward_layout,
            tonemap_pipeline,
            shadow_pipeline,
            shadow_mask_variants: HashMap::new(),
            shadow_mask_layout,
            shadow_mask_texture_layout,
            linear,
            nearest,
            shadow_sampler,
            white,
            flat_normal,
            no_shadows,
            shadow_atlas: None,
            targets: None,
            skin_pass: std::sync::OnceLock::new(),
            antialias_pipeline: std::sync::OnceLock::new(),
            linear_clamp: ctx_linear_clamp,
        })
    }

    /// The anti-aliasing pass's pipeline, made once (by the first frame that plans the pass).
    fn make_antialias_pipeline(&self) -> crate::Result<()> {
        if self.antialias_pipeline.get().is_none() {
            let _ = self
                .antialias_pipeline
                .set(self.ctx.create_graphics_pipeline(&GraphicsDesc {
                    name: "antialias[fxaa]",
                    vertex: &shaders::FULLSCREEN_VERT,
                    fragment: &shaders::FXAA_FRAG,
                    vertex_layout: None,
                    color_formats: &[LDR_FORMAT],
                    depth_format: None,
                    set_layouts: &[&self.tonemap_layout],
                    push_constant_size: 0,
                    push_stages: Stages::FRAGMENT,
                    constants: &[],
                    blend: false,
                    topology: Topology::Triangles,
                })?);
        }
        Ok(())
    }

    pub fn context(&self) -> &Context {
        &self.ctx
    }

    /// Every pipeline the renderer has made so far (the default variants at least), with its
    /// shaders, set layouts, push-constant size and specialization constants.
    pub fn pipelines(&mut self) -> crate::Result<Vec<&Pipeline>> {
        let options = RenderOptions::default();
        self.variants(&options, &Plan::new(&Scene::default(), &options))?;
        // The transparent pass's default variant: a scene with one blended draw.
        let blended = Scene {
            meshes: vec![crate::scene::Mesh {
                name: "blended".into(),
                vertices: Vec::new(),
                indices: Vec::new(),
                material: 0,
                colors: Vec::new(),
                topology: crate::scene::Topology::Triangles,
            }],
            draws: vec![crate::scene::Draw::new(0, glam::Mat4::IDENTITY)],
            materials: vec![crate::scene::Material {
                blend: true,
                ..Default::default()
            }],
            ..Default::default()
        };
        self.variants(&options, &Plan::new(&blended, &options))?;
        if self.skin_pass.get().is_none() {
            let _ = self.skin_pass.set(super::deform::SkinPass::new(&self.ctx)?);
        }
        self.make_antialias_pipeline()?;
        self.shadow_mask_pipeline(false)?;
        let mut all = vec![
            &self.weave_pipeline,
            &self.tonemap_pipeline,
            &self.shadow_pipeline,
        ];
        all.extend(self.env.pipelines());
        all.extend(self.shadow_mask_variants.values());
        all.extend(self.gbuffer_variants.values());
        all.extend(self.gbuffer_primitive_variants.values());
        all.extend(self.lighting_variants.values());
        all.extend(self.forward_variants.values());
        all.extend(self.skin_pass.get().map(|s| s.pipeline()));
        all.extend(self.antialias_pipeline.get());
        Ok(all)
    }

    /// The shadow pass's cut-out pipeline for alphaMode MASK casters, made on first use.
    fn shadow_mask_pipeline(&mut self, vertex_colors: bool) -> crate::Result<u32> {
        let key = vertex_colors as u32;
        if !self.shadow_mask_variants.contains_key(&key) {
            let pipeline = self.ctx.create_graphics_pipeline(&GraphicsDesc {
                name: &format!("shadow_mask[vertex_colors={key}]"),
                vertex: &shaders::SHADOW_MASK_VERT,
                fragment: &shaders::SHADOW_MASK_FRAG,
                vertex_layout: Some(VertexLayout {
                    stride: (VERTEX_FLOATS * 4) as u32,
                    attributes: vec![
                        (0, Format::R32G32B32_SFLOAT, 0),
                        (1, Format::R32G32_SFLOAT, 40),
                        (2, Format::R32G32_SFLOAT, 56),
                    ],
                }),
                color_formats: &[],
                depth_format: Some(SHADOW_FORMAT),
                set_layouts: &[&self.shadow_mask_layout, &self.shadow_mask_texture_layout],
                push_constant_size: std::mem::size_of::<super::gpu::ShadowMaskPush>() as u32,
                push_stages: Stages::GRAPHICS,
                constants: &[(0, key)],
                blend: false,
                topology: Topology::Triangles,
            })?;
            self.shadow_mask_variants.insert(key, pipeline);
        }
        Ok(key)
    }

    /// The G-buffer and lighting pipeline variants `options` needs, made if missing; returns their
    /// keys (specialization constants).
    fn variants(
        &mut self,
        options: &RenderOptions,
        plan: &Plan,
    ) -> crate::Result<(VariantKey, VariantKey)> {
        let (g, l, _, _) = self.prepare(options, plan, None)?;
        Ok((g, l))
    }

    /// The G-buffer and lighting pipeline variants `options` needs, and the environment `env`
    /// preprocessed if it is not cached: what is missing is made concurrently (the lighting
    /// pipeline on a thread of its own, the G-buffer pipeline and then the environment on this
    /// one), since a driver compiles pipelines on the CPU and lavapipe runs the compute passes
    /// there too. Returns the variants' keys and the environment's index in the cache.
    fn prepare(
        &mut self,
        options: &RenderOptions,
        plan: &Plan,
        env: Option<(&crate::env::Environment, &mut Vec<PassTiming>)>,
    ) -> crate::Result<(VariantKey, VariantKey, Option<VariantKey>, Option<usize>)> {
        let source = match options.weave_precision {
            super::WeavePrecision::Analytic => 1,
            // The summed-area table, filtered by the sampler where the device can filter RGBA32F
            // (2), else fetched (3).
            super::WeavePrecision::Sat
                if self.ctx.info().rgba32f_linear && !options.force.sat_fetch =>
            {
                2
            }
            super::WeavePrecision::Sat => 3,
            _ => 0,
        };
        let light_types = if options.force.light_types {
            7
        } else {
            plan.light_types_mask()
        };
        let shading = options.shading as u32;
        // Gouraud lights vertices: only then does the G-buffer pass depend on the light types.
        let gbuffer_key = vec![
            (0, options.accuracy.code()),
            (1, source),
            (2, shading),
            (
                3,
                if options.shading == super::Shading::Gouraud {
                    light_types
                } else {
                    7
                },
            ),
            (4, options.footprint.pieces()),
            (5, plan.vertex_colors as u32),
            (6, plan.alpha_mask as u32),
            (7, plan.features.thread_colours as u32),
        ];
        let lighting_key = vec![
            (0, options.accuracy.code()),
            (1, options.accuracy.samples()),
            (2, options.fabric_as_pbr as u32),
            (3, light_types),
            (4, shading),
            (5, plan.shadow_sampling as u32),
            (6, plan.range_culling as u32),
            (7, plan.ibl_code(options)),
            (
                8,
                options
                    .environment
                    .as_ref()
                    .map(|e| e.level.samples())
                    .unwrap_or(1),
            ),
            (9, plan.unlit as u32),
        ];
        // The transparent pass's pipeline: gbuffer.frag's constants under their ids (the vertex
        // stage reads 2, 3 and 5, with LIGHT_TYPES the scene's), lighting.frag's others + 10.
        let forward_key = plan.runs(Pass::Transparent).then(|| {
            let mut key: Vec<(u32, u32)> = gbuffer_key[..6].to_vec();
            key[3] = (3, light_types);
            key.extend(
                lighting_key
                    .iter()
                    .filter(|(id, _)| ![0, 3, 4].contains(id))
                    .map(|&(id, value)| (id + 10, value)),
            );
            key.push((20, (plan.transmission_draws > 0) as u32));
            key.push((21, (plan.coat_draws > 0) as u32));
            key.push((22, (plan.diffuse_transmission_draws > 0) as u32));
            key.push((23, (plan.iridescence_draws > 0) as u32));
            key.push((24, (plan.dispersion_draws > 0) as u32));
            key.push((25, plan.features.thread_colours as u32));
            key
        });
        // Two blend modes: opaque forward draws (transmissive, not BLEND) replace and write depth,
        // so they hide each other; BLEND draws blend and only test it.
        let forward_modes: Vec<bool> = [
            (plan.forward_opaque_draws > 0, false),
            (plan.blend_draws > 0, true),
        ]
        .into_iter()
        .filter(|(needed, _)| *needed)
        .map(|(_, blend)| blend)
        .collect();
        let need_forward: Vec<bool> = match &forward_key {
            Some(k) => forward_modes
                .iter()
                .copied()
                .filter(|&b| !self.forward_variants.contains_key(&(k.clone(), b)))
                .collect(),
            None => Vec::new(),
        };
        let need_gbuffer = !self.gbuffer_variants.contains_key(&gbuffer_key);
        let need_primitives: Vec<Topology> = [
            (plan.line_draws > 0, Topology::Lines),
            (plan.point_draws > 0, Topology::Points),
        ]
        .into_iter()
        .filter(|&(needed, t)| {
            needed
                && !self
                    .gbuffer_primitive_variants
                    .contains_key(&(gbuffer_key.clone(), t))
        })
        .map(|(_, t)| t)
        .collect();
        let need_lighting = !self.lighting_variants.contains_key(&lighting_key);
        let (env, timings) = match env {
            Some((e, t)) => (Some(e), Some(t)),
            None => (None, None),
        };
        let cached_env = env.and_then(|e| self.env_cache.iter().position(|g| g.hash == e.hash()));
        let need_env = env.filter(|_| cached_env.is_none());
        let make_gbuffer = |topology: Topology| -> crate::Result<Pipeline> {
            let vertex_layout = gbuffer_vertex_layout();
            self.ctx.create_graphics_pipeline(&GraphicsDesc {
                name: &format!(
                    "gbuffer[{}accuracy={}, weave={source}, shading={shading}, light_types={}, footprint={}, vertex_colors={}, alpha_mask={}, thread_colours={}]",
                    match topology {
                        Topology::Triangles => "",
                        Topology::Lines => "lines, ",
                        Topology::Points => "points, ",
                    },
                    options.accuracy.code(),
                    gbuffer_key[3].1,
                    gbuffer_key[4].1,
                    gbuffer_key[5].1,
                    gbuffer_key[6].1,
                    gbuffer_key[7].1
                ),
                vertex: &shaders::GBUFFER_VERT,
                fragment: &shaders::GBUFFER_FRAG,
                vertex_layout: Some(vertex_layout),
                color_formats: &[
                    ALBEDO_FORMAT,
                    FRAME_FORMAT,
                    SURFACE_FORMAT,
                    FABRIC_FORMAT,
                    EMISSIVE_FORMAT,
                    SPECULAR_FORMAT,
                ],
                depth_format: Some(DEPTH_FORMAT),
                set_layouts: &[&self.frame_layout, &self.material_layout],
                push_constant_size: std::mem::size_of::<DrawPush>() as u32,
                push_stages: Stages::GRAPHICS,
                constants: &gbuffer_key,
                blend: false,
                topology,
            })
        };
        let make_lighting = || -> crate::Result<Pipeline> {
            self.ctx.create_graphics_pipeline(&GraphicsDesc {
                name: &format!(
                    "lighting[accuracy={}, samples={}, fabric_as_pbr={}, light_types={light_types}, shading={shading}, shadows={}, range_culling={}, ibl={}, ibl_samples={}, unlit={}]",
                    options.accuracy.code(),
                    options.accuracy.samples(),
                    options.fabric_as_pbr as u32,
                    plan.shadow_sampling as u32,
                    plan.range_culling as u32,
                    lighting_key[7].1,
                    lighting_key[8].1,
                    lighting_key[9].1
                ),
                vertex: &shaders::FULLSCREEN_VERT,
                fragment: &shaders::LIGHTING_FRAG,
                vertex_layout: None,
                color_formats: &[HDR_FORMAT],
                depth_format: None,
                set_layouts: &[&self.lighting_layout],
                push_constant_size: 0,
                push_stages: Stages::FRAGMENT,
                constants: &lighting_key,
                blend: false,
                topology: Topology::Triangles,
            })
        };
        let make_forward = |blend: bool| -> crate::Result<Pipeline> {
            let key = forward_key.as_deref().unwrap_or_default();
            self.ctx.create_graphics_pipeline(&GraphicsDesc {
                name: &format!(
                    "forward[{}{}]",
                    if blend { "blend, " } else { "opaque, " },
                    key.iter()
                        .map(|(id, v)| format!("{id}={v}"))
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
                vertex: &shaders::GBUFFER_VERT,
                fragment: &shaders::FORWARD_FRAG,
                vertex_layout: Some(gbuffer_vertex_layout()),
                color_formats: &[HDR_FORMAT],
                depth_format: Some(DEPTH_FORMAT),
                set_layouts: &[&self.forward_layout, &self.forward_material_layout],
                push_constant_size: std::mem::size_of::<DrawPush>() as u32,
                push_stages: Stages::GRAPHICS,
                constants: key,
                blend,
                topology: Topology::Triangles,
            })
        };
        let (gbuffer, lighting, forward, built_env, primitives) = std::thread::scope(|scope| {
            let lighting = need_lighting.then(|| scope.spawn(make_lighting));
            let forward = (!need_forward.is_empty()).then(|| {
                scope.spawn(|| {
                    need_forward
                        .iter()
                        .map(|&b| make_forward(b).map(|p| (b, p)))
                        .collect::<crate::Result<Vec<_>>>()
                })
            });
            let gbuffer = need_gbuffer
                .then(|| make_gbuffer(Topology::Triangles))
                .transpose();
            // Points and lines (1 pixel wide): pipelines of their own topology, only for a
            // scene that has them.
            let primitives = need_primitives
                .iter()
                .map(|&t| make_gbuffer(t).map(|p| (t, p)))
                .collect::<crate::Result<Vec<_>>>();
            let built_env = need_env.map(|e| self.env.build(&self.ctx, e)).transpose();
            let lighting = lighting
                .map(|h| {
                    h.join()
                        .expect("the lighting pipeline's thread does not panic")
                })
                .transpose();
            let forward = forward
                .map(|h| {
                    h.join()
                        .expect("the forward pipeline's thread does not panic")
                })
                .transpose();
            (gbuffer, lighting, forward, built_env, primitives)
        });
        for (t, p) in primitives? {
            self.gbuffer_primitive_variants
                .insert((gbuffer_key.clone(), t), p);
        }
        if let (Some(made), Some(k)) = (forward?, &forward_key) {
            for (blend, p) in made {
                self.forward_variants.insert((k.clone(), blend), p);
            }
        }
        if let Some(p) = gbuffer? {
            self.gbuffer_variants.insert(gbuffer_key.clone(), p);
        }
        if let Some(p) = lighting? {
            self.lighting_variants.insert(lighting_key.clone(), p);
        }
        let env_index = match built_env? {
            Some(built) => {
                if let Some(t) = timings {
                    t.push(PassTiming {
                        name: "environment",
                        gpu_ms: None,
                        wall_ms: built.build_ms,
                    });
                }
                if self.env_cache.len() >= ENV_CACHE {
                    self.env_cache.remove(0);
                }
                self.env_cache.push(built);
                Some(self.env_cache.len() - 1)
            }
            None => cached_env,
        };
        Ok((gbuffer_key, lighting_key, forward_key, env_index))
    }

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
            let fabric = scene
                .materials
                .get(mesh.material)
                .and_then(|m| m.fabric.as_ref());
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
            draws.push(DrawRange {
                topology,
                first_index,
                index_count,
                vertex_offset,
                material: mesh.material as u32,
                world: d.world,
                double_sided: scene
                    .materials
                    .get(mesh.material)
                    .is_some_and(|m| m.double_sided),
                // Points and lines cover no area a shadow map could hold.
                cast_shadows: d.cast_shadows && topology == Topology::Triangles,
                receive_shadows: d.receive_shadows,
                alpha_mask: scene
                    .materials
                    .get(mesh.material)
                    .is_some_and(|m| m.alpha_cutoff.is_some() || m.blend),
                // Points and lines are the G-buffer pass's whatever their material (the loader
                // says so).
                forward: topology == Topology::Triangles
                    && scene
                        .materials
                        .get(mesh.material)
                        .is_some_and(|m| m.needs_forward()),
                blended: scene.materials.get(mesh.material).is_some_and(|m| m.blend),
                centre: passes::transparent::bounds_centre(
                    mesh.vertices.iter().map(|v| v.position),
                ),
                scene_draw,
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
        let weaves = weave_params
            .iter()
            .map(|f| self.build_weave(f))
            .collect::<crate::Result<Vec<_>>>()?;
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
            fabrics,
            thread_colours,
            weaves,
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

    /// Renders a scene: upload, then one frame.
    pub fn render(&mut self, scene: &Scene, options: &RenderOptions) -> crate::Result<Frame> {
        let gpu = self.upload(scene)?;
        self.render_frame(scene, &gpu, options)
    }

    /// Renders one frame of an uploaded scene.
    pub fn render_frame(
        &mut self,
        scene: &Scene,
        gpu: &GpuScene,
        options: &RenderOptions,
    ) -> crate::Result<Frame> {
        let n = options.supersample();
        if n > 1 {
            return self.render_supersampled(scene, gpu, options, n);
        }
        self.render_frame_impl(scene, gpu, options, true)
    }

    /// `--aa ssN`: N x N frames, each at the centre of its cell of an N x N grid over the pixel
    /// and without FXAA, averaged: the 8-bit images in linear display light (decoded from sRGB,
    /// averaged, encoded: a multisampled target's resolve after tone mapping, so a bright edge
    /// blends as the eye sees it), the HDR in radiance. The timings are the frames' sums; the
    /// plan is the one asked for.
    fn render_supersampled(
        &mut self,
        scene: &Scene,
        gpu: &GpuScene,
        options: &RenderOptions,
        n: u32,
    ) -> crate::Result<Frame> {
        use crate::reference::shading::{srgb_decode, srgb_encode};
        options.validate()?;
        let pixels = options.width as usize * options.height as usize;
        let mut ldr = vec![0f64; pixels * 4];
        let mut hdr = vec![0f64; if options.read_hdr { pixels * 4 } else { 0 }];
        let mut timings: Vec<PassTiming> = Vec::new();
        let mut last = None;
        for j in 0..n {
            for i in 0..n {
                let offset = |k: u32| (k as f32 + 0.5) / n as f32 - 0.5;
                let o = RenderOptions {
                    antialias: super::Antialias::None,
                    jitter: [offset(i), offset(j)],
                    ..options.clone()
                };
                let f = self.render_frame_impl(scene, gpu, &o, true)?;
                for (acc, px) in ldr.chunks_exact_mut(4).zip(f.ldr.chunks_exact(4)) {
                    for c in 0..3 {
                        acc[c] += srgb_decode(px[c] as f32 / 255.0) as f64;
                    }
                    acc[3] += px[3] as f64 / 255.0;
                }
                for (acc, v) in hdr.iter_mut().zip(&f.hdr) {
                    *acc += *v as f64;
                }
                for t in &f.timings {
                    match timings.iter_mut().find(|s| s.name == t.name) {
                        Some(s) => {
                            s.wall_ms += t.wall_ms;
                            s.gpu_ms = s.gpu_ms.zip(t.gpu_ms).map(|(a, b)| a + b);
                        }
                        None => timings.push(t.clone()),
                    }
                }
                last = Some(f);
            }
        }
        let mut frame = last.expect("n >= 2 frames");
        let scale = 1.0 / (n * n) as f64;
        frame.ldr = ldr
            .chunks_exact(4)
            .flat_map(|p| {
                let rgb = |c: usize| srgb_encode((p[c] * scale) as f32);
                [rgb(0), rgb(1), rgb(2), (p[3] * scale * 255.0 + 0.5) as u8]
            })
            .collect();
        frame.hdr = hdr.iter().map(|v| (v * scale) as f32).collect();
        frame.timings = timings;
        frame.plan = Plan::new(scene, options);
        Ok(frame)
    }

    /// As [`Renderer::render_frame`], without the readback: the tonemapped image stays on the
    /// device, returned in `ColorAttachment` usage (`weft view` copies it to the window). The
    /// returned frame's `ldr` and `hdr` are empty.
    pub fn render_frame_to_target(
        &mut self,
        scene: &Scene,
        gpu: &GpuScene,
        options: &RenderOptions,
    ) -> crate::Result<(Frame, &Image)> {
        if options.supersample() > 1 {
            return Err(crate::Error::input(format!(
                "--aa {} renders {} frames per image, for still renders (weft render); a live view takes fxaa or none",
                options.antialias.name(),
                options.antialias.frames_per_side().pow(2)
            )));
        }
        let frame = self.render_frame_impl(scene, gpu, options, false)?;
        let ldr = &self
            .targets
            .as_ref()
            .expect("render_frame_impl made them")
            .ldr;
        Ok((frame, ldr))
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
        gpu.fabrics =
            ctx.create_buffer_with("fabrics", BufferUsageFlags::STORAGE_BUFFER, &fabric_bytes)?;
        gpu.thread_colours = ctx.create_buffer_with(
            "thread colours",
            BufferUsageFlags::STORAGE_BUFFER,
            &thread_colours,
        )?;
        gpu.materials =
            ctx.create_buffer_with("materials", BufferUsageFlags::STORAGE_BUFFER, &materials)?;
        Ok(())
    }

    fn render_frame_impl(
        &mut self,
        scene: &Scene,
        gpu: &GpuScene,
        options: &RenderOptions,
        readback: bool,
    ) -> crate::Result<Frame> {
        options.validate()?;
        let plan = Plan::new(scene, options);
        let mut timings = Vec::new();
        // Pipelines and the environment (Pass::Environment, preprocessed on first use, then from
        // the cache), made concurrently.
        let env = match (&plan.environment, &options.environment) {
            (Some(_), Some(e)) => Some((e.env.as_ref(), &mut timings)),
            _ => None,
        };
        let (gbuffer_key, lighting_key, forward_key, env_index) =
            self.prepare(options, &plan, env)?;
        // The cut-out shadow pipeline only when a MASK material casts into a shadow map.
        let shadow_mask_key = if plan.mask_casters > 0 && plan.runs(Pass::Shadow) {
            Some(self.shadow_mask_pipeline(plan.vertex_colors)?)
        } else {
            None
        };
        if options.weave_precision == super::WeavePrecision::Rgba8 && gpu.weaves8.get().is_none() {
            let copies = gpu
                .weaves
                .iter()
                .map(|w| self.weave_rgba8(w))
                .collect::<crate::Result<Vec<_>>>()?;
            let _ = gpu.weaves8.set(copies);
        }
        if options.weave_precision == super::WeavePrecision::Sat && gpu.weaves_sat.get().is_none() {
            let tables = gpu
                .weave_params
                .iter()
                .map(|f| self.weave_sat(f))
                .collect::<crate::Result<Vec<_>>>()?;
            let _ = gpu.weaves_sat.set(tables);
        }
        let (width, height) = (options.width, options.height);
        if self.targets.as_ref().map(|t| t.hdr.extent()) != Some((width, height)) {
            self.targets = None;
            check_target_memory(
                self.ctx.info(),
                host_available_bytes(),
                width,
                height,
                options.read_hdr,
            )?;
            self.targets = Some(Targets::new(&self.ctx, width, height)?);
        }
        if plan.runs(Pass::Antialias) {
            let targets = self.targets.as_mut().expect("made above");
            if targets.tonemapped.is_none() {
                targets.tonemapped = Some(
                    self.ctx.create_image(
                        &ImageDesc::new_2d("tone-mapped", LDR_FORMAT, width, height)
                            .usage(ImageUsageFlags::COLOR_ATTACHMENT | ImageUsageFlags::SAMPLED),
                    )?,
                );
            }
            self.make_antialias_pipeline()?;
        }
        if plan.transmission_draws > 0 {
            let targets = self.targets.as_mut().expect("made above");
            if targets.backdrop.is_none() {
                targets.backdrop = Some(
                    self.ctx.create_image(
                        &ImageDesc::new_2d("backdrop", HDR_FORMAT, width, height)
                            .full_mips()
                            .usage(
                                ImageUsageFlags::SAMPLED
                                    | ImageUsageFlags::TRANSFER_DST
                                    | ImageUsageFlags::TRANSFER_SRC,
                            ),
                    )?,
                );
            }
        }
        let camera = match &options.camera_override {
            Some(c) => c.clone(),
            // An automatic framing fills this image's aspect ratio.
            None => scene
                .camera(options.camera)?
                .for_aspect(width as f32 / height.max(1) as f32),
        };
        let mut frame_data = FrameData::new(&camera, width, height).jittered(options.jitter);
        if let (Some(i), Some(e)) = (env_index, &options.environment) {
            let g = &self.env_cache[i];
            let rot = crate::env::env_from_world(e.rotation);
            for r in 0..3 {
                frame_data.env_rot[r] = [rot[r][0], rot[r][1], rot[r][2], 0.0];
            }
            let radiance_last = (g.radiance_levels() - 1) as f32;
            frame_data.env_params = [
                e.intensity,
                (super::environment::SPECULAR_LEVELS - 1) as f32,
                g.radiance_size() as f32,
                radiance_last,
            ];
            for k in 0..9 {
                frame_data.sh[k] = [g.sh[k][0], g.sh[k][1], g.sh[k][2], 0.0];
            }
            frame_data.env_background = match e.background {
                crate::env::Background::Env { blur } => [0.0, blur * radiance_last, 0.0, 0.0],
                crate::env::Background::Color(c) => {
                    frame_data.background = [c[0], c[1], c[2], 0.0];
                    [1.0, 0.0, 0.0, 0.0]
                }
                crate::env::Background::None => [2.0, 0.0, 0.0, 0.0],
            };
        }
        frame_data.light_count = gpu.light_count;
        frame_data.material_count = gpu.material_count;
        frame_data.debug_view = options.debug_view as u32;
        let frame_buffer = self.ctx.create_buffer_with(
            "frame",
            BufferUsageFlags::UNIFORM_BUFFER,
            &[frame_data],
        )?;
        let tile_lights = super::tiles::tile_lights(
            &frame_data,
            &gpu.light_records[..gpu.light_count as usize],
            plan.range_culling,
        );
        let tile_buffer = self.ctx.create_buffer_with(
            "tile light lists",
            BufferUsageFlags::STORAGE_BUFFER,
            &tile_lights,
        )?;

        // Shadow maps: the atlas, one record per map, and the lights with their map's index.
        // The maps cover what casts (a ground that only receives does not thin them out).
        let bounds = scene.caster_bounds().or_else(|| scene.bounds());
        let shadow_maps = match &bounds {
            Some(b) if !plan.shadows.is_empty() => {
                let layout = super::shadow::AtlasLayout::new(&plan.shadows);
                let size = layout.size();
                if self.shadow_atlas.as_ref().map(|a| a.extent()) != Some((size, size)) {
                    self.shadow_atlas = None;
                    self.shadow_atlas = Some(self.ctx.create_image(
                        &ImageDesc::new_2d("shadow atlas", SHADOW_FORMAT, size, size).usage(
                            ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT | ImageUsageFlags::SAMPLED,
                        ),
                    )?);
                }
                super::shadow::shadow_records(&plan.shadows, &scene.lights, b, &layout)
                    .into_iter()
                    .enumerate()
                    .map(|(i, (record, m))| {
                        let (x, y) = layout.origin(i);
                        (record, m, (x, y, plan.shadows[i].resolution))
                    })
                    .collect::<Vec<_>>()
            }
            _ => Vec::new(),
        };
        let mut shadow_records: Vec<GpuShadow> = shadow_maps.iter().map(|s| s.0).collect();
        let frame_lights = if shadow_maps.is_empty() {
            None
        } else {
            let mut records = gpu.light_records.clone();
            for (i, s) in plan.shadows.iter().enumerate() {
                if let Some(r) = records.get_mut(s.light) {
                    r.spot[2] = i as f32 + 1.0;
                }
            }
            Some(self.ctx.create_buffer_with(
                "lights with shadows",
                BufferUsageFlags::STORAGE_BUFFER,
                &records,
            )?)
        };
        if shadow_records.is_empty() {
            shadow_records.push(bytemuck::Zeroable::zeroed()); // a storage buffer cannot be empty
        }
        let shadow_buffer = self.ctx.create_buffer_with(
            "shadows",
            BufferUsageFlags::STORAGE_BUFFER,
            &shadow_records,
        )?;
        let lights_buffer = frame_lights.as_ref().unwrap_or(&gpu.lights);
        let atlas = match (&self.shadow_atlas, shadow_maps.is_empty()) {
            (Some(a), false) => a,
            _ => &self.no_shadows,
        };

        // Vertex colours compiled in (forced) for a scene that has none: every vertex reads white.
        let forced_colors = if plan.vertex_colors && !gpu.has_colors {
            Some(self.ctx.create_buffer_with(
                "vertex colours (white)",
                BufferUsageFlags::STORAGE_BUFFER,
                &vec![[1.0f32; 4]; gpu.vertex_count.max(1)],
            )?)
        } else {
            None
        };
        let colors = forced_colors.as_ref().unwrap_or(&gpu.colors);
        let ctx = self.ctx.clone();
        let targets = self.targets.as_ref().expect("created above");
        let gbuffer_pipeline = &self.gbuffer_variants[&gbuffer_key];
        let primitive = |t: Topology| {
            self.gbuffer_primitive_variants
                .get(&(gbuffer_key.clone(), t))
                .filter(|_| gpu.draws.iter().any(|d| d.topology == t))
        };
        let gbuffer_pipelines = passes::gbuffer::GBufferPipelines {
            triangles: gbuffer_pipeline,
            lines: primitive(Topology::Lines),
            points: primitive(Topology::Points),
        };
        let lighting_pipeline = &self.lighting_variants[&lighting_key];
        let pool = ctx.create_descriptor_pool(6 + 3 * gpu.material_count)?;
        let queries = ctx.create_query_pool(2)?;
        let (env_radiance, env_specular) = match env_index {
            Some(i) => (&self.env_cache[i].radiance, &self.env_cache[i].specular),
            None => (&self.env.black, &self.env.black),
        };
        let mut stats = FrameStats {
            draws: gpu.draws.len(),
            triangles: gpu.triangles,
            ..Default::default()
        };

        // Times one pass: a submission of its own between two timestamps. A function, not a
        // closure, so that the submission's lifetime `'s` can be named: every resource the pass
        // records is borrowed for it (see `Context::submit`).
        fn timed_pass<'s>(
            ctx: &'s crate::vk::Context,
            queries: Option<&'s crate::vk::QueryPool>,
            timings: &mut Vec<PassTiming>,
            name: &'static str,
            record: &mut dyn FnMut(&mut Cmd<'s>),
        ) -> crate::Result<()> {
            let start = Instant::now();
            ctx.submit(|cmd| {
                if let Some(q) = queries {
                    cmd.reset_queries(q);
                    cmd.timestamp(q, 0);
                }
                record(cmd);
                if let Some(q) = queries {
                    cmd.timestamp(q, 1);
                }
            })?;
            let gpu_ms = match queries {
                Some(q) => {
                    let t = q.read_ns(2)?;
                    Some((t[1] - t[0]) / 1e6)
                }
                None => None,
            };
            timings.push(PassTiming {
                name,
                gpu_ms,
                wall_ms: start.elapsed().as_secs_f64() * 1e3,
            });
            Ok(())
        }

        // Each material's textures: set 1 of the G-buffer pass (its slots but transmission's and
        // thickness's, which only the transparent pass reads) and, when that pass runs, of it.
        let material_set = |m: usize, forward: bool| {
            let tex = gpu
                .material_textures
                .get(m)
                .copied()
                .unwrap_or([None; TextureSlot::COUNT]);
            let samplers = gpu.material_samplers.get(m).copied();
            // A slot's own sampler where it has a texture; the default
            // (trilinear, repeat) for the 1x1 fallbacks.
            let sampler = |slot: usize| -> &Sampler {
                match (tex[slot], samplers) {
                    (Some(_), Some(s)) => gpu.samplers.get(s[slot]).unwrap_or(&self.linear),
                    _ => &self.linear,
                }
            };
            let pick = |slot: usize, fallback: &'static str| -> &Image {
                match tex[slot].and_then(|i| gpu.textures.get(i)) {
                    Some(t) => t,
                    None if fallback == "normal" => &self.flat_normal,
                    None => &self.white,
                }
            };
            let weave = match gpu.material_weave.get(m).copied().flatten() {
                Some(w) if options.weave_precision == super::WeavePrecision::Rgba8 => {
                    &gpu.weaves8.get().expect("made above for RGBA8 frames")[w]
                }
                Some(w) if options.weave_precision == super::WeavePrecision::Sat => &gpu
                    .weaves_sat
                    .get()
                    .expect("made above for summed-area frames")[w],
                Some(w) => &gpu.weaves[w],
                None => &self.white,
            };
            let mut bindings = vec![
                (0, Resource::Sampled(pick(0, "white"), sampler(0))),
                (1, Resource::Sampled(pick(1, "white"), sampler(1))),
                (2, Resource::Sampled(pick(2, "normal"), sampler(2))),
                (3, Resource::Sampled(pick(3, "white"), sampler(3))),
                (4, Resource::Sampled(weave, &self.linear)),
                (5, Resource::Sampled(pick(4, "white"), sampler(4))),
                (6, Resource::Sampled(pick(5, "white"), sampler(5))),
                (7, Resource::Sampled(pick(6, "white"), sampler(6))),
                (8, Resource::Sampled(pick(7, "white"), sampler(7))),
                (9, Resource::Sampled(pick(8, "white"), sampler(8))),
                (10, Resource::Sampled(pick(9, "white"), sampler(9))),
            ];
            if forward {
                bindings.push((11, Resource::Sampled(pick(10, "white"), sampler(10))));
                bindings.push((12, Resource::Sampled(pick(11, "white"), sampler(11))));
                bindings.push((13, Resource::Sampled(pick(12, "white"), sampler(12))));
                bindings.push((14, Resource::Sampled(pick(13, "white"), sampler(13))));
                bindings.push((15, Resource::Sampled(pick(14, "normal"), sampler(14))));
                bindings.push((16, Resource::Sampled(pick(15, "white"), sampler(15))));
                bindings.push((17, Resource::Sampled(pick(16, "white"), sampler(16))));
                bindings.push((18, Resource::Sampled(pick(17, "white"), sampler(17))));
                bindings.push((19, Resource::Sampled(pick(18, "white"), sampler(18))));
                pool.set(&self.forward_material_layout, &bindings)
            } else {
                pool.set(&self.material_layout, &bindings)
            }
        };
        let material_sets = (0..gpu.material_count as usize)
            .map(|m| material_set(m, false))
            .collect::<crate::Result<Vec<_>>>()?;
        let forward_material_sets = if plan.runs(Pass::Transparent) {
            (0..gpu.material_count as usize)
                .map(|m| material_set(m, true))
                .collect::<crate::Result<Vec<_>>>()?
        } else {
            Vec::new()
        };

        // Bindings 10-15 of the lighting and transparent passes' set 0: the shadow atlas and its
        // records, the tile light lists, the environment.
        let shadow_and_environment = || {
            [
                (10, Resource::Sampled(atlas, &self.shadow_sampler)),
                (11, Resource::Storage(&shadow_buffer)),
                (12, Resource::Storage(&tile_buffer)),
                (13, Resource::Sampled(env_radiance, &self.env.sampler)),
                (14, Resource::Sampled(env_specular, &self.env.sampler)),
                (15, Resource::Sampled(&self.env.dfg, &self.env.sampler)),
            ]
        };
        for pass in &plan.passes {
            match pass {
                Pass::Environment => {
                    // Preprocessed before the frame (above), or found in the cache.
                }
                Pass::Weave => {
                    // The weave pass ran when the scene was uploaded (once per distinct weave,
                    // one dispatch per mip level); a frame reuses its textures.
                    stats.weave_textures = gpu.weaves.len();
                    stats.weave_dispatches = gpu.weaves.iter().map(|w| w.desc.mip_levels).sum();
                }
                Pass::GBuffer => {
                    let frame_set = pool.set(
                        &self.frame_layout,
                        &[
                            (0, Resource::Uniform(&frame_buffer)),
                            (1, Resource::Storage(&gpu.materials)),
                            (2, Resource::Storage(&gpu.fabrics)),
                            (3, Resource::Storage(&gpu.lights)),
                            (4, Resource::Storage(colors)),
                            (5, Resource::Storage(&gpu.thread_colours)),
                        ],
                    )?;
                    timed_pass(
                        &ctx,
                        queries.as_ref(),
                        &mut timings,
                        "gbuffer",
                        &mut |cmd| {
                            passes::gbuffer::gbuffer_pass(
                                cmd,
                                &gbuffer_pipelines,
                                gpu,
                                frame_set,
                                &material_sets,
                                targets,
                            )
                        },
                    )?;
                    stats.pipelines.push(gbuffer_pipeline.name.clone());
                    for p in [gbuffer_pipelines.lines, gbuffer_pipelines.points]
                        .into_iter()
                        .flatten()
                    {
                        stats.pipelines.push(p.name.clone());
                    }
                }
                Pass::Shadow => {
                    let tiles: Vec<(u32, u32, u32, Mat4)> = shadow_maps
                        .iter()
                        .map(|(_, m, (x, y, r))| (*x, *y, *r, *m))
                        .collect();
                    // MASK casters: the cut-out pipeline, the materials and vertex colours, and
                    // each MASK material's base colour texture.
                    let mask = match shadow_mask_key {
                        Some(key) => {
                            let set = pool.set(
                                &self.shadow_mask_layout,
                                &[
                                    (0, Resource::Storage(&gpu.materials)),
                                    (1, Resource::Storage(&gpu.colors)),
                                ],
                            )?;
                            let textures = (0..gpu.material_count as usize)
                                .map(|m| {
                                    if !gpu.material_mask.get(m).copied().unwrap_or(false) {
                                        return Ok(None);
                                    }
                                    let base = gpu
                                        .material_textures
                                        .get(m)
                                        .and_then(|t| t[0])
                                        .and_then(|i| gpu.textures.get(i))
                                        .unwrap_or(&self.white);
                                    pool.set(
                                        &self.shadow_mask_texture_layout,
                                        &[(0, Resource::Sampled(base, &self.linear))],
                                    )
                                    .map(Some)
                                })
                                .collect::<crate::Result<Vec<_>>>()?;
                            Some(passes::shadow::MaskCasters {
                                pipeline: &self.shadow_mask_variants[&key],
                                set,
                                textures,
                            })
                        }
                        None => None,
                    };
                    if !tiles.is_empty() {
                        timed_pass(&ctx, queries.as_ref(), &mut timings, "shadow", &mut |cmd| {
                            passes::shadow::shadow_pass(
                                cmd,
                                &self.shadow_pipeline,
                                mask.as_ref(),
                                gpu,
                                atlas,
                                &tiles,
                            )
                        })?;
                        stats.pipelines.push(self.shadow_pipeline.name.clone());
                        if let Some(m) = &mask {
                            stats.pipelines.push(m.pipeline.name.clone());
                        }
                        stats.shadow_maps = tiles.len();
                        stats.shadow_draws =
                            tiles.len() * gpu.draws.iter().filter(|d| d.cast_shadows).count();
                    }
                }
                Pass::Lighting => {
                    let mut bindings = vec![
                        (0, Resource::Uniform(&frame_buffer)),
                        (1, Resource::Storage(lights_buffer)),
                        (2, Resource::Storage(&gpu.materials)),
                        (3, Resource::Sampled(&targets.albedo, &self.nearest)),
                        (4, Resource::Sampled(&targets.frame, &self.nearest)),
                        (5, Resource::Sampled(&targets.surface, &self.nearest)),
                        (6, Resource::Sampled(&targets.fabric, &self.nearest)),
                        (7, Resource::Sampled(&targets.emissive, &self.nearest)),
                        (8, Resource::Sampled(&targets.depth, &self.nearest)),
                        (9, Resource::Storage(&gpu.fabrics)),
                        (16, Resource::Sampled(&targets.specular, &self.nearest)),
                    ];
                    bindings.extend(shadow_and_environment());
                    let set = pool.set(&self.lighting_layout, &bindings)?;
                    timed_pass(
                        &ctx,
                        queries.as_ref(),
                        &mut timings,
                        "lighting",
                        &mut |cmd| {
                            passes::lighting::lighting_pass(cmd, lighting_pipeline, set, targets)
                        },
                    )?;
                    stats.pipelines.push(lighting_pipeline.name.clone());
                }
                Pass::Transparent => {
                    let key = forward_key
                        .as_ref()
                        .expect("prepare makes the forward pipeline when the plan has the pass");
                    let pipeline_opaque = self.forward_variants.get(&(key.clone(), false));
                    let pipeline_blend = self.forward_variants.get(&(key.clone(), true));
                    let backdrop = targets
                        .backdrop
                        .as_ref()
                        .filter(|_| plan.transmission_draws > 0);
                    let mut bindings = vec![
                        (0, Resource::Uniform(&frame_buffer)),
                        (1, Resource::Storage(&gpu.materials)),
                        (2, Resource::Storage(&gpu.fabrics)),
                        (3, Resource::Storage(lights_buffer)),
                        (4, Resource::Storage(colors)),
                        (5, Resource::Storage(&gpu.thread_colours)),
                        match backdrop {
                            Some(b) => (16, Resource::Sampled(b, &self.env.sampler)),
                            None => (16, Resource::Sampled(&self.white, &self.linear)),
                        },
                    ];
                    bindings.extend(shadow_and_environment());
                    let frame_set = pool.set(&self.forward_layout, &bindings)?;
                    let order = passes::transparent::back_to_front(gpu, camera.view);
                    timed_pass(
                        &ctx,
                        queries.as_ref(),
                        &mut timings,
                        "transparent",
                        &mut |cmd| {
                            passes::transparent::transparent_pass(
                                cmd,
                                passes::transparent::Pipelines {
                                    opaque: pipeline_opaque,
                                    blend: pipeline_blend,
                                },
                                gpu,
                                frame_set,
                                &forward_material_sets,
                                targets,
                                backdrop,
                                &order,
                                options.force.back_faces_first,
                            )
                        },
                    )?;
                    for p in [pipeline_opaque, pipeline_blend].into_iter().flatten() {
                        stats.pipelines.push(p.name.clone());
                    }
                    stats.blend_draws = order.len();
                }
                Pass::Tonemap => {
                    let set = pool.set(
                        &self.tonemap_layout,
                        &[(0, Resource::Sampled(&targets.hdr, &self.nearest))],
                    )?;
                    let push = TonemapPush {
                        exposure: 2f32.powf(options.exposure),
                        passthrough: (options.debug_view != super::DebugView::None) as u32,
                        curve: options.tonemap.code(),
                        _pad: 0,
                    };
                    timed_pass(
                        &ctx,
                        queries.as_ref(),
                        &mut timings,
                        "tonemap",
                        &mut |cmd| {
                            passes::tonemap::tonemap_pass(
                                cmd,
                                &self.tonemap_pipeline,
                                set,
                                &push,
                                targets,
                                plan.runs(Pass::Antialias),
                            )
                        },
                    )?;
                    stats.pipelines.push(self.tonemap_pipeline.name.clone());
                }
                Pass::Antialias => {
                    let pipeline = self
                        .antialias_pipeline
                        .get()
                        .expect("made when the plan has the pass");
                    let source = targets
                        .tonemapped
                        .as_ref()
                        .expect("made when the plan has the pass");
                    let set = pool.set(
                        &self.tonemap_layout,
                        &[(0, Resource::Sampled(source, &self.linear_clamp))],
                    )?;
                    timed_pass(
                        &ctx,
                        queries.as_ref(),
                        &mut timings,
                        "antialias",
                        &mut |cmd| passes::antialias::antialias_pass(cmd, pipeline, set, targets),
                    )?;
                    stats.pipelines.push(pipeline.name.clone());
                }
            }
            stats.passes.push(pass.name());
        }

        let start = Instant::now();
        let ldr = if readback {
            read_image(&ctx, &targets.ldr, Usage::ColorAttachment, 4)?
        } else {
            Vec::new()
        };
        // The HDR target only when asked for (EXR output, tests, the bench): the PNG needs only
        // the 8-bit target.
        let hdr: Vec<f32> = if readback && options.read_hdr {
            let hdr_half = read_image(&ctx, &targets.hdr, Usage::FragmentRead, 8)?;
            hdr_half
                .chunks_exact(2)
                .map(|b| f16_to_f32(u16::from_le_bytes([b[0], b[1]])))
                .collect()
        } else {
            Vec::new()
        };
        if readback {
            timings.push(PassTiming {
                name: "readback",
                gpu_ms: None,
                wall_ms: start.elapsed().as_secs_f64() * 1e3,
            });
        }
        drop(pool);
        ctx.check_validation()?;
        Ok(Frame {
            width,
            height,
            ldr,
            hdr,
            timings,
            stats,
            plan,
        })
    }

    /// Builds a weave texture: every mip level computed by weave.comp as the exact coverage of its
    /// texels' footprints (not a downsampling of level 0).
    pub fn build_weave(&self, fabric: &FabricParams) -> crate::Result<Image> {
        let ctx = &self.ctx;
        let level0 = weave_level0_size(&fabric.pattern);
        let mut desc = ImageDesc::new_2d("weave", WEAVE_FORMAT, level0.0, level0.1).usage(
            ImageUsageFlags::STORAGE | ImageUsageFlags::SAMPLED | ImageUsageFlags::TRANSFER_SRC,
        );
        desc.mip_levels = weave_mip_count(level0);
        let image = ctx.create_image(&desc)?;
        let pool = ctx.create_descriptor_pool(desc.mip_levels)?;
        let sets = (0..desc.mip_levels)
            .map(|level| {
                pool.set(
                    &self.weave_layout,
                    &[(0, Resource::StorageImage(&image, level))],
                )
            })
            .collect::<crate::Result<Vec<_>>>()?;
        ctx.submit(|cmd| {
            cmd.transition(&image, Usage::Undefined, Usage::ComputeWrite, None);
            cmd.bind_pipeline(&self.weave_pipeline);
            for (level, set) in sets.iter().enumerate() {
                let (w, h) = weave_level_size(level0, level as u32);
                cmd.bind_sets(&self.weave_pipeline, 0, &[*set]);
                cmd.push_constants(&self.weave_pipeline, &fabric.weave_push(w, h));
                cmd.dispatch(w.div_ceil(8), h.div_ceil(8), 1);
            }
            cmd.transition(&image, Usage::ComputeWrite, Usage::FragmentRead, None);
        })?;
        Ok(image)
    }

    /// The summed-area table of a weave ([`crate::fabric::WeaveSat`], computed on the
    /// CPU in f64), uploaded as one RGBA32F level.
    pub fn weave_sat(&self, fabric: &FabricParams) -> crate::Result<Image> {
        let level0 = weave_level0_size(&fabric.pattern);
        let sat = crate::fabric::WeaveSat::new(&fabric.weave_push(level0.0, level0.1));
        let desc = ImageDesc::new_2d(
            "weave summed-area table",
            WEAVE_SAT_FORMAT,
            sat.width,
            sat.height,
        )
        .usage(ImageUsageFlags::SAMPLED | ImageUsageFlags::TRANSFER_DST);
        let image = self.ctx.create_image(&desc)?;
        let bytes: Vec<u8> = sat
            .texels
            .iter()
            .flatten()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let staging = self.ctx.create_buffer_with(
            "weave summed-area staging",
            BufferUsageFlags::TRANSFER_SRC,
            &bytes,
        )?;
        self.ctx.submit(|cmd| {
            cmd.transition(&image, Usage::Undefined, Usage::TransferDst, None);
            cmd.copy_buffer_to_image_level(&staging, &image, 0);
            cmd.transition(&image, Usage::TransferDst, Usage::FragmentRead, None);
        })?;
        Ok(image)
    }

    /// The RGBA8 copy of a weave texture: every level read back and each coverage rounded to the
    /// nearest 1/255 here. A format-converting blit may round toward zero (lavapipe does), which
    /// darkened the far field by half a step on average (0.28 %: 54 against 61.5 dB).
    pub fn weave_rgba8(&self, weave: &Image) -> crate::Result<Image> {
        let mut desc = weave.desc.clone();
        desc.name = format!("{} (RGBA8)", desc.name);
        desc.format = WEAVE_FORMAT_8;
        desc.usage = ImageUsageFlags::SAMPLED
            | ImageUsageFlags::TRANSFER_DST
            | ImageUsageFlags::TRANSFER_SRC;
        let image = self.ctx.create_image(&desc)?;
        let staging = (0..desc.mip_levels)
            .map(|level| {
                let bytes = unorm8_round(&self.read_weave(weave, level)?);
                self.ctx.create_buffer_with(
                    "weave rgba8 staging",
                    BufferUsageFlags::TRANSFER_SRC,
                    &bytes,
                )
            })
            .collect::<crate::Result<Vec<_>>>()?;
        self.ctx.submit(|cmd| {
            cmd.transition(&image, Usage::Undefined, Usage::TransferDst, None);
            for (level, buffer) in staging.iter().enumerate() {
                cmd.copy_buffer_to_image_level(buffer, &image, level as u32);
            }
            cmd.transition(&image, Usage::TransferDst, Usage::FragmentRead, None);
        })?;
        Ok(image)
    }

    /// Reads mip `level` of an RGBA8 weave texture ([`Renderer::weave_rgba8`]) back (for tests).
    pub fn read_weave_rgba8(&self, image: &Image, level: u32) -> crate::Result<Vec<u8>> {
        read_image_level(&self.ctx, image, level, Usage::FragmentRead, 4)
    }

    /// Reads mip `level` of a weave texture back as RGBA f32 (for tests).
    pub fn read_weave(&self, image: &Image, level: u32) -> crate::Result<Vec<f32>> {
        let raw = read_image_level(&self.ctx, image, level, Usage::FragmentRead, 8)?;
        Ok(raw
            .chunks_exact(2)
            .map(|b| f16_to_f32(u16::from_le_bytes([b[0], b[1]])))
            .collect())
    }

    /// Reads back the G-buffer of the last frame (for tests and debugging): albedo RGBA8,
    /// then the five RGBA16F targets as f32, then depth.
    pub fn read_gbuffer(&self) -> crate::Result<GBufferReadback> {
        let t = self
            .targets
            .as_ref()
            .ok_or_else(|| Error::input("no frame has been rendered yet"))?;
        let ctx = &self.ctx;
        let half = |img: &Image| -> crate::Result<Vec<f32>> {
            let raw = read_image(ctx, img, Usage::FragmentRead, 8)?;
            Ok(raw
                .chunks_exact(2)
                .map(|b| f16_to_f32(u16::from_le_bytes([b[0], b[1]])))
                .collect())
        };
        let depth_raw = read_image(ctx, &t.depth, Usage::FragmentRead, 4)?;
        Ok(GBufferReadback {
            albedo: read_image(ctx, &t.albedo, Usage::FragmentRead, 4)?,
            frame: read_image(ctx, &t.frame, Usage::FragmentRead, 8)?
                .chunks_exact(2)
                .map(|b| frame_decode(u16::from_le_bytes([b[0], b[1]])))
                .collect(),
            surface: half(&t.surface)?,
            fabric: half(&t.fabric)?,
            emissive: half(&t.emissive)?,
            specular: half(&t.specular)?,
            depth: depth_raw
                .chunks_exact(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect(),
        })
    }
}

/// `frame_decode` of frame.glsl: one stored octahedral coordinate back to [-1, 1].
pub fn frame_decode(stored: u16) -> f32 {
    (stored as f32 - 32768.0) / 32767.0
}

/// The G-buffer of a frame on the CPU (the frame target decoded to its octahedral coordinates).
pub struct GBufferReadback {
    pub albedo: Vec<u8>,
    pub frame: Vec<f32>,
    pub surface: Vec<f32>,
    pub fabric: Vec<f32>,
    pub emissive: Vec<f32>,
    pub specular: Vec<f32>,
    pub depth: Vec<f32>,
}

fn solid(name: &str, rgba: [u8; 4], color_space: ColorSpace) -> Texture {
    Texture {
        name: name.into(),
        width: 1,
        height: 1,
        color_space,
        rgba8: rgba.to_vec(),
    }
}

/// Uploads an RGBA8 texture and builds its mip chain by linear blits.
fn upload_texture(ctx: &Context, texture: &Texture) -> crate::Result<Image> {
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

/// A scene's fabric records (80 bytes each; one zero record when there are none: a storage
/// buffer cannot be empty) and the material records, which index them (one default material when
/// the scene has none).
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

/// And the thread-colour buffer (`ThreadColours` of gbuffer.frag and forward.frag): each
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

/// Values in [0, 1] as UNORM8 bytes, rounded to nearest (NaN to 0).
pub fn unorm8_round(values: &[f32]) -> Vec<u8> {
    values
        .iter()
        .map(|v| {
            let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
            (v * 255.0).round() as u8
        })
        .collect()
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

/// Copies mip 0 of `image` (currently in `from` usage) to the host; `texel` bytes per texel.
fn read_image(ctx: &Context, image: &Image, from: Usage, texel: u64) -> crate::Result<Vec<u8>> {
    read_image_level(ctx, image, 0, from, texel)
}

fn read_image_level(
    ctx: &Context,
    image: &Image,
    level: u32,
    from: Usage,
    texel: u64,
) -> crate::Result<Vec<u8>> {
    let w = (image.desc.width >> level).max(1);
    let h = (image.desc.height >> level).max(1);
    let buffer = ctx.create_buffer(
        &format!("readback of {}", image.desc.name),
        w as u64 * h as u64 * texel,
        BufferUsageFlags::TRANSFER_DST,
        BufferLocation::Readback,
    )?;
    ctx.submit(|cmd| {
        cmd.transition(image, from, Usage::TransferSrc, Some((level, 1)));
        cmd.copy_image_to_buffer(image, level, &buffer);
        cmd.transition(image, Usage::TransferSrc, from, Some((level, 1)));
        cmd.buffer_barrier();
    })?;
    Ok(buffer.read()?.to_vec())
}

/// IEEE 754 half to single precision (the `half` crate's conversion).
pub fn f16_to_f32(h: u16) -> f32 {
    half::f16::from_bits(h).to_f32()
}

#[cfg(test)]
mod tests {
    use super::f16_to_f32;

    #[test]
    fn half_conversion() {
        assert_eq!(f16_to_f32(0x3c00), 1.0);
        assert_eq!(f16_to_f32(0xc000), -2.0);
        assert_eq!(f16_to_f32(0x7bff), 65504.0);
        assert_eq!(f16_to_f32(0x0001), 2f32.powi(-24));
        assert_eq!(f16_to_f32(0x0200), 2f32.powi(-15));
        assert!(f16_to_f32(0x7c00).is_infinite());
        assert!(f16_to_f32(0x7e00).is_nan());
    }
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
