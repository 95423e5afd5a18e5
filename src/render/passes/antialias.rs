//! The anti-aliasing pass (`--aa fxaa`): edge anti-aliasing of the tone-mapped image
//! (fullscreen.vert, fxaa.frag), which the tone-map pass then writes into `targets.tonemapped`
//! instead of the output.
//!
//! Where the G-buffer's depth has a stencil ([`Plan::antialias_edge_blocks`]), the pass draws
//! twice: fxaa_flat.frag copies every pixel off an edge and marks it in the stencil
//! ([`EDGE_MARK`], a bit the G-buffer's kinds leave free), then fxaa.frag runs where no mark
//! is. On lavapipe a shader costs all its code whatever branch a pixel takes, and a 4 x 4 block
//! the stencil test rejects everywhere is skipped: the edge search then runs on the blocks that
//! hold an edge, not on every pixel. The image is the same as one draw of fxaa.frag everywhere
//! (`Force::fxaa_everywhere`; tests/plan.rs).
//!
//! [`Plan::antialias_edge_blocks`]: crate::render::Plan::antialias_edge_blocks

use std::sync::OnceLock;

use super::Recorded;
use crate::render::targets::{depth_format, Targets, LDR_FORMAT};
use crate::vk::{
    shaders, Attachment, Context, DepthTest, DescriptorPool, GraphicsDesc, Load, Pipeline,
    Resource, Sampler, SetLayout, Shader, Stages, StencilMode, Topology, Usage,
};

/// The stencil bit the first draw sets on every pixel off an edge (the G-buffer writes each
/// pixel's kind of material in the low bits: `passes::gbuffer`).
pub const EDGE_MARK: u32 = 0x80;

/// The pass's set layout (reflected from fxaa.frag; fxaa_flat.frag reads the same bindings) and
/// its pipelines, made by the first frame that plans the pass: fxaa.frag over every pixel, and
/// the two draws over the stencil.
pub struct AntialiasPass {
    layout: SetLayout,
    everywhere: OnceLock<Pipeline>,
    flat: OnceLock<Pipeline>,
    edges: OnceLock<Pipeline>,
}

/// What the pass reads; it writes the 8-bit output target.
pub struct AntialiasInputs<'s> {
    /// `targets.tonemapped` is read, linear-filtered and clamped with `sampler`: decoded (its
    /// view) for the colour, encoded (its UNORM alias view) for the luma. With `edge_blocks`,
    /// `targets.depth`'s stencil is marked (it must have one).
    pub targets: &'s Targets,
    pub sampler: &'s Sampler,
    /// The two draws over the stencil, else fxaa.frag everywhere.
    pub edge_blocks: bool,
}

impl AntialiasPass {
    pub fn new(ctx: &Context) -> crate::Result<AntialiasPass> {
        let [layout] =
            ctx.reflected_set_layouts(&[&shaders::FULLSCREEN_VERT, &shaders::FXAA_FRAG])?;
        Ok(AntialiasPass {
            layout,
            everywhere: OnceLock::new(),
            flat: OnceLock::new(),
            edges: OnceLock::new(),
        })
    }

    fn pipeline_desc<'a>(
        ctx: &Context,
        layouts: &'a [&'a SetLayout],
        name: &'a str,
        fragment: &'a Shader,
        stencil: StencilMode,
    ) -> GraphicsDesc<'a> {
        GraphicsDesc {
            name,
            vertex: &shaders::FULLSCREEN_VERT,
            fragment,
            vertex_layout: None,
            color_formats: &[LDR_FORMAT],
            depth_format: (stencil != StencilMode::None).then(|| depth_format(ctx)),
            set_layouts: layouts,
            push_constant_size: 0,
            push_stages: Stages::FRAGMENT,
            constants: &[],
            blend: false,
            topology: Topology::Triangles,
            stencil,
            depth_test: DepthTest::Nearer,
        }
    }

    /// Makes the pipelines the pass draws with, once: with `edge_blocks` the two over the
    /// stencil, else the one everywhere.
    pub fn make(&self, ctx: &Context, edge_blocks: bool) -> crate::Result<()> {
        let layouts = [&self.layout];
        let make = |cell: &OnceLock<Pipeline>, desc: GraphicsDesc| -> crate::Result<()> {
            if cell.get().is_none() {
                let _ = cell.set(ctx.create_graphics_pipeline(&desc)?);
            }
            Ok(())
        };
        if edge_blocks {
            make(
                &self.flat,
                Self::pipeline_desc(
                    ctx,
                    &layouts,
                    "antialias[fxaa, off edges]",
                    &shaders::FXAA_FLAT_FRAG,
                    StencilMode::MarkBits(EDGE_MARK),
                ),
            )?;
            make(
                &self.edges,
                Self::pipeline_desc(
                    ctx,
                    &layouts,
                    "antialias[fxaa, edge blocks]",
                    &shaders::FXAA_FRAG,
                    StencilMode::BitsClear(EDGE_MARK),
                ),
            )
        } else {
            make(
                &self.everywhere,
                Self::pipeline_desc(
                    ctx,
                    &layouts,
                    "antialias[fxaa]",
                    &shaders::FXAA_FRAG,
                    StencilMode::None,
                ),
            )
        }
    }

    /// The pipelines made so far.
    pub fn pipelines(&self) -> Vec<&Pipeline> {
        [&self.everywhere, &self.flat, &self.edges]
            .into_iter()
            .filter_map(OnceLock::get)
            .collect()
    }

    pub fn record<'s>(
        &'s self,
        pool: &'s DescriptorPool,
        inputs: AntialiasInputs<'s>,
    ) -> crate::Result<Recorded<'s>> {
        let made = "the frame makes the pass's pipelines when it plans the pass";
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
        if !inputs.edge_blocks {
            let pipeline = self.everywhere.get().expect(made);
            return Ok(Recorded::new(
                "antialias",
                vec![pipeline.name.clone()],
                move |cmd| {
                    cmd.transition(source, Usage::ColorAttachment, Usage::FragmentRead, None);
                    super::fullscreen::<u32>(cmd, pipeline, set, None, &t.ldr);
                },
            ));
        }
        let (flat, edges) = (self.flat.get().expect(made), self.edges.get().expect(made));
        Ok(Recorded::new(
            "antialias",
            vec![flat.name.clone(), edges.name.clone()],
            move |cmd| {
                cmd.transition(source, Usage::ColorAttachment, Usage::FragmentRead, None);
                cmd.transition(&t.ldr, Usage::Undefined, Usage::ColorAttachment, None);
                cmd.transition(&t.depth, Usage::FragmentRead, Usage::DepthAttachment, None);
                // Every pixel is written by one of the two draws.
                cmd.begin_rendering(
                    &[Attachment {
                        image: &t.ldr,
                        load: Load::Undefined,
                    }],
                    Some(Attachment {
                        image: &t.depth,
                        load: Load::Keep,
                    }),
                );
                cmd.bind_pipeline(flat);
                cmd.bind_sets(flat, 0, &[set]);
                cmd.set_stencil_reference(EDGE_MARK);
                cmd.draw(3);
                cmd.bind_pipeline(edges);
                cmd.bind_sets(edges, 0, &[set]);
                cmd.set_stencil_reference(0);
                cmd.draw(3);
                cmd.end_rendering();
                cmd.transition(&t.depth, Usage::DepthAttachment, Usage::FragmentRead, None);
            },
        ))
    }
}
