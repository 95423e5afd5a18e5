//! The G-buffer pass: every draw into the five colour targets and depth.

use crate::render::frame::{GpuScene, Targets};
use crate::render::gpu::{DrawPush, DRAW_RECEIVES_SHADOWS};
use crate::vk::{Attachment, Cmd, Cull, DescriptorSet, Pipeline, Topology, Usage};

/// The G-buffer pass's pipelines: triangles, and (in scenes that have them) lines and points.
pub struct GBufferPipelines<'s> {
    pub triangles: &'s Pipeline,
    pub lines: Option<&'s Pipeline>,
    pub points: Option<&'s Pipeline>,
}

/// Writes every G-buffer target and depth. Reads: scene geometry, materials, frame uniform.
pub fn gbuffer_pass<'s>(
    cmd: &mut Cmd<'s>,
    pipelines: &GBufferPipelines<'s>,
    scene: &'s GpuScene,
    frame_set: DescriptorSet<'s>,
    material_sets: &[DescriptorSet<'s>],
    targets: &'s Targets,
) {
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
            clear: Some([0.0; 4]),
        })
        .collect();
    cmd.begin_rendering(
        &colors,
        Some(Attachment {
            image: &targets.depth,
            clear: Some([0.0; 4]),
        }),
    );
    cmd.bind_vertex_buffer(&scene.vertices);
    cmd.bind_index_buffer(&scene.indices);
    // Each topology with its pipeline (the same layout and shaders); depth makes the order moot.
    for (topology, pipeline) in [
        (Topology::Triangles, Some(pipelines.triangles)),
        (Topology::Lines, pipelines.lines),
        (Topology::Points, pipelines.points),
    ] {
        let Some(pipeline) = pipeline else { continue };
        // Draws the G-buffer cannot hold are the transparent pass's.
        let mut draws = scene
            .draws
            .iter()
            .filter(|d| !d.forward && d.topology == topology)
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
            let mut push = DrawPush::new(draw.world, material);
            if !draw.receive_shadows {
                push.flags &= !DRAW_RECEIVES_SHADOWS;
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
}
