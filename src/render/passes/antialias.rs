//! The anti-aliasing pass (`--aa fxaa`): edge anti-aliasing of the tone-mapped image, which the
//! tone-map pass then writes into `targets.tonemapped` instead of the output.

use crate::render::frame::Targets;
use crate::vk::{Attachment, Cmd, DescriptorSet, Pipeline, Usage};

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
    cmd.draw(3);
    cmd.end_rendering();
}
