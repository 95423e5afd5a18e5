//! The deferred lighting pass: one fullscreen triangle from the G-buffer into HDR
//! (fullscreen.vert, lighting.frag): lamps with their shadows, the environment, emission.

use std::collections::HashMap;

use super::{Recorded, SceneLighting, VariantKey};
use crate::render::plan::Plan;
use crate::render::targets::{Targets, HDR_FORMAT};
use crate::render::upload::GpuScene;
use crate::render::RenderOptions;
use crate::vk::{
    shaders, Context, DescriptorPool, GraphicsDesc, Image, Pipeline, Resource, Sampler, SetLayout,
    Stages, Topology, Usage,
};

/// The pass's pipelines by variant and its set layout (reflected from lighting.frag).
pub struct LightingPass {
    layout: SetLayout,
    variants: HashMap<VariantKey, Pipeline>,
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

    /// The variant `options` and `plan` ask for (lighting.frag's constants by id).
    pub fn key(options: &RenderOptions, plan: &Plan, light_types: u32) -> VariantKey {
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
            (12, "pixel_kinds", pixel_kinds(options, plan)),
            (13, "gltf_features", plan.gltf_features),
        ])
    }

    pub fn has(&self, key: &VariantKey) -> bool {
        self.variants.contains_key(key)
    }

    /// Makes the pipeline of variant `key` (not kept: see [`LightingPass::insert`]).
    pub fn make(&self, ctx: &Context, key: &VariantKey) -> crate::Result<Pipeline> {
        ctx.create_graphics_pipeline(&GraphicsDesc {
            name: &format!("lighting[{}]", key.describe()),
            vertex: &shaders::FULLSCREEN_VERT,
            fragment: &shaders::LIGHTING_FRAG,
            vertex_layout: None,
            color_formats: &[HDR_FORMAT],
            depth_format: None,
            set_layouts: &[&self.layout],
            push_constant_size: 0,
            push_stages: Stages::FRAGMENT,
            constants: &key.constants(),
            blend: false,
            topology: Topology::Triangles,
        })
    }

    pub fn insert(&mut self, key: VariantKey, pipeline: Pipeline) {
        self.variants.insert(key, pipeline);
    }

    pub fn pipelines(&self) -> impl Iterator<Item = &Pipeline> {
        self.variants.values()
    }

    /// Records the pass with variant `key` (made by [`LightingPass::make`]).
    pub fn record<'s>(
        &'s self,
        pool: &'s DescriptorPool,
        key: &VariantKey,
        inputs: LightingInputs<'s>,
    ) -> crate::Result<Recorded<'s>> {
        let pipeline = self
            .variants
            .get(key)
            .expect("the frame makes the lighting variant before recording");
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
            vec![pipeline.name.clone()],
            move |cmd| {
                super::fullscreen::<u32>(cmd, pipeline, set, None, &t.hdr);
                cmd.transition(&t.hdr, Usage::ColorAttachment, Usage::FragmentRead, None);
            },
        ))
    }
}
