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
    let mean = weft::sheet::mean_srgb(&frame.ldr);
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
        means.push((view.name(), weft::sheet::mean_srgb(&frame.ldr)));
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

/// An image viewed as a second format (FXAA reads the tone-mapped sRGB image's bytes as UNORM):
/// made MUTABLE_FORMAT with both formats listed, clean under validation; a view format of another
/// texel size, or a depth format, is refused with the image's name.
#[test]
fn images_take_an_alias_view_of_the_same_texel_size_only() {
    use weft::vk::{Format, ImageDesc, ImageUsageFlags, Usage};
    let ctx = common::context();
    let image = ctx
        .create_image(
            &ImageDesc::new_2d("srgb", Format::R8G8B8A8_SRGB, 8, 8)
                .usage(ImageUsageFlags::COLOR_ATTACHMENT | ImageUsageFlags::SAMPLED)
                .alias(Format::R8G8B8A8_UNORM),
        )
        .expect("an sRGB image with a UNORM view");
    ctx.submit(|cmd| cmd.transition(&image, Usage::Undefined, Usage::FragmentRead, None))
        .unwrap();
    let err = ctx
        .create_image(
            &ImageDesc::new_2d("half", Format::R8G8B8A8_SRGB, 8, 8)
                .usage(ImageUsageFlags::SAMPLED)
                .alias(Format::R16G16B16A16_SFLOAT),
        )
        .err()
        .expect("must fail");
    assert!(
        err.to_string().contains("'half'") && err.to_string().contains("not a view format"),
        "{err}"
    );
    // Four bytes a texel too, but a depth format is never a colour image's view.
    let err = ctx
        .create_image(
            &ImageDesc::new_2d("depth", Format::D32_SFLOAT, 8, 8)
                .usage(ImageUsageFlags::SAMPLED)
                .alias(Format::R8G8B8A8_UNORM),
        )
        .err()
        .expect("must fail");
    assert!(err.to_string().contains("not a view format"), "{err}");
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
        .expect_err("4 GiB of targets in 1 GiB")
        .to_string();
    assert!(
        err.contains("--size 8192x8192")
            && err.contains("4.0 GiB")
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
        .expect_err("6 GiB with readback in 2 GiB")
        .to_string();
    assert!(
        err.contains("6.0 GiB") && err.contains("2.0 GiB available"),
        "{err}"
    );
    check_target_memory(&cpu, Some(2 * gib), 8192, 8192, false)
        .expect_err("4.5 GiB without the HDR readback still does not fit");
    check_target_memory(&cpu, Some(8 * gib), 8192, 8192, true).expect("fits in 90 % of 8 GiB");
    check_target_memory(&cpu, Some(5 * gib + gib / 2), 8192, 8192, true)
        .expect_err("6 GiB is more than 90 % of 5.5 GiB");
    // Beyond maxImageDimension2D.
    let side = small.max_image_dimension_2d + 1;
    let err = check_target_memory(&small, None, side, 16, false)
        .expect_err("too wide")
        .to_string();
    assert!(err.contains("pixels a side"), "{err}");

    // Through the renderer on this device: 16384x16384 (24.0 GiB with readback on lavapipe).
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
                colors: Vec::new(),
                topology: weft::scene::Topology::Triangles,
            }],
            draws: vec![Draw::new(0, Mat4::IDENTITY)],
            materials: vec![material],
            textures: vec![Texture {
                name: "black-white".into(),
                width: 2,
                height: 1,
                color_space: ColorSpace::Srgb,
                rgba8: vec![0, 0, 0, 255, 255, 255, 255, 255],
                bc7: None,
            }],
            cameras: vec![Camera {
                name: "front".into(),
                view: Mat4::look_at_rh(Vec3::new(0.0, 0.0, 1.0), Vec3::ZERO, Vec3::Y),
                yfov: std::f32::consts::FRAC_PI_2,
                znear: 0.01,
                zfar: None,
                aspect_ratio: Some(3.0),
                orthographic: None,
                framing: None,
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
            // Only the curve in use is compiled in: its own pipeline ran.
            let name = format!("tonemap[CURVE={}]", curve.code());
            assert!(
                frame.stats.pipelines.contains(&name),
                "{name} not among {:?}",
                frame.stats.pipelines
            );
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
                means.push((curve, weft::sheet::mean_srgb(&frame.ldr)));
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
/// A 2 x 2 quad in z = 0 facing +z, with `colors` per corner (empty: none) and `material`, and
/// one directional light from the front; the automatic camera looks at its front.
fn quad_scene(colors: Vec<[f32; 4]>, material: scene::Material) -> scene::Scene {
    let corner = |x: f32, y: f32| scene::Vertex {
        position: [x, y, 0.0],
        normal: [0.0, 0.0, 1.0],
        tangent: [1.0, 0.0, 0.0, 1.0],
        uv: [x * 0.5 + 0.5, 0.5 - y * 0.5],
        uv1: [0.0; 2],
    };
    let mut s = scene::Scene {
        source: "quad".into(),
        meshes: vec![scene::Mesh {
            name: "quad".into(),
            vertices: vec![
                corner(-1.0, -1.0),
                corner(1.0, -1.0),
                corner(1.0, 1.0),
                corner(-1.0, 1.0),
            ],
            indices: vec![0, 1, 2, 0, 2, 3],
            material: 0,
            colors,
            topology: weft::scene::Topology::Triangles,
        }],
        draws: vec![scene::Draw::new(0, glam::Mat4::IDENTITY)],
        materials: vec![material],
        ..Default::default()
    };
    s.lights.push(scene::Light {
        name: "front".into(),
        kind: scene::LightKind::Directional,
        color: [1.0; 3],
        intensity: 3.0,
        range: None,
        position: glam::Vec3::ZERO,
        direction: glam::Vec3::new(0.0, 0.0, -1.0),
        shadow: None,
    });
    s
}

/// The HDR radiance at the centre of a frame.
fn centre(frame: &weft::render::Frame) -> [f32; 3] {
    let i = ((frame.height / 2) * frame.width + frame.width / 2) as usize * 4;
    [frame.hdr[i], frame.hdr[i + 1], frame.hdr[i + 2]]
}

fn small() -> RenderOptions {
    RenderOptions {
        width: 64,
        height: 48,
        ..Default::default()
    }
}

#[test]
fn vertex_colours_multiply_the_base_colour() {
    let material = scene::Material {
        base_color: [0.8, 0.8, 0.8, 1.0],
        metallic: 0.0,
        roughness: 0.6,
        ..Default::default()
    };
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let albedo = |s: &scene::Scene, r: &mut Renderer| {
        let options = RenderOptions {
            debug_view: DebugView::Albedo,
            ..small()
        };
        centre(&r.render(s, &options).expect("render"))
    };
    let tint = [1.0, 0.5, 0.25, 1.0];
    let coloured = quad_scene(vec![tint; 4], material.clone());
    let plain = quad_scene(Vec::new(), material);
    let a = albedo(&coloured, &mut renderer);
    let b = albedo(&plain, &mut renderer);
    for k in 0..3 {
        let want = 0.8 * tint[k];
        // The albedo target is sRGB 8-bit: within half a step there.
        assert!(
            (a[k] - want).abs() < 0.01,
            "channel {k}: {a:?}, want {want}"
        );
        assert!((b[k] - 0.8).abs() < 0.01, "channel {k}: {b:?}");
    }
    // And lit: the colour scales the diffuse light (the blue channel is darkest).
    let lit = renderer.render(&coloured, &small()).expect("render");
    let c = centre(&lit);
    assert!(c[0] > c[1] && c[1] > c[2], "{c:?}");
    assert!(lit
        .stats
        .pipelines
        .iter()
        .any(|p| p.starts_with("gbuffer[") && p.contains("vertex_colors=1")));
}

#[test]
fn unlit_materials_show_their_base_colour_exactly() {
    let material = scene::Material {
        base_color: [0.6, 0.3, 0.1, 1.0],
        metallic: 0.0,
        roughness: 0.2,
        unlit: true,
        ..Default::default()
    };
    let tint = [0.5, 1.0, 1.0, 1.0];
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    for (colors, want) in [
        (Vec::new(), [0.6, 0.3, 0.1]),
        (vec![tint; 4], [0.3, 0.3, 0.1]),
    ] {
        let frame = renderer
            .render(&quad_scene(colors, material.clone()), &small())
            .expect("render");
        let c = centre(&frame);
        for k in 0..3 {
            // The base colour passes the sRGB 8-bit albedo target: within half a step of it.
            assert!(
                (c[k] - want[k]).abs() < 0.006,
                "channel {k}: {c:?}, want {want:?}"
            );
        }
        assert!(frame
            .stats
            .pipelines
            .iter()
            .any(|p| p.starts_with("lighting[") && p.contains("unlit=1")));
    }
    // Unlit ignores the lights: a brighter light changes nothing; lit, it does.
    for unlit in [true, false] {
        let mut s = quad_scene(
            Vec::new(),
            scene::Material {
                unlit,
                ..material.clone()
            },
        );
        let before = centre(&renderer.render(&s, &small()).expect("render"));
        s.lights[0].intensity *= 3.0;
        let after = centre(&renderer.render(&s, &small()).expect("render"));
        assert_eq!(
            before == after,
            unlit,
            "unlit {unlit}: {before:?} then {after:?}"
        );
    }
}

#[test]
fn orthographic_cameras_keep_size_at_any_distance() {
    let material = scene::Material {
        metallic: 0.0,
        ..Default::default()
    };
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let mut rows_seen = Vec::new();
    for distance in [5.0f32, 50.0] {
        let mut s = quad_scene(Vec::new(), material.clone());
        s.cameras.push(scene::Camera {
            name: "ortho".into(),
            view: glam::Mat4::look_at_rh(glam::Vec3::Z * distance, glam::Vec3::ZERO, glam::Vec3::Y),
            yfov: 0.8,
            znear: 0.1,
            zfar: Some(100.0),
            aspect_ratio: None,
            orthographic: Some([2.0, 2.0]),
            framing: None,
        });
        let options = RenderOptions {
            camera: Some(0),
            ..small()
        };
        let frame = renderer.render(&s, &options).expect("render");
        assert!(frame.plan.camera.contains("orthographic"));
        // Rows of the centre column that show the quad (not the background).
        let x = frame.width / 2;
        let rows = (0..frame.height)
            .filter(|&y| {
                let i = ((y * frame.width + x) * 4) as usize;
                (frame.hdr[i] - 0.010).abs() > 1e-3
            })
            .count();
        rows_seen.push(rows);
    }
    // ymag 2: the view is 4 m tall, the quad 2 m: half the image, at 5 m as at 50 m.
    let half = (small().height / 2) as usize;
    for rows in &rows_seen {
        assert!(rows.abs_diff(half) <= 1, "{rows_seen:?}, want {half}");
    }
}

#[test]
fn alpha_mask_cuts_out_below_the_cutoff_in_the_image() {
    let material = |cutoff: Option<f32>| scene::Material {
        metallic: 0.0,
        alpha_cutoff: cutoff,
        ..Default::default()
    };
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let background = weft::render::gpu::BACKGROUND;
    let is_background = |c: [f32; 3]| (0..3).all(|k| (c[k] - background[k]).abs() < 1e-4);
    // Vertex alpha 0.4: cut out at cutoff 0.5, kept at 0.3; opaque ignores alpha.
    for (cutoff, cut) in [(Some(0.5), true), (Some(0.3), false), (None, false)] {
        let s = quad_scene(vec![[1.0, 1.0, 1.0, 0.4]; 4], material(cutoff));
        let frame = renderer.render(&s, &small()).expect("render");
        assert_eq!(
            is_background(centre(&frame)),
            cut,
            "cutoff {cutoff:?}: {:?}",
            centre(&frame)
        );
        assert!(frame
            .stats
            .pipelines
            .iter()
            .any(|p| p.starts_with("gbuffer[")
                && p.contains(if cutoff.is_some() {
                    "alpha_mask=1"
                } else {
                    "alpha_mask=0"
                })));
    }
}

/// A floor (y = 0, receiving) under a 1 x 1 m MASK card at y = 1 (casting), a directional
/// light at 45° with a shadow map, looked at from above.
fn card_over_floor(card_alpha: f32) -> scene::Scene {
    let v = |p: [f32; 3], n: [f32; 3]| scene::Vertex {
        position: p,
        normal: n,
        tangent: [1.0, 0.0, 0.0, 1.0],
        uv: [0.0; 2],
        uv1: [0.0; 2],
    };
    let up = [0.0, 1.0, 0.0];
    let floor = scene::Mesh {
        name: "floor".into(),
        vertices: vec![
            v([-3.0, 0.0, 3.0], up),
            v([3.0, 0.0, 3.0], up),
            v([3.0, 0.0, -3.0], up),
            v([-3.0, 0.0, -3.0], up),
        ],
        indices: vec![0, 1, 2, 0, 2, 3],
        material: 0,
        colors: Vec::new(),
        topology: weft::scene::Topology::Triangles,
    };
    let card = scene::Mesh {
        name: "card".into(),
        vertices: vec![
            v([-0.5, 1.0, 0.5], up),
            v([0.5, 1.0, 0.5], up),
            v([0.5, 1.0, -0.5], up),
            v([-0.5, 1.0, -0.5], up),
        ],
        indices: vec![0, 1, 2, 0, 2, 3],
        material: 1,
        colors: vec![[1.0, 1.0, 1.0, card_alpha]; 4],
        topology: weft::scene::Topology::Triangles,
    };
    let mut floor_draw = scene::Draw::new(0, glam::Mat4::IDENTITY);
    floor_draw.cast_shadows = false;
    let mut card_draw = scene::Draw::new(1, glam::Mat4::IDENTITY);
    card_draw.receive_shadows = false;
    let mut s = scene::Scene {
        source: "card".into(),
        meshes: vec![floor, card],
        draws: vec![floor_draw, card_draw],
        materials: vec![
            scene::Material {
                metallic: 0.0,
                ..Default::default()
            },
            scene::Material {
                metallic: 0.0,
                alpha_cutoff: Some(0.5),
                double_sided: true,
                ..Default::default()
            },
        ],
        ..Default::default()
    };
    s.lights.push(scene::Light {
        name: "sun".into(),
        kind: scene::LightKind::Directional,
        color: [1.0; 3],
        intensity: 3.0,
        range: None,
        position: glam::Vec3::ZERO,
        // 45° from +x: the card's shadow falls 1 m to its +x side.
        direction: glam::Vec3::new(1.0, -1.0, 0.0).normalize(),
        shadow: Some(scene::Shadow::default()),
    });
    // From above and to the side, so the card's shadow on the floor is in view beside it.
    s.cameras.push(
        s.look_at_camera(
            glam::Vec3::new(0.0, 6.0, 3.0),
            glam::Vec3::new(0.5, 0.0, 0.0),
            0.9,
        )
        .unwrap(),
    );
    s
}

#[test]
fn alpha_mask_cut_outs_cast_cut_out_shadows() {
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let options = RenderOptions {
        camera: Some(0),
        width: 96,
        height: 72,
        ..Default::default()
    };
    // The middle of the card's shadow on the floor (1 m to its +x side, not behind the card as
    // the camera sees it), projected into the image.
    let floor_pixel = |s: &scene::Scene| {
        let cam = s.cameras[0].clone();
        let frame = weft::render::gpu::FrameData::new(&cam, options.width, options.height);
        let vp = glam::Mat4::from_cols_array_2d(&frame.view_proj);
        let p = vp.project_point3(glam::Vec3::new(1.0, 0.0, 0.0));
        let x = ((p.x * 0.5 + 0.5) * options.width as f32) as u32;
        let y = ((p.y * 0.5 + 0.5) * options.height as f32) as u32;
        ((y * options.width + x) * 4) as usize
    };
    let mut lum = Vec::new();
    for alpha in [1.0, 0.2] {
        let s = card_over_floor(alpha);
        let frame = renderer.render(&s, &options).expect("render");
        assert!(
            frame
                .stats
                .pipelines
                .iter()
                .any(|p| p.starts_with("shadow_mask[")),
            "{:?}",
            frame.stats.pipelines
        );
        let i = floor_pixel(&s);
        lum.push(frame.hdr[i] + frame.hdr[i + 1] + frame.hdr[i + 2]);
    }
    // Without the card at all: the floor fully lit.
    let mut bare = card_over_floor(1.0);
    bare.draws.truncate(1);
    let frame = renderer.render(&bare, &options).expect("render");
    let i = floor_pixel(&bare);
    let lit = frame.hdr[i] + frame.hdr[i + 1] + frame.hdr[i + 2];
    assert!(
        lum[0] < 0.5 * lit,
        "the opaque card shadows the floor: {lum:?} vs {lit}"
    );
    assert!(
        (lum[1] - lit).abs() < 0.02 * lit,
        "the cut-out card casts nothing: {lum:?} vs {lit}"
    );
}

/// glTF LINES and POINTS are drawn 1 pixel wide by the G-buffer pass with pipelines of their own
/// topology, only in a scene that has them; unlit (no normals), each shows its base colour
/// exactly: a horizontal segment across the quad covers exactly one pixel of each column, a
/// point exactly one pixel of the frame.
#[test]
fn lines_and_points_are_one_pixel_and_show_their_colour() {
    let quad = scene::Material {
        base_color: [0.5, 0.5, 0.5, 1.0],
        metallic: 0.0,
        roughness: 0.6,
        ..Default::default()
    };
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let plain = renderer
        .render(&quad_scene(Vec::new(), quad.clone()), &small())
        .expect("render");
    assert!(
        !plain
            .stats
            .pipelines
            .iter()
            .any(|p| p.contains("lines,") || p.contains("points,")),
        "a scene of triangles builds no line or point pipeline: {:?}",
        plain.stats.pipelines
    );
    let mut s = quad_scene(Vec::new(), quad);
    let green = [0.1f32, 0.8, 0.2];
    let blue = [0.2f32, 0.3, 0.9];
    for (name, colour, topology, positions) in [
        (
            "segment",
            green,
            scene::Topology::Lines,
            vec![[-0.9f32, 0.0, 0.01], [0.9, 0.0, 0.01]],
        ),
        (
            "point",
            blue,
            scene::Topology::Points,
            vec![[0.5f32, 0.5, 0.01]],
        ),
    ] {
        s.materials.push(scene::Material {
            base_color: [colour[0], colour[1], colour[2], 1.0],
            unlit: true,
            ..Default::default()
        });
        let material = s.materials.len() - 1;
        s.meshes.push(scene::Mesh {
            name: name.into(),
            vertices: positions
                .iter()
                .map(|&position| scene::Vertex {
                    position,
                    normal: [0.0, 0.0, 1.0],
                    tangent: [1.0, 0.0, 0.0, 1.0],
                    uv: [0.0; 2],
                    uv1: [0.0; 2],
                })
                .collect(),
            indices: (0..positions.len() as u32).collect(),
            material,
            colors: Vec::new(),
            topology,
        });
        s.draws
            .push(scene::Draw::new(s.meshes.len() - 1, glam::Mat4::IDENTITY));
    }
    let f = renderer.render(&s, &small()).expect("render");
    assert!(f.plan.line_draws == 1 && f.plan.point_draws == 1);
    for kind in ["gbuffer[lines,", "gbuffer[points,"] {
        assert!(
            f.stats.pipelines.iter().any(|p| p.starts_with(kind)),
            "{kind}: {:?}",
            f.stats.pipelines
        );
    }
    let px = |x: u32, y: u32| {
        let i = (y * f.width + x) as usize * 4;
        [f.hdr[i], f.hdr[i + 1], f.hdr[i + 2]]
    };
    // Within half a step of the sRGB 8-bit albedo target.
    let is = |c: [f32; 3], want: [f32; 3]| (0..3).all(|k| (c[k] - want[k]).abs() < 0.006);
    for x in [16, 32, 48] {
        let rows = (0..f.height).filter(|&y| is(px(x, y), green)).count();
        assert_eq!(rows, 1, "column {x}: the segment covers {rows} pixels");
    }
    let points = (0..f.height)
        .flat_map(|y| (0..f.width).map(move |x| (x, y)))
        .filter(|&(x, y)| is(px(x, y), blue))
        .count();
    assert_eq!(points, 1, "the point covers {points} pixels");
    // The quad around them is lit as before (grey, not the primitives' colours).
    assert!(!is(px(32, 8), green) && !is(px(32, 8), blue));
}

/// KHR_materials_pbrSpecularGlossiness on the GPU: the glossiness comes from the texture's alpha
/// (roughness 1 − glossiness × A) and the F0 from its RGB. A specular-glossiness quad whose
/// texture's alpha runs across it renders as the same quad in the metallic-roughness model with a
/// roughness texture of 1 − that alpha (G) and the texture as KHR_materials_specular's colour.
#[test]
fn specular_glossiness_renders_as_its_metallic_roughness_equivalent() {
    // Two texels: specular (sRGB) dark red and pale grey, glossiness (A) 0.9 and 0.3.
    let (gloss_a, gloss_b) = (230u8, 77u8);
    let spec_gloss_texture = scene::Texture {
        name: "specular-glossiness".into(),
        width: 2,
        height: 1,
        color_space: scene::ColorSpace::Srgb,
        rgba8: vec![90, 20, 20, gloss_a, 200, 200, 200, gloss_b],
        bc7: None,
    };
    let roughness_texture = scene::Texture {
        name: "roughness".into(),
        width: 2,
        height: 1,
        color_space: scene::ColorSpace::Linear,
        rgba8: vec![0, 255 - gloss_a, 0, 255, 0, 255 - gloss_b, 0, 255],
        bc7: None,
    };
    let base = scene::Material {
        base_color: [0.5, 0.4, 0.3, 1.0],
        metallic: 0.0,
        ..Default::default()
    };
    let specular = |texture: usize| scene::Specular {
        factor: 1.0,
        color: [0.5 / 0.04, 0.5 / 0.04, 0.5 / 0.04],
        texture: None,
        color_texture: Some(texture),
        ior: 1.5,
    };
    let spec_gloss = scene::Material {
        roughness: 0.0,
        glossiness: Some(1.0),
        metallic_roughness_texture: Some(0),
        specular: specular(0),
        ..base.clone()
    };
    let metal_rough = scene::Material {
        roughness: 1.0,
        metallic_roughness_texture: Some(1),
        specular: specular(0),
        ..base
    };
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let render = |m: &scene::Material, debug_view: DebugView, r: &mut Renderer| {
        let mut s = quad_scene(Vec::new(), m.clone());
        s.textures = vec![spec_gloss_texture.clone(), roughness_texture.clone()];
        s.lights[0].direction = glam::Vec3::new(0.3, -0.2, -1.0).normalize();
        let options = RenderOptions {
            debug_view,
            ..small()
        };
        r.render(&s, &options).expect("render")
    };
    // The G-buffer's roughness (8-bit): the same to its last bit, but where 1 − a and the
    // texture's own 1 − a round to neighbouring steps.
    let ra = render(&spec_gloss, DebugView::RoughnessMetallic, &mut renderer);
    let rb = render(&metal_rough, DebugView::RoughnessMetallic, &mut renderer);
    let worst_r = ra
        .hdr
        .iter()
        .zip(&rb.hdr)
        .map(|(x, y)| (x - y).abs())
        .fold(0f32, f32::max);
    println!("roughness differs by {worst_r} at most");
    assert!(worst_r <= 1.5 / 255.0, "roughness differs by {worst_r}");
    let a = render(&spec_gloss, DebugView::None, &mut renderer);
    let b = render(&metal_rough, DebugView::None, &mut renderer);
    let mut worst = (0f32, 0usize);
    for (i, (x, y)) in a.hdr.iter().zip(&b.hdr).enumerate() {
        let d = (x - y).abs() / x.abs().max(y.abs()).max(1e-3);
        if d > worst.0 {
            worst = (d, i);
        }
    }
    println!(
        "lit: differs by {} at pixel {} ({} against {})",
        worst.0,
        worst.1 / 4,
        a.hdr[worst.1],
        b.hdr[worst.1]
    );
    // One 8-bit step of roughness moves the highlight (measured 1.2 % at one pixel): 2 %.
    assert!(worst.0 < 0.02, "differs by {}", worst.0);
    // And the glossiness matters: the two texels' halves differ (sharp red against blurred grey).
    let row = (a.height / 2 * a.width) as usize * 4;
    let (left, right) = (
        &a.hdr[row + 22 * 4..row + 22 * 4 + 3],
        &a.hdr[row + 42 * 4..row + 42 * 4 + 3],
    );
    assert!(left != right, "{left:?} {right:?}");
    let rough = |x: usize| ra.hdr[row + x * 4];
    println!("roughness left {} right {}", rough(22), rough(42));
    assert!(rough(22) < rough(42), "the glossier texel is the smoother");
}

/// A node whose world transform mirrors its mesh (negative determinant) has clockwise front
/// faces (glTF 2.0, "Instantiation"; Khronos' NegativeScaleTest): a single-sided quad mirrored in
/// x still faces the camera and is drawn, and a double-sided one is lit on its true outside, as
/// the same quads unmirrored are. Red quads, single-sided above, double-sided below, the right
/// column scaled by (-1, 1, 1).
#[test]
fn a_mirrored_node_keeps_its_front_faces() {
    let mut bin = Vec::new();
    for p in [
        [-0.5f32, -0.5, 0.0],
        [0.5, -0.5, 0.0],
        [0.5, 0.5, 0.0],
        [-0.5, 0.5, 0.0],
    ] {
        for f in p {
            bin.extend(f.to_le_bytes());
        }
    }
    for n in [[0.0f32, 0.0, 1.0]; 4] {
        for f in n {
            bin.extend(f.to_le_bytes());
        }
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        bin.extend(i.to_le_bytes());
    }
    let material = |double: bool| {
        serde_json::json!({"doubleSided": double, "pbrMetallicRoughness":
            {"baseColorFactor": [0.8, 0.05, 0.05, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}})
    };
    let quad = |x: f32, y: f32, mirrored: bool, mesh: u32| {
        serde_json::json!({"mesh": mesh, "translation": [x, y, 0.0],
            "scale": if mirrored { [-1.0, 1.0, 1.0] } else { [1.0, 1.0, 1.0] }})
    };
    let meshes: Vec<serde_json::Value> = (0..2)
        .map(|m| serde_json::json!({"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2, "material": m}]}))
        .collect();
    let doc = serde_json::json!({
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 48},
            {"buffer": 0, "byteOffset": 96, "byteLength": 12},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-0.5, -0.5, 0.0], "max": [0.5, 0.5, 0.0]},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"},
        ],
        "materials": [material(false), material(true)],
        "meshes": meshes,
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.785398, "znear": 0.1}}],
        "nodes": [
            quad(-0.6, 0.6, false, 0), quad(0.6, 0.6, true, 0),
            quad(-0.6, -0.6, false, 1), quad(0.6, -0.6, true, 1),
            {"camera": 0, "translation": [0.0, 0.0, 4.0]},
        ],
        "scenes": [{"nodes": [0, 1, 2, 3, 4]}],
    });
    let mut text = serde_json::to_vec(&doc).unwrap();
    while text.len() % 4 != 0 {
        text.push(b' ');
    }
    let mut glb = Vec::new();
    glb.extend(b"glTF");
    glb.extend(2u32.to_le_bytes());
    glb.extend(((12 + 8 + text.len() + 8 + bin.len()) as u32).to_le_bytes());
    glb.extend((text.len() as u32).to_le_bytes());
    glb.extend(b"JSON");
    glb.extend(&text);
    glb.extend((bin.len() as u32).to_le_bytes());
    glb.extend(b"BIN\0");
    glb.extend(&bin);
    let scene = scene::load_slice(&glb, "mirrored.glb", None).unwrap();
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let size = 160u32;
    let frame = renderer
        .render(
            &scene,
            &RenderOptions {
                width: size,
                height: size,
                ..Default::default()
            },
        )
        .unwrap();
    // The mean linear colour of a 12 x 12 patch about each quad's centre (0.6 of the half view,
    // 1.657 m at 4 m for a 45° field: 29 pixels from the middle).
    let patch = |cx: u32, cy: u32| -> [f64; 3] {
        let mut m = [0.0f64; 3];
        for y in cy - 6..cy + 6 {
            for x in cx - 6..cx + 6 {
                let i = ((y * size + x) * 4) as usize;
                for c in 0..3 {
                    m[c] += frame.hdr[i + c] as f64 / 144.0;
                }
            }
        }
        m
    };
    for (row, what) in [(51, "single-sided"), (109, "double-sided")] {
        let (plain, mirrored) = (patch(51, row), patch(109, row));
        eprintln!("{what}: unmirrored {plain:.4?}, mirrored {mirrored:.4?}");
        assert!(
            plain[0] > 4.0 * plain[1],
            "{what}: the unmirrored quad is not red: {plain:?}"
        );
        assert!(
            mirrored[0] > 4.0 * mirrored[1],
            "{what}: the mirrored quad is not drawn (culled as a back face?): {mirrored:?}"
        );
        // Measured: within 0.3 % (the default key light is directional; only the specular's view
        // direction differs between the columns). Lit as a back face, it is several times darker.
        let rel = (mirrored[0] - plain[0]).abs() / plain[0];
        assert!(
            rel < 0.03,
            "{what}: mirrored red {} against {}",
            mirrored[0],
            plain[0]
        );
    }
}
