//! The tonemap pass: exposure and tone curve into the 8-bit target.

use crate::render::frame::Targets;
use crate::render::gpu::TonemapPush;
use crate::vk::{Cmd, DescriptorSet, Pipeline};

/// Reads HDR, writes the display-referred 8-bit image: the output target, or with the
/// anti-aliasing pass planned, `targets.tonemapped` for it to read.
pub fn tonemap_pass<'s>(
    cmd: &mut Cmd<'s>,
    pipeline: &'s Pipeline,
    set: DescriptorSet<'s>,
    push: &TonemapPush,
    targets: &'s Targets,
    antialiased: bool,
) {
    let target = match (&targets.tonemapped, antialiased) {
        (Some(t), true) => t,
        _ => &targets.ldr,
    };
    super::fullscreen(cmd, pipeline, set, Some(push), target);
}
