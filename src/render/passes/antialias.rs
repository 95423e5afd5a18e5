//! The anti-aliasing pass (`--aa fxaa`): edge anti-aliasing of the tone-mapped image
//! (fullscreen.vert, fxaa.frag), which the tone-map pass then writes into `targets.tonemapped`
//! instead of the output.

use std::sync::OnceLock;

use super::Recorded;
use crate::render::targets::{Targets, LDR_FORMAT};
use crate::vk::{
    shaders, Context, DepthTest, DescriptorPool, GraphicsDesc, Pipeline, Resource, Sampler,
    SetLayout, Stages, StencilMode, Topology, Usage,
};

/// The pass's set layout (reflected from fxaa.frag) and its pipeline, made by the first frame
/// that plans the pass.
pub struct AntialiasPass {
    layout: SetLayout,
    pipeline: OnceLock<Pipeline>,
}

/// What the pass reads; it writes the 8-bit output target.
pub struct AntialiasInputs<'s> {
    /// `targets.tonemapped` is read, linear-filtered and clamped with `sampler`: decoded (its
    /// view) for the colour, encoded (its UNORM alias view) for the luma.
    pub targets: &'s Targets,
    pub sampler: &'s Sampler,
}

impl AntialiasPass {
    pub fn new(ctx: &Context) -> crate::Result<AntialiasPass> {
        let [layout] =
            ctx.reflected_set_layouts(&[&shaders::FULLSCREEN_VERT, &shaders::FXAA_FRAG])?;
        Ok(AntialiasPass {
            layout,
            pipeline: OnceLock::new(),
        })
    }

    /// Makes the pipeline once.
    pub fn make(&self, ctx: &Context) -> crate::Result<()> {
        if self.pipeline.get().is_none() {
            let _ = self
                .pipeline
                .set(ctx.create_graphics_pipeline(&GraphicsDesc {
                    name: "antialias[fxaa]",
                    vertex: &shaders::FULLSCREEN_VERT,
                    fragment: &shaders::FXAA_FRAG,
                    vertex_layout: None,
                    color_formats: &[LDR_FORMAT],
                    depth_format: None,
                    set_layouts: &[&self.layout],
                    push_constant_size: 0,
                    push_stages: Stages::FRAGMENT,
                    constants: &[],
                    blend: false,
                    topology: Topology::Triangles,
                    stencil: StencilMode::None,
                    depth_test: DepthTest::Nearer,
                })?);
        }
        Ok(())
    }

    pub fn pipeline(&self) -> Option<&Pipeline> {
        self.pipeline.get()
    }

    pub fn record<'s>(
        &'s self,
        pool: &'s DescriptorPool,
        inputs: AntialiasInputs<'s>,
    ) -> crate::Result<Recorded<'s>> {
        let pipeline = self
            .pipeline
            .get()
            .expect("the frame makes the pipeline when it plans the pass");
        let t = inputs.targets;
        let source = t
            .tonemapped
            .as_ref()
            .expect("the frame makes the tone-mapped target when it plans this pass");
        let set = pool.set(
            &self.layout,
            &[
                (0, Resource::Sampled(source, inputs.sampler)),
                (1, Resource::SampledAlias(source, inputs.sampler)),
            ],
        )?;
        Ok(Recorded::new(
            "antialias",
            vec![pipeline.name.clone()],
            move |cmd| {
                cmd.transition(source, Usage::ColorAttachment, Usage::FragmentRead, None);
                super::fullscreen::<u32>(cmd, pipeline, set, None, &t.ldr);
            },
        ))
    }
}
