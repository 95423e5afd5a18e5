//! The G-buffer pass: every draw the G-buffer can hold into the six colour targets and depth
//! (gbuffer.vert, gbuffer.frag; where the kinds of material are split, glTF materials with
//! gbuffer_gltf.frag: include/gbuffer_main.glsl without the weave's code).

use std::collections::HashMap;
use std::sync::OnceLock;

use super::lighting::stencil_of;
use super::{Recorded, VariantKey};
use crate::render::gpu::{DrawPush, DRAW_RECEIVES_SHADOWS, DRAW_WORLD_LIGHT};
use crate::render::plan::Plan;
use crate::render::targets::{
    depth_format, Targets, ALBEDO_FORMAT, EMISSIVE_FORMAT, FABRIC_FORMAT, FRAME_FORMAT,
    SPECULAR_FORMAT, SURFACE_FORMAT,
};
use crate::render::upload::{gbuffer_vertex_layout, position_vertex_layout, GpuScene};
use crate::render::{RenderOptions, Shading};
use crate::vk::{
    shaders, Attachment, Buffer, Context, Cull, DepthTest, DescriptorPool, DescriptorSet,
    GraphicsDesc, Load, Pipeline, Resource, SetLayout, Stages, StencilMode, Topology, Usage,
};

/// The pass's pipelines (one per variant, topology and kind of material, and the depth
/// pre-pass's) and its two set layouts: set 0 (frame, materials, fabrics, lights, vertex colours,
/// thread colours) and set 1 (a material's textures).
pub struct GBufferPass {
    frame_layout: SetLayout,
    pub(crate) material_layout: SetLayout,
    /// The specialization constants gbuffer.vert and gbuffer_gltf.frag declare (the glTF kind's
    /// pipeline gives only these: its MATERIAL_KIND and the weave's constants are compiled out).
    gltf_constants: Vec<u32>,
    /// By variant, topology, kind and whether a depth pre-pass runs before (its depth test).
    variants: HashMap<(VariantKey, Topology, Kind, bool), Pipeline>,
    /// The depth pre-pass (depth.vert, shadow.frag), made once when a plan first has one, and
    /// its set 0 (the frame uniform alone).
    depth: OnceLock<Pipeline>,
    depth_layout: SetLayout,
}

/// What a G-buffer pipeline draws (gbuffer.frag's MATERIAL_KIND): every kind of material, or one
/// kind with the other's code compiled out.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Kind {
    Any = 0,
    /// Fabric: the woven model's coverage, no glTF extension.
    Woven = 1,
    /// glTF materials: no weave.
    Gltf = 2,
}

impl Kind {
    /// The kind a draw of a fabric (`woven`) or glTF material is drawn with: its own where the
    /// kinds are split ([`Plan::material_kinds`]).
    pub fn of(woven: bool, split: bool) -> Kind {
        match (split, woven) {
            (false, _) => Kind::Any,
            (true, true) => Kind::Woven,
            (true, false) => Kind::Gltf,
        }
    }

    /// The kinds `plan` draws (glTF's for a scene that draws nothing: the default variant).
    pub fn drawn(plan: &Plan) -> Vec<Kind> {
        if !plan.material_kinds {
            return vec![Kind::Any];
        }
        if plan.woven_draws + plan.gltf_draws == 0 {
            return vec![Kind::Gltf];
        }
        [
            (plan.woven_draws > 0, Kind::Woven),
            (plan.gltf_draws > 0, Kind::Gltf),
        ]
        .into_iter()
        .filter(|&(drawn, _)| drawn)
        .map(|(_, k)| k)
        .collect()
    }

    fn name(self) -> &'static str {
        match self {
            Kind::Any => "",
            Kind::Woven => ", woven",
            Kind::Gltf => ", glTF",
        }
    }
}

/// What the pass reads; it writes every G-buffer target and depth.
pub struct GBufferInputs<'s> {
    pub scene: &'s GpuScene,
    /// The frame's uniform (camera, environment, counts).
    pub frame: &'s Buffer,
    /// The lamps (read by the vertex stage for Gouraud shading only).
    pub lights: &'s Buffer,
    /// Vertex colours: the scene's, or white per vertex when the plan compiles them in for a
    /// scene without any.
    pub colors: &'s Buffer,
    /// Per material, the set of its textures (`material_layout`).
    pub material_sets: Vec<DescriptorSet<'s>>,
    pub targets: &'s Targets,
    /// A pipeline per kind of material ([`Plan::material_kinds`]), else one for every kind.
    pub material_kinds: bool,
    /// Fabric is shaded with the glTF BRDF (its pixels' stencil is glTF's).
    pub fabric_as_pbr: bool,
    /// The plan's depth pre-pass ([`Plan::depth_prepass`]): its opaque draws' depth first, with
    /// the variant's pipelines then testing GREATER_OR_EQUAL.
    pub depth_prepass: bool,
    /// The world light when the plan has it (render::world_light): per draw where its
    /// vertices' entries begin in its buffer.
    pub world_light: Option<&'s crate::render::upload::WorldLightGpu>,
}

impl GBufferPass {
    pub fn new(ctx: &Context) -> crate::Result<GBufferPass> {
        let shaders = [&shaders::GBUFFER_VERT, &shaders::GBUFFER_FRAG];
        let [frame_layout, material_layout] = ctx.reflected_set_layouts(&shaders)?;
        let [depth_layout] =
            ctx.reflected_set_layouts(&[&shaders::DEPTH_VERT, &shaders::SHADOW_FRAG])?;
        Ok(GBufferPass {
            frame_layout,
            material_layout,
            gltf_constants: crate::vk::spec_constant_ids(&[
                &shaders::GBUFFER_VERT,
                &shaders::GBUFFER_GLTF_FRAG,
            ])?,
            variants: HashMap::new(),
            depth: OnceLock::new(),
            depth_layout,
        })
    }

    /// Makes the depth pre-pass' pipeline once: depth.vert's position of each opaque draw, the
    /// frame uniform and gbuffer.vert's push block, depth test GREATER and written, the stencil
    /// cleared with it (the shading draws write it).
    pub fn make_depth(&self, ctx: &Context) -> crate::Result<()> {
        if self.depth.get().is_none() {
            let pipeline = ctx.create_graphics_pipeline(&GraphicsDesc {
                name: "gbuffer depth pre-pass",
                vertex: &shaders::DEPTH_VERT,
                fragment: &shaders::SHADOW_FRAG,
                vertex_layout: Some(position_vertex_layout()),
                color_formats: &[],
                depth_format: Some(depth_format(ctx)),
                set_layouts: &[&self.depth_layout],
                push_constant_size: std::mem::size_of::<DrawPush>() as u32,
                push_stages: Stages::VERTEX,
                constants: &[],
                blend: false,
                topology: Topology::Triangles,
                stencil: StencilMode::None,
                depth_test: DepthTest::Nearer,
            })?;
            let _ = self.depth.set(pipeline);
        }
        Ok(())
    }

    /// The variant `options` and `plan` ask for (gbuffer.frag's constants by id). `weave_source`:
    /// 0 the RGBA16F/RGBA8 mip chain, 1 analytic, 2 the summed-area table filtered, 3 fetched;
    /// `light_types`: the scene's lamp types (the vertex stage's, for Gouraud shading only).
    pub fn key(
        options: &RenderOptions,
        plan: &Plan,
        weave_source: u32,
        light_types: u32,
    ) -> VariantKey {
        VariantKey(vec![
            (0, "accuracy", options.accuracy.code()),
            (1, "weave", weave_source),
            (2, "shading", options.shading as u32),
            // Gouraud lights vertices: only then does the pass depend on the light types.
            (
                3,
                "light_types",
                if options.shading == Shading::Gouraud {
                    light_types
                } else {
                    7
                },
            ),
            (4, "footprint", options.footprint.pieces()),
            (5, "vertex_colors", plan.vertex_colors as u32),
            (6, "alpha_mask", plan.alpha_mask as u32),
            (7, "thread_colours", plan.features.thread_colours as u32),
            (9, "texture_slots", plan.texture_slots),
            (
                10,
                "world_light",
                plan.occlusion.as_ref().is_some_and(|o| o.world.is_some()) as u32,
            ),
        ])
    }

    /// The topologies and kinds of `key` the plan draws whose pipeline is not made yet.
    pub fn missing(&self, key: &VariantKey, plan: &Plan) -> Vec<(Topology, Kind)> {
        let kinds = Kind::drawn(plan);
        [
            (true, Topology::Triangles),
            (plan.line_draws > 0, Topology::Lines),
            (plan.point_draws > 0, Topology::Points),
        ]
        .into_iter()
        .filter(|&(needed, _)| needed)
        .flat_map(|(_, t)| kinds.iter().map(move |&k| (t, k)))
        .filter(|&(t, k)| {
            !self
                .variants
                .contains_key(&(key.clone(), t, k, plan.depth_prepass > 0))
        })
        .collect()
    }

    /// Makes the pipeline of variant `key` for `topology` and `kind` (not kept: see
    /// [`GBufferPass::insert`]); after a depth pre-pass (`prepassed`) its depth test is
    /// GREATER_OR_EQUAL (named "depth >=").
    pub fn make(
        &self,
        ctx: &Context,
        key: &VariantKey,
        topology: Topology,
        kind: Kind,
        prepassed: bool,
    ) -> crate::Result<Pipeline> {
        let mut constants = key.constants();
        constants.push((8, kind as u32));
        // glTF materials alone: the module without the weave's code (MATERIAL_KIND fixed), with
        // gbuffer.frag's set layouts (its bindings are a subset of theirs, at the same numbers),
        // so every material's set serves both kinds' pipelines.
        let fragment = if kind == Kind::Gltf {
            constants.retain(|c| self.gltf_constants.contains(&c.0));
            &shaders::GBUFFER_GLTF_FRAG
        } else {
            &shaders::GBUFFER_FRAG
        };
        ctx.create_graphics_pipeline(&GraphicsDesc {
            name: &format!(
                "gbuffer[{}{}{}{}]",
                match topology {
                    Topology::Triangles => "",
                    Topology::Lines => "lines, ",
                    Topology::Points => "points, ",
                },
                key.describe(),
                if prepassed { ", depth >=" } else { "" },
                kind.name()
            ),
            vertex: &shaders::GBUFFER_VERT,
            fragment,
            vertex_layout: Some(gbuffer_vertex_layout()),
            color_formats: &[
                ALBEDO_FORMAT,
                FRAME_FORMAT,
                SURFACE_FORMAT,
                FABRIC_FORMAT,
                EMISSIVE_FORMAT,
                SPECULAR_FORMAT,
            ],
            depth_format: Some(depth_format(ctx)),
            set_layouts: &[&self.frame_layout, &self.material_layout],
            push_constant_size: std::mem::size_of::<DrawPush>() as u32,
            push_stages: Stages::GRAPHICS,
            constants: &constants,
            blend: false,
            topology,
            // Each draw marks its pixels with the kind the lighting pass shades them as.
            stencil: if ctx.info().depth_stencil {
                StencilMode::Write
            } else {
                StencilMode::None
            },
            depth_test: if prepassed {
                DepthTest::NearerOrEqual
            } else {
                DepthTest::Nearer
            },
        })
    }

    pub fn insert(
        &mut self,
        key: VariantKey,
        topology: Topology,
        kind: Kind,
        prepassed: bool,
        pipeline: Pipeline,
    ) {
        self.variants
            .insert((key, topology, kind, prepassed), pipeline);
    }

    pub fn pipelines(&self) -> impl Iterator<Item = &Pipeline> {
        self.variants.values().chain(self.depth.get())
    }

    /// Records the pass with variant `key` (made by [`GBufferPass::make`] for every topology
    /// the scene draws).
    pub fn record<'s>(
        &'s self,
        pool: &'s DescriptorPool,
        key: &VariantKey,
        inputs: GBufferInputs<'s>,
    ) -> crate::Result<Recorded<'s>> {
        let scene = inputs.scene;
        let frame_set = pool.set(
            &self.frame_layout,
            &[
                (0, Resource::Uniform(inputs.frame)),
                (1, Resource::Storage(&scene.materials)),
                (2, Resource::Storage(&scene.fabrics)),
                (3, Resource::Storage(inputs.lights)),
                (4, Resource::Storage(inputs.colors)),
                (5, Resource::Storage(&scene.thread_colours)),
                // Read only where the plan compiles the world light in (any buffer otherwise).
                (
                    6,
                    Resource::Storage(inputs.world_light.map_or(inputs.colors, |w| &w.buffer)),
                ),
            ],
        )?;
        let split = inputs.material_kinds;
        let fabric_as_pbr = inputs.fabric_as_pbr;
        // The draws mark their kind where the depth has a stencil (the pipelines then write it).
        let stencil = crate::vk::has_stencil(inputs.targets.depth.desc.format);
        let kind_of = move |woven: bool| Kind::of(woven, split);
        let pipelines: Vec<(Topology, Kind, &'s Pipeline)> =
            [Topology::Triangles, Topology::Lines, Topology::Points]
                .into_iter()
                .flat_map(|t| [Kind::Any, Kind::Woven, Kind::Gltf].map(|k| (t, k)))
                .filter(|&(t, k)| {
                    scene
                        .draws
                        .iter()
                        .any(|d| !d.forward && d.topology == t && kind_of(d.woven) == k)
                })
                .filter_map(|(t, k)| {
                    self.variants
                        .get(&(key.clone(), t, k, inputs.depth_prepass))
                        .map(|p| (t, k, p))
                })
                .collect();
        let depth_pipeline = if inputs.depth_prepass {
            let pipeline = self.depth.get().ok_or_else(|| {
                crate::Error::device("the G-buffer's depth pre-pass pipeline was not made")
            })?;
            let set = pool.set(&self.depth_layout, &[(0, Resource::Uniform(inputs.frame))])?;
            Some((pipeline, set))
        } else {
            None
        };
        let names = depth_pipeline
            .iter()
            .map(|(p, _)| p.name.clone())
            .chain(pipelines.iter().map(|(_, _, p)| p.name.clone()))
            .collect();
        let targets = inputs.targets;
        let material_sets = inputs.material_sets;
        let world_light = inputs.world_light;
        Ok(Recorded::new("gbuffer", names, move |cmd| {
            for img in targets.gbuffer_colors() {
                cmd.transition(img, Usage::Undefined, Usage::ColorAttachment, None);
            }
            cmd.transition(
                &targets.depth,
                Usage::Undefined,
                Usage::DepthAttachment,
                None,
            );
            let colors: Vec<Attachment> = targets
                .gbuffer_colors()
                .into_iter()
                .map(|image| Attachment {
                    image,
                    // Cleared: the frame (normals, tangents) and surface (material) targets,
                    // which fabric_lobes.frag reads at its neighbours, empty or not (an empty
                    // pixel's zeros pool with nothing). The albedo, fabric, emissive and
                    // specular targets are read only at pixels a draw wrote (the lighting's
                    // pipelines run over their stencil kinds, the background's reads depth
                    // alone, debug views show empty pixels black before any read): not cleared,
                    // about 20 ms of a 1080p frame on lavapipe.
                    load: if std::ptr::eq(image, &targets.frame)
                        || std::ptr::eq(image, &targets.surface)
                    {
                        Load::Clear([0.0; 4])
                    } else {
                        Load::Undefined
                    },
                })
                .collect();
            // The depth pre-pass: the opaque draws' depth (and the stencil cleared), so that the
            // shading below passes (GREATER_OR_EQUAL) only the visible fragment of each pixel.
            if let Some((depth, depth_set)) = depth_pipeline {
                cmd.begin_rendering(
                    &[],
                    Some(Attachment {
                        image: &targets.depth,
                        load: Load::Clear([0.0; 4]),
                    }),
                );
                cmd.bind_vertex_buffer(&scene.vertices);
                cmd.bind_index_buffer(&scene.indices);
                cmd.bind_pipeline(depth);
                cmd.bind_sets(depth, 0, &[depth_set]);
                for draw in scene.draws.iter().filter(|d| {
                    d.visible && !d.forward && !d.alpha_mask && d.topology == Topology::Triangles
                }) {
                    cmd.set_cull(if draw.double_sided {
                        Cull::None
                    } else {
                        Cull::Back
                    });
                    cmd.set_front_face(draw.mirrored());
                    cmd.push_constants(depth, &DrawPush::new(draw.world, draw.material));
                    cmd.draw_indexed(draw.index_count, draw.first_index, draw.vertex_offset);
                }
                cmd.end_rendering();
                cmd.transition(
                    &targets.depth,
                    Usage::DepthAttachment,
                    Usage::DepthAttachment,
                    None,
                );
            }
            cmd.begin_rendering(
                &colors,
                Some(Attachment {
                    image: &targets.depth,
                    load: if depth_pipeline.is_some() {
                        Load::Keep
                    } else {
                        Load::Clear([0.0; 4])
                    },
                }),
            );
            cmd.bind_vertex_buffer(&scene.vertices);
            cmd.bind_index_buffer(&scene.indices);
            // Each topology and kind of material with its pipeline (the same layout and
            // shaders); depth makes the order moot.
            for (topology, kind, pipeline) in pipelines {
                // Draws the G-buffer cannot hold are the transparent pass's.
                let mut draws = scene
                    .draws
                    .iter()
                    .filter(|d| {
                        d.visible
                            && !d.forward
                            && d.topology == topology
                            && kind_of(d.woven) == kind
                    })
                    .peekable();
                if draws.peek().is_none() {
                    continue;
                }
                cmd.bind_pipeline(pipeline);
                cmd.bind_sets(pipeline, 0, &[frame_set]);
                for draw in draws {
                    let material = draw.material.min(scene.material_count - 1);
                    cmd.bind_sets(pipeline, 1, &[material_sets[material as usize]]);
                    cmd.set_cull(if draw.double_sided {
                        Cull::None
                    } else {
                        Cull::Back
                    });
                    cmd.set_front_face(draw.mirrored());
                    if stencil {
                        cmd.set_stencil_reference(stencil_of(draw.woven, fabric_as_pbr));
                    }
                    let mut push = DrawPush::new(draw.world, material);
                    if !draw.receive_shadows {
                        push.flags &= !DRAW_RECEIVES_SHADOWS;
                    }
                    if let Some(base) =
                        world_light.and_then(|w| w.base.get(draw.scene_draw).copied().flatten())
                    {
                        push.world_base = base.wrapping_sub(draw.vertex_offset as u32);
                        push.flags |= DRAW_WORLD_LIGHT;
                    }
                    cmd.push_constants(pipeline, &push);
                    cmd.draw_indexed(draw.index_count, draw.first_index, draw.vertex_offset);
                }
            }
            cmd.end_rendering();
            for img in targets.gbuffer_colors() {
                cmd.transition(img, Usage::ColorAttachment, Usage::FragmentRead, None);
            }
            cmd.transition(
                &targets.depth,
                Usage::DepthAttachment,
                Usage::FragmentRead,
                None,
            );
        }))
    }
}
