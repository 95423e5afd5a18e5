//! Pipelines and descriptors: set layouts described as plain values, pipeline layouts, graphics
//! pipelines for dynamic rendering, compute pipelines, and a descriptor pool whose sets live as
//! long as the pool.

use std::sync::Arc;

use ash::vk;

use super::context::{vkerr, Context, Shared};
use super::resources::{Buffer, Image, Sampler};
use super::{Shader, Stage};
use crate::Error;

/// What a shader binding holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BindingKind {
    UniformBuffer,
    StorageBuffer,
    SampledImage,
    StorageImage,
}

impl BindingKind {
    pub fn vk(self) -> vk::DescriptorType {
        match self {
            BindingKind::UniformBuffer => vk::DescriptorType::UNIFORM_BUFFER,
            BindingKind::StorageBuffer => vk::DescriptorType::STORAGE_BUFFER,
            BindingKind::SampledImage => vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
            BindingKind::StorageImage => vk::DescriptorType::STORAGE_IMAGE,
        }
    }
}

/// One binding of a descriptor set layout.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Binding {
    pub binding: u32,
    pub kind: BindingKind,
    pub stages: Stages,
}

/// Shader stages a binding or push constant is visible to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Stages(pub(crate) vk::ShaderStageFlags);

impl Stages {
    pub const VERTEX: Stages = Stages(vk::ShaderStageFlags::VERTEX);
    pub const FRAGMENT: Stages = Stages(vk::ShaderStageFlags::FRAGMENT);
    pub const COMPUTE: Stages = Stages(vk::ShaderStageFlags::COMPUTE);
    pub const GRAPHICS: Stages = Stages(vk::ShaderStageFlags::from_raw(
        vk::ShaderStageFlags::VERTEX.as_raw() | vk::ShaderStageFlags::FRAGMENT.as_raw(),
    ));
}

pub struct SetLayout {
    shared: Arc<Shared>,
    pub(crate) raw: vk::DescriptorSetLayout,
    pub bindings: Vec<Binding>,
}

impl Drop for SetLayout {
    fn drop(&mut self) {
        self.shared.settle();
        unsafe {
            self.shared
                .device
                .destroy_descriptor_set_layout(self.raw, None)
        };
    }
}

/// A pipeline and its layout.
pub struct Pipeline {
    shared: Arc<Shared>,
    pub(crate) raw: vk::Pipeline,
    pub(crate) layout: vk::PipelineLayout,
    pub(crate) bind_point: vk::PipelineBindPoint,
    pub(crate) push_stages: vk::ShaderStageFlags,
    pub name: String,
    /// Source file names of the shader modules, in stage order.
    pub shaders: Vec<&'static str>,
    /// The bindings of each descriptor set, by set number.
    pub sets: Vec<Vec<Binding>>,
    pub push_constant_size: u32,
    /// Specialization constants the pipeline was made with (id, value).
    pub constants: Vec<(u32, u32)>,
}

impl Drop for Pipeline {
    fn drop(&mut self) {
        // Waits for lavapipe's queue to finish (Shared::compile_lock); a pipeline is only dropped
        // when nothing pending uses it, so on a GPU nothing is waited for.
        self.shared.settle();
        let _compiling = self.shared.compile_lock();
        unsafe {
            self.shared.device.destroy_pipeline(self.raw, None);
            self.shared
                .device
                .destroy_pipeline_layout(self.layout, None);
        }
    }
}

/// Vertex input: one interleaved buffer; attributes are (location, format, offset).
#[derive(Clone, Debug)]
pub struct VertexLayout {
    pub stride: u32,
    pub attributes: Vec<(u32, vk::Format, u32)>,
}

/// A graphics pipeline for dynamic rendering. Viewport, scissor and cull mode are dynamic.
pub struct GraphicsDesc<'a> {
    pub name: &'a str,
    pub vertex: &'a Shader,
    pub fragment: &'a Shader,
    pub vertex_layout: Option<VertexLayout>,
    pub color_formats: &'a [vk::Format],
    pub depth_format: Option<vk::Format>,
    pub set_layouts: &'a [&'a SetLayout],
    pub push_constant_size: u32,
    pub push_stages: Stages,
    /// Specialization constants (id, value), given to both stages (Vulkan ignores an id a stage
    /// does not declare, so the vertex and fragment shaders share one numbering).
    pub constants: &'a [(u32, u32)],
    /// Blending: false replaces the attachments (and writes depth); true blends premultiplied
    /// colour over them (ONE, ONE_MINUS_SRC_ALPHA, alpha alike) and only tests depth.
    pub blend: bool,
    /// How vertices assemble: triangle, line or point lists (lines and points 1 pixel wide).
    pub topology: Topology,
    /// What the pipeline does with the stencil of a depth-stencil attachment.
    pub stencil: StencilMode,
    /// Which fragments pass the depth test (with a depth format).
    pub depth_test: DepthTest,
}

/// A graphics pipeline's depth test (reversed-Z: near is 1, far is 0).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DepthTest {
    /// Nearer than what the attachment holds (GREATER): the first of equally near fragments wins.
    #[default]
    Nearer,
    /// As near or nearer (GREATER_OR_EQUAL): after a depth pre-pass of the same positions, the
    /// visible fragment passes and every hidden one fails.
    NearerOrEqual,
    /// Every fragment passes and writes its depth (ALWAYS): a copy of depth.
    Always,
    /// Farther than what the attachment holds (LESS), writing nothing: a fullscreen triangle at
    /// the far plane (depth 0) is drawn where the attachment holds a surface.
    Farther,
}

/// A graphics pipeline's use of the stencil (of a `depth_format` with a stencil aspect; the
/// reference value is dynamic: [`Cmd::set_stencil_reference`](super::Cmd::set_stencil_reference)).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum StencilMode {
    /// Not tested, not written.
    #[default]
    None,
    /// Every fragment that passes the depth test writes the reference.
    Write,
    /// Only fragments whose stencil equals the reference are drawn; no depth test, nothing
    /// written to the attachment (it may be attached read-only).
    Equal,
    /// Every fragment the shader keeps writes the reference's bits under this mask (the other
    /// bits stay); no depth test.
    MarkBits(u32),
    /// Only fragments whose stencil has none of these bits set are drawn; no depth test,
    /// nothing written.
    BitsClear(u32),
}

/// The primitive topology of a graphics pipeline.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Topology {
    #[default]
    Triangles,
    Lines,
    Points,
}

pub struct ComputeDesc<'a> {
    pub name: &'a str,
    pub shader: &'a Shader,
    pub set_layouts: &'a [&'a SetLayout],
    pub push_constant_size: u32,
    pub constants: &'a [(u32, u32)],
}

/// Descriptor sets allocated from here are freed with the pool.
pub struct DescriptorPool {
    shared: Arc<Shared>,
    raw: vk::DescriptorPool,
    /// Vulkan requires allocation from one pool to be externally synchronized; the pool is
    /// `Sync`, so [`DescriptorPool::set`] takes this lock.
    lock: std::sync::Mutex<()>,
}

impl Drop for DescriptorPool {
    fn drop(&mut self) {
        self.shared.settle();
        unsafe { self.shared.device.destroy_descriptor_pool(self.raw, None) };
    }
}

/// A descriptor set, borrowing its pool and every resource written into it for `'r`: neither
/// can be dropped while the set can still be bound, and [`Cmd::bind_sets`](super::Cmd::bind_sets)
/// needs `'r` to outlive the submission. A set naming a dropped image does not compile:
///
/// ```compile_fail,E0505
/// # fn misuse(ctx: &weft::vk::Context, layout: &weft::vk::SetLayout, pipeline: &weft::vk::Pipeline) -> weft::Result<()> {
/// use weft::vk::{BufferLocation, BufferUsageFlags, Resource};
/// let pool = ctx.create_descriptor_pool(1)?;
/// let uniforms = ctx.create_buffer("u", 64, BufferUsageFlags::UNIFORM_BUFFER, BufferLocation::Upload)?;
/// let set = pool.set(layout, &[(0, Resource::Uniform(&uniforms))])?;
/// drop(uniforms);
/// ctx.submit(|cmd| cmd.bind_sets(pipeline, 0, &[set]))?;
/// # Ok(()) }
/// ```
///
/// (stable rustdoc does not check the error code), while the same code that drops the buffer
/// after the submission compiles:
///
/// ```no_run
/// # fn fine(ctx: &weft::vk::Context, layout: &weft::vk::SetLayout, pipeline: &weft::vk::Pipeline) -> weft::Result<()> {
/// use weft::vk::{BufferLocation, BufferUsageFlags, Resource};
/// let pool = ctx.create_descriptor_pool(1)?;
/// let uniforms = ctx.create_buffer("u", 64, BufferUsageFlags::UNIFORM_BUFFER, BufferLocation::Upload)?;
/// let set = pool.set(layout, &[(0, Resource::Uniform(&uniforms))])?;
/// ctx.submit(|cmd| cmd.bind_sets(pipeline, 0, &[set]))?;
/// drop(uniforms);
/// # Ok(()) }
/// ```
#[derive(Clone, Copy, Debug)]
pub struct DescriptorSet<'r> {
    pub(crate) raw: vk::DescriptorSet,
    _resources: std::marker::PhantomData<&'r ()>,
}

/// What to bind at one binding of a set.
#[derive(Clone, Copy)]
pub enum Resource<'a> {
    Uniform(&'a Buffer),
    Storage(&'a Buffer),
    /// An image in SHADER_READ_ONLY_OPTIMAL layout (a depth-stencil image's depth in
    /// DEPTH_STENCIL_READ_ONLY_OPTIMAL), with a sampler.
    Sampled(&'a Image, &'a Sampler),
    /// The same through the image's alias view ([`crate::vk::ImageDesc::alias_format`]).
    SampledAlias(&'a Image, &'a Sampler),
    /// One mip level of an image, in GENERAL layout.
    StorageImage(&'a Image, u32),
}

struct ShaderModule<'a> {
    shared: &'a Shared,
    raw: vk::ShaderModule,
}

impl Drop for ShaderModule<'_> {
    fn drop(&mut self) {
        unsafe { self.shared.device.destroy_shader_module(self.raw, None) };
    }
}

fn module<'a>(
    shared: &'a Shared,
    shader: &Shader,
    expect: Stage,
) -> crate::Result<ShaderModule<'a>> {
    if shader.stage != expect {
        return Err(Error::device(format!(
            "shader {} is a {:?} shader, used as {:?}",
            shader.name, shader.stage, expect
        )));
    }
    module_of(shared, shader, shader.spirv)
}

/// `shader`'s SPIR-V for a pipeline with `constants` on this device: on a CPU device with the
/// constants applied first ([`super::specialize`]); None where the module goes as it is (a GPU,
/// or where that cannot be done).
fn specialized_spirv(
    shared: &Shared,
    shader: &Shader,
    constants: &[(u32, u32)],
) -> Option<std::sync::Arc<Vec<u8>>> {
    if !shared.info.is_cpu() {
        return None;
    }
    super::specialize::specialize(shader.name, shader.spirv, constants)
}

/// The module of `shader`, of `specialized` (its [`specialized_spirv`]) when there is one.
fn module_for<'a>(
    shared: &'a Shared,
    shader: &Shader,
    expect: Stage,
    specialized: Option<&[u8]>,
) -> crate::Result<ShaderModule<'a>> {
    match specialized {
        Some(spirv) if shader.stage == expect => module_of(shared, shader, spirv),
        _ => module(shared, shader, expect),
    }
}

/// A module of `spirv`, `shader`'s code or a specialisation of it.
fn module_of<'a>(
    shared: &'a Shared,
    shader: &Shader,
    spirv: &[u8],
) -> crate::Result<ShaderModule<'a>> {
    let words = ash::util::read_spv(&mut std::io::Cursor::new(spirv)).map_err(|e| {
        Error::device(format!(
            "embedded SPIR-V of {} is malformed: {e}",
            shader.name
        ))
    })?;
    let info = vk::ShaderModuleCreateInfo::default().code(&words);
    let raw = unsafe { shared.device.create_shader_module(&info, None) }
        .map_err(vkerr("vkCreateShaderModule"))?;
    Ok(ShaderModule { shared, raw })
}

struct Specialization {
    entries: Vec<vk::SpecializationMapEntry>,
    data: Vec<u8>,
}

fn specialization(constants: &[(u32, u32)]) -> Specialization {
    let mut entries = Vec::new();
    let mut data = Vec::new();
    for (i, &(id, value)) in constants.iter().enumerate() {
        entries.push(vk::SpecializationMapEntry {
            constant_id: id,
            offset: (i * 4) as u32,
            size: 4,
        });
        data.extend_from_slice(&value.to_ne_bytes());
    }
    Specialization { entries, data }
}

/// The specialization constant ids `shaders` declare, reflected from their SPIR-V: what a
/// pipeline of them may specialise (a module compiled with a constant fixed no longer declares
/// it, nor those only its compiled-out code read).
pub fn spec_constant_ids(shaders: &[&Shader]) -> crate::Result<Vec<u32>> {
    let mut ids = Vec::new();
    for shader in shaders {
        ids.extend(
            crate::reflect::reflect(shader.spirv)?
                .spec_constants
                .iter()
                .map(|c| c.id),
        );
    }
    Ok(ids)
}

/// The bindings of each descriptor set `shaders` declare (index: the set number), reflected from
/// their SPIR-V, each shader read once: each binding once, visible to every stage that declares
/// it. A binding two stages declare with different kinds, or a kind weft does not bind, is an
/// error naming both.
pub fn reflected_bindings(shaders: &[&Shader]) -> crate::Result<Vec<Vec<Binding>>> {
    use crate::reflect::DescriptorKind as K;
    let mut sets: Vec<Vec<Binding>> = Vec::new();
    for shader in shaders {
        let stage = match shader.stage {
            Stage::Vertex => vk::ShaderStageFlags::VERTEX,
            Stage::Fragment => vk::ShaderStageFlags::FRAGMENT,
            Stage::Compute => vk::ShaderStageFlags::COMPUTE,
        };
        let reflection = crate::reflect::reflect(shader.spirv)?;
        for b in &reflection.bindings {
            let set = b.set;
            let kind = match b.kind {
                K::UniformBuffer => BindingKind::UniformBuffer,
                K::StorageBuffer => BindingKind::StorageBuffer,
                K::CombinedImageSampler => BindingKind::SampledImage,
                K::StorageImage => BindingKind::StorageImage,
                other => {
                    return Err(Error::device(format!(
                        "{} declares set {set} binding {} as {}, which weft does not bind",
                        shader.name,
                        b.binding,
                        other.name()
                    )))
                }
            };
            if sets.len() <= set as usize {
                sets.resize_with(set as usize + 1, Vec::new);
            }
            let out = &mut sets[set as usize];
            match out.iter_mut().find(|o| o.binding == b.binding) {
                Some(o) if o.kind != kind => {
                    return Err(Error::device(format!(
                        "set {set} binding {} is a {:?} in one stage and a {kind:?} in {}",
                        b.binding, o.kind, shader.name
                    )))
                }
                Some(o) => o.stages = Stages(o.stages.0 | stage),
                None => out.push(Binding {
                    binding: b.binding,
                    kind,
                    stages: Stages(stage),
                }),
            }
        }
    }
    for set in &mut sets {
        set.sort_by_key(|b| b.binding);
    }
    Ok(sets)
}

impl Context {
    /// The `N` descriptor set layouts of a pipeline made of `shaders` (sets 0 to N - 1), from
    /// their reflection ([`reflected_bindings`]): the GLSL declaration is the one place a binding
    /// is written. Shaders that declare another number of sets are an error.
    pub fn reflected_set_layouts<const N: usize>(
        &self,
        shaders: &[&Shader],
    ) -> crate::Result<[SetLayout; N]> {
        let sets = reflected_bindings(shaders)?;
        if sets.len() != N {
            let names: Vec<&str> = shaders.iter().map(|s| s.name).collect();
            return Err(Error::device(format!(
                "{names:?} declare {} descriptor set(s), the pass expects {N}",
                sets.len()
            )));
        }
        let layouts = sets
            .iter()
            .map(|b| self.create_set_layout(b))
            .collect::<crate::Result<Vec<_>>>()?;
        Ok(layouts
            .try_into()
            .unwrap_or_else(|_| unreachable!("N layouts for N sets")))
    }

    pub fn create_set_layout(&self, bindings: &[Binding]) -> crate::Result<SetLayout> {
        let vk_bindings: Vec<_> = bindings
            .iter()
            .map(|b| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b.binding)
                    .descriptor_type(b.kind.vk())
                    .descriptor_count(1)
                    .stage_flags(b.stages.0)
            })
            .collect();
        let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&vk_bindings);
        let raw = unsafe { self.shared.device.create_descriptor_set_layout(&info, None) }
            .map_err(vkerr("vkCreateDescriptorSetLayout"))?;
        Ok(SetLayout {
            shared: self.shared.clone(),
            raw,
            bindings: bindings.to_vec(),
        })
    }

    fn pipeline_layout(
        &self,
        sets: &[&SetLayout],
        push_size: u32,
        stages: vk::ShaderStageFlags,
    ) -> crate::Result<vk::PipelineLayout> {
        let raw_sets: Vec<_> = sets.iter().map(|s| s.raw).collect();
        let ranges = [vk::PushConstantRange {
            stage_flags: stages,
            offset: 0,
            size: push_size,
        }];
        let mut info = vk::PipelineLayoutCreateInfo::default().set_layouts(&raw_sets);
        if push_size > 0 {
            info = info.push_constant_ranges(&ranges);
        }
        unsafe { self.shared.device.create_pipeline_layout(&info, None) }
            .map_err(vkerr("vkCreatePipelineLayout"))
    }

    pub fn create_graphics_pipeline(&self, desc: &GraphicsDesc) -> crate::Result<Pipeline> {
        // Specialised (a process of its own, on a CPU device) before the compiler is taken, so
        // that one thread's optimizer runs while another's pipeline compiles.
        let specialized = specialized_spirv(&self.shared, desc.fragment, desc.constants);
        let _compiling = self.shared.compile_lock()?;
        let device = &self.shared.device;
        let vs = module(&self.shared, desc.vertex, Stage::Vertex)?;
        let fs = module_for(
            &self.shared,
            desc.fragment,
            Stage::Fragment,
            specialized.as_deref().map(Vec::as_slice),
        )?;
        let spec = specialization(desc.constants);
        let spec_info = vk::SpecializationInfo::default()
            .map_entries(&spec.entries)
            .data(&spec.data);
        let stages = [
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::VERTEX)
                .module(vs.raw)
                .name(c"main")
                .specialization_info(&spec_info),
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::FRAGMENT)
                .module(fs.raw)
                .name(c"main")
                .specialization_info(&spec_info),
        ];
        let (vbind, vattrs) = match &desc.vertex_layout {
            Some(l) => (
                vec![vk::VertexInputBindingDescription {
                    binding: 0,
                    stride: l.stride,
                    input_rate: vk::VertexInputRate::VERTEX,
                }],
                l.attributes
                    .iter()
                    .map(
                        |&(location, format, offset)| vk::VertexInputAttributeDescription {
                            location,
                            binding: 0,
                            format,
                            offset,
                        },
                    )
                    .collect(),
            ),
            None => (vec![], vec![]),
        };
        let vertex_input = vk::PipelineVertexInputStateCreateInfo::default()
            .vertex_binding_descriptions(&vbind)
            .vertex_attribute_descriptions(&vattrs);
        let assembly =
            vk::PipelineInputAssemblyStateCreateInfo::default().topology(match desc.topology {
                Topology::Triangles => vk::PrimitiveTopology::TRIANGLE_LIST,
                Topology::Lines => vk::PrimitiveTopology::LINE_LIST,
                Topology::Points => vk::PrimitiveTopology::POINT_LIST,
            });
        let viewport = vk::PipelineViewportStateCreateInfo::default()
            .viewport_count(1)
            .scissor_count(1);
        // glTF front faces are counter-clockwise. The projection flips Y (Vulkan clip space is
        // Y-down), and Vulkan's facing test is defined in that Y-down framebuffer space, so
        // counter-clockwise stays front.
        let raster = vk::PipelineRasterizationStateCreateInfo::default()
            .polygon_mode(vk::PolygonMode::FILL)
            .cull_mode(vk::CullModeFlags::BACK)
            .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
            .line_width(1.0);
        let multisample = vk::PipelineMultisampleStateCreateInfo::default()
            .rasterization_samples(vk::SampleCountFlags::TYPE_1);
        let stencil_op = |compare: vk::CompareOp, pass: vk::StencilOp, tested: u32, write: u32| {
            vk::StencilOpState::default()
                .fail_op(vk::StencilOp::KEEP)
                .pass_op(pass)
                .depth_fail_op(vk::StencilOp::KEEP)
                .compare_op(compare)
                .compare_mask(tested)
                .write_mask(write)
        };
        let tests_depth = desc.depth_format.is_some()
            && matches!(desc.stencil, StencilMode::None | StencilMode::Write);
        let mut depth = vk::PipelineDepthStencilStateCreateInfo::default()
            .depth_test_enable(tests_depth)
            .depth_write_enable(tests_depth && !desc.blend && desc.depth_test != DepthTest::Farther)
            .depth_compare_op(match desc.depth_test {
                DepthTest::Nearer => vk::CompareOp::GREATER,
                DepthTest::NearerOrEqual => vk::CompareOp::GREATER_OR_EQUAL,
                DepthTest::Always => vk::CompareOp::ALWAYS,
                DepthTest::Farther => vk::CompareOp::LESS,
            });
        let with_stencil = desc.depth_format.is_some_and(super::resources::has_stencil);
        match desc.stencil {
            StencilMode::None => {}
            StencilMode::Write => {
                let op = stencil_op(vk::CompareOp::ALWAYS, vk::StencilOp::REPLACE, 0xff, 0xff);
                depth = depth.stencil_test_enable(true).front(op).back(op);
            }
            StencilMode::Equal => {
                let op = stencil_op(vk::CompareOp::EQUAL, vk::StencilOp::KEEP, 0xff, 0);
                depth = depth.stencil_test_enable(true).front(op).back(op);
            }
            StencilMode::MarkBits(bits) => {
                let op = stencil_op(vk::CompareOp::ALWAYS, vk::StencilOp::REPLACE, 0, bits);
                depth = depth.stencil_test_enable(true).front(op).back(op);
            }
            StencilMode::BitsClear(bits) => {
                // (stencil & bits) == (reference & bits), the reference 0.
                let op = stencil_op(vk::CompareOp::EQUAL, vk::StencilOp::KEEP, bits, 0);
                depth = depth.stencil_test_enable(true).front(op).back(op);
            }
        }
        if desc.stencil != StencilMode::None && !with_stencil {
            return Err(Error::device(format!(
                "pipeline {}: a stencil mode without a depth-stencil format",
                desc.name
            )));
        }
        let attachments: Vec<_> = desc
            .color_formats
            .iter()
            .map(|_| {
                let state = vk::PipelineColorBlendAttachmentState::default()
                    .color_write_mask(vk::ColorComponentFlags::RGBA);
                if desc.blend {
                    state
                        .blend_enable(true)
                        .src_color_blend_factor(vk::BlendFactor::ONE)
                        .dst_color_blend_factor(vk::BlendFactor::ONE_MINUS_SRC_ALPHA)
                        .color_blend_op(vk::BlendOp::ADD)
                        .src_alpha_blend_factor(vk::BlendFactor::ONE)
                        .dst_alpha_blend_factor(vk::BlendFactor::ONE_MINUS_SRC_ALPHA)
                        .alpha_blend_op(vk::BlendOp::ADD)
                } else {
                    state
                }
            })
            .collect();
        let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&attachments);
        let mut dynamic_states = vec![
            vk::DynamicState::VIEWPORT,
            vk::DynamicState::SCISSOR,
            vk::DynamicState::CULL_MODE,
            // Per draw: a node whose world transform mirrors (negative determinant) has clockwise
            // front faces (glTF 2.0, "Instantiation").
            vk::DynamicState::FRONT_FACE,
        ];
        if desc.stencil != StencilMode::None {
            dynamic_states.push(vk::DynamicState::STENCIL_REFERENCE);
        }
        let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
        let mut rendering = vk::PipelineRenderingCreateInfo::default()
            .color_attachment_formats(desc.color_formats)
            .depth_attachment_format(desc.depth_format.unwrap_or(vk::Format::UNDEFINED))
            .stencil_attachment_format(if with_stencil {
                desc.depth_format.unwrap_or(vk::Format::UNDEFINED)
            } else {
                vk::Format::UNDEFINED
            });
        let layout = self.pipeline_layout(
            desc.set_layouts,
            desc.push_constant_size,
            desc.push_stages.0,
        )?;
        let info = vk::GraphicsPipelineCreateInfo::default()
            .stages(&stages)
            .vertex_input_state(&vertex_input)
            .input_assembly_state(&assembly)
            .viewport_state(&viewport)
            .rasterization_state(&raster)
            .multisample_state(&multisample)
            .depth_stencil_state(&depth)
            .color_blend_state(&blend)
            .dynamic_state(&dynamic)
            .layout(layout)
            .push_next(&mut rendering);
        let raw = match unsafe {
            device.create_graphics_pipelines(self.shared.pipeline_cache, &[info], None)
        } {
            Ok(p) => p[0],
            Err((_, e)) => {
                unsafe { device.destroy_pipeline_layout(layout, None) };
                return Err(vkerr("vkCreateGraphicsPipelines")(e));
            }
        };
        Ok(Pipeline {
            shared: self.shared.clone(),
            raw,
            layout,
            bind_point: vk::PipelineBindPoint::GRAPHICS,
            push_stages: desc.push_stages.0,
            name: desc.name.into(),
            shaders: vec![desc.vertex.name, desc.fragment.name],
            sets: desc
                .set_layouts
                .iter()
                .map(|s| s.bindings.clone())
                .collect(),
            push_constant_size: desc.push_constant_size,
            constants: desc.constants.to_vec(),
        })
    }

    pub fn create_compute_pipeline(&self, desc: &ComputeDesc) -> crate::Result<Pipeline> {
        let specialized = specialized_spirv(&self.shared, desc.shader, desc.constants);
        let _compiling = self.shared.compile_lock()?;
        let device = &self.shared.device;
        let cs = module_for(
            &self.shared,
            desc.shader,
            Stage::Compute,
            specialized.as_deref().map(Vec::as_slice),
        )?;
        let spec = specialization(desc.constants);
        let spec_info = vk::SpecializationInfo::default()
            .map_entries(&spec.entries)
            .data(&spec.data);
        let stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(cs.raw)
            .name(c"main")
            .specialization_info(&spec_info);
        let layout = self.pipeline_layout(
            desc.set_layouts,
            desc.push_constant_size,
            vk::ShaderStageFlags::COMPUTE,
        )?;
        let info = vk::ComputePipelineCreateInfo::default()
            .stage(stage)
            .layout(layout);
        let raw = match unsafe {
            device.create_compute_pipelines(self.shared.pipeline_cache, &[info], None)
        } {
            Ok(p) => p[0],
            Err((_, e)) => {
                unsafe { device.destroy_pipeline_layout(layout, None) };
                return Err(vkerr("vkCreateComputePipelines")(e));
            }
        };
        Ok(Pipeline {
            shared: self.shared.clone(),
            raw,
            layout,
            bind_point: vk::PipelineBindPoint::COMPUTE,
            push_stages: vk::ShaderStageFlags::COMPUTE,
            name: desc.name.into(),
            shaders: vec![desc.shader.name],
            sets: desc
                .set_layouts
                .iter()
                .map(|s| s.bindings.clone())
                .collect(),
            push_constant_size: desc.push_constant_size,
            constants: desc.constants.to_vec(),
        })
    }

    /// A pool with room for `max_sets` sets of up to 16 bindings of each kind.
    pub fn create_descriptor_pool(&self, max_sets: u32) -> crate::Result<DescriptorPool> {
        let n = max_sets.max(1) * 16;
        let sizes = [
            vk::DescriptorPoolSize {
                ty: vk::DescriptorType::UNIFORM_BUFFER,
                descriptor_count: n,
            },
            vk::DescriptorPoolSize {
                ty: vk::DescriptorType::STORAGE_BUFFER,
                descriptor_count: n,
            },
            vk::DescriptorPoolSize {
                ty: vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
                descriptor_count: n,
            },
            vk::DescriptorPoolSize {
                ty: vk::DescriptorType::STORAGE_IMAGE,
                descriptor_count: n,
            },
        ];
        let info = vk::DescriptorPoolCreateInfo::default()
            .max_sets(max_sets.max(1))
            .pool_sizes(&sizes);
        let raw = unsafe { self.shared.device.create_descriptor_pool(&info, None) }
            .map_err(vkerr("vkCreateDescriptorPool"))?;
        Ok(DescriptorPool {
            shared: self.shared.clone(),
            raw,
            lock: std::sync::Mutex::new(()),
        })
    }
}

impl DescriptorPool {
    /// Allocates a set of `layout` and writes `resources` (binding, resource) into it.
    ///
    /// The set borrows the pool and the resources for `'r` (see [`DescriptorSet`]).
    pub fn set<'r>(
        &'r self,
        layout: &SetLayout,
        resources: &[(u32, Resource<'r>)],
    ) -> crate::Result<DescriptorSet<'r>> {
        let _pool = self
            .lock
            .lock()
            .map_err(|_| Error::device("descriptor pool lock poisoned"))?;
        for (binding, r) in resources {
            if let Resource::SampledAlias(img, _) = r {
                if img.alias_view == vk::ImageView::null() {
                    return Err(Error::device(format!(
                        "binding {binding}: image '{}' has no alias format to be sampled as",
                        img.desc.name
                    )));
                }
            }
            if let Resource::StorageImage(img, level) = r {
                if *level >= img.desc.mip_levels {
                    return Err(Error::device(format!(
                        "binding {binding}: mip level {level} of image '{}', which has {}",
                        img.desc.name, img.desc.mip_levels
                    )));
                }
            }
        }
        let layouts = [layout.raw];
        let info = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(self.raw)
            .set_layouts(&layouts);
        let raw = unsafe { self.shared.device.allocate_descriptor_sets(&info) }
            .map_err(vkerr("vkAllocateDescriptorSets"))?[0];
        let mut buffer_infos = Vec::new();
        let mut image_infos = Vec::new();
        for (_, r) in resources {
            match r {
                Resource::Uniform(b) | Resource::Storage(b) => {
                    buffer_infos.push([vk::DescriptorBufferInfo {
                        buffer: b.raw,
                        offset: 0,
                        range: vk::WHOLE_SIZE,
                    }])
                }
                Resource::Sampled(img, s) => image_infos.push([vk::DescriptorImageInfo {
                    sampler: s.raw,
                    image_view: img.view,
                    image_layout: img.layout_for(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL),
                }]),
                Resource::SampledAlias(img, s) => image_infos.push([vk::DescriptorImageInfo {
                    sampler: s.raw,
                    image_view: img.alias_view,
                    image_layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                }]),
                Resource::StorageImage(img, level) => image_infos.push([vk::DescriptorImageInfo {
                    sampler: vk::Sampler::null(),
                    image_view: if img.mip_views.is_empty() {
                        img.view
                    } else {
                        img.mip_views[*level as usize]
                    },
                    image_layout: vk::ImageLayout::GENERAL,
                }]),
            }
        }
        let (mut bi, mut ii) = (0, 0);
        let mut writes = Vec::new();
        for (binding, r) in resources {
            let w = vk::WriteDescriptorSet::default()
                .dst_set(raw)
                .dst_binding(*binding);
            let w = match r {
                Resource::Uniform(_) => {
                    bi += 1;
                    w.descriptor_type(vk::DescriptorType::UNIFORM_BUFFER)
                        .buffer_info(&buffer_infos[bi - 1])
                }
                Resource::Storage(_) => {
                    bi += 1;
                    w.descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                        .buffer_info(&buffer_infos[bi - 1])
                }
                Resource::Sampled(..) | Resource::SampledAlias(..) => {
                    ii += 1;
                    w.descriptor_type(vk::DescriptorType::COMBINED_IMAGE_SAMPLER)
                        .image_info(&image_infos[ii - 1])
                }
                Resource::StorageImage(..) => {
                    ii += 1;
                    w.descriptor_type(vk::DescriptorType::STORAGE_IMAGE)
                        .image_info(&image_infos[ii - 1])
                }
            };
            writes.push(w);
        }
        unsafe { self.shared.device.update_descriptor_sets(&writes, &[]) };
        Ok(DescriptorSet {
            raw,
            _resources: std::marker::PhantomData,
        })
    }
}
