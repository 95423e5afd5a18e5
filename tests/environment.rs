//! Environment lighting in the plan and the frame (lavapipe, validation on): the environment
//! passes run only when an environment lights the scene, once per environment (cached by content),
//! not for debug views; ambient occlusion darkens environment light and nothing else; the default
//! lighting (`weft::env::stage`) adds a shadow-casting key light and a ground only where it should.

mod common;

use std::sync::Arc;

use glam::Mat4;
use weft::env::{stage, EnvLighting, Environment, LightsMode};
use weft::render::{DebugView, Pass, Plan, RenderOptions, Renderer};
use weft::scene::{self, ColorSpace, Draw, Material, Mesh, Scene, Texture, Vertex};

fn options(env: Option<Arc<Environment>>) -> RenderOptions {
    RenderOptions {
        width: 64,
        height: 36,
        environment: env.map(EnvLighting::new),
        ..Default::default()
    }
}

#[test]
fn environment_passes_run_only_when_an_environment_lights_the_scene() {
    let scene = scene::default_scene();
    let plan = Plan::new(&scene, &options(None));
    assert!(!plan.runs(Pass::Environment) && plan.environment.is_none());
    let studio = Arc::new(Environment::studio());
    let plan = Plan::new(&scene, &options(Some(studio.clone())));
    assert_eq!(plan.passes.first(), Some(&Pass::Environment));
    assert_eq!(plan.environment.as_ref().unwrap().name, "built-in studio");
    // Debug views show no lighting: no environment work.
    let debug = RenderOptions {
        debug_view: DebugView::Normals,
        ..options(Some(studio.clone()))
    };
    assert!(!Plan::new(&scene, &debug).runs(Pass::Environment));

    let mut renderer = Renderer::new(common::context()).unwrap();
    let plain = renderer.render(&scene, &options(None)).unwrap();
    assert!(plain.timings.iter().all(|t| t.name != "environment"));
    assert!(plain.stats.pipelines.iter().any(|p| p.contains("ibl=0")));
    // The first frame with an environment preprocesses it; the next reuses it.
    let first = renderer
        .render(&scene, &options(Some(studio.clone())))
        .unwrap();
    assert_eq!(
        first
            .timings
            .iter()
            .filter(|t| t.name == "environment")
            .count(),
        1
    );
    assert!(first.stats.pipelines.iter().any(|p| p.contains("ibl=2")));
    let second = renderer
        .render(&scene, &options(Some(studio.clone())))
        .unwrap();
    assert!(second.timings.iter().all(|t| t.name != "environment"));
    assert_eq!(
        first.hdr, second.hdr,
        "the cached environment gives the same image"
    );
    // A different environment (different content) is preprocessed again.
    let other = Arc::new(Environment::uniform([0.5; 3]));
    let third = renderer.render(&scene, &options(Some(other))).unwrap();
    assert_eq!(
        third
            .timings
            .iter()
            .filter(|t| t.name == "environment")
            .count(),
        1
    );
    // An environment of zero intensity adds nothing to the lamps: every pixel at most what the
    // lamps alone give with the fixed ambient removed, and the lamps' highlights stay.
    let mut dark = EnvLighting::new(studio);
    dark.intensity = 0.0;
    dark.background = weft::env::Background::Color([0.0; 3]);
    let zero = renderer
        .render(
            &scene,
            &RenderOptions {
                environment: Some(dark),
                ..options(None)
            },
        )
        .unwrap();
    assert!(zero.hdr.iter().all(|v| v.is_finite()));
    assert!(
        zero.hdr
            .iter()
            .zip(&plain.hdr)
            .all(|(z, p)| *z <= *p + 1e-3),
        "zero environment brighter than the ambient-lit frame somewhere"
    );
}

/// A 1 m quad facing +z with one material, seen from the front.
fn quad_scene(material: Material, textures: Vec<Texture>) -> Scene {
    let v = |x: f32, y: f32, u: f32, w: f32| Vertex {
        position: [x, y, 0.0],
        normal: [0.0, 0.0, 1.0],
        tangent: [1.0, 0.0, 0.0, 1.0],
        uv: [u, w],
        uv1: [0.0; 2],
    };
    let mut s = Scene {
        source: "test quad".into(),
        meshes: vec![Mesh {
            name: "quad".into(),
            vertices: vec![
                v(-1.0, -1.0, 0.0, 1.0),
                v(1.0, -1.0, 1.0, 1.0),
                v(1.0, 1.0, 1.0, 0.0),
                v(-1.0, 1.0, 0.0, 0.0),
            ],
            indices: vec![0, 1, 2, 0, 2, 3],
            material: 0,
            colors: Vec::new(),
            topology: weft::scene::Topology::Triangles,
        }],
        draws: vec![Draw::new(0, Mat4::IDENTITY)],
        materials: vec![material],
        textures,
        ..Default::default()
    };
    s.cameras.push(
        s.look_at_camera(
            glam::Vec3::new(0.0, 0.0, 2.5),
            glam::Vec3::ZERO,
            50f32.to_radians(),
        )
        .unwrap(),
    );
    s
}

#[test]
fn ambient_occlusion_darkens_environment_light_only() {
    let grey = Material {
        base_color: [0.6, 0.6, 0.6, 1.0],
        metallic: 0.0,
        roughness: 0.5,
        ..Material::default()
    };
    // Occlusion 0 on the left half, 1 on the right (8 texels, so bilinear filtering at the
    // quarters reads only one side).
    let occ = Texture {
        name: "occlusion".into(),
        width: 8,
        height: 1,
        color_space: ColorSpace::Linear,
        rgba8: (0..8)
            .flat_map(|i| if i < 4 { [0, 0, 0, 255] } else { [255; 4] })
            .collect(),
        bc7: None,
    };
    let occluded = Material {
        occlusion_texture: Some(0),
        occlusion_strength: 1.0,
        ..grey.clone()
    };
    let plain = quad_scene(grey, vec![]);
    let with_ao = quad_scene(occluded, vec![occ]);
    let mut renderer = Renderer::new(common::context()).unwrap();
    let env = Arc::new(Environment::uniform([1.0; 3]));
    let mut o = options(Some(env));
    o.width = 64;
    o.height = 64;
    let a = renderer.render(&plain, &o).unwrap();
    let b = renderer.render(&with_ao, &o).unwrap();
    let px = |f: &weft::render::Frame, x: usize, y: usize| f.hdr[(y * 64 + x) * 4 + 1];
    // Left quarter of the quad: occluded, dark; right quarter: unoccluded, as without the
    // texture.
    let (left, right) = ((20, 32), (44, 32));
    assert!(px(&a, left.0, left.1) > 0.3, "{}", px(&a, left.0, left.1));
    assert!(
        px(&b, left.0, left.1) < 0.15 * px(&a, left.0, left.1),
        "occluded: {} vs {}",
        px(&b, left.0, left.1),
        px(&a, left.0, left.1)
    );
    assert!((px(&b, right.0, right.1) - px(&a, right.0, right.1)).abs() < 1e-3);
    // Lamps (and the fixed ambient of a frame without an environment) are not occluded by it:
    // with one light and no environment the two scenes give the same image.
    let light = weft::scene::Light {
        name: "key".into(),
        kind: weft::scene::LightKind::Directional,
        color: [1.0; 3],
        intensity: 2.0,
        range: None,
        position: glam::Vec3::ZERO,
        direction: glam::Vec3::new(0.0, 0.0, -1.0),
        shadow: None,
    };
    let (mut plain, mut with_ao) = (plain, with_ao);
    plain.lights.push(light.clone());
    with_ao.lights.push(light);
    let lamps = RenderOptions {
        environment: None,
        ..o
    };
    let a = renderer.render(&plain, &lamps).unwrap();
    let b = renderer.render(&with_ao, &lamps).unwrap();
    assert_eq!(a.hdr, b.hdr, "occlusion changed lamp light");
}

#[test]
fn default_lighting_adds_a_key_light_and_ground_only_where_asked() {
    // A file with lights keeps them and gets nothing added.
    let mut s = scene::default_scene();
    let lights = s.lights.len();
    let draws = s.draws.len();
    assert!(!stage(&mut s, LightsMode::Auto, 0.0, false));
    assert_eq!((s.lights.len(), s.draws.len()), (lights, draws));
    // Without lights: the key light (which casts a shadow map) and a ground that casts none.
    s.lights.clear();
    assert!(stage(&mut s, LightsMode::Auto, 0.0, false));
    assert_eq!(s.lights.len(), 1);
    assert!(s.lights[0].shadow.is_some());
    let ground = s.draws.last().unwrap();
    assert!(!ground.cast_shadows && ground.receive_shadows);
    let plan = Plan::new(&s, &options(Some(Arc::new(Environment::studio()))));
    assert_eq!(
        plan.shadows.len(),
        1,
        "the key light's shadow map is planned"
    );
    // With the user's own environment, no key light is added; `none` removes the file's.
    let mut s = scene::default_scene();
    s.lights.clear();
    assert!(!stage(&mut s, LightsMode::Auto, 0.0, true));
    assert!(s.lights.is_empty());
    let mut s = scene::default_scene();
    stage(&mut s, LightsMode::None, 0.0, false);
    assert!(s.lights.is_empty());
    // The ground does not change what the automatic camera frames.
    let mut s = quad_scene(Material::default(), vec![]);
    s.cameras.clear();
    let before = s.camera(None).unwrap().view;
    stage(&mut s, LightsMode::Default, 0.0, false);
    assert_eq!(s.camera(None).unwrap().view, before);
}

/// Environment maps of the wrong shape or kind are refused by name (project issue 30): an
/// equirectangular map is twice as wide as high; a PNG renamed .hdr is not radiance; an EXR with
/// no finite texel holds no light. A map with a few non-finite texels loads, with a warning.
#[test]
fn environment_maps_of_the_wrong_shape_or_kind_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let hdr = |name: &str, w: u32, h: u32| {
        let path = dir.path().join(name);
        let img = image::Rgb32FImage::from_pixel(w, h, image::Rgb([0.5, 0.5, 0.5]));
        image::DynamicImage::ImageRgb32F(img).save(&path).unwrap();
        path
    };
    for (w, h) in [(1, 2), (4096, 1), (64, 64), (48, 64)] {
        let path = hdr(&format!("shape-{w}x{h}.hdr"), w, h);
        let e = Environment::load(&path).expect_err("not 2:1").to_string();
        assert!(
            e.contains(&format!("is {w}x{h}, not an equirectangular")) && e.contains("shape-"),
            "{e}"
        );
    }
    for (w, h) in [(2, 1), (64, 32), (2048, 1024)] {
        let env = Environment::load(&hdr(&format!("ok-{w}x{h}.hdr"), w, h)).unwrap();
        assert_eq!((env.width, env.height), (w, h));
        assert!(env.warnings.is_empty(), "{:?}", env.warnings);
    }
    // A PNG under an HDR's name: its sRGB bytes are not radiance.
    let png = dir.path().join("photo.png");
    image::RgbImage::from_pixel(64, 32, image::Rgb([200, 100, 50]))
        .save(&png)
        .unwrap();
    for name in ["photo.hdr", "photo.exr"] {
        std::fs::copy(&png, dir.path().join(name)).unwrap();
        let e = Environment::load(&dir.path().join(name))
            .expect_err("a PNG")
            .to_string();
        assert!(e.contains(name) && e.contains("holds a PNG image"), "{e}");
    }
    // EXRs with NaN: all of it refused; some of it taken as black, said.
    let exr = |name: &str, f: &dyn Fn(u32) -> f32| {
        let path = dir.path().join(name);
        let img = image::Rgb32FImage::from_fn(64, 32, |x, y| {
            let v = f(y * 64 + x);
            image::Rgb([v, v, v])
        });
        image::DynamicImage::ImageRgb32F(img).save(&path).unwrap();
        path
    };
    let e = Environment::load(&exr("all-nan.exr", &|_| f32::NAN))
        .expect_err("no finite texel")
        .to_string();
    assert!(
        e.contains("all-nan.exr") && e.contains("no finite texel"),
        "{e}"
    );
    let env = Environment::load(&exr("some-nan.exr", &|i| {
        if i % 8 == 0 {
            f32::INFINITY
        } else {
            1.0
        }
    }))
    .unwrap();
    assert_eq!(env.warnings.len(), 1, "{:?}", env.warnings);
    assert!(
        env.warnings[0].contains("256 of its 2048 texels are NaN or infinite"),
        "{:?}",
        env.warnings
    );
    assert!(env.rgb.iter().all(|v| v.is_finite()));
}

/// A single-sided sheet whose fronts face away from +Z (a curtain seen from behind) showed
/// nothing but its shadow from the automatic camera (project issue 30): automatic framing now
/// looks from the side the single-sided surfaces face, and the default key light turns with it.
/// Double-sided surfaces and closed meshes keep the usual view from +Z.
#[test]
fn automatic_framing_looks_at_the_side_single_sided_surfaces_face() {
    let red = Material {
        name: "red".into(),
        base_color: [0.8, 0.05, 0.05, 1.0],
        ..Material::default()
    };
    // quad_scene's quad faces +Z; turned about +Y by `degrees`.
    let curtain = |degrees: f32, double_sided: bool| {
        let mut s = quad_scene(
            Material {
                double_sided,
                ..red.clone()
            },
            vec![],
        );
        s.cameras.clear();
        s.draws[0].world = Mat4::from_rotation_y(degrees.to_radians());
        s
    };
    for (degrees, expect) in [
        (0.0, 0.0),
        (180.0, 180.0),
        (90.0, 90.0),
        (-90.0, 270.0),
        (150.0, 180.0),
    ] {
        assert_eq!(
            curtain(degrees, false).framing_azimuth(),
            expect,
            "turned {degrees}"
        );
    }
    assert_eq!(curtain(180.0, true).framing_azimuth(), 0.0, "double-sided");
    assert_eq!(scene::default_scene().framing_azimuth(), 0.0);
    let eye = |s: &Scene| {
        s.camera(None)
            .unwrap()
            .view
            .inverse()
            .transform_point3(glam::Vec3::ZERO)
    };
    let behind = curtain(180.0, false);
    let e = eye(&behind);
    assert!(e.z < -1.0 && e.y > 0.0 && e.x.abs() < 1e-4, "{e}");

    // Rendered with the default lighting, the turned curtain shows as the unturned one does:
    // its red front fills the middle, lit by the key light from the same side of the camera.
    let mut renderer = Renderer::new(common::context()).unwrap();
    let studio = Arc::new(Environment::studio());
    let mut red_pixels = Vec::new();
    let mut light_sides = Vec::new();
    for degrees in [0.0, 180.0] {
        let mut s = curtain(degrees, false);
        assert!(stage(&mut s, LightsMode::Auto, 0.0, false));
        let frame = renderer.render(&s, &options(Some(studio.clone()))).unwrap();
        red_pixels.push(
            frame
                .ldr
                .chunks_exact(4)
                .filter(|p| p[0] > 60 && p[0] as u32 > 2 * p[1] as u32 + 10)
                .count(),
        );
        // The light's direction seen from the camera: the same for both.
        let camera = s.camera(None).unwrap();
        light_sides.push(camera.view.transform_vector3(s.lights[0].direction));
    }
    println!(
        "red pixels from the front {} and from behind {}",
        red_pixels[0], red_pixels[1]
    );
    assert!(red_pixels[0] > 300, "{red_pixels:?}");
    assert!(
        red_pixels[1] * 10 >= red_pixels[0] * 9 && red_pixels[1] * 10 <= red_pixels[0] * 11,
        "{red_pixels:?}"
    );
    assert!(
        (light_sides[0] - light_sides[1]).length() < 1e-4,
        "{light_sides:?}"
    );
}

/// Automatic framing fits the model, not its bounding box (issue 28 item 9): a quad tilted and
/// turned fills its box's projection only in part, and the box's corners left it small and off
/// centre (SheenCloth filled about half the frame, low and to the left). Now its vertices' projection
/// is centred and reaches the view's 5 % margin in the tighter direction, at every aspect.
#[test]
fn automatic_framing_fills_the_frame_with_the_model() {
    let tilted = |world: Mat4| {
        let mut s = quad_scene(Material::default(), vec![]);
        s.cameras.clear();
        s.draws[0].world = world;
        s
    };
    for (name, world) in [
        ("square-on", Mat4::IDENTITY),
        (
            "tilted and turned",
            Mat4::from_rotation_y(0.5) * Mat4::from_rotation_x(-1.1),
        ),
        (
            "far off the origin, rolled",
            Mat4::from_translation(glam::Vec3::new(40.0, -7.0, 3.0))
                * Mat4::from_rotation_z(0.7)
                * Mat4::from_rotation_x(0.6),
        ),
    ] {
        let s = tilted(world);
        for aspect in [1.0f32, 16.0 / 9.0, 0.5] {
            let camera = s.camera(None).unwrap().for_aspect(aspect);
            let tan_v = (camera.yfov * 0.5).tan();
            let (mut lo, mut hi) = ([f32::MAX; 2], [f32::MIN; 2]);
            for v in &s.meshes[0].vertices {
                let world_p = s.draws[0].world.transform_point3(v.position.into());
                let p = camera.view.transform_point3(world_p);
                assert!(p.z < 0.0, "{name}: a vertex behind the camera");
                let ndc = [p.x / (-p.z * tan_v * aspect), p.y / (-p.z * tan_v)];
                for k in 0..2 {
                    lo[k] = lo[k].min(ndc[k]);
                    hi[k] = hi[k].max(ndc[k]);
                }
            }
            let reach = (0..2).map(|k| hi[k].max(-lo[k])).fold(0f32, f32::max);
            let off = (0..2)
                .map(|k| (lo[k] + hi[k]).abs() * 0.5)
                .fold(0f32, f32::max);
            println!("{name}, aspect {aspect}: reaches {reach:.3} of the half view, centred within {off:.3}");
            // 1/1.05 = 0.952 is the margin's edge: measured 0.952 in every case, centred within
            // 0.001 after four centring steps (two left 0.016: perspective makes each step
            // approximate); the box's corners reached 0.952 only square-on.
            assert!(
                (0.945..=0.953).contains(&reach),
                "{name}, aspect {aspect}: the model reaches {reach} of the half view"
            );
            assert!(off < 0.005, "{name}, aspect {aspect}: off centre by {off}");
        }
    }
}

/// The irradiance (the specular cube's roughness-1 level, env_irradiance) under a map whose light
/// is a few small, bright sources, against the map's own f64 quadrature: a white Lambertian quad
/// (no specular layer) facing +z reflects irradiance/π. Sampled with 256 fixed directions, that
/// level aliased with such maps (lightroom_14b, whose 0.5 % brightest pixels hold 30 % of its
/// light, came out 8.6 % low straight up); summed over the radiance cube's 32² level it is within
/// the box mips' own error (0.13 % on lightroom_14b by a NumPy model).
#[test]
fn the_irradiance_of_small_bright_lights_is_their_quadrature() {
    let (w, h) = (512u32, 256u32);
    let mut rgb = vec![0.05f32; (w * h * 3) as usize];
    // Softboxes of 3 x 2 pixels, radiance 400, at assorted directions above and below the quad's
    // horizon (pixel columns and rows of the map).
    let boxes = [
        (37u32, 40u32),
        (101, 77),
        (200, 55),
        (260, 100),
        (333, 30),
        (420, 88),
        (470, 140),
        (150, 170),
        (300, 200),
    ];
    for (i0, j0) in boxes {
        for j in j0..j0 + 2 {
            for i in i0..i0 + 3 {
                let k = ((j * w + i) * 3) as usize;
                rgb[k..k + 3].copy_from_slice(&[400.0; 3]);
            }
        }
    }
    // Irradiance/π about world +z, pixel by pixel (each pixel's radiance × solid angle × cosine
    // at its centre), f64.
    let mut truth = 0.0f64;
    for j in 0..h {
        let theta = std::f64::consts::PI * (j as f64 + 0.5) / h as f64;
        let d_omega = (std::f64::consts::PI / h as f64)
            * (2.0 * std::f64::consts::PI / w as f64)
            * theta.sin();
        for i in 0..w {
            let d = weft::env::world_from_env(0.0, weft::env::pixel_dir(i, j, w, h));
            if d[2] > 0.0 {
                truth += rgb[((j * w + i) * 3) as usize] as f64 * d[2] * d_omega;
            }
        }
    }
    truth /= std::f64::consts::PI;
    let env = Arc::new(Environment::from_rgb("softboxes", w, h, rgb).unwrap());
    let white = Material {
        base_color: [1.0; 4],
        metallic: 0.0,
        roughness: 1.0,
        specular: weft::scene::Specular {
            factor: 0.0,
            ..Material::default().specular
        },
        ..Material::default()
    };
    let mut renderer = Renderer::new(common::context()).unwrap();
    let mut o = options(Some(env));
    o.width = 32;
    o.height = 32;
    let frame = renderer.render(&quad_scene(white, vec![]), &o).unwrap();
    // The centre 4 x 4 pixels: the quad is flat, so every pixel sees the same irradiance.
    let mut sum = 0.0f64;
    for y in 14..18 {
        for x in 14..18 {
            sum += frame.hdr[(y * 32 + x) * 4 + 1] as f64;
        }
    }
    let got = sum / 16.0;
    let rel = (got - truth).abs() / truth;
    eprintln!(
        "irradiance/pi about +z: GPU {got:.5}, quadrature {truth:.5}, relative error {rel:.4}"
    );
    // Measured on lavapipe: 0.50 % (0.23511 against 0.23629); the sampled level it replaced
    // gave 0.20825, 11.9 % low. The bound leaves the box mips' error on such a map (a light's
    // texels averaged without their solid angles) a 4x margin and fails the sampled level.
    assert!(
        rel < 0.02,
        "irradiance {got} against the quadrature's {truth} ({rel})"
    );
}
