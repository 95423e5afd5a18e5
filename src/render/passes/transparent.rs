//! The transparent pass: after deferred lighting, the draws the G-buffer cannot hold. First the
//! transmissive ones (KHR_materials_transmission, not BLEND), which read a backdrop (the lit
//! opaque image, copied with mips at the start of the pass) and are opaque here: nearest first,
//! writing depth. Then the alphaMode BLEND ones, back to front, depth-tested against everything
//! without writing depth, blended premultiplied by their base colour's alpha. forward.frag
//! computes each fragment's surface as gbuffer.frag does and lights it as lighting.frag lights a
//! pixel (glsl/include/surface.glsl and shade.glsl).
//!
//! Order of the blended draws: whole draws, by the distance along the view direction of their
//! bounds' centres, farthest first; within a draw, its triangles in index order, except that a double-sided draw
//! is drawn twice, back faces first, then front faces, so a closed blended mesh shows its far
//! side through its near side. What this gets wrong: blended draws that interpenetrate, or a
//! large one whose centre is nearer than a small one in front of it, and the back faces of a
//! single-sided mesh (culled, as the spec says). No order-independent transparency.

use std::collections::HashMap;

use glam::{Mat4, Vec3};

use super::{Recorded, SceneLighting, VariantKey};
use crate::render::gpu::{DrawPush, DRAW_RECEIVES_SHADOWS};
use crate::render::plan::Plan;
use crate::render::targets::{depth_format, Targets, HDR_FORMAT};
use crate::render::upload::{gbuffer_vertex_layout, GpuScene};
use crate::vk::{
    shaders, spec_constant_ids, Attachment, Buffer, Cmd, Context, Cull, DepthTest, DescriptorPool,
    DescriptorSet, GraphicsDesc, Image, Load, Pipeline, Resource, Sampler, SetLayout, Stages,
    StencilMode, Topology, Usage,
};

/// The pass's pipelines by variant and blend mode (true: BLEND, blended without depth writes;
/// false: transmissive draws, opaque, writing depth), and its two set layouts (reflected from
/// gbuffer.vert and forward.frag: set 0 the G-buffer pass's buffers and the lighting pass's
/// shadow and environment bindings, set 1 a material's textures, every slot).
pub struct TransparentPass {
    layout: SetLayout,
    pub(crate) material_layout: SetLayout,
    /// The specialization constants gbuffer.vert and forward.frag declare, and gbuffer.vert and
    /// forward_gltf.frag (the woven model's compiled out).
    constants: Vec<u32>,
    gltf_constants: Vec<u32>,
    variants: HashMap<(VariantKey, bool), Pipeline>,
}

/// What the pass reads (see [`TransparentPass::record`]).
pub struct TransparentInputs<'s> {
    pub scene: &'s GpuScene,
    pub lighting: SceneLighting<'s>,
    /// Vertex colours (the G-buffer pass's).
    pub colors: &'s Buffer,
    /// Per material, the set of its textures (`material_layout`).
    pub material_sets: Vec<DescriptorSet<'s>>,
    pub targets: &'s Targets,
    /// The backdrop for transmissive draws (the lit opaque image with mips, made by the frame
    /// when the plan has transmissive draws) and its sampler; else `white` is bound.
    pub backdrop: Option<(&'s Image, &'s Sampler)>,
    pub white: (&'s Image, &'s Sampler),
    /// The camera's view matrix (the blended draws' order).
    pub view: Mat4,
    /// `Force::back_faces_first` for the opaque forward draws (a bench comparison).
    pub opaque_back_faces_first: bool,
}

impl TransparentPass {
    pub fn new(ctx: &Context) -> crate::Result<TransparentPass> {
        let shaders = [&shaders::GBUFFER_VERT, &shaders::FORWARD_FRAG];
        let [layout, material_layout] = ctx.reflected_set_layouts(&shaders)?;
        Ok(TransparentPass {
            layout,
            material_layout,
            constants: spec_constant_ids(&shaders)?,
            gltf_constants: spec_constant_ids(&[
                &shaders::GBUFFER_VERT,
                &shaders::FORWARD_GLTF_FRAG,
            ])?,
            variants: HashMap::new(),
        })
    }

    /// The variant for `plan`: gbuffer.frag's constants under their ids (the vertex stage reads
    /// 2, 3 and 5, with LIGHT_TYPES the scene's), lighting.frag's others + 10 (but OCCLUSION: the
    /// occlusion pass's visibility is not read here), then the
    /// forward-only features.
    pub fn key(
        gbuffer: &VariantKey,
        lighting: &VariantKey,
        light_types: u32,
        plan: &Plan,
    ) -> VariantKey {
        let mut key: Vec<(u32, &'static str, u32)> = gbuffer.0[..6].to_vec();
        key[3].2 = light_types;
        key.extend(
            lighting
                .0
                .iter()
                // (Not the occlusion, debug views, pixel kinds and glTF features: the
                // transparent pass compiles every kind and feature in.)
                .filter(|(id, _, _)| ![0, 3, 4].contains(id) && *id < 10)
                .map(|&(id, name, value)| (id + 10, name, value)),
        );
        key.extend([
            (20, "transmission", (plan.transmission_draws > 0) as u32),
            (21, "coat", (plan.coat_draws > 0) as u32),
            (
                22,
                "diffuse_transmission",
                (plan.diffuse_transmission_draws > 0) as u32,
            ),
            (23, "iridescence", (plan.iridescence_draws > 0) as u32),
            (24, "dispersion", (plan.dispersion_draws > 0) as u32),
            (25, "thread_colours", plan.features.thread_colours as u32),
            (26, "fabric_sheets", plan.fabric_sheets as u32),
            // Not a constant of either module: which module (forward_gltf.frag without fabric).
            (27, "woven", (plan.forward_woven_draws > 0) as u32),
        ]);
        VariantKey(key)
    }

    /// The blend modes of `key` the plan draws whose pipeline is not made yet.
    pub fn missing(&self, key: &VariantKey, plan: &Plan) -> Vec<bool> {
        [
            (plan.forward_opaque_draws > 0, false),
            (plan.blend_draws > 0, true),
        ]
        .into_iter()
        .filter(|&(needed, b)| needed && !self.variants.contains_key(&(key.clone(), b)))
        .map(|(_, b)| b)
        .collect()
    }

    /// Makes the pipeline of variant `key` and blend mode `blend` (not kept: see
    /// [`TransparentPass::insert`]).
    pub fn make(&self, ctx: &Context, key: &VariantKey, blend: bool) -> crate::Result<Pipeline> {
        // No fabric drawn forward: the module without the woven model, with forward.frag's set
        // layouts (its bindings are a subset, at the same numbers). Each module gets the
        // constants it declares.
        let (fragment, declared) = if key.value(27) != 0 {
            (&shaders::FORWARD_FRAG, &self.constants)
        } else {
            (&shaders::FORWARD_GLTF_FRAG, &self.gltf_constants)
        };
        let mut constants = key.constants();
        constants.retain(|c| declared.contains(&c.0));
        ctx.create_graphics_pipeline(&GraphicsDesc {
            name: &format!(
                "forward[{}{}]",
                if blend { "blend, " } else { "opaque, " },
                key.describe()
            ),
            vertex: &shaders::GBUFFER_VERT,
            fragment,
            vertex_layout: Some(gbuffer_vertex_layout()),
            color_formats: &[HDR_FORMAT],
            depth_format: Some(depth_format(ctx)),
            set_layouts: &[&self.layout, &self.material_layout],
            push_constant_size: std::mem::size_of::<DrawPush>() as u32,
            push_stages: Stages::GRAPHICS,
            constants: &constants,
            blend,
            topology: Topology::Triangles,
            stencil: StencilMode::None,
            depth_test: DepthTest::Nearer,
        })
    }

    pub fn insert(&mut self, key: VariantKey, blend: bool, pipeline: Pipeline) {
        self.variants.insert((key, blend), pipeline);
    }

    pub fn pipelines(&self) -> impl Iterator<Item = &Pipeline> {
        self.variants.values()
    }

    /// Records the pass with variant `key`: the transmissive draws, then the blended ones, over
    /// the HDR target (see [`transparent_pass`]). Returns also how many draws it blends.
    pub fn record<'s>(
        &'s self,
        pool: &'s DescriptorPool,
        key: &VariantKey,
        inputs: TransparentInputs<'s>,
    ) -> crate::Result<(Recorded<'s>, usize)> {
        let scene = inputs.scene;
        let pipelines = Pipelines {
            opaque: self.variants.get(&(key.clone(), false)),
            blend: self.variants.get(&(key.clone(), true)),
        };
        let (backdrop_image, backdrop_sampler) = inputs.backdrop.unwrap_or(inputs.white);
        let mut bindings = vec![
            (1, Resource::Storage(&scene.materials)),
            (2, Resource::Storage(&scene.fabrics)),
            (4, Resource::Storage(inputs.colors)),
            (5, Resource::Storage(&scene.thread_colours)),
            // gbuffer.vert's world light, which the forward pipelines never read (WORLD_LIGHT 0):
            // any buffer.
            (6, Resource::Storage(inputs.colors)),
            (16, Resource::Sampled(backdrop_image, backdrop_sampler)),
        ];
        bindings.extend(inputs.lighting.bindings());
        let frame_set = pool.set(&self.layout, &bindings)?;
        let order = back_to_front(scene, inputs.view);
        let blended = order.len();
        let names = [pipelines.opaque, pipelines.blend]
            .into_iter()
            .flatten()
            .map(|p| p.name.clone())
            .collect();
        let targets = inputs.targets;
        let backdrop = inputs.backdrop.map(|(b, _)| b);
        let material_sets = inputs.material_sets;
        let back_first = inputs.opaque_back_faces_first;
        Ok((
            Recorded::new("transparent", names, move |cmd| {
                transparent_pass(
                    cmd,
                    pipelines,
                    scene,
                    frame_set,
                    &material_sets,
                    targets,
                    backdrop,
                    &order,
                    back_first,
                )
            }),
            blended,
        ))
    }
}

/// The indices into `scene.draws` of the transparent pass's draws, farthest first from a camera with view
/// matrix `view` (view space looks down -Z): by the view-space depth of each draw's bounds'
/// centre; ties keep the scene's order.
pub fn back_to_front(scene: &GpuScene, view: Mat4) -> Vec<usize> {
    let mut order: Vec<(f32, usize)> = scene
        .draws
        .iter()
        .enumerate()
        .filter(|(_, d)| d.forward && d.visible)
        .map(|(i, d)| {
            let centre = view.transform_point3(d.world.transform_point3(d.centre));
            // -z is the distance in front of the camera; NaN (a degenerate matrix) sorts last.
            let depth = -centre.z;
            (
                if depth.is_nan() {
                    f32::NEG_INFINITY
                } else {
                    depth
                },
                i,
            )
        })
        .collect();
    order.sort_by(|a, b| b.0.total_cmp(&a.0));
    order.into_iter().map(|(_, i)| i).collect()
}

/// The centre of the bounds of the positions `positions`; the origin when there are none.
pub fn bounds_centre(positions: impl Iterator<Item = [f32; 3]>) -> Vec3 {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for p in positions {
        let p = Vec3::from(p);
        lo = lo.min(p);
        hi = hi.max(p);
    }
    if lo.cmple(hi).all() {
        (lo + hi) * 0.5
    } else {
        Vec3::ZERO
    }
}

/// Blends the draws `order` (indices into `scene.draws`, farthest first) over the HDR target,
/// first copying it into `backdrop` (with mips) when transmissive draws need it.
/// Reads: the G-buffer depth (as the depth attachment, test only), the frame set (frame,
/// materials, fabrics, lights, vertex colours, shadows, tile light lists, environment), each
/// draw's material set. Writes: the HDR target (left readable by fragment shaders, as the
/// lighting pass leaves it).
/// The pass's two pipelines (forward.frag): for its opaque draws (transmissive, not BLEND:
/// replacing, depth written) and for its BLEND draws (blended, depth only tested); each only when
/// the scene has such draws.
struct Pipelines<'s> {
    opaque: Option<&'s Pipeline>,
    blend: Option<&'s Pipeline>,
}

#[allow(clippy::too_many_arguments)]
fn transparent_pass<'s>(
    cmd: &mut Cmd<'s>,
    pipelines: Pipelines<'s>,
    scene: &'s GpuScene,
    frame_set: DescriptorSet<'s>,
    material_sets: &[DescriptorSet<'s>],
    targets: &'s Targets,
    backdrop: Option<&'s Image>,
    order: &[usize],
    opaque_back_faces_first: bool,
) {
    if let Some(b) = backdrop {
        // The lit opaque image, and its mips for rough transmission.
        cmd.transition(targets.hdr(), Usage::FragmentRead, Usage::TransferSrc, None);
        cmd.transition(b, Usage::Undefined, Usage::TransferDst, None);
        cmd.copy_image(targets.hdr(), b);
        cmd.generate_mips(b, Usage::FragmentRead);
        cmd.transition(targets.hdr(), Usage::TransferSrc, Usage::FragmentRead, None);
    }
    cmd.transition(
        targets.hdr(),
        Usage::FragmentRead,
        Usage::ColorAttachment,
        None,
    );
    cmd.transition(
        &targets.depth,
        Usage::FragmentRead,
        Usage::DepthAttachment,
        None,
    );
    cmd.begin_rendering(
        &[Attachment {
            image: targets.hdr(),
            load: Load::Keep,
        }],
        Some(Attachment {
            image: &targets.depth,
            load: Load::Keep,
        }),
    );
    // The opaque ones first, nearest first (depth hides what is behind them, among themselves
    // too), then the blended ones farthest first over everything.
    let opaque = order.iter().rev().filter(|&&i| !scene.draws[i].blended);
    let blended = order.iter().filter(|&&i| scene.draws[i].blended);
    // Blended: a double-sided draw's back faces first, so its far side shows through its near
    // side; opaque: front faces first, so depth rejects the back faces they hide before shading
    // them (`weft bench --plan` measures what that saves against `Force::back_faces_first`).
    for (pipeline, draws, back_first) in [
        (
            pipelines.opaque,
            opaque.copied().collect::<Vec<_>>(),
            opaque_back_faces_first,
        ),
        (pipelines.blend, blended.copied().collect::<Vec<_>>(), true),
    ] {
        let Some(pipeline) = pipeline.filter(|_| !draws.is_empty()) else {
            continue;
        };
        cmd.bind_pipeline(pipeline);
        cmd.bind_vertex_buffer(&scene.vertices);
        cmd.bind_index_buffer(&scene.indices);
        cmd.bind_sets(pipeline, 0, &[frame_set]);
        draw_all(cmd, pipeline, scene, material_sets, &draws, back_first);
    }
    cmd.end_rendering();
    cmd.transition(
        targets.hdr(),
        Usage::ColorAttachment,
        Usage::FragmentRead,
        None,
    );
    cmd.transition(
        &targets.depth,
        Usage::DepthAttachment,
        Usage::FragmentRead,
        None,
    );
}

/// Records `draws` (indices into `scene.draws`) with `pipeline` bound: a double-sided draw twice,
/// back faces first when `back_first`, else front faces first.
fn draw_all<'s>(
    cmd: &mut Cmd<'s>,
    pipeline: &'s Pipeline,
    scene: &'s GpuScene,
    material_sets: &[DescriptorSet<'s>],
    draws: &[usize],
    back_first: bool,
) {
    for &i in draws {
        let draw = &scene.draws[i];
        let material = draw.material.min(scene.material_count - 1);
        cmd.bind_sets(pipeline, 1, &[material_sets[material as usize]]);
        let mut push = DrawPush::new(draw.world, material);
        if !draw.receive_shadows {
            push.flags &= !DRAW_RECEIVES_SHADOWS;
        }
        cmd.push_constants(pipeline, &push);
        cmd.set_front_face(draw.mirrored());
        let faces: &[Cull] = if draw.double_sided && back_first {
            &[Cull::Front, Cull::Back]
        } else if draw.double_sided {
            &[Cull::Back, Cull::Front]
        } else {
            &[Cull::Back]
        };
        for &cull in faces {
            cmd.set_cull(cull);
            cmd.draw_indexed(draw.index_count, draw.first_index, draw.vertex_offset);
        }
    }
}
