//! The fabric material in whole frames on lavapipe (validation on):
//! - the lighting pass's output equals the CPU twin (`reference::shading::shade`) evaluated on the
//!   read-back G-buffer, pixel by pixel;
//! - orientation: for a thread along the tangent, the highlight in a render is stretched across
//!   the thread (along the bitangent);
//! - huge texture coordinates keep the pattern.

mod common;

use glam::{Mat4, Vec3};
use weft::fabric::{FabricParams, WeavePattern};
use weft::reference::shading::shade;
use weft::render::gpu::{FrameData, GpuLight};
use weft::render::{DebugView, RenderOptions, Renderer};
use weft::scene::{self, Light, LightKind, Scene};

/// Shades every covered pixel of the last frame's G-buffer on the CPU and compares with the HDR
/// output. Returns (pixels compared, fabric pixels, worst error relative to the bound).
fn compare_lighting(
    renderer: &Renderer,
    scene: &Scene,
    options: &RenderOptions,
    hdr: &[f32],
) -> (usize, usize, f32) {
    let g = renderer.read_gbuffer().expect("gbuffer");
    let camera = match &options.camera_override {
        Some(c) => c.clone(),
        None => scene.camera(options.camera).unwrap(),
    };
    let lights: Vec<GpuLight> = scene.lights.iter().map(GpuLight::new).collect();
    let mut frame = FrameData::new(&camera, options.width, options.height);
    frame.light_count = lights.len() as u32;
    frame.material_count = scene.materials.len() as u32;
    let inv_view_proj = Mat4::from_cols_array_2d(&frame.inv_view_proj);
    let (w, h) = (options.width as usize, options.height as usize);
    let (mut compared, mut fabric_pixels, mut worst) = (0, 0, 0f32);
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            let Some(s) =
                common::gbuffer_surface(&g, scene, inv_view_proj, (w as u32, h as u32), i)
            else {
                continue;
            };
            fabric_pixels += s.fabric.is_some() as usize;
            let material = g.surface[i * 4 + 1].round() as usize;
            let cpu = shade(&frame, &lights, &s);
            for c in 0..3 {
                // Bound: the HDR target is f16 (relative rounding 2^-11); both sides read the same
                // G-buffer values, so what is left is f32 evaluation order, the Vulkan precision of
                // pow/exp/log/inversesqrt, and the sRGB decode of the albedo target (the GPU's
                // table vs the formula here, < 1e-3 relative at the bright bytes of these
                // scenes' plain materials; a plain fabric's albedo target is white, 255, exact).
                // A fabric with thread-by-thread colours stores mid-grey bytes there, which
                // lavapipe decodes up to 0.74 % off the formula (measured with the albedo debug
                // view over this close-up, bytes 84-99): 1 % more, on the whole value.
                let threads = s
                    .fabric
                    .is_some_and(|f| f.flags & weft::fabric::FLAG_THREAD_COLOURS != 0);
                let bound = (if threads { 1.2e-2 } else { 2e-3 }) * cpu[c].abs() + 2e-4;
                let err = (hdr[i * 4 + c] - cpu[c]).abs();
                worst = worst.max(err / bound);
                assert!(
                    err <= bound,
                    "pixel ({x}, {y}) channel {c}: GPU {} vs CPU {} (material {material}, fabric {}, albedo {:?}, coverage {:?})",
                    hdr[i * 4 + c],
                    cpu[c],
                    s.fabric.is_some(),
                    &g.albedo[i * 4..i * 4 + 4],
                    s.coverage
                );
            }
            compared += 1;
        }
    }
    (compared, fabric_pixels, worst)
}

#[test]
fn lighting_pass_matches_cpu_shading_of_the_gbuffer() {
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let scene = scene::default_scene();
    // The scene's camera (threads partly resolved) and a close-up (threads resolved).
    let close = scene
        .look_at_camera(
            Vec3::new(0.15, 1.12, 0.45),
            Vec3::new(0.0, 1.0, 0.1),
            30f32.to_radians(),
        )
        .unwrap();
    // And the cloth with thread-by-thread colours (the lighting pass takes the G-buffer's
    // thread colour as both threads' albedo).
    let mut striped = scene.clone();
    for m in striped.materials.iter_mut() {
        if let Some(f) = m.fabric.as_mut() {
            f.warp_colours = vec![[0.8, 0.1, 0.1], [0.1, 0.6, 0.2], [0.9, 0.9, 0.8]];
            f.weft_colours = vec![[0.1, 0.1, 0.6], [0.05, 0.05, 0.05]];
        }
    }
    for (name, camera, scene) in [
        ("scene camera", None, &scene),
        ("close-up", Some(close.clone()), &scene),
        ("close-up, thread colours", Some(close), &striped),
    ] {
        let options = RenderOptions {
            width: 192,
            height: 108,
            camera_override: camera,
            ..Default::default()
        };
        let frame = renderer.render(&scene, &options).expect("render");
        let (compared, fabric, worst) = compare_lighting(&renderer, &scene, &options, &frame.hdr);
        println!(
            "{name}: {compared} pixels ({fabric} fabric), worst error {worst:.3} of the bound"
        );
        assert!(
            compared > 192 * 108 / 3 && fabric > 1000,
            "{name}: too few pixels compared: {compared}, {fabric} fabric"
        );
    }
}

/// `common::fabric_patch` lit by a point lamp half a metre above its centre.
fn patch_scene(fabric: FabricParams, uv_origin: [f32; 2]) -> Scene {
    common::fabric_patch(
        fabric,
        uv_origin,
        Light {
            name: "lamp".into(),
            kind: LightKind::Point,
            color: [1.0; 3],
            intensity: 1.0,
            range: None,
            position: Vec3::new(0.0, 0.5, 0.0),
            direction: Vec3::NEG_Y,
            shadow: None,
        },
    )
}

#[test]
fn highlight_of_a_thread_along_t_is_stretched_across_it() {
    // Every cell weft-up, no gap: a single thread direction, along t (+u = +X).
    let fabric = FabricParams {
        pattern: WeavePattern::from_fn(1, 1, |_, _| true),
        gap: 0.0,
        e_along: 400.0,
        e_across: 4.0,
        rd_warp: [0.0; 3],
        rd_weft: [0.0; 3],
        rs: 0.5,
        shadow_strength: 0.0,
        ..Default::default()
    };
    let scene = patch_scene(fabric, [0.0, 0.0]);
    // Looking straight down from beside the lamp; the camera's up is +Z, so screen x is world +X
    // (along the thread) and screen y is world +Z (across it).
    let camera = scene
        .look_at_camera(Vec3::new(0.0, 0.5, 0.0), Vec3::ZERO, 90f32.to_radians())
        .unwrap();
    let (w, h) = (128usize, 128usize);
    let options = RenderOptions {
        width: w as u32,
        height: h as u32,
        camera_override: Some(camera),
        ..Default::default()
    };
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let frame = renderer.render(&scene, &options).expect("render");
    // Second moments of the highlight's luminance about its centroid, in pixels.
    let lum = |i: usize| frame.hdr[i * 4] + frame.hdr[i * 4 + 1] + frame.hdr[i * 4 + 2];
    let peak = (0..w * h).map(lum).fold(0f32, f32::max);
    assert!(peak > 0.0);
    let (mut sum, mut sx, mut sy) = (0f64, 0f64, 0f64);
    for i in 0..w * h {
        let l = lum(i);
        if l > 0.1 * peak {
            sum += l as f64;
            sx += l as f64 * (i % w) as f64;
            sy += l as f64 * (i / w) as f64;
        }
    }
    let (cx, cy) = (sx / sum, sy / sum);
    let (mut vxx, mut vyy) = (0f64, 0f64);
    for i in 0..w * h {
        let l = lum(i);
        if l > 0.1 * peak {
            vxx += l as f64 * ((i % w) as f64 - cx).powi(2);
            vyy += l as f64 * ((i / w) as f64 - cy).powi(2);
        }
    }
    let (spread_along, spread_across) = ((vxx / sum).sqrt(), (vyy / sum).sqrt());
    println!(
        "highlight spread: {spread_along:.2} px along the thread, {spread_across:.2} px across it"
    );
    assert!(
        spread_across > 3.0 * spread_along,
        "the highlight must be stretched across the thread: {spread_along:.2} px along, {spread_across:.2} px across"
    );
}

#[test]
fn huge_texture_coordinates_keep_the_weave() {
    // The same patch near the UV origin and at u, v = 1e7: the coverage images must agree.
    let fabric = FabricParams {
        repeat: 0.25,
        ..Default::default()
    };
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let mut images = Vec::new();
    for origin in [[0.0f32, 0.0], [1.0e7, -1.0e7]] {
        let scene = patch_scene(fabric.clone(), origin);
        let camera = scene
            .look_at_camera(Vec3::new(0.0, 1.5, 0.0), Vec3::ZERO, 60f32.to_radians())
            .unwrap();
        let options = RenderOptions {
            width: 96,
            height: 96,
            camera_override: Some(camera),
            debug_view: DebugView::Coverage,
            ..Default::default()
        };
        images.push(renderer.render(&scene, &options).expect("render").hdr);
    }
    // 1e7 and -1e7 are whole multiples of the repeat (0.25): the pattern lines up exactly.
    let max_diff = images[0]
        .iter()
        .zip(&images[1])
        .map(|(a, b)| (a - b).abs())
        .fold(0f32, f32::max);
    let covered = images[0]
        .chunks_exact(4)
        .filter(|p| p[0] + p[1] > 0.0)
        .count();
    assert!(covered > 96 * 96 / 2);
    assert!(
        max_diff < 2e-3,
        "the weave at u = 1e7 differs from the weave at 0 by {max_diff}"
    );
}

#[test]
fn accuracy_levels_render_clean_and_mixture_is_closest_to_ground_truth_far_away() {
    use weft::render::{Accuracy, WeavePrecision};
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let scene = scene::default_scene();
    let far = scene
        .look_at_camera(
            Vec3::new(0.0, 6.0, 14.0),
            Vec3::new(0.0, 0.4, 0.0),
            20f32.to_radians(),
        )
        .unwrap();
    let render = |r: &mut Renderer, accuracy, weave_precision| {
        let options = RenderOptions {
            width: 160,
            height: 90,
            camera_override: Some(far.clone()),
            accuracy,
            weave_precision,
            ..Default::default()
        };
        let frame = r
            .render(&scene, &options)
            .unwrap_or_else(|e| panic!("{}: {e}", accuracy.name()));
        assert!(
            frame.hdr.iter().all(|v| v.is_finite()),
            "{}: non-finite output",
            accuracy.name()
        );
        frame.hdr
    };
    // Ground truth: the analytic weave at 16 x 16 points of each pixel's footprint.
    let truth = render(
        &mut renderer,
        Accuracy::Supersampled(16),
        WeavePrecision::Analytic,
    );
    let rmse = |img: &[f32]| {
        let sum: f64 = img
            .iter()
            .zip(&truth)
            .map(|(a, b)| ((a - b) as f64).powi(2))
            .sum();
        (sum / img.len() as f64).sqrt()
    };
    let mut errors = Vec::new();
    for (accuracy, precision) in [
        (Accuracy::Nearest, WeavePrecision::Rgba16f),
        (Accuracy::FilteredParams, WeavePrecision::Rgba16f),
        (Accuracy::Mixture, WeavePrecision::Rgba8),
        (Accuracy::Mixture, WeavePrecision::Rgba16f),
        (Accuracy::Mixture, WeavePrecision::Analytic),
        (Accuracy::Supersampled(4), WeavePrecision::Rgba16f),
    ] {
        let e = rmse(&render(&mut renderer, accuracy, precision));
        println!(
            "far view, {} / {}: RMSE {e:.5} against supersampled:16",
            accuracy.name(),
            precision.name()
        );
        errors.push((accuracy, precision, e));
    }
    let err =
        |a: Accuracy, p: WeavePrecision| errors.iter().find(|e| e.0 == a && e.1 == p).unwrap().2;
    let mixture = err(Accuracy::Mixture, WeavePrecision::Rgba16f);
    assert!(
        mixture < err(Accuracy::Nearest, WeavePrecision::Rgba16f),
        "mixture must beat nearest far away"
    );
    assert!(
        mixture < err(Accuracy::FilteredParams, WeavePrecision::Rgba16f),
        "mixture must beat filtered-params far away"
    );
    assert!(
        mixture < err(Accuracy::Supersampled(4), WeavePrecision::Rgba16f),
        "mixture must beat 4x4 supersampling far away"
    );
}
