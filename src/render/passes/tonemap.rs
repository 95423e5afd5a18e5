//! The tonemap pass: exposure and tone curve from HDR into the 8-bit target
//! (fullscreen.vert, tonemap.frag).

use super::Recorded;
use crate::render::gpu::TonemapPush;
use crate::render::targets::{Targets, LDR_FORMAT};
use crate::vk::{
    shaders, Context, DescriptorPool, GraphicsDesc, Pipeline, Resource, Sampler, SetLayout, Stages,
    StencilMode, Topology,
};

/// The pass's pipeline and set layout (reflected from tonemap.frag).
pub struct TonemapPass {
    layout: SetLayout,
    pipeline: Pipeline,
}

/// What the pass reads and where it writes.
pub struct TonemapInputs<'s> {
    pub targets: &'s Targets,
    pub nearest: &'s Sampler,
    /// Exposure, curve, and whether a debug view passes through untouched.
    pub push: TonemapPush,
    /// The anti-aliasing pass follows: write `targets.tonemapped` for it (else the output).
    pub antialiased: bool,
}

impl TonemapPass {
    pub fn new(ctx: &Context) -> crate::Result<TonemapPass> {
        let [layout] =
            ctx.reflected_set_layouts(&[&shaders::FULLSCREEN_VERT, &shaders::TONEMAP_FRAG])?;
        let pipeline = ctx.create_graphics_pipeline(&GraphicsDesc {
            name: "tonemap",
            vertex: &shaders::FULLSCREEN_VERT,
            fragment: &shaders::TONEMAP_FRAG,
            vertex_layout: None,
            color_formats: &[LDR_FORMAT],
            depth_format: None,
            set_layouts: &[&layout],
            push_constant_size: std::mem::size_of::<TonemapPush>() as u32,
            push_stages: Stages::FRAGMENT,
            constants: &[],
            blend: false,
            topology: Topology::Triangles,
            stencil: StencilMode::None,
        })?;
        Ok(TonemapPass { layout, pipeline })
    }

    pub fn pipeline(&self) -> &Pipeline {
        &self.pipeline
    }

    /// Reads HDR, writes the display-referred 8-bit image.
    pub fn record<'s>(
        &'s self,
        pool: &'s DescriptorPool,
        inputs: TonemapInputs<'s>,
    ) -> crate::Result<Recorded<'s>> {
        let t = inputs.targets;
        let set = pool.set(
            &self.layout,
            &[(0, Resource::Sampled(&t.hdr, inputs.nearest))],
        )?;
        let target = match (&t.tonemapped, inputs.antialiased) {
            (Some(i), true) => i,
            _ => &t.ldr,
        };
        let push = inputs.push;
        let pipeline = &self.pipeline;
        Ok(Recorded::new(
            "tonemap",
            vec![pipeline.name.clone()],
            move |cmd| super::fullscreen(cmd, pipeline, set, Some(&push), target),
        ))
    }
}
