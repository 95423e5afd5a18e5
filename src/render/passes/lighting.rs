//! The deferred lighting pass: one fullscreen triangle from the G-buffer into HDR
//! (fullscreen.vert, lighting.frag): lamps with their shadows, the environment, emission; where
//! nothing reads the HDR image (`Plan::tone_in_lighting`), into the 8-bit image through the
//! exposure and the tone curve instead (TONE_CURVE), and no tonemap pass follows; where
//! the G-buffer's stencil says what each pixel is, one triangle per kind of pixel instead, each
//! with the module compiled for that kind alone (lighting_background.frag, lighting_woven.frag,
//! lighting_gltf.frag: include/lighting_main.glsl with PIXEL_KINDS fixed). Where
//! the woven model pools its environment lobe samples (the plan's `pool`), a first fullscreen
//! triangle over the woven pixels writes each one's lobe sums (fabric_lobes.frag) into the
//! target the lighting then reads around each pixel.

use std::collections::HashMap;

use super::{Recorded, SceneLighting, VariantKey};
use crate::render::plan::{OcclusionPlan, Plan};
use crate::render::targets::{depth_format, Targets, HDR_FORMAT, LDR_FORMAT, LOBES_FORMAT};
use crate::render::upload::GpuScene;
use crate::render::RenderOptions;
use crate::vk::{
    shaders, spec_constant_ids, Attachment, Context, DepthTest, DescriptorPool, GraphicsDesc,
    Image, Load, Pipeline, Resource, Sampler, SetLayout, Shader, Stages, StencilMode, Topology,
    Usage,
};

/// The pass's pipelines by variant and whether they test the stencil (each with the lobe sums
/// draw's pipeline when the variant pools the fabric lobes' samples), and the set layouts of
/// their modules (reflected from lighting.frag, from each kind's module and from
/// fabric_lobes.frag).
pub struct LightingPass {
    layout: SetLayout,
    /// The modules that shade one kind of pixel alone, by PIXEL_* bit, with their set layouts
    /// and the specialization constants their SPIR-V keeps (the other kinds' are compiled out).
    kind_modules: Vec<(u32, &'static Shader, SetLayout, Vec<u32>)>,
    lobes_layout: SetLayout,
    variants: HashMap<(VariantKey, bool), (Pipeline, Option<Pipeline>)>,
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

/// What the pass reads; it writes `output` (the HDR target, left readable by fragment shaders;
/// or the 8-bit image, left a colour attachment as the tonemap pass leaves it).
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
    /// The occlusion pass's blurred bounced light when the plan has the pass (any image
    /// otherwise: lighting.frag reads it only with OCCLUSION's bit 1).
    pub bounce: &'s Image,
    /// The fabric lobes' sums (`LOBES_FORMAT`) when a variant pools them (made by the frame).
    pub lobes: Option<&'s Image>,
    /// Where the pass writes: the HDR target, or where its variants tone-map
    /// ([`LightingPass::tone_maps`]) the 8-bit image (the anti-aliasing pass's input, or the
    /// output).
    pub output: &'s Image,
}

/// The constants fabric_lobes.frag declares (ACCURACY, IBL_SAMPLES, POOL), by lighting.frag's ids.
const LOBES_CONSTANTS: [u32; 3] = [0, 8, 14];

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
        let [lobes_layout] =
            ctx.reflected_set_layouts(&[&shaders::FULLSCREEN_VERT, &shaders::FABRIC_LOBES_FRAG])?;
        let mut kind_modules = Vec::new();
        for (kind, module) in [
            (PIXEL_BACKGROUND, &shaders::LIGHTING_BACKGROUND_FRAG),
            (PIXEL_WOVEN, &shaders::LIGHTING_WOVEN_FRAG),
            (PIXEL_GLTF, &shaders::LIGHTING_GLTF_FRAG),
        ] {
            let [layout] = ctx.reflected_set_layouts(&[&shaders::FULLSCREEN_VERT, module])?;
            kind_modules.push((kind, module, layout, spec_constant_ids(&[module])?));
        }
        Ok(LightingPass {
            layout,
            kind_modules,
            lobes_layout,
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
            // 0: none; any bit the visibility, bit 1 the occluders' bounced light the screen
            // shows, bit 2 the world light (the G-buffer's specular target holds it).
            (
                10,
                "occlusion",
                plan.occlusion
                    .as_ref()
                    .map_or(0, OcclusionPlan::lighting_code),
            ),
            (
                11,
                "debug_views",
                (options.debug_view != crate::render::DebugView::None) as u32,
            ),
            (12, "pixel_kinds", kinds),
            (13, "gltf_features", plan.gltf_features),
            (14, "pool", plan.pool_code(options)),
            // 0: linear HDR out; c + 1: the tone curve c applied here, into the 8-bit target.
            (
                15,
                "tone_curve",
                if plan.tone_in_lighting {
                    super::tonemap::TonemapPass::curve(options) + 1
                } else {
                    0
                },
            ),
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

    /// Whether `key` applies the tone curve and writes the 8-bit target (TONE_CURVE ≥ 1).
    pub fn tone_maps(key: &VariantKey) -> bool {
        key.value(15) > 0
    }

    /// Whether `key` pools the fabric lobes' samples (POOL ≥ 1) where it shades woven pixels:
    /// its pass first runs the lobe sums draw.
    pub fn pools(key: &VariantKey) -> bool {
        key.value(14) > 0 && key.value(12) & PIXEL_WOVEN != 0
    }

    /// The pipelines of `variant` (not kept: see [`LightingPass::insert`]) are made in two
    /// halves, so that two threads can compile them: with a stencil value, over the G-buffer's
    /// depth-stencil attachment, drawing only where the stencil equals it; and where it pools the
    /// fabric lobes' samples, the lobe sums draw's (fabric_lobes.frag, the same constants, into
    /// `LOBES_FORMAT`).
    ///
    /// The lobe sums draw's pipeline of `variant` (None where it does not pool).
    pub fn make_lobes(
        &self,
        ctx: &Context,
        variant: &LightingVariant,
    ) -> crate::Result<Option<Pipeline>> {
        let (key, stencil) = variant;
        if !Self::pools(key) {
            return Ok(None);
        }
        // fabric_lobes.frag's constants: lighting.frag's of the same ids.
        let lobes_key = VariantKey(
            key.0
                .iter()
                .filter(|c| LOBES_CONSTANTS.contains(&c.0))
                .copied()
                .collect(),
        );
        Ok(Some(ctx.create_graphics_pipeline(&GraphicsDesc {
            name: &format!("fabric lobes[{}]", lobes_key.describe()),
            vertex: &shaders::FULLSCREEN_VERT,
            fragment: &shaders::FABRIC_LOBES_FRAG,
            vertex_layout: None,
            color_formats: &[LOBES_FORMAT],
            depth_format: stencil.map(|_| depth_format(ctx)),
            set_layouts: &[&self.lobes_layout],
            push_constant_size: 0,
            push_stages: Stages::FRAGMENT,
            constants: &lobes_key.constants(),
            blend: false,
            topology: Topology::Triangles,
            stencil: stencil_mode(stencil),
            depth_test: DepthTest::Nearer,
        })?))
    }

    /// The module and set layout `variant` shades with: over a stencil (one kind of pixel), the
    /// module compiled for that kind alone (its PIXEL_KINDS is no constant to specialise); else
    /// lighting.frag, every kind its PIXEL_KINDS names.
    fn module(&self, variant: &LightingVariant) -> (&'static Shader, &SetLayout, Option<&[u32]>) {
        let (key, stencil) = variant;
        match self.kind_modules.iter().find(|m| m.0 == key.value(12)) {
            Some((_, module, layout, constants)) if stencil.is_some() => {
                (module, layout, Some(constants))
            }
            _ => (&shaders::LIGHTING_FRAG, &self.layout, None),
        }
    }

    /// The shading draw's pipeline of `variant`.
    pub fn make_shade(&self, ctx: &Context, variant: &LightingVariant) -> crate::Result<Pipeline> {
        let (key, stencil) = variant;
        let (module, layout, kept) = self.module(variant);
        let mut constants = key.constants();
        if let Some(kept) = kept {
            constants.retain(|c| kept.contains(&c.0));
        }
        ctx.create_graphics_pipeline(&GraphicsDesc {
            name: &format!("lighting[{}]", key.describe()),
            vertex: &shaders::FULLSCREEN_VERT,
            fragment: module,
            vertex_layout: None,
            color_formats: &[if Self::tone_maps(key) {
                LDR_FORMAT
            } else {
                HDR_FORMAT
            }],
            depth_format: stencil.map(|_| depth_format(ctx)),
            set_layouts: &[layout],
            push_constant_size: 0,
            push_stages: Stages::FRAGMENT,
            constants: &constants,
            blend: false,
            topology: Topology::Triangles,
            stencil: stencil_mode(stencil),
            depth_test: DepthTest::Nearer,
        })
    }

    pub fn insert(&mut self, variant: LightingVariant, pipelines: (Pipeline, Option<Pipeline>)) {
        self.variants
            .insert((variant.0, variant.1.is_some()), pipelines);
    }

    pub fn pipelines(&self) -> impl Iterator<Item = &Pipeline> {
        self.variants
            .values()
            .flat_map(|(shade, lobes)| std::iter::once(shade).chain(lobes.as_ref()))
    }

    /// Records the pass with `variants` (made by [`LightingPass::make_shade`] and [`LightingPass::make_lobes`]).
    pub fn record<'s>(
        &'s self,
        pool: &'s DescriptorPool,
        variants: &[LightingVariant],
        inputs: LightingInputs<'s>,
    ) -> crate::Result<Recorded<'s>> {
        let pipelines: Vec<(
            &'s Pipeline,
            Option<&'s Pipeline>,
            Option<u32>,
            &'s SetLayout,
        )> = variants
            .iter()
            .map(|variant| {
                let (key, stencil) = variant;
                let (p, lobes) = self
                    .variants
                    .get(&(key.clone(), stencil.is_some()))
                    .expect("the frame makes the lighting variants before recording");
                (p, lobes.as_ref(), *stencil, self.module(variant).1)
            })
            .collect();
        let lobes = match pipelines.iter().find_map(|(_, l, s, _)| l.map(|l| (l, *s))) {
            Some((pipeline, stencil)) => Some((
                pipeline,
                stencil,
                inputs.lobes.ok_or_else(|| {
                    crate::Error::device(
                        "the lighting pass pools the fabric lobes without their target".to_string(),
                    )
                })?,
            )),
            None => None,
        };
        let t = inputs.targets;
        let output = inputs.output;
        let tone_maps = variants.iter().any(|(key, _)| Self::tone_maps(key));
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
            (29, g(inputs.bounce)),
            // The lobe sums where a variant pools them (the first draw writes them); else any
            // unsigned-integer image in the layout sampled images are in (unread).
            (28, g(lobes.map_or(&t.frame, |(_, _, image)| image))),
        ];
        bindings.extend(inputs.lighting.bindings());
        // Each module's set holds the resources its layout names (the lobe sums draw and the
        // one-kind modules read some of the same resources at the same numbers).
        let set_of = |layout: &SetLayout| {
            let wanted: Vec<(u32, Resource)> = bindings
                .iter()
                .filter(|(b, _)| layout.bindings.iter().any(|l| l.binding == *b))
                .cloned()
                .collect();
            pool.set(layout, &wanted)
        };
        let shades = pipelines
            .iter()
            .map(|(p, _, stencil, layout)| Ok((*p, *stencil, set_of(layout)?)))
            .collect::<crate::Result<Vec<_>>>()?;
        let lobes = match lobes {
            Some((pipeline, stencil, image)) => {
                Some((pipeline, stencil, image, set_of(&self.lobes_layout)?))
            }
            None => None,
        };
        let mut names: Vec<String> = lobes.iter().map(|(p, _, _, _)| p.name.clone()).collect();
        names.extend(pipelines.iter().map(|(p, _, _, _)| p.name.clone()));
        Ok(Recorded::new("lighting", names, move |cmd| {
            if let Some((pipeline, stencil, image, lobes_set)) = lobes {
                // The fabric lobes' samples first, over the woven pixels (every pixel where
                // the kinds are not split), for the lighting to pool.
                cmd.transition(image, Usage::Undefined, Usage::ColorAttachment, None);
                match stencil {
                    Some(_) => cmd.begin_rendering_stencil_test(&[image], &t.depth),
                    None => cmd.begin_rendering(
                        &[Attachment {
                            image,
                            load: Load::Keep,
                        }],
                        None,
                    ),
                }
                cmd.bind_pipeline(pipeline);
                cmd.bind_sets(pipeline, 0, &[lobes_set]);
                if let Some(s) = stencil {
                    cmd.set_stencil_reference(s);
                }
                cmd.draw(3);
                cmd.end_rendering();
                cmd.transition(image, Usage::ColorAttachment, Usage::FragmentRead, None);
            }
            match shades.as_slice() {
                [(pipeline, None, set)] => {
                    super::fullscreen::<u32>(cmd, pipeline, *set, None, output)
                }
                _ => {
                    // A fullscreen triangle per kind of pixel, each where the stencil is
                    // its kind: together they cover every pixel once.
                    cmd.transition(output, Usage::Undefined, Usage::ColorAttachment, None);
                    cmd.begin_rendering_stencil_test(&[output], &t.depth);
                    for (pipeline, stencil, set) in &shades {
                        cmd.bind_pipeline(pipeline);
                        cmd.bind_sets(pipeline, 0, &[*set]);
                        cmd.set_stencil_reference(stencil.unwrap_or(0));
                        cmd.draw(3);
                    }
                    cmd.end_rendering();
                }
            }
            // The HDR target for the fragment shaders that read it; the 8-bit image as the
            // tonemap pass leaves it (a colour attachment, which the anti-aliasing pass and the
            // readback take it from).
            if !tone_maps {
                cmd.transition(output, Usage::ColorAttachment, Usage::FragmentRead, None);
            }
        }))
    }
}

/// A variant's stencil test: drawn where the stencil equals its kind, or everywhere.
fn stencil_mode(stencil: &Option<u32>) -> StencilMode {
    if stencil.is_some() {
        StencilMode::Equal
    } else {
        StencilMode::None
    }
}
