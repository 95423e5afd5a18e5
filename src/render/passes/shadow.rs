//! The shadow pass: casters into the shadow atlas, one tile per light.

use glam::Mat4;

use crate::render::frame::GpuScene;
use crate::render::gpu::{ShadowMaskPush, ShadowPush};
use crate::vk::{Attachment, Cmd, DescriptorSet, Image, Pipeline, Usage};

/// What casting alphaMode MASK draws needs (only when a MASK material casts): the cut-out
/// pipeline, its set of materials and vertex colours, and per material the set of its base
/// colour texture (None for materials that are not MASK).
pub struct MaskCasters<'s> {
    pub pipeline: &'s Pipeline,
    pub set: DescriptorSet<'s>,
    pub textures: Vec<Option<DescriptorSet<'s>>>,
}

/// Renders every caster into each light's tile of the shadow atlas (depth only, both faces):
/// opaque casters with `pipeline`, MASK casters (when `mask` is given) with its cut-out pipeline,
/// which discards where the base colour's alpha is below the cutoff.
pub fn shadow_pass<'s>(
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
            clear: Some([0.0; 4]),
        }),
    );
    cmd.bind_vertex_buffer(&scene.vertices);
    cmd.bind_index_buffer(&scene.indices);
    let cut = |d: &crate::render::frame::DrawRange| mask.is_some() && d.alpha_mask;
    for &(x, y, resolution, clip_from_world) in tiles {
        cmd.set_viewport(x, y, resolution, resolution);
        cmd.bind_pipeline(pipeline);
        for draw in scene.draws.iter().filter(|d| d.cast_shadows && !cut(d)) {
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
        for draw in scene.draws.iter().filter(|d| d.cast_shadows && cut(d)) {
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
