//! The deferred lighting pass: one fullscreen triangle from the G-buffer into HDR
//! (fullscreen.vert, lighting.frag): lamps with their shadows, the environment, emission.

use std::collections::HashMap;

use super::{Recorded, SceneLighting, VariantKey};
use crate::render::plan::Plan;
use crate::render::targets::{depth_format, Targets, HDR_FORMAT};
use crate::render::upload::GpuScene;
use crate::render::RenderOptions;
use crate::vk::{
    shaders, Context, DescriptorPool, GraphicsDesc, Image, Pipeline, Resource, Sampler, SetLayout,
    Stages, StencilMode, Topology, Usage,
};

/// The pass's pipelines by variant and whether they test the stencil, and its set layout
/// (reflected from lighting.frag).
pub struct LightingPass {
    layout: SetLayout,
    variants: HashMap<(VariantKey, bool), Pipeline>,
}

/// One lighting pipeline of a frame: its variant, and the stencil value of the pixels it shades
/// (None: every pixel, no stencil test).
pub type LightingVariant = (VariantKey, Option<u32>);

/// The stencil the G-buffer pass writes: 0 (its clear) where nothing is drawn, then per draw the
/// kind of pixel the lighting pass shades it as.
pub const STENCIL_BACKGROUND: u32 = 0;
pub const STENCIL_WOVEN: u32 = 1;
pub const STENCIL_GLTF: u32 = 2;

/// The stencil value of a G-buffer draw of a fabric (`woven`) or glTF material.
pub fn stencil_of(woven: bool, fabric_as_pbr: bool) -> u32 {
    if woven && !fabric_as_pbr {
        STENCIL_WOVEN
    } else {
        STENCIL_GLTF
    }
}

/// What the pass reads; it writes the HDR target (left readable by fragment shaders).
pub struct LightingInputs<'s> {
    /// Materials and fabrics (the G-buffer's material index points into them).
    pub scene: &'s GpuScene,
    pub lighting: SceneLighting<'s>,
    /// The G-buffer, fetched per pixel with `nearest`.
    pub targets: &'s Targets,
    pub nearest: &'s Sampler,
    /// The occlusion pass's visibility when the plan has the pass (any image otherwise: the
    /// variant without OCCLUSION does not read it).
    pub occlusion: &'s Image,
}

/// lighting.frag's PIXEL_KIND_* bits.
pub const PIXEL_BACKGROUND: u32 = 1;
pub const PIXEL_WOVEN: u32 = 2;
pub const PIXEL_GLTF: u32 = 4;

/// The kinds of pixel a frame has (PIXEL_* bits): the background, and the woven model's and the
/// glTF BRDF's pixels where the G-buffer holds draws of them (fabric shaded as glTF is glTF's);
/// every kind when the kinds are not split (forced).
pub fn pixel_kinds(options: &RenderOptions, plan: &Plan) -> u32 {
    if !plan.material_kinds {
        return PIXEL_BACKGROUND | PIXEL_WOVEN | PIXEL_GLTF;
    }
    let (woven, gltf) = if options.fabric_as_pbr {
        (0, plan.woven_draws + plan.gltf_draws)
    } else {
        (plan.woven_draws, plan.gltf_draws)
    };
    PIXEL_BACKGROUND | ((woven > 0) as u32 * PIXEL_WOVEN) | ((gltf > 0) as u32 * PIXEL_GLTF)
}

impl LightingPass {
    pub fn new(ctx: &Context) -> crate::Result<LightingPass> {
        let [layout] =
            ctx.reflected_set_layouts(&[&shaders::FULLSCREEN_VERT, &shaders::LIGHTING_FRAG])?;
        Ok(LightingPass {
            layout,
            variants: HashMap::new(),
        })
    }

    /// The variant `options` and `plan` ask for (lighting.frag's constants by id), shading the
    /// kinds of pixel `kinds` (PIXEL_* bits).
    pub fn key(options: &RenderOptions, plan: &Plan, light_types: u32, kinds: u32) -> VariantKey {
        VariantKey(vec![
            (0, "accuracy", options.accuracy.code()),
            (1, "samples", options.accuracy.samples()),
            (2, "fabric_as_pbr", options.fabric_as_pbr as u32),
            (3, "light_types", light_types),
            (4, "shading", options.shading as u32),
            (5, "shadows", plan.shadow_sampling as u32),
            (6, "range_culling", plan.range_code()),
            (7, "ibl", plan.ibl_code(options)),
            (
                8,
                "ibl_samples",
                options
                    .environment
                    .as_ref()
                    .map(|e| e.level.samples())
                    .unwrap_or(1),
            ),
            (9, "unlit", plan.unlit as u32),
            (10, "occlusion", plan.occlusion.is_some() as u32),
            (
                11,
                "debug_views",
                (options.debug_view != crate::render::DebugView::None) as u32,
            ),
            (12, "pixel_kinds", kinds),
            (13, "gltf_features", plan.gltf_features),
            (14, "quad_pool", plan.quad_pool_code(options)),
        ])
    }

    /// The pipelines a frame shades with: where the G-buffer's depth has a stencil
    /// (`split`: the device has the format, the kinds are not forced together, no debug view),
    /// one per kind of pixel the frame has (PIXEL_KINDS that kind alone), each drawn over the
    /// pixels whose stencil is its kind; else one of every kind the frame has, over every pixel.
    pub fn variants(
        options: &RenderOptions,
        plan: &Plan,
        light_types: u32,
        split: bool,
    ) -> Vec<LightingVariant> {
        let kinds = pixel_kinds(options, plan);
        if !split {
            return vec![(Self::key(options, plan, light_types, kinds), None)];
        }
        [
            (PIXEL_BACKGROUND, STENCIL_BACKGROUND),
            (PIXEL_WOVEN, STENCIL_WOVEN),
            (PIXEL_GLTF, STENCIL_GLTF),
        ]
        .into_iter()
        .filter(|(kind, _)| kinds & kind != 0)
        .map(|(kind, stencil)| (Self::key(options, plan, light_types, kind), Some(stencil)))
        .collect()
    }

    pub fn has(&self, variant: &LightingVariant) -> bool {
        self.variants
            .contains_key(&(variant.0.clone(), variant.1.is_some()))
    }

    /// Makes the pipeline of `variant` (not kept: see [`LightingPass::insert`]): with a stencil
    /// value, over the G-buffer's depth-stencil attachment, drawing only where the stencil equals
    /// it.
    pub fn make(&self, ctx: &Context, variant: &LightingVariant) -> crate::Result<Pipeline> {
        let (key, stencil) = variant;
        ctx.create_graphics_pipeline(&GraphicsDesc {
            name: &format!("lighting[{}]", key.describe()),
            vertex: &shaders::FULLSCREEN_VERT,
            fragment: &shaders::LIGHTING_FRAG,
            vertex_layout: None,
            color_formats: &[HDR_FORMAT],
            depth_format: stencil.map(|_| depth_format(ctx)),
            set_layouts: &[&self.layout],
            push_constant_size: 0,
            push_stages: Stages::FRAGMENT,
            constants: &key.constants(),
            blend: false,
            topology: Topology::Triangles,
            stencil: if stencil.is_some() {
                StencilMode::Equal
            } else {
                StencilMode::None
            },
        })
    }

    pub fn insert(&mut self, variant: LightingVariant, pipeline: Pipeline) {
        self.variants
            .insert((variant.0, variant.1.is_some()), pipeline);
    }

    pub fn pipelines(&self) -> impl Iterator<Item = &Pipeline> {
        self.variants.values()
    }

    /// Records the pass with `variants` (made by [`LightingPass::make`]).
    pub fn record<'s>(
        &'s self,
        pool: &'s DescriptorPool,
        variants: &[LightingVariant],
        inputs: LightingInputs<'s>,
    ) -> crate::Result<Recorded<'s>> {
        let pipelines: Vec<(&'s Pipeline, Option<u32>)> = variants
            .iter()
            .map(|(key, stencil)| {
                let p = self
                    .variants
                    .get(&(key.clone(), stencil.is_some()))
                    .expect("the frame makes the lighting variants before recording");
                (p, *stencil)
            })
            .collect();
        let t = inputs.targets;
        let g = |image| Resource::Sampled(image, inputs.nearest);
        let mut bindings = vec![
            (1, Resource::Storage(&inputs.scene.materials)),
            (2, Resource::Storage(&inputs.scene.fabrics)),
            (20, g(&t.albedo)),
            (21, g(&t.frame)),
            (22, g(&t.surface)),
            (23, g(&t.fabric)),
            (24, g(&t.emissive)),
            (25, g(&t.depth)),
            (26, g(&t.specular)),
            (27, g(inputs.occlusion)),
        ];
        bindings.extend(inputs.lighting.bindings());
        let set = pool.set(&self.layout, &bindings)?;
        Ok(Recorded::new(
            "lighting",
            pipelines.iter().map(|(p, _)| p.name.clone()).collect(),
            move |cmd| {
                match pipelines.as_slice() {
                    [(pipeline, None)] => {
                        super::fullscreen::<u32>(cmd, pipeline, set, None, &t.hdr)
                    }
                    _ => {
                        // A fullscreen triangle per kind of pixel, each where the stencil is
                        // its kind: together they cover every pixel once.
                        cmd.transition(&t.hdr, Usage::Undefined, Usage::ColorAttachment, None);
                        cmd.begin_rendering_stencil_test(&[&t.hdr], &t.depth);
                        for (pipeline, stencil) in &pipelines {
                            cmd.bind_pipeline(pipeline);
                            cmd.bind_sets(pipeline, 0, &[set]);
                            cmd.set_stencil_reference(stencil.unwrap_or(0));
                            cmd.draw(3);
                        }
                        cmd.end_rendering();
                    }
                }
                cmd.transition(&t.hdr, Usage::ColorAttachment, Usage::FragmentRead, None);
            },
        ))
    }
}
