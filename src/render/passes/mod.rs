//! The passes of a frame, one file each, in the order a frame runs them (the plan's
//! [`crate::render::Pass`] list; `Renderer::render_frame` in frame.rs records them in this order):
//!
//! 1. [`environment`]: once per environment, cached: radiance cube, GGX-prefiltered cube, SH;
//! 2. weave (at upload, `Renderer::build_weave`): the coverage textures of each distinct weave;
//! 3. [`gbuffer`]: every draw into the G-buffer;
//! 4. [`shadow`]: casters into the shadow atlas;
//! 5. [`lighting`]: lamps and the environment from the G-buffer into HDR;
//! 6. [`transparent`]: alphaMode BLEND draws, forward-lit, back to front over HDR;
//! 7. [`tonemap`]: exposure and tone curve into the 8-bit target;
//! 8. [`antialias`] (`--aa fxaa`): edge anti-aliasing of the tone-mapped image into the 8-bit
//!    target (the tone-map pass then writes an intermediate one).
//!
//! Each function's signature says what it reads and writes.

pub mod antialias;
pub mod environment;
pub mod gbuffer;
pub mod lighting;
pub mod shadow;
pub mod tonemap;
pub mod transparent;

/// The body of a fullscreen pass (lighting, tone map, anti-aliasing): `target` from undefined to
/// a colour attachment, `pipeline` with `set` (and `push`, if any) over one fullscreen triangle.
pub(crate) fn fullscreen<'s, P: bytemuck::Pod>(
    cmd: &mut crate::vk::Cmd<'s>,
    pipeline: &'s crate::vk::Pipeline,
    set: crate::vk::DescriptorSet<'s>,
    push: Option<&P>,
    target: &'s crate::vk::Image,
) {
    use crate::vk::{Attachment, Usage};
    cmd.transition(target, Usage::Undefined, Usage::ColorAttachment, None);
    cmd.begin_rendering(
        &[Attachment {
            image: target,
            clear: None,
        }],
        None,
    );
    cmd.bind_pipeline(pipeline);
    cmd.bind_sets(pipeline, 0, &[set]);
    if let Some(push) = push {
        cmd.push_constants(pipeline, push);
    }
    cmd.draw(3);
    cmd.end_rendering();
}
