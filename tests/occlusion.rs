//! The occlusion pass (issue 28 item 4): screen-space occlusion of the environment's light.
//!
//! - Against an independent truth: a floor before a wall of height H, whose visibility at
//!   distance d from the wall is computed here by f64 quadrature of the cosine-weighted
//!   hemisphere, ray by ray against the wall's rectangle (no horizon, slice or screen in it), and
//!   cross-checked with the infinite strip's form factor ½(1 − d/√(d² + H²)).
//! - Nothing to occlude changes nothing: a lone floor under the environment renders as without
//!   the pass.
//! - The light the occluders bounce (`gtao`, against `gtao-nobounce`) takes the occluder's colour
//!   where it exceeds the multi-bounce fit, and only there.
//! - The plan runs the pass only with an environment (or for its debug view), and
//!   `--occlusion none` compiles its read out of the lighting pass.

mod common;

use glam::{Mat4, Vec3, Vec4};
use weft::render::{DebugView, Occlusion, Pass, Plan, RenderOptions, Renderer};
use weft::scene::{Draw, Material, Mesh, Scene, Topology, Vertex};

/// A quad with corners `c` (counter-clockwise seen from where `normal` points).
fn quad(name: &str, c: [[f32; 3]; 4], normal: [f32; 3]) -> Mesh {
    let tangent = Vec3::from(c[1]) - Vec3::from(c[0]);
    let t = tangent.normalize();
    Mesh {
        name: name.into(),
        vertices: c
            .iter()
            .enumerate()
            .map(|(i, p)| Vertex {
                position: *p,
                normal,
                tangent: [t.x, t.y, t.z, 1.0],
                uv: [(i == 1 || i == 2) as u32 as f32, (i >= 2) as u32 as f32],
                uv1: [0.0; 2],
            })
            .collect(),
        indices: vec![0, 1, 2, 0, 2, 3],
        material: 0,
        colors: Vec::new(),
        topology: Topology::Triangles,
    }
}

const WALL_HALF_WIDTH: f32 = 10.0;
const WALL_HEIGHT: f32 = 1.0;

/// A floor (y = 0, z from 0 to 6, facing +y) and, when `wall`, a wall standing on its edge
/// (z = 0, y from 0 to WALL_HEIGHT, facing +z); both grey and rough.
fn wall_scene(wall: bool) -> Scene {
    let w = WALL_HALF_WIDTH;
    let mut meshes = vec![quad(
        "floor",
        [[-w, 0.0, 6.0], [w, 0.0, 6.0], [w, 0.0, 0.0], [-w, 0.0, 0.0]],
        [0.0, 1.0, 0.0],
    )];
    if wall {
        meshes.push(quad(
            "wall",
            [
                [-w, 0.0, 0.0],
                [w, 0.0, 0.0],
                [w, WALL_HEIGHT, 0.0],
                [-w, WALL_HEIGHT, 0.0],
            ],
            [0.0, 0.0, 1.0],
        ));
    }
    let draws = (0..meshes.len())
        .map(|m| Draw::new(m, Mat4::IDENTITY))
        .collect();
    Scene {
        source: "occlusion test".into(),
        meshes,
        draws,
        materials: vec![Material {
            name: "grey".into(),
            base_color: [0.5, 0.5, 0.5, 1.0],
            metallic: 0.0,
            roughness: 1.0,
            double_sided: true,
            ..Default::default()
        }],
        ..Default::default()
    }
}

/// The cosine-weighted visibility of the sky from the floor point (0, 0, d) past the wall's
/// rectangle, by an n x n midpoint quadrature of the cosine-weighted hemisphere (f64).
fn wall_visibility_truth(d: f64, n: usize) -> f64 {
    let (w, h) = (WALL_HALF_WIDTH as f64, WALL_HEIGHT as f64);
    let mut open = 0usize;
    for i in 0..n {
        for j in 0..n {
            // Malley's method: a uniform point of the unit disc lifted onto the hemisphere.
            let r = ((i as f64 + 0.5) / n as f64).sqrt();
            let phi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / n as f64;
            let (x, z) = (r * phi.cos(), r * phi.sin());
            let y = (1.0 - r * r).max(0.0).sqrt();
            // The wall's plane z = 0 lies behind (-z) the point.
            let hit = z < 0.0 && {
                let t = -d / z;
                let (hx, hy) = (t * x, t * y);
                hx.abs() <= w && (0.0..=h).contains(&hy)
            };
            open += (!hit) as usize;
        }
    }
    open as f64 / (n * n) as f64
}

fn options(width: u32, height: u32, scene: &Scene, occlusion: Occlusion) -> RenderOptions {
    let camera = scene
        .look_at_camera(
            Vec3::new(0.0, 2.2, 4.2),
            Vec3::new(0.0, 0.3, 0.9),
            50f32.to_radians(),
        )
        .expect("a valid camera");
    RenderOptions {
        width,
        height,
        camera_override: Some(camera),
        debug_view: DebugView::Occlusion,
        occlusion,
        ..Default::default()
    }
}

/// The pixel (x, y) a world point lands on.
fn pixel_of(o: &RenderOptions, p: Vec3) -> (usize, usize) {
    let camera = o.camera_override.as_ref().expect("set");
    let data = weft::render::gpu::FrameData::new(camera, o.width, o.height);
    let clip = Mat4::from_cols_array_2d(&data.view_proj) * Vec4::new(p.x, p.y, p.z, 1.0);
    let ndc = clip.truncate() / clip.w;
    (
        ((ndc.x * 0.5 + 0.5) * o.width as f32) as usize,
        ((ndc.y * 0.5 + 0.5) * o.height as f32) as usize,
    )
}

#[test]
fn the_infinite_strip_form_factor_agrees_with_the_quadrature() {
    // The truth's own check: a wall 10 heights wide to each side is an infinite strip to
    // within the quadrature's resolution near its middle.
    for d in [0.25f64, 0.5, 1.0, 2.0] {
        let strip = 1.0 - 0.5 * (1.0 - d / (d * d + 1.0).sqrt());
        let quad = wall_visibility_truth(d, 1000);
        assert!(
            (quad - strip).abs() < 0.01,
            "d = {d}: quadrature {quad:.4}, strip {strip:.4}"
        );
    }
}

#[test]
fn a_wall_occludes_the_floor_as_the_truth_says() {
    let ctx = common::context();
    let mut renderer = Renderer::new(ctx).expect("renderer");
    let scene = wall_scene(true);
    let o = options(
        320,
        240,
        &scene,
        Occlusion::Gtao {
            radius: Some(4.0),
            bounce: true,
            world: false,
        },
    );
    let plan = Plan::new(&scene, &o);
    assert!(plan.runs(Pass::Occlusion), "{plan}");
    let frame = renderer.render(&scene, &o).expect("render");
    let at = |p: Vec3| {
        let (x, y) = pixel_of(&o, p);
        assert!(
            x < o.width as usize && y < o.height as usize,
            "{p} is off the image"
        );
        frame.hdr[(y * o.width as usize + x) * 4]
    };
    println!("| d / H | truth (f64 quadrature) | occlusion pass | difference |");
    println!("|---|---|---|---|");
    let (mut worst, mut lowest) = (0f64, 0f64);
    for d in [0.25f32, 0.5, 1.0, 1.5] {
        let truth = wall_visibility_truth(d as f64, 1000);
        let got = at(Vec3::new(0.0, 0.0, d)) as f64;
        println!("| {d} | {truth:.4} | {got:.4} | {:+.4} |", got - truth);
        worst = worst.max((got - truth).abs());
        lowest = lowest.min(got - truth);
    }
    // Far from the wall, open.
    let far = at(Vec3::new(0.0, 0.0, 2.5)) as f64;
    let far_truth = wall_visibility_truth(2.5, 1000);
    println!(
        "| 2.5 | {far_truth:.4} | {far:.4} | {:+.4} |",
        far - far_truth
    );
    worst = worst.max((far - far_truth).abs());
    // Measured on lavapipe (2 slices x 6 steps, radius 4 H): +0.035, +0.057, +0.071, +0.057,
    // always short of the truth: the steps land below the wall's top (the highest sample on the
    // wall is the horizon), and occluders beyond 40 % of the radius fade (the truth cut at that
    // distance is 0.007-0.033 more open at these d). The bound keeps 0.02 beyond the worst, for
    // another CPU's rounding, and fails on a pass that finds a third less occlusion or none
    // (the truth's occlusion here is 0.08-0.38).
    assert!(worst < 0.09, "worst difference {worst:.4}");
    assert!(lowest > -0.02, "darker than the truth by {lowest:.4}");
}

/// Light bounced between occluders takes their colour (issue 28: the Duck's crease, yellow in
/// Cycles, was darkened grey): an orange floor and wall under a uniform white environment, no
/// lamps, with and without the pass. Each channel's diffuse light is scaled by its own
/// multi-bounce, gtao_multibounce(visibility, albedo of that channel) (Rust twin; visibility from
/// the pass's debug view), not by the one of the albedo's luminance. The scene has no lamps.
#[test]
fn the_multi_bounce_takes_the_albedo_s_colour() {
    use weft::reference::ibl_twin::gtao_multibounce;
    let ctx = common::context();
    let mut renderer = Renderer::new(ctx).expect("renderer");
    let mut scene = wall_scene(true);
    let albedo = [0.9f32, 0.45, 0.05];
    scene.materials[0].base_color = [albedo[0], albedo[1], albedo[2], 1.0];
    scene.materials[0].specular.factor = 0.0;
    let env = weft::env::EnvLighting::new(std::sync::Arc::new(weft::env::Environment::uniform(
        [1.0; 3],
    )));
    let lit = |occlusion, debug_view| {
        let mut o = options(320, 240, &scene, occlusion);
        o.debug_view = debug_view;
        o.environment = Some(env.clone());
        o
    };
    // The fit alone (the bounce adds where the screen shows more: the next test).
    let occlusion = Occlusion::Gtao {
        radius: Some(4.0),
        bounce: false,
        world: false,
    };
    let visibility = renderer
        .render(&scene, &lit(occlusion, DebugView::Occlusion))
        .expect("render");
    let with = renderer
        .render(&scene, &lit(occlusion, DebugView::None))
        .expect("render");
    let without = renderer
        .render(&scene, &lit(Occlusion::None, DebugView::None))
        .expect("render");
    let o = lit(occlusion, DebugView::None);
    let lum = 0.2126 * albedo[0] + 0.7152 * albedo[1] + 0.0722 * albedo[2];
    let (mut worst, mut spread) = (0f32, 0f32);
    for d in [0.25f32, 0.5, 1.0] {
        let (x, y) = pixel_of(&o, Vec3::new(0.0, 0.0, d));
        let i = (y * o.width as usize + x) * 4;
        let v = visibility.hdr[i];
        // No specular (KHR_materials_specular factor 0): the pixel is the diffuse alone, so
        // with/without is the diffuse's occlusion per channel.
        let ratio: Vec<f32> = (0..3)
            .map(|c| with.hdr[i + c] / without.hdr[i + c])
            .collect();
        let want: Vec<f32> = (0..3).map(|c| gtao_multibounce(v, albedo[c])).collect();
        let grey = gtao_multibounce(v, lum);
        println!(
            "d = {d}: visibility {v:.3}; with/without per channel {ratio:.4?}; own bounce {want:.4?}; grey {grey:.4}"
        );
        for c in 0..3 {
            worst = worst.max((ratio[c] - want[c]).abs());
        }
        spread = spread.max(want[0] - want[2]);
    }
    println!(
        "worst |ratio - own bounce| {worst:.5}; red's bounce above blue's by up to {spread:.3}"
    );
    // Measured 0.0012 (f16 storage of the HDR target and of the debug view's visibility): bound
    // 0.004. The grey bounce (before) gave every channel the same ratio, 0.12 above blue's own
    // and 0.12 below red's at d = 0.25.
    assert!(
        spread > 0.05,
        "the case does not tell the colours apart: {spread}"
    );
    assert!(worst < 0.004, "{worst}");
    renderer.context().check_validation().unwrap();
}

#[test]
fn nothing_to_occlude_leaves_the_image_as_it_was() {
    let ctx = common::context();
    let mut renderer = Renderer::new(ctx).expect("renderer");
    let scene = wall_scene(false);
    let env = weft::env::EnvLighting::new(std::sync::Arc::new(weft::env::Environment::studio()));
    let lit = |occlusion| {
        let mut o = options(320, 240, &scene, occlusion);
        o.debug_view = DebugView::None;
        o.environment = Some(env.clone());
        o
    };
    let with = lit(Occlusion::DEFAULT);
    let without = lit(Occlusion::None);
    assert!(Plan::new(&scene, &with).runs(Pass::Occlusion));
    assert!(!Plan::new(&scene, &without).runs(Pass::Occlusion));
    let a = renderer.render(&scene, &with).expect("render");
    let b = renderer.render(&scene, &without).expect("render");
    let worst = a
        .hdr
        .iter()
        .zip(&b.hdr)
        .map(|(x, y)| ((x - y) / y.abs().max(1e-3)).abs())
        .fold(0f32, f32::max);
    println!("largest relative difference of a lone floor with and without the pass: {worst:e}");
    // Measured: 0.0047 (the open floor's visibility is 0.993-1 where the floor ends against the
    // empty background).
    assert!(worst < 0.01, "{worst}");
}

#[test]
fn the_plan_runs_the_pass_only_where_it_is_read() {
    let scene = wall_scene(true);
    let env = weft::env::EnvLighting::new(std::sync::Arc::new(weft::env::Environment::studio()));
    let mut o = options(64, 48, &scene, Occlusion::DEFAULT);
    o.debug_view = DebugView::None;
    // No environment: nothing to occlude.
    let plan = Plan::new(&scene, &o);
    assert!(
        !plan.runs(Pass::Occlusion) && plan.occlusion.is_none(),
        "{plan}"
    );
    // With one: planned, its radius 0.3 of the diagonal of what casts.
    o.environment = Some(env);
    let plan = Plan::new(&scene, &o);
    assert!(plan.runs(Pass::Occlusion), "{plan}");
    let b = scene.caster_bounds().expect("bounds");
    let expected = (b.max - b.min).length() * Occlusion::RADIUS_OF_DIAGONAL;
    let radius = plan.occlusion.as_ref().expect("planned").radius;
    assert!((radius - expected).abs() < 1e-5, "{radius} vs {expected}");
    let order: Vec<_> = plan.passes.iter().map(|p| p.name()).collect();
    let at = |n: &str| order.iter().position(|p| *p == n).expect(n);
    assert!(at("gbuffer") < at("occlusion") && at("occlusion") < at("lighting"));
    // Turned off: not planned.
    o.occlusion = Occlusion::None;
    assert!(!Plan::new(&scene, &o).runs(Pass::Occlusion));
    // Bad radii are refused with the flag's own words.
    for bad in ["gtao:0", "gtao:-1", "gtao:nan", "gtao:x", "ssao"] {
        let e = Occlusion::parse(bad).expect_err(bad).to_string();
        assert!(e.contains("gtao:R"), "{bad}: {e}");
    }
    assert_eq!(
        Occlusion::parse("gtao:0.5").unwrap(),
        Occlusion::Gtao {
            radius: Some(0.5),
            bounce: true,
            world: true,
        }
    );
    assert_eq!(Occlusion::parse("gtao").unwrap(), Occlusion::DEFAULT);
    for (text, radius) in [("gtao-nobounce", None), ("gtao-nobounce:2", Some(2.0))] {
        let o = Occlusion::parse(text).unwrap();
        assert_eq!(
            o,
            Occlusion::Gtao {
                radius,
                bounce: false,
                world: false,
            }
        );
        assert_eq!(o.name(), text);
    }
    for (text, radius) in [("gtao-screen", None), ("gtao-screen:2", Some(2.0))] {
        let o = Occlusion::parse(text).unwrap();
        assert_eq!(
            o,
            Occlusion::Gtao {
                radius,
                bounce: true,
                world: false,
            }
        );
        assert_eq!(o.name(), text);
    }
    for bad in ["gtao-nobounce:0", "gtao-nobounce:", "gtaox", "gtao-bounce"] {
        assert!(Occlusion::parse(bad).is_err(), "{bad}");
    }
}

/// The occluders' bounced light (`--occlusion gtao`, issue 28): a light grey floor before a red
/// wall (glTF, then woven), under a uniform white environment, no lamps, no specular. The wall's one bounce (its
/// albedo times the environment's irradiance/π, 1 here) reaches the floor from the part of its
/// hemisphere the wall hides, 1 − visibility: per channel the pass's diffuse light is the larger
/// of the fit's, gtao_multibounce(v, the floor's albedo), and v + the wall's albedo · (1 − v)
/// (Rust twin; v from the pass's debug view). The red channel, whose wall albedo is far above
/// the floor's, gains over `gtao-nobounce` that much; the green and blue, whose wall albedo is
/// near 0, keep the fit's exactly.
#[test]
fn the_occluders_bounce_takes_their_colour_where_it_exceeds_the_fit() {
    use weft::reference::ibl_twin::gtao_multibounce;
    let ctx = common::context();
    let mut renderer = Renderer::new(ctx).expect("renderer");
    let (floor, wall) = (0.6f32, [0.95f32, 0.04, 0.04]);
    // The wall a glTF material, then woven: plain weave, no gaps and no thread shadowing, so its
    // threads' diffuse colour over any coverage is the wall colour (fabric_albedo).
    for woven in [false, true] {
        let mut scene = wall_scene(true);
        scene.materials[0].base_color = [floor, floor, floor, 1.0];
        scene.materials[0].specular.factor = 0.0;
        let mut red = scene.materials[0].clone();
        red.name = "red".into();
        red.base_color = [wall[0], wall[1], wall[2], 1.0];
        if woven {
            let mut p = weft::fabric::presets::by_name("cotton-plain")
                .expect("preset")
                .params(8.0);
            p.rd_warp = wall;
            p.rd_weft = wall;
            p.gap = 0.0;
            p.shadow_strength = 0.0;
            p.coupled_diffuse = false;
            red.fabric = Some(p);
        }
        scene.materials.push(red);
        scene.meshes[1].material = 1;
        let env = weft::env::EnvLighting::new(std::sync::Arc::new(
            weft::env::Environment::uniform([1.0; 3]),
        ));
        let lit = |bounce, debug_view| {
            let mut o = options(
                320,
                240,
                &scene,
                Occlusion::Gtao {
                    radius: Some(4.0),
                    bounce,
                    world: false,
                },
            );
            o.debug_view = debug_view;
            o.environment = Some(env.clone());
            o
        };
        let visibility = renderer
            .render(&scene, &lit(true, DebugView::Occlusion))
            .expect("render");
        let with = renderer
            .render(&scene, &lit(true, DebugView::None))
            .expect("render");
        let without = renderer
            .render(&scene, &lit(false, DebugView::None))
            .expect("render");
        let o = lit(true, DebugView::None);
        let mut gains = Vec::new();
        let (mut worst_blue, mut worst_over) = (0f32, 0f32); // worst_over: signed, largest |.|
        for d in [0.25f32, 0.5, 1.0] {
            let (x, y) = pixel_of(&o, Vec3::new(0.0, 0.0, d));
            let i = (y * o.width as usize + x) * 4;
            let v = visibility.hdr[i];
            let fit = gtao_multibounce(v, floor);
            let ratio: Vec<f32> = (0..3)
                .map(|c| with.hdr[i + c] / without.hdr[i + c])
                .collect();
            // The one bounce of the wall (where it exceeds the fit), over the fit.
            let most = (v + wall[0] * (1.0 - v)).max(fit) / fit;
            println!(
                "{} wall, d = {d}: visibility {v:.3}, fit {fit:.4}; with / without per channel {ratio:.4?}; one bounce {most:.4}",
                if woven { "woven" } else { "glTF" }
            );
            gains.push(ratio[0]);
            worst_blue = worst_blue.max((ratio[1] - 1.0).abs().max((ratio[2] - 1.0).abs()));
            if (ratio[0] - most).abs() > worst_over.abs() {
                worst_over = ratio[0] - most;
            }
        }
        // Measured on lavapipe: red gains 1.1869, 1.1086, 1.0367 (glTF wall) and 1.1889,
        // 1.1095, 1.0367 (woven) against the one bounce's 1.1877, 1.1094, 1.0371 (the hidden arc
        // is all wall, and the pass measures its light from the same horizons as the
        // visibility); green and blue exactly 1. Bounds: red
        // within 0.005 of the one bounce (f16 targets, another CPU's rounding) and at least 3 %
        // up near the wall (a pass that bounced half the light would miss it by 0.04-0.09); the
        // others within 0.002.
        assert!(
            gains[0] > 1.03 && gains[1] > 1.03,
            "woven {woven}: {gains:?}"
        );
        assert!(
            worst_over.abs() < 0.005,
            "woven {woven}: red off the wall's one bounce by {worst_over}"
        );
        assert!(
            worst_blue < 0.002,
            "woven {woven}: green/blue moved by {worst_blue}"
        );
    }
    renderer.context().check_validation().unwrap();
}

/// A floor of `cols` x `rows` vertices over x in [-2, 2] and z in `zs` (facing +y), so the
/// world light, baked per vertex, has vertices at those distances from the wall.
fn floor_grid(zs: &[f32], cols: usize) -> Mesh {
    let mut vertices = Vec::new();
    for &z in zs {
        for i in 0..cols {
            let x = -2.0 + 4.0 * i as f32 / (cols - 1) as f32;
            vertices.push(Vertex {
                position: [x, 0.0, z],
                normal: [0.0, 1.0, 0.0],
                tangent: [1.0, 0.0, 0.0, 1.0],
                uv: [0.0; 2],
                uv1: [0.0; 2],
            });
        }
    }
    let mut indices = Vec::new();
    for r in 0..zs.len() as u32 - 1 {
        for i in 0..cols as u32 - 1 {
            let (a, b) = (r * cols as u32 + i, (r + 1) * cols as u32 + i);
            indices.extend_from_slice(&[a, b, b + 1, a, b + 1, a + 1]);
        }
    }
    Mesh {
        name: "floor grid".into(),
        vertices,
        indices,
        material: 0,
        colors: Vec::new(),
        topology: Topology::Triangles,
    }
}

/// The world light's visibility (render::world_light: rays per vertex against a BVH, on the
/// CPU) against the same independent truth as the screen's: the floor before the wall, each
/// distance's row of vertices averaged (41 vertices of 64 rays each: a standard error about
/// 0.01), and its bounce against the wall's light: under a uniform sky of radiance 1 the grey
/// wall (0.5) sends back 0.5 times its own visibility, so the floor's bounce is at most
/// 0.5 · (1 − visibility) and at least a quarter of it (the wall's visibility, seen from the
/// floor, is between 0.5 at its foot and 1 at its top).
#[test]
fn the_world_light_sees_the_wall_as_the_truth_says() {
    use weft::render::world_light::{bake, SkyLight};
    let mut scene = wall_scene(true);
    let zs = [0.25f32, 0.5, 1.0, 2.0];
    scene.meshes[0] = floor_grid(&zs, 41);
    let sky = SkyLight {
        sh: weft::env::Environment::uniform([1.0; 3]).sh9(),
        rotation: 0.0,
        intensity: 1.0,
    };
    let b = bake(&scene, &sky);
    let base = b.base[0].expect("the floor receives") as usize;
    for (r, &z) in zs.iter().enumerate() {
        let row = &b.texels[base + r * 41..base + (r + 1) * 41];
        let v = row.iter().map(|t| t[3]).sum::<f32>() / 41.0;
        let bounce = row.iter().map(|t| t[0]).sum::<f32>() / 41.0;
        let truth = wall_visibility_truth(z as f64, 400) as f32;
        println!("d = {z}: world visibility {v:.4}, truth {truth:.4}; bounce {bounce:.4}");
        assert!((v - truth).abs() < 0.03, "d = {z}: {v} against {truth}");
        let hidden = 1.0 - truth;
        assert!(
            bounce <= 0.5 * hidden + 0.02 && bounce >= 0.25 * hidden - 0.02,
            "d = {z}: bounce {bounce} for {hidden} of the hemisphere hidden"
        );
    }
}

/// What the world light is for: an occluder the screen cannot see. A red plate (y = 0.5, in
/// front of a light grey wall) seen exactly edge-on from a camera level with it is not on the
/// screen at all, yet the wall just above it sees the plate's top over half its hemisphere, lit
/// red by the white sky. With `--occlusion gtao` the wall there turns red (its red over its green
/// rises from 1 to about 1.8: half its sky is the plate, whose red albedo is 0.9, and the fit
/// gives back no grey bounce for what only the world sees); with
/// `gtao-screen` it keeps its grey, as the screen shows nothing there. And where the plan leaves
/// the world light out (a material with KHR_materials_specular's data takes the target), `gtao`
/// renders exactly as `gtao-screen`.
#[test]
fn the_world_light_brings_back_what_the_screen_hides() {
    let ctx = common::context();
    let mut renderer = Renderer::new(ctx).expect("renderer");
    let w = 3.0f32;
    // Vertices every 0.1 across and 0.05 to 0.25 up: the world light counts an occluder fully
    // from as far as the longest edge of a vertex's triangles (world_light::reach).
    let rows = [
        0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.55, 0.6, 0.65, 0.7, 0.75, 0.8, 0.9, 1.0, 1.25, 1.5, 1.75,
        1.9, 2.0,
    ];
    let mut wall = floor_grid(&rows, 61);
    // The grid stood up: (x, 0, z) -> (x, z, 0), facing +z.
    for v in &mut wall.vertices {
        v.position = [v.position[0] * w / 2.0, v.position[2], 0.0];
        v.normal = [0.0, 0.0, 1.0];
    }
    wall.indices.chunks_exact_mut(3).for_each(|t| t.swap(1, 2));
    let plate = quad(
        "plate",
        [[-w, 0.5, 3.0], [w, 0.5, 3.0], [w, 0.5, 0.0], [-w, 0.5, 0.0]],
        [0.0, 1.0, 0.0],
    );
    let mut scene = wall_scene(false);
    scene.meshes = vec![wall, plate];
    scene.meshes[1].material = 1;
    scene.materials[0].base_color = [0.8, 0.8, 0.8, 1.0];
    scene.materials[0].specular.factor = 1.0;
    let mut red = scene.materials[0].clone();
    red.name = "red".into();
    red.base_color = [0.9, 0.05, 0.05, 1.0];
    scene.materials.push(red);
    scene.draws = vec![Draw::new(0, Mat4::IDENTITY), Draw::new(1, Mat4::IDENTITY)];
    let env = weft::env::EnvLighting::new(std::sync::Arc::new(weft::env::Environment::uniform(
        [1.0; 3],
    )));
    let camera = scene
        .look_at_camera(
            Vec3::new(0.0, 0.5, 6.0),
            Vec3::new(0.0, 0.5, 0.0),
            40f32.to_radians(),
        )
        .expect("a valid camera");
    let lit = |scene: &Scene, world: bool| {
        let o = RenderOptions {
            width: 160,
            height: 120,
            camera_override: Some(camera.clone()),
            occlusion: Occlusion::Gtao {
                radius: Some(2.0),
                bounce: true,
                world,
            },
            environment: Some(env.clone()),
            ..Default::default()
        };
        let plan = Plan::new(scene, &o);
        (o, plan)
    };
    let (o, plan) = lit(&scene, true);
    assert!(
        plan.occlusion.as_ref().is_some_and(|p| p.world.is_some()),
        "{plan}"
    );
    // The plate is one quad 6 wide: its vertices cannot hold what the screen sees near the
    // wall, so the screen's bounce stays beside the world's.
    assert!(
        plan.occlusion
            .as_ref()
            .is_some_and(|p| p.bounce && !p.world_bounce()),
        "{plan}"
    );
    let with = renderer.render(&scene, &o).expect("render");
    let (o, plan) = lit(&scene, false);
    assert!(plan.occlusion.as_ref().is_some_and(|p| p.world.is_none()));
    let without = renderer.render(&scene, &o).expect("render");
    // The plate is edge-on: no pixel shows it (every covered pixel is the wall's grey, the
    // screen-only render's red equal to its green).
    let at = |img: &weft::render::Frame, y: f32| {
        let (x, py) = pixel_of(&o, Vec3::new(0.0, y, 0.0));
        let i = (py * o.width as usize + x) * 4;
        [img.hdr[i], img.hdr[i + 1], img.hdr[i + 2]]
    };
    let mut ratios = Vec::new();
    for y in [0.6f32, 0.75, 1.9] {
        let (a, b) = (at(&with, y), at(&without, y));
        println!("wall at y = {y}: with the world light {a:?}, screen alone {b:?}");
        assert!(
            (b[0] / b[1] - 1.0).abs() < 0.02,
            "screen alone at {y}: {b:?}"
        );
        ratios.push(a[0] / a[1]);
    }
    // Just above the plate half the wall's sky is the plate: its green falls to about the sky's
    // half (0.5 + 0.05 · 0.5 of the wall's 0.8), its red stays near 0.5 + 0.9 · 0.5 (measured
    // on lavapipe: red over green 1.7 at y = 0.6); higher up the plate is less of the sky.
    assert!(ratios[0] > 1.4 && ratios[1] > 1.4, "{ratios:?}");
    assert!(ratios[2] < ratios[1] && ratios[2] > 1.0, "{ratios:?}");
    // Where the plan cannot take the target, gtao renders as gtao-screen, bit for bit.
    scene.materials[0].specular.factor = 0.9;
    let (o, plan) = lit(&scene, true);
    let why = plan
        .occlusion
        .as_ref()
        .and_then(|p| p.world_off.clone())
        .expect("the world light is left out");
    assert!(why.contains("KHR_materials_specular"), "{why}");
    let asked = renderer.render(&scene, &o).expect("render");
    let (o, _) = lit(&scene, false);
    let screen = renderer.render(&scene, &o).expect("render");
    assert_eq!(asked.ldr, screen.ldr);
    assert_eq!(asked.hdr, screen.hdr);
}

/// Where every receiving triangle is within a quarter of the occlusion radius (the default
/// scene, whose floor is 16 x 16 cells of 0.375 m against a radius of 2.56 m), the world light's
/// vertices hold the occluders' light the screen would add, and the plan leaves the screen's
/// bounce out of the occlusion pass (`OcclusionPlan::world_bounce()`: the lighting takes the
/// world's bounce alone). `Force::screen_bounce` puts it back. Measured on lavapipe (AMD EPYC,
/// 256-bit) at 480x270: the world's bounce alone against both, mean 8-bit difference
/// 0.0005/255, 2 pixels beyond 8/255, at most 15 (where the screen's half-resolution bounce
/// exceeded the vertices' at the cloth's hem); against the screen's bounce without the world
/// light, mean 0.61/255 and 1452 pixels beyond 8/255. The bounds (mean 0.005, 20 pixels) are
/// ten times the measured: the two renders share every other term, so another CPU's lavapipe
/// moves both alike; a frame without the world light moves 1452.
#[test]
fn the_world_light_alone_carries_the_bounce_where_its_vertices_are_fine() {
    let ctx = common::context();
    let mut renderer = Renderer::new(ctx).expect("renderer");
    let scene = weft::scene::default_scene();
    let env = weft::env::EnvLighting::new(std::sync::Arc::new(weft::env::Environment::studio()));
    let options = |force_screen: bool, world: bool| RenderOptions {
        width: 480,
        height: 270,
        environment: Some(env.clone()),
        occlusion: Occlusion::Gtao {
            radius: None,
            bounce: true,
            world,
        },
        force: weft::render::Force {
            screen_bounce: force_screen,
            ..weft::render::Force::NONE
        },
        ..Default::default()
    };
    let planned = options(false, true);
    let plan = Plan::new(&scene, &planned);
    let o = plan.occlusion.as_ref().expect("planned");
    let w = o.world.as_ref().expect("the world light is planned");
    assert!(
        o.world_bounce() && !o.bounce,
        "the screen's bounce is left out: {plan}"
    );
    assert!(w.longest_edge <= 0.25 * o.radius, "{plan}");
    assert!(
        plan.to_string().contains("from the world light alone"),
        "{plan}"
    );
    let forced = options(true, true);
    let plan = Plan::new(&scene, &forced);
    let o = plan.occlusion.as_ref().expect("planned");
    assert!(o.bounce && !o.world_bounce(), "forced back: {plan}");
    let alone = renderer.render(&scene, &planned).expect("render");
    let both = renderer.render(&scene, &forced).expect("render");
    let screen = renderer
        .render(&scene, &options(false, false))
        .expect("render");
    // Mean 8-bit difference over the pixels and how many differ by more than 8 (of 255).
    let diff = |a: &weft::render::Frame, b: &weft::render::Frame| {
        let d: Vec<u8> = a
            .ldr
            .iter()
            .zip(&b.ldr)
            .map(|(x, y)| x.abs_diff(*y))
            .collect();
        let mean = d.iter().map(|&x| x as f64).sum::<f64>() / d.len().max(1) as f64;
        let beyond = d
            .chunks_exact(4)
            .filter(|p| p[..3].iter().any(|&x| x > 8))
            .count();
        (mean, beyond, d.iter().copied().max().unwrap_or(0))
    };
    let (mean, beyond, most) = diff(&alone, &both);
    let (mean_screen, beyond_screen, most_screen) = diff(&alone, &screen);
    println!(
        "world's bounce alone against both: mean {mean:.4}/255, {beyond} pixels beyond 8/255, at most {most}; against the screen's alone (no world light): mean {mean_screen:.4}, {beyond_screen} beyond 8, at most {most_screen}"
    );
    assert!(alone.ldr.len() == 480 * 270 * 4);
    const BOUND_MEAN: f64 = 0.005;
    const BOUND_BEYOND: usize = 20;
    assert!(
        mean < BOUND_MEAN && beyond < BOUND_BEYOND,
        "mean {mean}, {beyond} beyond 8/255"
    );
    // Not the image of the screen's bounce without the world light: the world light is what
    // the frame keeps.
    assert!(mean_screen > 2.0 * mean, "{mean_screen} against {mean}");
}
