//! The tonemap pass: exposure and tone curve into the 8-bit target.

use crate::render::frame::Targets;
use crate::render::gpu::TonemapPush;
use crate::vk::{Attachment, Cmd, DescriptorSet, Pipeline, Usage};

/// Reads HDR, writes the display-referred 8-bit image.
pub fn tonemap_pass<'s>(
    cmd: &mut Cmd<'s>,
    pipeline: &'s Pipeline,
    set: DescriptorSet<'s>,
    push: &TonemapPush,
    targets: &'s Targets,
) {
    cmd.transition(&targets.ldr, Usage::Undefined, Usage::ColorAttachment, None);
    cmd.begin_rendering(
        &[Attachment {
            image: &targets.ldr,
            clear: None,
        }],
        None,
    );
    cmd.bind_pipeline(pipeline);
    cmd.bind_sets(pipeline, 0, &[set]);
    cmd.push_constants(pipeline, push);
    cmd.draw(3);
    cmd.end_rendering();
}
