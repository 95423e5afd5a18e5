//! The shadow pass: casters into the shadow atlas, one tile per light.

use glam::Mat4;

use crate::render::frame::GpuScene;
use crate::render::gpu::ShadowPush;
use crate::vk::{Attachment, Cmd, Image, Pipeline, Usage};

/// Renders every caster into each light's tile of the shadow atlas (depth only, both faces).
pub fn shadow_pass<'s>(
    cmd: &mut Cmd<'s>,
    pipeline: &'s Pipeline,
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
    cmd.bind_pipeline(pipeline);
    cmd.bind_vertex_buffer(&scene.vertices);
    cmd.bind_index_buffer(&scene.indices);
    for &(x, y, resolution, clip_from_world) in tiles {
        cmd.set_viewport(x, y, resolution, resolution);
        for draw in scene.draws.iter().filter(|d| d.cast_shadows) {
            let push = ShadowPush {
                clip_from_object: (clip_from_world * draw.world).to_cols_array_2d(),
            };
            cmd.push_constants(pipeline, &push);
            cmd.draw_indexed(draw.index_count, draw.first_index, draw.vertex_offset);
        }
    }
    cmd.end_rendering();
    cmd.transition(atlas, Usage::DepthAttachment, Usage::FragmentRead, None);
}
