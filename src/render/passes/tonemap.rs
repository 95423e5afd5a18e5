//! The tonemap pass: exposure and tone curve from HDR into the 8-bit target
//! (fullscreen.vert, tonemap.frag).

use std::sync::OnceLock;

use super::Recorded;
use crate::render::gpu::TonemapPush;
use crate::render::targets::{Targets, LDR_FORMAT};
use crate::render::{DebugView, RenderOptions};
use crate::vk::{
    shaders, Context, DepthTest, DescriptorPool, GraphicsDesc, Pipeline, Resource, Sampler,
    SetLayout, Stages, StencilMode, Topology,
};

/// tonemap.frag's CURVE for a debug view: no exposure, no curve.
pub const CURVE_PASSTHROUGH: u32 = 4;

/// The pass's set layout (reflected from tonemap.frag) and a pipeline per tone curve
/// (specialization constant 0, CURVE: llvmpipe runs every side of a branch on a uniform value,
/// so only the curve in use is compiled in), each made by the first frame that runs the pass
/// with it.
pub struct TonemapPass {
    layout: SetLayout,
    pipelines: [OnceLock<Pipeline>; CURVE_PASSTHROUGH as usize + 1],
}

/// What the pass reads and where it writes.
pub struct TonemapInputs<'s> {
    pub targets: &'s Targets,
    pub nearest: &'s Sampler,
    /// The exposure (the curve is [`TonemapPass::curve`]'s pipeline).
    pub push: TonemapPush,
    /// tonemap.frag's CURVE ([`TonemapPass::curve`]); its pipeline made by [`TonemapPass::make`].
    pub curve: u32,
    /// The anti-aliasing pass follows: write `targets.tonemapped` for it (else the output).
    pub antialiased: bool,
}

impl TonemapPass {
    pub fn new(ctx: &Context) -> crate::Result<TonemapPass> {
        let [layout] =
            ctx.reflected_set_layouts(&[&shaders::FULLSCREEN_VERT, &shaders::TONEMAP_FRAG])?;
        // No pipeline yet: a frame whose lighting pass tone-maps (nothing reads its HDR image:
        // `weft render` without --exr) never runs this pass; the frame makes its curve's pipeline
        // where the plan has the pass.
        Ok(TonemapPass {
            layout,
            pipelines: Default::default(),
        })
    }

    /// tonemap.frag's CURVE for `options`: the tone curve's code, or [`CURVE_PASSTHROUGH`] for a
    /// debug view.
    pub fn curve(options: &RenderOptions) -> u32 {
        if options.debug_view != DebugView::None {
            CURVE_PASSTHROUGH
        } else {
            options.tonemap.code()
        }
    }

    /// Makes the pipeline of `curve` once.
    pub fn make(&self, ctx: &Context, curve: u32) -> crate::Result<()> {
        let slot = &self.pipelines[curve.min(CURVE_PASSTHROUGH) as usize];
        if slot.get().is_none() {
            let pipeline = ctx.create_graphics_pipeline(&GraphicsDesc {
                name: &format!("tonemap[CURVE={curve}]"),
                vertex: &shaders::FULLSCREEN_VERT,
                fragment: &shaders::TONEMAP_FRAG,
                vertex_layout: None,
                color_formats: &[LDR_FORMAT],
                depth_format: None,
                set_layouts: &[&self.layout],
                push_constant_size: std::mem::size_of::<TonemapPush>() as u32,
                push_stages: Stages::FRAGMENT,
                constants: &[(0, curve)],
                blend: false,
                topology: Topology::Triangles,
                stencil: StencilMode::None,
                depth_test: DepthTest::Nearer,
            })?;
            let _ = slot.set(pipeline);
        }
        Ok(())
    }

    /// Every curve's pipeline made so far.
    pub fn pipelines(&self) -> impl Iterator<Item = &Pipeline> {
        self.pipelines.iter().filter_map(|p| p.get())
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
            &[(0, Resource::Sampled(t.hdr(), inputs.nearest))],
        )?;
        let target = t.tone_mapped_target(inputs.antialiased);
        let push = inputs.push;
        let pipeline = self.pipelines[inputs.curve.min(CURVE_PASSTHROUGH) as usize]
            .get()
            .expect("the frame makes the tone curve's pipeline before recording");
        Ok(Recorded::new(
            "tonemap",
            vec![pipeline.name.clone()],
            move |cmd| super::fullscreen(cmd, pipeline, set, Some(&push), target),
        ))
    }
}
