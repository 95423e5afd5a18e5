//! The anti-aliasing pass (`--aa fxaa`): edge anti-aliasing of the tone-mapped image, which the
//! tone-map pass then writes into `targets.tonemapped` instead of the output.

use crate::render::frame::Targets;
use crate::vk::{Cmd, DescriptorSet, Pipeline, Usage};

/// Reads the tone-mapped image (`set`: `targets.tonemapped`, linear-filtered), writes the
/// 8-bit output target.
pub fn antialias_pass<'s>(
    cmd: &mut Cmd<'s>,
    pipeline: &'s Pipeline,
    set: DescriptorSet<'s>,
    targets: &'s Targets,
) {
    let source = targets
        .tonemapped
        .as_ref()
        .expect("the frame makes the tone-mapped target when it plans this pass");
    cmd.transition(source, Usage::ColorAttachment, Usage::FragmentRead, None);
    super::fullscreen::<u32>(cmd, pipeline, set, None, &targets.ldr);
}
