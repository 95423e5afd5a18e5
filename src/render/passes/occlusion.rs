//! The occlusion pass (`--occlusion gtao`, planned when an environment lights the scene): how
//! open each pixel's hemisphere is, for the environment's light. Three fullscreen draws at half
//! resolution: the depth of each 2 x 2 block's top-left pixel (occlusion_depth.frag), the
//! ground-truth ambient occlusion estimate there from that depth and the G-buffer normal
//! (fullscreen.vert, occlusion.frag, turned per estimate by a 4 x 4 pattern), then
//! the mean of the 4 x 4 estimates around each on its own surface (occlusion_blur.frag), which
//! the lighting pass reads, bringing it to full resolution (lighting.frag's OCCLUSION and
//! screen_visibility). The depth copy also writes a half-resolution depth attachment, and the
//! estimates and the blur are drawn against it at the far plane (depth test LESS): only where a
//! surface is. On lavapipe, where a shader's early return skips nothing, that skips the empty
//! 4 x 4 blocks; the empty texels keep the targets' clear, which is what the shaders would write
//! there (`Force::occlusion_everywhere` draws them everywhere: the same image). The estimates and
//! the blur also write the occluders' bounced light (a second target; BOUNCE, `--occlusion gtao`),
//! from each half-resolution texel's light as an occluder, which the depth copy makes (a second
//! target of its own) from the G-buffer's albedo, normal, surface and fabric coverage, the
//! material and fabric records and the environment's prefiltered cube.

use std::sync::OnceLock;

use glam::{DMat4, Mat4};

use super::Recorded;
use crate::render::plan::OcclusionPlan;
use crate::render::targets::{
    Targets, OCCLUSION_BOUNCE_FORMAT, OCCLUSION_COVERAGE_FORMAT, OCCLUSION_DEPTH_FORMAT,
    OCCLUSION_FORMAT, OCCLUSION_LIGHT_FORMAT,
};
use crate::vk::{
    shaders, Attachment, Buffer, Context, DepthTest, DescriptorPool, GraphicsDesc, Load, Pipeline,
    Resource, Sampler, SetLayout, Stages, StencilMode, Topology, Usage,
};

/// occlusion.frag's push constants (80 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct OcclusionPush {
    /// The inverse of the frame's projection: view space from clip space.
    pub view_from_clip: [[f32; 4]; 4],
    /// x: the radius (world units), y and z: the falloff's scale and offset (the weight of an
    /// occluder at distance d is clamp(d·y + z, 0, 1): 1 to 40 % of the radius, 0 at it), w: 0.
    pub params: [f32; 4],
}

impl OcclusionPush {
    /// The share of the radius over which an occluder's weight falls from 1 to 0.
    pub const FALLOFF: f32 = 0.6;

    /// For a frame with projection `proj` (the frame uniform's, jittered if the frame is).
    pub fn new(proj: Mat4, radius: f32) -> OcclusionPush {
        // Inverted in f64: a reversed-Z infinite projection is badly conditioned in f32.
        let p = DMat4::from_cols_array(&proj.to_cols_array().map(f64::from));
        let inv = p.inverse().to_cols_array().map(|x| x as f32);
        let range = Self::FALLOFF * radius;
        let from = radius - range;
        OcclusionPush {
            view_from_clip: bytemuck::cast(inv),
            params: [radius, -1.0 / range, from / range + 1.0, 0.0],
        }
    }
}

/// The pass's three set layouts (reflected from occlusion_depth.frag, occlusion.frag and
/// occlusion_blur.frag) and its pipelines, made by the first frame that plans the pass: the
/// depth copy, then the estimates and the blur drawn where a surface is (against the copy's
/// depth attachment) or, forced, over every pixel; each without and with the bounce.
pub struct OcclusionPass {
    depth_layout: SetLayout,
    layout: SetLayout,
    blur_layout: SetLayout,
    pipelines: [OnceLock<[Pipeline; 3]>; 2],
    everywhere: [OnceLock<[Pipeline; 2]>; 2],
}

/// What the pass reads; it writes `targets.occlusion` (left readable by fragment shaders).
pub struct OcclusionInputs<'s> {
    /// The frame uniform (the projection, the view matrix for the normals, the viewport).
    pub frame: &'s Buffer,
    pub push: OcclusionPush,
    /// The G-buffer's depth and normals, fetched per pixel with `nearest`.
    pub targets: &'s Targets,
    pub nearest: &'s Sampler,
    /// The estimates and blur only where a surface is ([`OcclusionPlan::covered_only`]).
    pub covered_only: bool,
    /// The occluders' bounced light ([`OcclusionPlan::bounce`]), and what it reads: the
    /// material and fabric records and the environment's prefiltered cube with its sampler.
    pub bounce: bool,
    pub materials: &'s Buffer,
    pub fabrics: &'s Buffer,
    pub env_specular: &'s crate::vk::Image,
    pub env_sampler: &'s Sampler,
}

impl OcclusionPass {
    pub fn new(ctx: &Context) -> crate::Result<OcclusionPass> {
        let [depth_layout] = ctx
            .reflected_set_layouts(&[&shaders::FULLSCREEN_VERT, &shaders::OCCLUSION_DEPTH_FRAG])?;
        let [layout] =
            ctx.reflected_set_layouts(&[&shaders::FULLSCREEN_VERT, &shaders::OCCLUSION_FRAG])?;
        let [blur_layout] =
            ctx.reflected_set_layouts(&[&shaders::FULLSCREEN_VERT, &shaders::OCCLUSION_BLUR_FRAG])?;
        Ok(OcclusionPass {
            depth_layout,
            layout,
            blur_layout,
            pipelines: [OnceLock::new(), OnceLock::new()],
            everywhere: [OnceLock::new(), OnceLock::new()],
        })
    }

    /// Makes the pipelines once: the depth copy and the estimates and blur where a surface is,
    /// and with `everywhere` the estimates and blur over every pixel, with or without `bounce`.
    pub fn make(&self, ctx: &Context, everywhere: bool, bounce: bool) -> crate::Result<()> {
        // Each draws one fullscreen triangle into a half-resolution target; `depth` says how it
        // uses the half-resolution depth attachment (none: not attached).
        let make = |name: &str,
                    fragment,
                    formats: &[crate::vk::Format],
                    layout,
                    push: u32,
                    constants: &[(u32, u32)],
                    depth: Option<DepthTest>| {
            ctx.create_graphics_pipeline(&GraphicsDesc {
                name,
                vertex: &shaders::FULLSCREEN_VERT,
                fragment,
                vertex_layout: None,
                color_formats: formats,
                depth_format: depth.map(|_| OCCLUSION_COVERAGE_FORMAT),
                set_layouts: &[layout],
                push_constant_size: push,
                push_stages: Stages::FRAGMENT,
                constants,
                blend: false,
                topology: Topology::Triangles,
                stencil: StencilMode::None,
                depth_test: depth.unwrap_or_default(),
            })
        };
        let b = bounce as u32;
        let estimate_name = format!(
            "occlusion[slices={}, steps={}, bounce={b}]",
            OcclusionPlan::SLICES,
            OcclusionPlan::STEPS
        );
        let blur_name = format!("occlusion blur[bounce={b}]");
        let constants = [
            (0, OcclusionPlan::SLICES),
            (1, OcclusionPlan::STEPS),
            (2, b),
        ];
        let bounce_constant = [(2, b)];
        let two = [OCCLUSION_FORMAT, OCCLUSION_BOUNCE_FORMAT];
        let push = std::mem::size_of::<OcclusionPush>() as u32;
        let i = bounce as usize;
        if self.pipelines[i].get().is_none() {
            let depth_formats = [OCCLUSION_DEPTH_FORMAT, OCCLUSION_LIGHT_FORMAT];
            let depth = make(
                &format!("occlusion depth[bounce={b}]"),
                &shaders::OCCLUSION_DEPTH_FRAG,
                &depth_formats[..1 + bounce as usize],
                &self.depth_layout,
                0,
                &bounce_constant,
                Some(DepthTest::Always),
            )?;
            let estimate = make(
                &estimate_name,
                &shaders::OCCLUSION_FRAG,
                &two,
                &self.layout,
                push,
                &constants,
                Some(DepthTest::Farther),
            )?;
            let blur = make(
                &blur_name,
                &shaders::OCCLUSION_BLUR_FRAG,
                &two,
                &self.blur_layout,
                0,
                &bounce_constant,
                Some(DepthTest::Farther),
            )?;
            let _ = self.pipelines[i].set([depth, estimate, blur]);
        }
        if everywhere && self.everywhere[i].get().is_none() {
            let estimate = make(
                &format!("{estimate_name} everywhere"),
                &shaders::OCCLUSION_FRAG,
                &two,
                &self.layout,
                push,
                &constants,
                None,
            )?;
            let blur = make(
                &format!("{blur_name} everywhere"),
                &shaders::OCCLUSION_BLUR_FRAG,
                &two,
                &self.blur_layout,
                0,
                &bounce_constant,
                None,
            )?;
            let _ = self.everywhere[i].set([estimate, blur]);
        }
        Ok(())
    }

    pub fn pipelines(&self) -> impl Iterator<Item = &Pipeline> {
        self.pipelines
            .iter()
            .flat_map(|p| p.get().into_iter().flatten())
            .chain(
                self.everywhere
                    .iter()
                    .flat_map(|p| p.get().into_iter().flatten()),
            )
    }

    pub fn record<'s>(
        &'s self,
        pool: &'s DescriptorPool,
        inputs: OcclusionInputs<'s>,
    ) -> crate::Result<Recorded<'s>> {
        let made = "the frame makes the pipelines when it plans the pass";
        let i = inputs.bounce as usize;
        let [depth, covered_estimate, covered_blur] = self.pipelines[i].get().expect(made);
        let (estimate, blur) = if inputs.covered_only {
            (covered_estimate, covered_blur)
        } else {
            let [estimate, blur] = self.everywhere[i].get().expect(made);
            (estimate, blur)
        };
        let covered_only = inputs.covered_only;
        let bounce = inputs.bounce;
        let t = inputs.targets;
        let o = t
            .occlusion
            .as_ref()
            .expect("the frame makes the occlusion targets when it plans the pass");
        let depth_set = pool.set(
            &self.depth_layout,
            &[
                (0, Resource::Uniform(inputs.frame)),
                (1, Resource::Storage(inputs.materials)),
                (2, Resource::Storage(inputs.fabrics)),
                (
                    14,
                    Resource::Sampled(inputs.env_specular, inputs.env_sampler),
                ),
                (20, Resource::Sampled(&t.albedo, inputs.nearest)),
                (21, Resource::Sampled(&t.frame, inputs.nearest)),
                (22, Resource::Sampled(&t.surface, inputs.nearest)),
                (23, Resource::Sampled(&t.fabric, inputs.nearest)),
                (25, Resource::Sampled(&t.depth, inputs.nearest)),
            ],
        )?;
        let set = pool.set(
            &self.layout,
            &[
                (0, Resource::Uniform(inputs.frame)),
                (21, Resource::Sampled(&t.frame, inputs.nearest)),
                (26, Resource::Sampled(&o.depth, inputs.nearest)),
                (30, Resource::Sampled(&o.light, inputs.nearest)),
            ],
        )?;
        let blur_set = pool.set(
            &self.blur_layout,
            &[
                (28, Resource::Sampled(&o.raw, inputs.nearest)),
                (29, Resource::Sampled(&o.raw_bounce, inputs.nearest)),
            ],
        )?;
        let push = inputs.push;
        Ok(Recorded::new(
            "occlusion",
            vec![depth.name.clone(), estimate.name.clone(), blur.name.clone()],
            move |cmd| {
                // The depth copy writes every texel of both targets.
                cmd.transition(&o.coverage, Usage::Undefined, Usage::DepthAttachment, None);
                let depth_targets = [
                    Attachment {
                        image: &o.depth,
                        load: Load::Undefined,
                    },
                    Attachment {
                        image: &o.light,
                        load: Load::Undefined,
                    },
                ];
                let depth_targets = &depth_targets[..1 + bounce as usize];
                super::fullscreen_targets::<u32>(
                    cmd,
                    depth,
                    depth_set,
                    None,
                    depth_targets,
                    Some(Attachment {
                        image: &o.coverage,
                        load: Load::Undefined,
                    }),
                );
                for target in depth_targets {
                    cmd.transition(
                        target.image,
                        Usage::ColorAttachment,
                        Usage::FragmentRead,
                        None,
                    );
                }
                if !bounce {
                    // Bound but not read without the bounce: readable, its contents undefined.
                    cmd.transition(&o.light, Usage::Undefined, Usage::FragmentRead, None);
                }
                // The copy's depth writes before the draws' depth tests read them.
                cmd.transition(
                    &o.coverage,
                    Usage::DepthAttachment,
                    Usage::DepthAttachment,
                    None,
                );
                // Drawn where a surface is, an empty texel keeps the clear, what the shaders write
                // there: open (1), no surface (distance 0), no bounce; drawn everywhere, the
                // shaders write every texel.
                let (open, none) = if covered_only {
                    (Load::Clear([1.0, 0.0, 0.0, 0.0]), Load::Clear([0.0; 4]))
                } else {
                    (Load::Keep, Load::Keep)
                };
                let coverage = || {
                    covered_only.then_some(Attachment {
                        image: &o.coverage,
                        load: Load::Keep,
                    })
                };
                let into = |image, load| Attachment { image, load };
                super::fullscreen_targets(
                    cmd,
                    estimate,
                    set,
                    Some(&push),
                    &[into(&o.raw, open), into(&o.raw_bounce, none)],
                    coverage(),
                );
                cmd.transition(&o.raw, Usage::ColorAttachment, Usage::FragmentRead, None);
                cmd.transition(
                    &o.raw_bounce,
                    Usage::ColorAttachment,
                    Usage::FragmentRead,
                    None,
                );
                super::fullscreen_targets::<u32>(
                    cmd,
                    blur,
                    blur_set,
                    None,
                    &[into(&o.visibility, open), into(&o.bounce, none)],
                    coverage(),
                );
                for image in [&o.visibility, &o.bounce] {
                    cmd.transition(image, Usage::ColorAttachment, Usage::FragmentRead, None);
                }
            },
        ))
    }
}
