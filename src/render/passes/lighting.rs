//! The deferred lighting pass: one fullscreen triangle from the G-buffer into HDR.

use crate::render::frame::Targets;
use crate::vk::{Cmd, DescriptorSet, Pipeline, Usage};

/// Reads the G-buffer, writes HDR radiance.
pub fn lighting_pass<'s>(
    cmd: &mut Cmd<'s>,
    pipeline: &'s Pipeline,
    set: DescriptorSet<'s>,
    targets: &'s Targets,
) {
    super::fullscreen::<u32>(cmd, pipeline, set, None, &targets.hdr);
    cmd.transition(
        &targets.hdr,
        Usage::ColorAttachment,
        Usage::FragmentRead,
        None,
    );
}
