//! The frame on lavapipe, with the validation layer on: any validation message fails the test
//! (Renderer::render_frame returns Error::Validation).

mod common;

use weft::render::{DebugView, RenderOptions, Renderer};
use weft::scene;

fn render(options: &RenderOptions) -> weft::render::Frame {
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    renderer
        .render(&scene::default_scene(), options)
        .expect("render without validation messages")
}

#[test]
fn default_scene_renders_clean_and_lit() {
    let options = RenderOptions {
        width: 320,
        height: 180,
        ..Default::default()
    };
    let frame = render(&options);
    assert_eq!(frame.ldr.len(), 320 * 180 * 4);
    assert_eq!(frame.hdr.len(), 320 * 180 * 4);
    assert!(
        frame.hdr.iter().all(|v| v.is_finite()),
        "non-finite value in the HDR image"
    );
    // Lit: clearly brighter than the background, and not flat.
    let mean = common::mean_rgb(&frame.ldr);
    assert!(mean > 20.0, "image too dark: mean {mean}");
    let lum: Vec<f64> = frame
        .ldr
        .chunks_exact(4)
        .map(|p| (p[0] as f64 + p[1] as f64 + p[2] as f64) / 3.0)
        .collect();
    let var = lum.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / lum.len() as f64;
    assert!(
        var.sqrt() > 10.0,
        "image has almost no contrast: std dev {}",
        var.sqrt()
    );
    // Every pass the plan lists ran.
    assert_eq!(
        frame.stats.passes,
        vec!["weave", "gbuffer", "lighting", "tonemap"]
    );
    assert!(frame.stats.draws >= 3);
}

#[test]
fn every_debug_view_renders_clean() {
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let scene = scene::default_scene();
    let mut means = Vec::new();
    for view in DebugView::ALL {
        let options = RenderOptions {
            width: 96,
            height: 54,
            debug_view: view,
            ..Default::default()
        };
        let frame = renderer
            .render(&scene, &options)
            .unwrap_or_else(|e| panic!("debug view {}: {e}", view.name()));
        assert!(frame.hdr.iter().all(|v| v.is_finite()));
        means.push((view.name(), common::mean_rgb(&frame.ldr)));
    }
    // The normals view of a scene seen from the front is far from black.
    let normals = means.iter().find(|m| m.0 == "normals").unwrap().1;
    assert!(normals > 40.0, "normals view mean {normals}");
}

#[test]
fn validation_messages_fail_the_frame() {
    // The mechanism every GPU test relies on: a deliberate invalid call must be caught.
    let ctx = common::context();
    assert!(ctx.validating());
    // SAFETY: the context was made with validation on (common::context), which catches the
    // invalid call; nothing else uses the device meanwhile.
    unsafe { ctx.provoke_validation_error() };
    let err = ctx
        .check_validation()
        .expect_err("the validation layer must report the invalid call");
    assert!(
        err.to_string().contains("VUID"),
        "unexpected message: {err}"
    );
    // And the check leaves the context clean for the next frame.
    ctx.check_validation().expect("messages were taken");
}

#[test]
fn gbuffer_holds_unit_normals_and_known_material() {
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let scene = scene::default_scene();
    let options = RenderOptions {
        width: 160,
        height: 90,
        ..Default::default()
    };
    renderer.render(&scene, &options).expect("render");
    let g = renderer.read_gbuffer().expect("gbuffer readback");
    let mut covered = 0;
    for i in 0..(160 * 90) {
        if g.depth[i] <= 0.0 {
            continue;
        }
        covered += 1;
        let material = g.surface[i * 4 + 1];
        assert!(
            material >= 0.0 && (material as usize) < scene.materials.len(),
            "material index {material}"
        );
        // Fabric: the tangent's handedness; other materials: the anisotropy strength (none here).
        let z = g.surface[i * 4 + 2];
        if scene.materials[material as usize].fabric.is_some() {
            assert!(z == 1.0 || z == -1.0, "tangent sign {z}");
        } else {
            assert_eq!(
                z, 0.0,
                "anisotropy strength of a material without anisotropy"
            );
        }
    }
    assert!(covered > 160 * 90 / 3, "only {covered} pixels covered");
}

#[test]
fn image_too_large_for_the_device_is_a_clear_error() {
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let options = RenderOptions {
        width: 100_000,
        height: 100_000,
        ..Default::default()
    };
    let err = renderer
        .render(&scene::default_scene(), &options)
        .err()
        .expect("must fail");
    let msg = err.to_string();
    assert!(
        msg.contains("100000x100000") && msg.contains("--size"),
        "{msg}"
    );
}

/// `Context` is `Sync`: submissions from several threads at once must be serialized inside
/// (Vulkan requires the command pool and the queue to be externally synchronized; the validation
/// layer's thread-safety checks report any overlap, and any message fails the test).
#[test]
fn submissions_from_two_threads_are_safe() {
    use weft::vk::{Format, ImageDesc, ImageUsageFlags, Usage};
    let ctx = common::context();
    std::thread::scope(|scope| {
        for t in 0..2 {
            let ctx = &ctx;
            scope.spawn(move || {
                for i in 0..25 {
                    let image = ctx
                        .create_image(
                            &ImageDesc::new_2d(format!("t{t} i{i}"), Format::R8G8B8A8_UNORM, 4, 4)
                                .usage(ImageUsageFlags::SAMPLED | ImageUsageFlags::TRANSFER_DST),
                        )
                        .unwrap();
                    ctx.submit(|cmd| {
                        cmd.transition(&image, Usage::Undefined, Usage::TransferDst, None);
                        cmd.transition(&image, Usage::TransferDst, Usage::FragmentRead, None);
                    })
                    .unwrap();
                }
            });
        }
    });
    ctx.check_validation().expect("no validation message");
}

/// A readback copy into a buffer too small for the image would make the GPU write past the
/// buffer's end: `Cmd::copy_image_to_buffer` refuses it (a panic, before anything is recorded),
/// the context stays usable, and nothing invalid reaches the driver (no validation message).
#[test]
fn short_readback_buffer_is_refused_before_the_gpu_runs() {
    use weft::vk::{BufferLocation, BufferUsageFlags, Format, ImageDesc, ImageUsageFlags, Usage};
    let ctx = common::context();
    // An image without a view-capable usage is refused (every image gets a view).
    let err = ctx
        .create_image(
            &ImageDesc::new_2d("transfer only", Format::R8G8B8A8_UNORM, 8, 8)
                .usage(ImageUsageFlags::TRANSFER_SRC),
        )
        .err()
        .expect("must fail");
    assert!(err.to_string().contains("needs one of SAMPLED"), "{err}");
    let image = ctx
        .create_image(
            &ImageDesc::new_2d("8x8", Format::R8G8B8A8_UNORM, 8, 8)
                .usage(ImageUsageFlags::TRANSFER_SRC | ImageUsageFlags::SAMPLED),
        )
        .unwrap();
    // 8 x 8 x 4 = 256 bytes needed.
    let short = ctx
        .create_buffer(
            "short",
            255,
            BufferUsageFlags::TRANSFER_DST,
            BufferLocation::Readback,
        )
        .unwrap();
    let panic = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        ctx.submit(|cmd| {
            cmd.transition(&image, Usage::Undefined, Usage::TransferSrc, None);
            cmd.copy_image_to_buffer(&image, 0, &short);
        })
    }))
    .expect_err("a short buffer must be refused");
    let msg = panic.downcast_ref::<String>().cloned().unwrap_or_default();
    assert!(
        msg.contains("'short' of 255 bytes is too small") && msg.contains("256"),
        "{msg}"
    );
    // Level 3 of an image with one level: refused the same way.
    let fits = ctx
        .create_buffer(
            "fits",
            256,
            BufferUsageFlags::TRANSFER_DST,
            BufferLocation::Readback,
        )
        .unwrap();
    let panic = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        ctx.submit(|cmd| cmd.copy_image_to_buffer(&image, 3, &fits))
    }))
    .expect_err("a missing level must be refused");
    let msg = panic.downcast_ref::<String>().cloned().unwrap_or_default();
    assert!(msg.contains("mip level 3"), "{msg}");
    // The context is still usable: a correct copy goes through.
    ctx.submit(|cmd| {
        cmd.transition(&image, Usage::Undefined, Usage::TransferSrc, None);
        cmd.copy_image_to_buffer(&image, 0, &fits);
        cmd.buffer_barrier();
    })
    .unwrap();
    ctx.check_validation().expect("no validation message");
}

/// A frame size the device cannot hold is refused before any target is created, with what is
/// needed, what the device has and what to do (`--size 16384x16384` on lavapipe used to be
/// ended by the kernel's OOM killer instead).
#[test]
fn oversize_targets_are_refused_before_allocation() {
    use weft::render::check_target_memory;
    let ctx = common::context();
    let gib = 1u64 << 30;
    // The device's own figures, with a small heap.
    let mut small = ctx.info().clone();
    small.device_local_heap_bytes = gib;
    small.device_type = "discrete-gpu".into();
    let err = check_target_memory(&small, None, 8192, 8192, false)
        .expect_err("3.75 GiB of targets in 1 GiB")
        .to_string();
    assert!(
        err.contains("--size 8192x8192")
            && err.contains("3.8 GiB")
            && err.contains("1.0 GiB")
            && err.contains("choose a smaller --size"),
        "{err}"
    );
    check_target_memory(&small, None, 1920, 1080, true).expect("100 MiB fits");
    // A CPU device: targets and readback against the memory the host has available.
    let mut cpu = small.clone();
    cpu.device_type = "cpu".into();
    cpu.device_local_heap_bytes = 64 * gib;
    let err = check_target_memory(&cpu, Some(2 * gib), 8192, 8192, true)
        .expect_err("5.8 GiB with readback in 2 GiB")
        .to_string();
    assert!(
        err.contains("5.8 GiB") && err.contains("2.0 GiB available"),
        "{err}"
    );
    check_target_memory(&cpu, Some(2 * gib), 8192, 8192, false)
        .expect_err("4.3 GiB without the HDR readback still does not fit");
    check_target_memory(&cpu, Some(8 * gib), 8192, 8192, true).expect("fits in 90 % of 8 GiB");
    check_target_memory(&cpu, Some(5 * gib + gib / 2), 8192, 8192, true)
        .expect_err("5.8 GiB is more than 90 % of 5.5 GiB");
    // Beyond maxImageDimension2D.
    let side = small.max_image_dimension_2d + 1;
    let err = check_target_memory(&small, None, side, 16, false)
        .expect_err("too wide")
        .to_string();
    assert!(err.contains("pixels a side"), "{err}");

    // Through the renderer on this device: 16384x16384 (23.0 GiB with readback on lavapipe).
    // Rendered only where the check refuses it, so the test never allocates that much.
    let info = ctx.info().clone();
    let refused = check_target_memory(
        &info,
        weft::render::host_available_bytes(),
        16384,
        16384,
        true,
    );
    println!(
        "device heap {} bytes: 16384x16384 {refused:?}",
        info.device_local_heap_bytes
    );
    if refused.is_err() {
        let mut renderer = Renderer::new(ctx).expect("renderer");
        let options = RenderOptions {
            width: 16384,
            height: 16384,
            ..Default::default()
        };
        let err = renderer
            .render(&scene::default_scene(), &options)
            .err()
            .expect("must fail")
            .to_string();
        assert!(
            err.contains("--size 16384x16384") && err.contains("GiB"),
            "{err}"
        );
        // And the renderer is still usable at a size that fits.
        let options = RenderOptions {
            width: 64,
            height: 36,
            ..Default::default()
        };
        renderer
            .render(&scene::default_scene(), &options)
            .expect("a small frame after the refused one");
    }
}

/// glTF samplers: a 2 x 1 texture (black, white) on a quad whose u runs from -1 to 2, seen in the
/// albedo view at the middle of each half-unit of u, with nearest filtering: REPEAT tiles it,
/// CLAMP_TO_EDGE holds the edge texels outside [0, 1], MIRRORED_REPEAT mirrors every other tile
/// (issue 28: wrap modes were ignored, every texture repeated).
#[test]
fn texture_wrap_modes_follow_the_sampler() {
    use glam::{Mat4, Vec3};
    use weft::scene::{
        Camera, ColorSpace, Draw, Material, Mesh, MipFilter, Scene, TexelFilter, Texture,
        TextureSampler, TextureSlot, Vertex, Wrap,
    };
    let (w, h) = (120u32, 40u32);
    let v = |x: f32, y: f32, u: f32| Vertex {
        position: [x, y, 0.0],
        normal: [0.0, 0.0, 1.0],
        tangent: [1.0, 0.0, 0.0, 1.0],
        uv: [u, 0.5],
        uv1: [0.0; 2],
    };
    let scene_with = |wrap: Wrap| {
        let mut material = Material {
            base_color_texture: Some(0),
            metallic: 0.0,
            ..Material::default()
        };
        material.samplers[TextureSlot::BaseColor as usize] = TextureSampler {
            wrap_s: wrap,
            wrap_t: Wrap::Repeat,
            mag: TexelFilter::Nearest,
            min: TexelFilter::Nearest,
            mip: MipFilter::None,
        };
        // The quad fills the frame: 6 x 2 units, seen from 1 unit away with a 90° vertical
        // field of view at an aspect ratio of 3.
        Scene {
            source: "wrap-mode quad".into(),
            meshes: vec![Mesh {
                name: "quad".into(),
                vertices: vec![
                    v(-3.0, -1.0, -1.0),
                    v(3.0, -1.0, 2.0),
                    v(3.0, 1.0, 2.0),
                    v(-3.0, 1.0, -1.0),
                ],
                indices: vec![0, 1, 2, 0, 2, 3],
                material: 0,
            }],
            draws: vec![Draw::new(0, Mat4::IDENTITY)],
            materials: vec![material],
            textures: vec![Texture {
                name: "black-white".into(),
                width: 2,
                height: 1,
                color_space: ColorSpace::Srgb,
                rgba8: vec![0, 0, 0, 255, 255, 255, 255, 255],
            }],
            cameras: vec![Camera {
                name: "front".into(),
                view: Mat4::look_at_rh(Vec3::new(0.0, 0.0, 1.0), Vec3::ZERO, Vec3::Y),
                yfov: std::f32::consts::FRAC_PI_2,
                znear: 0.01,
                zfar: None,
                aspect_ratio: Some(3.0),
            }],
            ..Default::default()
        }
    };
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let options = RenderOptions {
        width: w,
        height: h,
        debug_view: DebugView::Albedo,
        ..Default::default()
    };
    // u at the middle of each sixth of the frame: -0.75, -0.25, 0.25, 0.75, 1.25, 1.75.
    let expect = [
        (Wrap::Repeat, "BWBWBW"),
        (Wrap::ClampToEdge, "BBBWWW"),
        (Wrap::MirroredRepeat, "WBBWWB"),
    ];
    for (wrap, want) in expect {
        let frame = renderer
            .render(&scene_with(wrap), &options)
            .expect("render without validation messages");
        let got: String = (0..6)
            .map(|i| {
                let x = (2 * i + 1) * w as usize / 12;
                let p = (h as usize / 2 * w as usize + x) * 4;
                match frame.ldr[p] {
                    0..=20 => 'B',
                    235..=255 => 'W',
                    _ => '?',
                }
            })
            .collect();
        assert_eq!(got, want, "{wrap:?}");
    }
}

/// Every tone curve of the tonemap pass against its CPU twin
/// (`reference::shading::display_rgba8_with`) on the GPU's own HDR image: the 8-bit image is the
/// twin's within rounding (1/255; the curves' pow, log2 and divisions are a few ulp apart).
#[test]
fn every_tone_curve_matches_its_twin() {
    use weft::reference::shading::display_rgba8_with;
    use weft::render::ToneCurve;
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let scene = scene::default_scene();
    let mut means = Vec::new();
    for curve in ToneCurve::ALL {
        for exposure in [-1.0f32, 0.0, 2.0] {
            let options = RenderOptions {
                width: 96,
                height: 54,
                exposure,
                tonemap: curve,
                ..Default::default()
            };
            let frame = renderer.render(&scene, &options).expect("render");
            let (mut worst, mut off) = (0i32, 0usize);
            for (px, hdr) in frame.ldr.chunks_exact(4).zip(frame.hdr.chunks_exact(4)) {
                let want = display_rgba8_with(curve, [hdr[0], hdr[1], hdr[2]], 2f32.powf(exposure));
                for c in 0..3 {
                    let d = (px[c] as i32 - want[c] as i32).abs();
                    worst = worst.max(d);
                    off += (d > 0) as usize;
                }
            }
            assert!(
                worst <= 1,
                "{} at {exposure} EV: GPU and twin {worst}/255 apart ({off} channels differ)",
                curve.name()
            );
            if exposure == 0.0 {
                means.push((curve, common::mean_rgb(&frame.ldr)));
            }
        }
    }
    // The curves are different curves: no two give the same image.
    for (i, a) in means.iter().enumerate() {
        for b in &means[i + 1..] {
            assert!(
                (a.1 - b.1).abs() > 0.5,
                "{} and {} give the same mean {}",
                a.0.name(),
                b.0.name(),
                a.1
            );
        }
    }
}
