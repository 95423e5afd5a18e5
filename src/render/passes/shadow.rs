//! The shadow pass: casters into the shadow atlas, one tile per light.

use std::collections::HashMap;

use glam::Mat4;

use super::Recorded;
use crate::render::gpu::{ShadowMaskPush, ShadowPush};
use crate::render::targets::SHADOW_FORMAT;
use crate::render::upload::{position_vertex_layout, GpuScene, VERTEX_FLOATS};
use crate::vk::{
    shaders, Attachment, Buffer, Cmd, Context, DepthTest, DescriptorPool, DescriptorSet, Format,
    GraphicsDesc, Image, Load, Pipeline, Resource, Sampler, SetLayout, Stages, StencilMode,
    Topology, Usage, VertexLayout,
};

/// The pass's pipelines: depth only for opaque casters (shadow.vert/.frag), and for alphaMode
/// MASK casters the cut-out pipeline (shadow_mask.vert/.frag) by VERTEX_COLORS, made when a frame
/// first needs it, with its two set layouts (materials and vertex colours; the base colour
/// texture) reflected from its shaders.
pub struct ShadowPass {
    pipeline: Pipeline,
    mask_variants: HashMap<u32, Pipeline>,
    mask_layout: SetLayout,
    mask_texture_layout: SetLayout,
}

/// What the pass reads; it writes the shadow atlas (left readable by fragment shaders).
pub struct ShadowInputs<'s> {
    pub scene: &'s GpuScene,
    pub atlas: &'s Image,
    /// Per map: its tile's origin (x, y) and side in the atlas, and the light's clip-from-world.
    pub tiles: Vec<(u32, u32, u32, Mat4)>,
    /// Cut out alphaMode MASK casters (a MASK material casts into a map); with the vertex
    /// colours (the frame's), and each MASK material's base colour texture sampled with
    /// `sampler` (`white` where it has none).
    pub mask_casters: bool,
    pub vertex_colors: bool,
    pub colors: &'s Buffer,
    pub white: &'s Image,
    pub sampler: &'s Sampler,
}

impl ShadowPass {
    pub fn new(ctx: &Context) -> crate::Result<ShadowPass> {
        let mask = [&shaders::SHADOW_MASK_VERT, &shaders::SHADOW_MASK_FRAG];
        let [mask_layout, mask_texture_layout] = ctx.reflected_set_layouts(&mask)?;
        Ok(ShadowPass {
            pipeline: ctx.create_graphics_pipeline(&GraphicsDesc {
                name: "shadow",
                vertex: &shaders::SHADOW_VERT,
                fragment: &shaders::SHADOW_FRAG,
                vertex_layout: Some(position_vertex_layout()),
                color_formats: &[],
                depth_format: Some(SHADOW_FORMAT),
                set_layouts: &[],
                push_constant_size: std::mem::size_of::<ShadowPush>() as u32,
                push_stages: Stages::VERTEX,
                constants: &[],
                blend: false,
                topology: Topology::Triangles,
                stencil: StencilMode::None,
                depth_test: DepthTest::Nearer,
            })?,
            mask_variants: HashMap::new(),
            mask_layout,
            mask_texture_layout,
        })
    }

    /// Makes the cut-out pipeline for `vertex_colors` if it is not made yet.
    pub fn make_mask(&mut self, ctx: &Context, vertex_colors: bool) -> crate::Result<()> {
        let key = vertex_colors as u32;
        if !self.mask_variants.contains_key(&key) {
            let pipeline = ctx.create_graphics_pipeline(&GraphicsDesc {
                name: &format!("shadow_mask[vertex_colors={key}]"),
                vertex: &shaders::SHADOW_MASK_VERT,
                fragment: &shaders::SHADOW_MASK_FRAG,
                vertex_layout: Some(VertexLayout {
                    stride: (VERTEX_FLOATS * 4) as u32,
                    attributes: vec![
                        (0, Format::R32G32B32_SFLOAT, 0),
                        (1, Format::R32G32_SFLOAT, 40),
                        (2, Format::R32G32_SFLOAT, 56),
                    ],
                }),
                color_formats: &[],
                depth_format: Some(SHADOW_FORMAT),
                set_layouts: &[&self.mask_layout, &self.mask_texture_layout],
                push_constant_size: std::mem::size_of::<ShadowMaskPush>() as u32,
                push_stages: Stages::GRAPHICS,
                constants: &[(0, key)],
                blend: false,
                topology: Topology::Triangles,
                stencil: StencilMode::None,
                depth_test: DepthTest::Nearer,
            })?;
            self.mask_variants.insert(key, pipeline);
        }
        Ok(())
    }

    pub fn pipelines(&self) -> impl Iterator<Item = &Pipeline> {
        std::iter::once(&self.pipeline).chain(self.mask_variants.values())
    }

    /// Records the pass (the cut-out pipeline made by [`ShadowPass::make_mask`] when
    /// `mask_casters`). Returns also the caster draws it makes.
    pub fn record<'s>(
        &'s self,
        pool: &'s DescriptorPool,
        inputs: ShadowInputs<'s>,
    ) -> crate::Result<(Recorded<'s>, usize)> {
        let scene = inputs.scene;
        let mask = if inputs.mask_casters {
            let pipeline = self
                .mask_variants
                .get(&(inputs.vertex_colors as u32))
                .expect("the frame makes the cut-out pipeline before recording");
            let set = pool.set(
                &self.mask_layout,
                &[
                    (1, Resource::Storage(&scene.materials)),
                    (4, Resource::Storage(inputs.colors)),
                ],
            )?;
            let textures = (0..scene.material_count as usize)
                .map(|m| {
                    if !scene.material_mask.get(m).copied().unwrap_or(false) {
                        return Ok(None);
                    }
                    let base = scene
                        .material_textures
                        .get(m)
                        .and_then(|t| t[0])
                        .and_then(|i| scene.textures.get(i))
                        .unwrap_or(inputs.white);
                    pool.set(
                        &self.mask_texture_layout,
                        &[(0, Resource::Sampled(base, inputs.sampler))],
                    )
                    .map(Some)
                })
                .collect::<crate::Result<Vec<_>>>()?;
            Some(MaskCasters {
                pipeline,
                set,
                textures,
            })
        } else {
            None
        };
        let mut names = vec![self.pipeline.name.clone()];
        names.extend(mask.as_ref().map(|m| m.pipeline.name.clone()));
        let draws = inputs.tiles.len()
            * scene
                .draws
                .iter()
                .filter(|d| d.cast_shadows && d.visible)
                .count();
        let (atlas, tiles, pipeline) = (inputs.atlas, inputs.tiles, &self.pipeline);
        Ok((
            Recorded::new("shadow", names, move |cmd| {
                shadow_pass(cmd, pipeline, mask.as_ref(), scene, atlas, &tiles)
            }),
            draws,
        ))
    }
}

/// What casting alphaMode MASK draws needs (only when a MASK material casts): the cut-out
/// pipeline, its set of materials and vertex colours, and per material the set of its base
/// colour texture (None for materials that are not MASK).
struct MaskCasters<'s> {
    pipeline: &'s Pipeline,
    set: DescriptorSet<'s>,
    textures: Vec<Option<DescriptorSet<'s>>>,
}

/// Renders every caster into each light's tile of the shadow atlas (depth only, both faces):
/// opaque casters with `pipeline`, MASK casters (when `mask` is given) with its cut-out pipeline,
/// which discards where the base colour's alpha is below the cutoff.
fn shadow_pass<'s>(
    cmd: &mut Cmd<'s>,
    pipeline: &'s Pipeline,
    mask: Option<&MaskCasters<'s>>,
    scene: &'s GpuScene,
    atlas: &'s Image,
    tiles: &[(u32, u32, u32, Mat4)],
) {
    cmd.transition(atlas, Usage::Undefined, Usage::DepthAttachment, None);
    cmd.begin_rendering(
        &[],
        Some(Attachment {
            image: atlas,
            load: Load::Clear([0.0; 4]),
        }),
    );
    cmd.bind_vertex_buffer(&scene.vertices);
    cmd.bind_index_buffer(&scene.indices);
    let cut = |d: &crate::render::upload::DrawRange| mask.is_some() && d.alpha_mask;
    for &(x, y, resolution, clip_from_world) in tiles {
        cmd.set_viewport(x, y, resolution, resolution);
        cmd.bind_pipeline(pipeline);
        for draw in scene
            .draws
            .iter()
            .filter(|d| d.cast_shadows && d.visible && !cut(d))
        {
            let push = ShadowPush {
                clip_from_object: (clip_from_world * draw.world).to_cols_array_2d(),
            };
            cmd.push_constants(pipeline, &push);
            cmd.draw_indexed(draw.index_count, draw.first_index, draw.vertex_offset);
        }
        let Some(mask) = mask else {
            continue;
        };
        cmd.bind_pipeline(mask.pipeline);
        cmd.bind_sets(mask.pipeline, 0, &[mask.set]);
        for draw in scene
            .draws
            .iter()
            .filter(|d| d.cast_shadows && d.visible && cut(d))
        {
            let material = draw.material.min(scene.material_count - 1);
            let Some(Some(texture)) = mask.textures.get(material as usize) else {
                continue;
            };
            cmd.bind_sets(mask.pipeline, 1, &[*texture]);
            let push = ShadowMaskPush {
                clip_from_object: (clip_from_world * draw.world).to_cols_array_2d(),
                material,
                pad: [0; 3],
            };
            cmd.push_constants(mask.pipeline, &push);
            cmd.draw_indexed(draw.index_count, draw.first_index, draw.vertex_offset);
        }
    }
    cmd.end_rendering();
    cmd.transition(atlas, Usage::DepthAttachment, Usage::FragmentRead, None);
}
