//! The Vulkan layer: every `unsafe` call in weft lives in this module.
//!
//! - [`Context`]: loader, instance (+ validation layer and debug messenger when asked), device
//!   selection, device, queue, allocator.
//! - resources: buffers, images, samplers, timestamp queries; freed on Drop.
//! - pipelines and descriptors, described as plain values.
//! - [`Cmd`]: a safe command recorder and one-shot submission.
//!
//! Objects hold an `Arc` of the device, so the device is destroyed after all of them.

mod cmd;
mod context;
mod pipeline;
mod resources;
pub mod specialize;
mod swapchain;

pub use ash::vk::Format;
pub use ash::vk::{BufferUsageFlags, ImageUsageFlags};
pub use cmd::{Attachment, Cmd, Cull, InFlight, Load, Recording, Usage};
pub use context::{Context, ContextOptions, DeviceChoice, DeviceInfo};
pub use pipeline::spec_constant_ids;
pub use pipeline::{
    Binding, BindingKind, ComputeDesc, DepthTest, DescriptorPool, DescriptorSet, GraphicsDesc,
    Pipeline, Resource, SetLayout, Stages, StencilMode, Topology, VertexLayout,
};
pub use resources::{
    has_stencil, Address, Buffer, BufferLocation, Filter, Image, ImageDesc, QueryPool, Sampler,
    TextureSamplerDesc,
};
pub use swapchain::{PanelDraw, Presented, Presenter, FRAMES_IN_FLIGHT};

/// The pipeline stage a shader module is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    Vertex,
    Fragment,
    Compute,
}

/// A SPIR-V module compiled from `glsl/` by build.rs and embedded in the binary.
#[derive(Clone, Copy, Debug)]
pub struct Shader {
    /// The source file name, e.g. `lighting.frag`.
    pub name: &'static str,
    pub stage: Stage,
    /// SPIR-V bytes (little-endian words).
    pub spirv: &'static [u8],
    /// The GLSL it was compiled from (its `#include`s are `weft::package::INCLUDES`): the
    /// package reads each binding's prose from the comment at its declaration.
    pub source: &'static str,
}

/// Every shader module, by source file name (constants such as `shaders::LIGHTING_FRAG`).
pub mod shaders {
    use super::{Shader, Stage};
    include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
}
