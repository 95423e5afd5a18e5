//! `weft view`'s overlapped frames (`Renderer::render_frame_overlapped`: a frame's submission is
//! not waited for; the next frame records itself, then waits for it, then submits) on lavapipe
//! with the validation layer on (synchronization validation included): the image is bit for bit
//! the synchronous path's, and resizing, switching scenes and dropping the renderer while a frame
//! is in flight are safe and clean.

mod common;

use weft::render::{GpuScene, RenderOptions, Renderer, ToneCurve};
use weft::scene::{self, Scene};
use weft::vk::{BufferLocation, BufferUsageFlags, Context, Image, Usage};

fn options(width: u32, height: u32) -> RenderOptions {
    RenderOptions {
        width,
        height,
        ..Default::default()
    }
}

/// Two frames that differ in every pass: the projection (jitter: G-buffer, shadows, lighting),
/// exposure and tone curve (tonemap).
fn frame_a(width: u32, height: u32) -> RenderOptions {
    options(width, height)
}

fn frame_b(width: u32, height: u32) -> RenderOptions {
    RenderOptions {
        jitter: [0.37, -0.21],
        exposure: 0.7,
        tonemap: ToneCurve::Aces,
        ..options(width, height)
    }
}

/// The 8-bit target as a frame left it (ColorAttachment usage), copied to the host by a
/// submission of its own, after whatever is in flight in queue order.
fn read_target(ctx: &Context, ldr: &Image) -> Vec<u8> {
    let (w, h) = ldr.extent();
    let buffer = ctx
        .create_buffer(
            "test readback",
            u64::from(w) * u64::from(h) * 4,
            BufferUsageFlags::TRANSFER_DST,
            BufferLocation::Readback,
        )
        .expect("buffer");
    ctx.submit(|cmd| {
        cmd.transition(ldr, Usage::ColorAttachment, Usage::TransferSrc, None);
        cmd.copy_image_to_buffer(ldr, 0, &buffer);
        cmd.transition(ldr, Usage::TransferSrc, Usage::ColorAttachment, None);
        cmd.buffer_barrier();
    })
    .expect("readback");
    buffer.read().expect("host-visible").to_vec()
}

fn synchronous(r: &mut Renderer, scene: &Scene, gpu: &GpuScene, o: &RenderOptions) -> Vec<u8> {
    r.render_frame(scene, gpu, o)
        .expect("synchronous frame without validation messages")
        .ldr
}

fn overlapped(r: &mut Renderer, scene: &Scene, gpu: &GpuScene, o: &RenderOptions) {
    r.render_frame_overlapped(scene, gpu, o)
        .expect("overlapped frame without validation messages");
}

fn differing(a: &[u8], b: &[u8]) -> usize {
    a.chunks_exact(4)
        .zip(b.chunks_exact(4))
        .filter(|(p, q)| p != q)
        .count()
}

#[test]
fn overlapped_frames_are_the_synchronous_frames() {
    let ctx = common::context();
    let mut r = Renderer::new(ctx.clone()).expect("renderer");
    let scene = scene::default_scene();
    let gpu = r.upload(&scene).expect("upload");
    let (w, h) = (160, 90);
    let want_a = synchronous(&mut r, &scene, &gpu, &frame_a(w, h));
    let want_b = synchronous(&mut r, &scene, &gpu, &frame_b(w, h));
    assert!(
        differing(&want_a, &want_b) > (w * h / 2) as usize,
        "the two frames should differ almost everywhere"
    );

    // Back to back, each recorded while the one before is in flight; read after the last.
    overlapped(&mut r, &scene, &gpu, &frame_a(w, h));
    overlapped(&mut r, &scene, &gpu, &frame_b(w, h));
    overlapped(&mut r, &scene, &gpu, &frame_a(w, h));
    let (first, ldr) = r
        .render_frame_overlapped(&scene, &gpu, &frame_b(w, h))
        .expect("overlapped frame");
    let got_b = read_target(&ctx, ldr);
    // The frame's GPU times are the previous frame's, read when it was waited for.
    assert!(first
        .timings
        .iter()
        .any(|t| t.name == "submission (previous frame)"));
    assert!(first
        .timings
        .iter()
        .any(|t| t.name == "wait for the previous frame" && t.wall_ms.is_some()));
    assert_eq!(first.stats.submissions, 1);
    let last = r
        .finish()
        .expect("last frame's timings, no validation messages");
    assert!(last
        .iter()
        .any(|t| t.name == "gbuffer" && t.gpu_ms.is_some()));
    assert_eq!(
        differing(&got_b, &want_b),
        0,
        "overlapped frame B differs from the synchronous one"
    );

    overlapped(&mut r, &scene, &gpu, &frame_b(w, h));
    let (_, ldr) = r
        .render_frame_overlapped(&scene, &gpu, &frame_a(w, h))
        .expect("overlapped frame");
    let got_a = read_target(&ctx, ldr);
    assert_eq!(
        differing(&got_a, &want_a),
        0,
        "overlapped frame A differs from the synchronous one"
    );
    // The synchronous path after an overlapped frame waits for it, and is unchanged.
    assert_eq!(synchronous(&mut r, &scene, &gpu, &frame_b(w, h)), want_b);
    ctx.check_validation().expect("no validation messages");
}

#[test]
fn resizing_switching_scenes_and_dropping_mid_flight_are_safe() {
    let ctx = common::context();
    let mut r = Renderer::new(ctx.clone()).expect("renderer");
    let scene = scene::default_scene();
    let gpu = r.upload(&scene).expect("upload");

    // Resized with a frame in flight: the new targets wait for it; the image is right.
    overlapped(&mut r, &scene, &gpu, &frame_a(96, 54));
    let (_, ldr) = r
        .render_frame_overlapped(&scene, &gpu, &frame_b(128, 72))
        .expect("resized overlapped frame");
    let got = read_target(&ctx, ldr);
    let want = synchronous(&mut r, &scene, &gpu, &frame_b(128, 72));
    assert_eq!(differing(&got, &want), 0, "resized frame differs");

    // Another scene uploaded, rendered, and dropped while its frame is in flight (its buffers
    // wait for the frame as they go), then the first again.
    let other = {
        let mut s = scene::default_scene();
        s.draws.truncate(1);
        s
    };
    let gpu_other = r.upload(&other).expect("upload");
    overlapped(&mut r, &other, &gpu_other, &frame_a(128, 72));
    drop(gpu_other);
    overlapped(&mut r, &scene, &gpu, &frame_a(128, 72));
    r.finish().expect("no validation messages");

    // The renderer dropped with a frame in flight, the scene after it.
    overlapped(&mut r, &scene, &gpu, &frame_b(128, 72));
    drop(r);
    drop(gpu);
    ctx.check_validation().expect("no validation messages");
}

#[test]
fn a_scene_dropped_before_the_renderer_waits_for_the_frame() {
    let ctx = common::context();
    let mut r = Renderer::new(ctx.clone()).expect("renderer");
    let scene = scene::default_scene();
    let gpu = r.upload(&scene).expect("upload");
    overlapped(&mut r, &scene, &gpu, &frame_a(96, 54));
    // The vertex, index and material buffers the frame reads: each waits for it.
    drop(gpu);
    drop(r);
    ctx.check_validation().expect("no validation messages");
}
