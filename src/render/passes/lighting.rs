//! The deferred lighting pass: one fullscreen triangle from the G-buffer into HDR.

use crate::render::frame::Targets;
use crate::vk::{Attachment, Cmd, DescriptorSet, Pipeline, Usage};

/// Reads the G-buffer, writes HDR radiance.
pub fn lighting_pass<'s>(
    cmd: &mut Cmd<'s>,
    pipeline: &'s Pipeline,
    set: DescriptorSet<'s>,
    targets: &'s Targets,
) {
    cmd.transition(&targets.hdr, Usage::Undefined, Usage::ColorAttachment, None);
    cmd.begin_rendering(
        &[Attachment {
            image: &targets.hdr,
            clear: None,
        }],
        None,
    );
    cmd.bind_pipeline(pipeline);
    cmd.bind_sets(pipeline, 0, &[set]);
    cmd.draw(3);
    cmd.end_rendering();
    cmd.transition(
        &targets.hdr,
        Usage::ColorAttachment,
        Usage::FragmentRead,
        None,
    );
}
