//! alphaMode BLEND (issue 25): the transparent pass draws blended surfaces after deferred
//! lighting, lit by the same code (glsl/include/shade.glsl) from the same surface values
//! (glsl/include/surface.glsl), blended over what is behind them, back to front. Checked here on
//! lavapipe with validation on, in linear HDR, against renders of the same scene with the blended
//! surfaces opaque: compositing is linear, so the blended image is known exactly from them.

mod common;

use std::sync::Arc;

use glam::{Mat4, Vec3};
use weft::env::{EnvLighting, Environment};
use weft::render::{Pass, Plan, RenderOptions, Renderer};
use weft::scene::{self, Draw, Light, LightKind, Material, Mesh, Scene, Vertex};

/// A square of half-size `half` in the plane z = `z`, facing +z, its vertex alpha `alpha`.
fn square(name: &str, z: f32, half: f32, material: usize, alpha: f32) -> Mesh {
    let corner = |x: f32, y: f32| Vertex {
        position: [x * half, y * half, z],
        normal: [0.0, 0.0, 1.0],
        tangent: [1.0, 0.0, 0.0, 1.0],
        uv: [x * 0.5 + 0.5, 0.5 - y * 0.5],
        uv1: [0.0; 2],
    };
    Mesh {
        name: name.into(),
        vertices: vec![
            corner(-1.0, -1.0),
            corner(1.0, -1.0),
            corner(1.0, 1.0),
            corner(-1.0, 1.0),
        ],
        indices: vec![0, 1, 2, 0, 2, 3],
        material,
        colors: vec![[1.0, 1.0, 1.0, alpha]; 4],
        topology: weft::scene::Topology::Triangles,
    }
}

/// Squares (mesh, material) seen from +z, a lamp from the front-left, its own camera.
fn scene_of(meshes: Vec<Mesh>, materials: Vec<Material>) -> Scene {
    let draws = (0..meshes.len())
        .map(|i| Draw::new(i, Mat4::IDENTITY))
        .collect();
    let mut s = Scene {
        source: "squares".into(),
        meshes,
        draws,
        materials,
        ..Default::default()
    };
    s.lights.push(Light {
        name: "lamp".into(),
        kind: LightKind::Directional,
        color: [1.0; 3],
        intensity: 3.0,
        range: None,
        position: Vec3::ZERO,
        direction: Vec3::new(0.4, -0.3, -1.0).normalize(),
        shadow: None,
    });
    s.cameras.push(
        s.look_at_camera(Vec3::new(0.3, 0.2, 3.0), Vec3::ZERO, 0.8)
            .expect("camera"),
    );
    s
}

fn options(env: Option<&Arc<Environment>>) -> RenderOptions {
    RenderOptions {
        camera: Some(0),
        width: 64,
        height: 48,
        read_hdr: true,
        environment: env.cloned().map(EnvLighting::new),
        ..Default::default()
    }
}

fn blend(m: &Material) -> Material {
    Material {
        blend: true,
        ..m.clone()
    }
}

/// The materials the pass must light as the lighting pass does: a rough dielectric, a metal,
/// a sheen layer, an anisotropic one, a woven fabric.
fn materials() -> Vec<(&'static str, Material)> {
    let dielectric = Material {
        base_color: [0.7, 0.3, 0.2, 1.0],
        metallic: 0.0,
        roughness: 0.6,
        ..Default::default()
    };
    let metal = Material {
        base_color: [0.9, 0.8, 0.5, 1.0],
        metallic: 1.0,
        roughness: 0.3,
        ..Default::default()
    };
    let sheen = Material {
        sheen: Some(scene::Sheen {
            color: [0.6, 0.6, 0.9],
            roughness: 0.5,
            color_texture: None,
            roughness_texture: None,
        }),
        ..dielectric.clone()
    };
    let fabric = Material {
        metallic: 0.0,
        fabric: Some(
            weft::fabric::presets::by_name("cotton-plain")
                .expect("preset")
                .params(8.0),
        ),
        ..Default::default()
    };
    vec![
        ("dielectric", dielectric),
        ("metal", metal),
        ("sheen", sheen),
        ("fabric", fabric),
    ]
}

/// Largest difference between two HDR images (RGB), relative to max(1, the larger value).
fn max_relative_difference(a: &[f32], b: &[f32]) -> f32 {
    a.chunks_exact(4)
        .zip(b.chunks_exact(4))
        .flat_map(|(p, q)| {
            (0..3).map(move |k| (p[k] - q[k]).abs() / p[k].abs().max(q[k].abs()).max(1.0))
        })
        .fold(0.0, f32::max)
}

#[test]
fn a_blended_surface_at_alpha_one_is_lit_as_the_same_surface_opaque() {
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let studio = Arc::new(Environment::studio());
    for env in [None, Some(&studio)] {
        for (name, m) in materials() {
            let mut render = |m: Material| {
                let s = scene_of(vec![square("square", 0.0, 1.0, 0, 1.0)], vec![m]);
                renderer_frame(&mut renderer, &s, &options(env))
            };
            let opaque = render(m.clone());
            let blended = render(blend(&m));
            assert!(!opaque.plan.runs(Pass::Transparent));
            assert!(blended.plan.runs(Pass::Transparent) && blended.stats.blend_draws == 1);
            // What the G-buffer's storage rounds and the forward pass does not: the base colour
            // in 8-bit sRGB (half a step: up to 0.2 % of a mid value, 1.4 % of a dark one at
            // 0.03), the rest in half floats (0.05 %), the position reconstructed from 32-bit
            // depth instead of interpolated. Measured on lavapipe: at most 0.95 % (the metal, whose
            // F0 is the 8-bit base colour), 0.05-0.35 % for the others; the bound is twice that,
            // and a wrong light, BRDF or environment term moves pixels by far more.
            let d = max_relative_difference(&opaque.hdr, &blended.hdr);
            assert!(
                d < 0.02,
                "{name} ({}): blended at alpha 1 differs from opaque by {d} (relative)",
                if env.is_some() { "studio" } else { "lamp" }
            );
        }
    }
}

fn renderer_frame(renderer: &mut Renderer, s: &Scene, o: &RenderOptions) -> weft::render::Frame {
    renderer.render(s, o).expect("render")
}

/// The HDR pixel at (x, y).
fn pixel(f: &weft::render::Frame, x: u32, y: u32) -> [f32; 3] {
    let i = ((y * f.width + x) * 4) as usize;
    [f.hdr[i], f.hdr[i + 1], f.hdr[i + 2]]
}

#[test]
fn blending_is_linear_over_what_is_behind_and_back_to_front_in_any_file_order() {
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let studio = Arc::new(Environment::studio());
    let back = Material {
        base_color: [0.2, 0.6, 0.3, 1.0],
        metallic: 0.0,
        roughness: 0.5,
        ..Default::default()
    };
    let middle = Material {
        base_color: [0.9, 0.2, 0.2, 1.0],
        metallic: 0.0,
        roughness: 0.4,
        ..Default::default()
    };
    let front = Material {
        base_color: [0.2, 0.3, 0.9, 1.0],
        metallic: 0.0,
        roughness: 0.7,
        ..Default::default()
    };
    let (a_mid, a_front) = (0.6f32, 0.35f32);
    for env in [None, Some(&studio)] {
        let o = options(env);
        // Each layer alone, opaque (its vertex alpha is ignored), over the same background.
        let layer = |mesh: Mesh, m: &Material, r: &mut Renderer| {
            r.render(&scene_of(vec![mesh], vec![m.clone()]), &o)
                .expect("render")
        };
        let b = layer(square("back", -1.0, 3.0, 0, 1.0), &back, &mut renderer);
        let m = layer(
            square("middle", -0.5, 1.0, 0, a_mid),
            &middle,
            &mut renderer,
        );
        let f = layer(square("front", 0.0, 0.5, 0, a_front), &front, &mut renderer);
        // The three together, the two in front blended, in both file orders.
        for reversed in [false, true] {
            let mut meshes = vec![
                square("back", -1.0, 3.0, 0, 1.0),
                square("middle", -0.5, 1.0, 1, a_mid),
                square("front", 0.0, 0.5, 2, a_front),
            ];
            if reversed {
                meshes.reverse();
            }
            let mut mats = vec![back.clone(), blend(&middle), blend(&front)];
            if reversed {
                mats.reverse();
                for (k, mesh) in meshes.iter_mut().enumerate() {
                    mesh.material = k;
                }
            }
            let s = scene_of(meshes, mats);
            let all = renderer.render(&s, &o).expect("render");
            assert_eq!(all.stats.blend_draws, 2);
            // At the centre all three layers overlap; between the front's and the middle's edges
            // two do.
            let mut checked = 0;
            for (x, y) in [(32, 24), (32, 20), (30, 26), (26, 24), (24, 30), (38, 18)] {
                let (pb, pm, pf, got) = (
                    pixel(&b, x, y),
                    pixel(&m, x, y),
                    pixel(&f, x, y),
                    pixel(&all, x, y),
                );
                // Which layers cover this pixel: where a layer alone shows the background colour
                // of the back-only render, it does not.
                let covers_mid = (0..3).any(|k| (pm[k] - pb[k]).abs() > 1e-3);
                let covers_front = (0..3).any(|k| (pf[k] - pb[k]).abs() > 1e-3);
                let mut want = pb;
                if covers_mid {
                    want = [0, 1, 2].map(|k| a_mid * pm[k] + (1.0 - a_mid) * want[k]);
                }
                if covers_front {
                    want = [0, 1, 2].map(|k| a_front * pf[k] + (1.0 - a_front) * want[k]);
                }
                checked += (covers_mid && covers_front) as usize;
                for k in 0..3 {
                    // Half-float storage of the HDR target between the passes (0.05 %) and the
                    // 8-bit base colour of the opaque reference layers: 2 %, as above.
                    let tol = 0.02 * want[k].abs().max(got[k].abs()).max(0.05);
                    assert!(
                        (got[k] - want[k]).abs() <= tol,
                        "pixel ({x}, {y}) channel {k}, reversed {reversed}, env {}: got {got:?}, want {want:?} (back {pb:?}, middle {pm:?}, front {pf:?})",
                        env.is_some()
                    );
                }
            }
            assert!(checked >= 1, "no pixel had all three layers");
        }
    }
}

#[test]
fn a_scene_without_blend_plans_and_compiles_no_transparent_pass() {
    let (_, m) = materials().remove(0);
    let s = scene_of(vec![square("square", 0.0, 1.0, 0, 0.5)], vec![m.clone()]);
    let plan = Plan::new(&s, &options(None));
    assert!(!plan.runs(Pass::Transparent) && plan.blend_draws == 0);
    assert!(!plan.to_string().contains("blend "));
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let frame = renderer.render(&s, &options(None)).expect("render");
    assert!(!frame.stats.passes.contains(&"transparent"));
    assert!(!frame
        .stats
        .pipelines
        .iter()
        .any(|p| p.starts_with("forward")));
    let s = scene_of(vec![square("square", 0.0, 1.0, 0, 0.5)], vec![blend(&m)]);
    let plan = Plan::new(&s, &options(None));
    assert_eq!(plan.blend_draws, 1);
    let names: Vec<_> = plan.passes.iter().map(|p| p.name()).collect();
    assert_eq!(names, ["gbuffer", "lighting", "transparent", "tonemap"]);
}

fn transmissive(base: [f32; 3], thickness: f32, attenuation: Option<([f32; 3], f32)>) -> Material {
    Material {
        base_color: [base[0], base[1], base[2], 1.0],
        metallic: 0.0,
        roughness: 0.3,
        transmission: Some(scene::Transmission {
            factor: 1.0,
            texture: None,
            thickness,
            thickness_texture: None,
            attenuation_color: attenuation.map_or([1.0; 3], |a| a.0),
            attenuation_distance: attenuation.map(|a| a.1),
            dispersion: 0.0,
        }),
        ..Default::default()
    }
}

/// KHR_materials_transmission and _volume end to end: a transmissive square in front of a large
/// opaque one. Everything the front square shows except the transmitted backdrop is the same
/// whatever colour the back square has, so changing that colour changes the front pixel by
/// exactly weight × the change of the backdrop: the measured weight must be proportional to the
/// base colour (the tint), and a volume's must be the thin wall's times the twin's Beer–Lambert
/// attenuation over the thickness (`weft::reference::shading::volume_attenuation`).
#[test]
fn transmission_shows_the_backdrop_tinted_and_attenuated_as_the_twin_says() {
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let backs = [[0.2f32, 0.5, 0.8], [0.9, 0.3, 0.1]];
    let back = |c: [f32; 3]| Material {
        base_color: [c[0], c[1], c[2], 1.0],
        metallic: 0.0,
        roughness: 0.8,
        ..Default::default()
    };
    // The weight of the backdrop in the front square's centre pixel, per channel.
    let mut weight = |front: Option<Material>| -> [f32; 3] {
        let px: Vec<[f32; 3]> = backs
            .iter()
            .map(|&c| {
                let mut meshes = vec![square("back", -1.0, 4.0, 0, 1.0)];
                let mut mats = vec![back(c)];
                if let Some(f) = &front {
                    meshes.push(square("front", 0.0, 0.6, 1, 1.0));
                    mats.push(f.clone());
                }
                let frame = renderer
                    .render(&scene_of(meshes, mats), &options(None))
                    .expect("render");
                if front.is_some() {
                    assert!(
                        frame.plan.runs(Pass::Transparent) && frame.plan.transmission_draws == 1
                    );
                    assert!(frame
                        .stats
                        .pipelines
                        .iter()
                        .any(|p| p.starts_with("forward[") && p.contains(", transmission=1")));
                }
                pixel(&frame, 32, 24)
            })
            .collect();
        [0, 1, 2].map(|k| px[0][k] - px[1][k])
    };
    let behind = weight(None);
    let ratio = |front: Material, w: &mut dyn FnMut(Option<Material>) -> [f32; 3]| {
        let d = w(Some(front));
        [0, 1, 2].map(|k| d[k] / behind[k])
    };
    let (b1, b2) = ([0.8f32, 0.6, 0.3], [0.3f32, 0.7, 0.9]);
    let w1 = ratio(transmissive(b1, 0.0, None), &mut weight);
    let w2 = ratio(transmissive(b2, 0.0, None), &mut weight);
    // A thin wall shows the backdrop tinted by its base colour times what the specular
    // reflection leaves (1 − F0·A − B: the same for both, the same roughness and angle).
    let leaves: Vec<f32> = (0..3).map(|k| w1[k] / b1[k]).collect();
    for k in 0..3 {
        assert!(
            leaves[k] > 0.8 && leaves[k] < 1.0,
            "channel {k}: the thin wall passes {} of its tint (weights {w1:?})",
            leaves[k]
        );
        // Half-float backdrop and HDR target: 0.1 % each; 1 % bound.
        assert!(
            (w2[k] / b2[k] - leaves[k]).abs() < 0.01 * leaves[k],
            "channel {k}: tint {b2:?} passes {w2:?}, tint {b1:?} passes {w1:?}"
        );
    }
    // A volume 0.3 thick with attenuation colour c at distance 0.2: c^(0.3/0.2) more.
    let (c, distance, thickness) = ([0.5f32, 0.8, 1.0], 0.2f32, 0.3f32);
    let wv = ratio(
        transmissive(b1, thickness, Some((c, distance))),
        &mut weight,
    );
    let att = weft::reference::shading::volume_attenuation(thickness, c, distance);
    println!(
        "thin wall {w1:?} (tint {b1:?}), {w2:?} (tint {b2:?}); volume {wv:?}, attenuation {att:?}"
    );
    for k in 0..3 {
        let want = w1[k] * att[k];
        assert!(
            (wv[k] - want).abs() < 0.01 * w1[k],
            "channel {k}: the volume passes {}, the thin wall {} × attenuation {} = {want}",
            wv[k],
            w1[k],
            att[k]
        );
    }
}

#[test]
fn a_transmissive_surface_with_transmission_zero_is_lit_as_the_same_surface_opaque() {
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let studio = Arc::new(Environment::studio());
    for env in [None, Some(&studio)] {
        let opaque = Material {
            base_color: [0.7, 0.3, 0.2, 1.0],
            metallic: 0.0,
            roughness: 0.6,
            ..Default::default()
        };
        let mut none = transmissive([0.7, 0.3, 0.2], 0.0, None);
        none.roughness = 0.6;
        none.transmission.as_mut().unwrap().factor = 0.0;
        let render = |m: Material, r: &mut Renderer| {
            r.render(
                &scene_of(vec![square("square", 0.0, 1.0, 0, 1.0)], vec![m]),
                &options(env),
            )
            .expect("render")
        };
        let a = render(opaque, &mut renderer);
        let b = render(none, &mut renderer);
        assert!(b.plan.runs(Pass::Transparent) && b.plan.transmission_draws == 1);
        // As for BLEND at alpha 1: the G-buffer's 8-bit base colour, 2 % bound.
        let d = max_relative_difference(&a.hdr, &b.hdr);
        assert!(d < 0.02, "transmission 0 differs from opaque by {d}");
    }
}

/// The transparent pass's opaque draws (transmissive, not BLEND) write depth: the nearer of two
/// hides the farther whatever their order, as in the G-buffer.
#[test]
fn transmissive_draws_hide_each_other_by_depth_in_any_order() {
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let colour = |c: [f32; 3], transmits: bool| {
        let mut m = transmissive(c, 0.0, None);
        if !transmits {
            m.transmission = None;
        }
        m.transmission.iter_mut().for_each(|t| t.factor = 0.0);
        m
    };
    let render = |transmits: bool, reversed: bool, r: &mut Renderer| {
        let mut meshes = vec![
            square("near", 0.0, 0.5, 0, 1.0),
            square("far", -0.5, 1.0, 1, 1.0),
        ];
        let mut mats = vec![
            colour([0.9, 0.1, 0.1], transmits),
            colour([0.1, 0.9, 0.1], transmits),
        ];
        if reversed {
            meshes.reverse();
            mats.reverse();
            for (k, m) in meshes.iter_mut().enumerate() {
                m.material = k;
            }
        }
        r.render(&scene_of(meshes, mats), &options(None))
            .expect("render")
    };
    let reference = render(false, false, &mut renderer);
    for reversed in [false, true] {
        let f = render(true, reversed, &mut renderer);
        assert_eq!(f.plan.forward_opaque_draws, 2);
        let d = max_relative_difference(&reference.hdr, &f.hdr);
        assert!(
            d < 0.02,
            "reversed {reversed}: differs from the G-buffer's order by {d}"
        );
    }
}

/// KHR_materials_clearcoat goes through the transparent pass: a coat of factor 0 renders as the
/// same material through the G-buffer; a full coat adds its highlight and dims the layers below
/// (at this view, by less than it adds under the studio's bright soft boxes).
#[test]
fn a_clearcoat_of_factor_zero_is_the_material_alone_and_a_full_one_changes_it() {
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let studio = Arc::new(Environment::studio());
    let plain = Material {
        base_color: [0.1, 0.2, 0.6, 1.0],
        metallic: 0.0,
        roughness: 0.7,
        ..Default::default()
    };
    let coated = |factor: f32| Material {
        clearcoat: Some(scene::Clearcoat {
            factor,
            texture: None,
            roughness: 0.05,
            roughness_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
        }),
        ..plain.clone()
    };
    for env in [None, Some(&studio)] {
        let render = |m: Material, r: &mut Renderer| {
            r.render(
                &scene_of(vec![square("square", 0.0, 1.0, 0, 1.0)], vec![m]),
                &options(env),
            )
            .expect("render")
        };
        let a = render(plain.clone(), &mut renderer);
        let zero = render(coated(0.0), &mut renderer);
        assert!(zero.plan.runs(Pass::Transparent) && zero.plan.coat_draws == 1);
        assert!(zero.stats.pipelines.iter().any(|p| p.contains("coat=1")));
        let d = max_relative_difference(&a.hdr, &zero.hdr);
        assert!(d < 0.02, "a coat of factor 0 differs from none by {d}");
        let full = render(coated(1.0), &mut renderer);
        let d = max_relative_difference(&a.hdr, &full.hdr);
        assert!(d > 0.05, "a full coat changes the image by only {d}");
    }
}

/// KHR_materials_diffuse_transmission end to end: a sheet lit only from behind by a lamp. The
/// lamp reaches the viewer's side only through the diffuse BTDF, so the change of the pixel with
/// the lamp's intensity is exactly ΔI × diffuse transmission × the twin's `diffuse_btdf_cos`
/// (`weft::reference::shading`); without diffuse transmission it does not change at all.
#[test]
fn a_sheet_lit_from_behind_shows_the_lamp_through_its_diffuse_transmission() {
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let (factor, colour) = (0.7f32, [0.9f32, 0.5, 0.2]);
    let sheet = |transmits: bool| Material {
        base_color: [0.0, 0.0, 0.0, 1.0],
        metallic: 0.0,
        roughness: 0.5,
        diffuse_transmission: transmits.then_some(scene::DiffuseTransmission {
            factor,
            texture: None,
            color: colour,
            color_texture: None,
        }),
        ..Default::default()
    };
    let behind = Vec3::new(0.2, -0.3, 1.0).normalize();
    let centre = |transmits: bool, intensity: f32, r: &mut Renderer| {
        let mut s = scene_of(
            vec![square("sheet", 0.0, 1.0, 0, 1.0)],
            vec![sheet(transmits)],
        );
        s.lights[0].direction = behind;
        s.lights[0].intensity = intensity;
        let f = r.render(&s, &options(None)).expect("render");
        if transmits {
            assert!(f.plan.diffuse_transmission_draws == 1 && f.plan.runs(Pass::Transparent));
            assert!(f
                .stats
                .pipelines
                .iter()
                .any(|p| p.contains("diffuse_transmission=1")));
        }
        pixel(&f, 32, 24)
    };
    let (i1, i2) = (4.0f32, 1.0f32);
    let opaque = [
        centre(false, i1, &mut renderer),
        centre(false, i2, &mut renderer),
    ];
    for k in 0..3 {
        assert!(
            (opaque[0][k] - opaque[1][k]).abs() < 1e-4,
            "an opaque sheet shows the lamp behind it: {opaque:?}"
        );
    }
    let (a, b) = (
        centre(true, i1, &mut renderer),
        centre(true, i2, &mut renderer),
    );
    let eye = Vec3::new(0.3, 0.2, 3.0);
    let v = eye.normalize(); // the centre pixel sees the origin
    let s = weft::reference::shading::GltfSurface {
        specular: 1.0,
        f0: [0.04; 3],
        ..weft::reference::shading::GltfSurface::core([0.0; 3], 0.0, 0.5)
    };
    let btdf = weft::reference::shading::diffuse_btdf_cos(
        [0.0, 0.0, 1.0],
        v.to_array(),
        (-behind).to_array(),
        &s,
        colour,
    );
    for k in 0..3 {
        let want = (i1 - i2) * factor * btdf[k];
        let got = a[k] - b[k];
        println!("channel {k}: the lamp behind adds {got}, the twin says {want}");
        // The HDR target in half floats (0.1 %) and the pixel's view direction a little off the
        // origin's (the pixel centre, 0.3 % of n·v here): 1 %.
        assert!(
            (got - want).abs() <= 0.01 * want.abs() + 1e-4,
            "channel {k}: the lamp behind adds {got}, the twin says {want}"
        );
    }
}

/// KHR_materials_transmission under a lamp, end to end: a glass square lit only by a lamp behind
/// it, nearly in line with the eye. The lamp reaches the eye only through the transmitted specular
/// lobe, so the change of the pixel with the lamp's intensity is exactly ΔI × transmission × the
/// twin's `specular_btdf_cos`; an opaque square shows nothing of it.
#[test]
fn a_lamp_behind_glass_shows_through_its_specular_transmission() {
    const ROUGHNESS: f32 = 0.3;
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let colour = [0.9f32, 0.6, 0.3];
    let eye = Vec3::new(0.3, 0.2, 3.0);
    let v = eye.normalize(); // the centre pixel sees the origin exactly
                             // The light travels away from the lamp: from behind the glass towards the eye, 0.3 rad off
                             // the line of sight, inside the lobe of roughness 0.3.
    let travels = (v + Vec3::new(0.25, -0.15, 0.0)).normalize();
    let centre = |glass: bool, intensity: f32, r: &mut Renderer| {
        let mut m = transmissive(colour, 0.0, None);
        m.roughness = ROUGHNESS;
        if !glass {
            m.transmission = None;
        }
        let mut s = scene_of(vec![square("glass", 0.0, 1.0, 0, 1.0)], vec![m]);
        s.lights[0].direction = travels;
        s.lights[0].intensity = intensity;
        // An odd size: the centre pixel's centre is the image's, on the line to the origin.
        let o = RenderOptions {
            width: 65,
            height: 49,
            ..options(None)
        };
        let f = r.render(&s, &o).expect("render");
        assert_eq!(f.plan.runs(Pass::Transparent), glass);
        pixel(&f, 32, 24)
    };
    let (i1, i2) = (4.0f32, 1.0f32);
    let opaque = [
        centre(false, i1, &mut renderer),
        centre(false, i2, &mut renderer),
    ];
    for k in 0..3 {
        assert!(
            (opaque[0][k] - opaque[1][k]).abs() < 1e-4,
            "an opaque square shows the lamp behind it: {opaque:?}"
        );
    }
    let (a, b) = (
        centre(true, i1, &mut renderer),
        centre(true, i2, &mut renderer),
    );
    let s = weft::reference::shading::GltfSurface {
        specular: 1.0,
        f0: [0.04; 3],
        ..weft::reference::shading::GltfSurface::core(colour, 0.0, ROUGHNESS)
    };
    let btdf = weft::reference::shading::specular_btdf_cos(
        [0.0, 0.0, 1.0],
        v.to_array(),
        (-travels).to_array(),
        &s,
        1.5,
    );
    for k in 0..3 {
        let want = (i1 - i2) * btdf[k];
        let got = a[k] - b[k];
        println!("channel {k}: the lamp behind adds {got}, the twin says {want}");
        assert!(want > 0.05, "the test's lamp is outside the lobe ({want})");
        // The HDR target in half floats (0.1 %) and the rasterised position and view direction
        // (a few ulp, through the lobe's slope): 0.5 %.
        assert!(
            (got - want).abs() <= 0.005 * want.abs() + 1e-4,
            "channel {k}: the lamp behind adds {got}, the twin says {want}"
        );
    }
}

/// The transmitted lobe's energy: under a white dome of light behind a clear surface (base 1,
/// specular 0, so 1 − F = 1), `specular_btdf_cos` over the lower hemisphere gives what the GGX
/// lobe at the transmitted alpha reflects of a white furnace, Ess(n·v). The truth is this test's
/// own f64 GGX (D and the height-correlated Smith G2 of Heitz 2014, written from the paper, not
/// the twin's `smith_v`), by quadrature over the upper hemisphere; the twin's by the same
/// quadrature over the lower one. Both on a (cos θ, φ) grid fine enough for alpha ≥ 0.09.
#[test]
fn the_transmitted_lobe_carries_the_reflected_lobes_energy() {
    use std::f64::consts::PI;
    let (nt, np) = (1200usize, 600usize);
    for (roughness, ior) in [(0.3f32, 1.5f32), (0.6, 1.5), (1.0, 1.5), (0.8, 1.25)] {
        let alpha = weft::reference::shading::transmission_alpha(roughness, ior) as f64;
        let a2 = alpha * alpha;
        let lambda = |mu: f64| {
            let t2 = (1.0 - mu * mu).max(0.0) / (mu * mu);
            0.5 * ((1.0 + a2 * t2).sqrt() - 1.0)
        };
        for nv in [0.2f64, 0.6, 0.95] {
            let v = [(1.0 - nv * nv).sqrt(), 0.0, nv];
            let s = weft::reference::shading::GltfSurface {
                specular: 0.0,
                ..weft::reference::shading::GltfSurface::core([1.0; 3], 0.0, roughness)
            };
            let (mut truth, mut twin) = (0.0f64, 0.0f64);
            for i in 0..nt {
                let mu = (i as f64 + 0.5) / nt as f64;
                let st = (1.0 - mu * mu).sqrt();
                for j in 0..np {
                    let phi = (j as f64 + 0.5) / np as f64 * 2.0 * PI;
                    let d_omega = (1.0 / nt as f64) * (2.0 * PI / np as f64);
                    let l = [st * phi.cos(), st * phi.sin(), mu];
                    let h = [l[0] + v[0], l[1] + v[1], l[2] + v[2]];
                    let hl = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
                    let nh = h[2] / hl;
                    let dd = nh * nh * (a2 - 1.0) + 1.0;
                    let d = a2 / (PI * dd * dd);
                    let g2 = 1.0 / (1.0 + lambda(nv) + lambda(mu));
                    truth += d * g2 / (4.0 * nv) * d_omega;
                    let lb = [l[0] as f32, l[1] as f32, -l[2] as f32];
                    let v32 = v.map(|x| x as f32);
                    let f = weft::reference::shading::specular_btdf_cos(
                        [0.0, 0.0, 1.0],
                        v32,
                        lb,
                        &s,
                        ior,
                    );
                    twin += f[0] as f64 * d_omega;
                }
            }
            println!("roughness {roughness} ior {ior} (alpha {alpha:.4}) n·v {nv}: the lobe through {twin:.5}, Ess {truth:.5}");
            assert!(
                (twin - truth).abs() <= 0.005 * truth,
                "roughness {roughness} ior {ior} n·v {nv}: the transmitted lobe carries {twin}, the reflected lobe's albedo is {truth}"
            );
        }
    }
}

/// The woven model under both alpha modes (lace and gauze): a fabric square whose alpha (here the
/// vertex colour's) is below a MASK cutoff is cut out, showing exactly what is behind; above it,
/// it is the same fabric as opaque; under BLEND it composites linearly over what is behind, as
/// the glTF materials do.
#[test]
fn the_woven_model_is_cut_out_by_mask_and_blended_by_blend() {
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let back = Material {
        base_color: [0.2, 0.6, 0.3, 1.0],
        metallic: 0.0,
        roughness: 0.5,
        ..Default::default()
    };
    let cloth = |alpha_cutoff: Option<f32>, blend: bool| Material {
        metallic: 0.0,
        alpha_cutoff,
        blend,
        fabric: Some(
            weft::fabric::presets::by_name("cotton-plain")
                .expect("preset")
                .params(8.0),
        ),
        ..Default::default()
    };
    let mut render = |front: Option<(Material, f32)>| {
        let mut meshes = vec![square("back", -1.0, 4.0, 0, 1.0)];
        let mut mats = vec![back.clone()];
        if let Some((m, alpha)) = front {
            meshes.push(square("cloth", 0.0, 0.6, 1, alpha));
            mats.push(m);
        }
        renderer
            .render(&scene_of(meshes, mats), &options(None))
            .expect("render")
    };
    let behind = render(None);
    let opaque = render(Some((cloth(None, false), 1.0)));
    let lace_cut = render(Some((cloth(Some(0.5), false), 0.3)));
    let lace_kept = render(Some((cloth(Some(0.5), false), 0.8)));
    let gauze = render(Some((cloth(None, true), 0.4)));
    assert!(gauze.plan.runs(Pass::Transparent) && gauze.plan.fabric_materials == 1);
    let (x, y) = (32, 24);
    let (b, o) = (pixel(&behind, x, y), pixel(&opaque, x, y));
    assert!(
        (0..3).any(|k| (b[k] - o[k]).abs() > 0.02),
        "the cloth must differ from what is behind"
    );
    for k in 0..3 {
        let near = |got: f32, want: f32| (got - want).abs() <= 0.02 * want.abs().max(0.05);
        let cut = pixel(&lace_cut, x, y)[k];
        assert!(
            near(cut, b[k]),
            "channel {k}: cut lace {cut} instead of what is behind, {}",
            b[k]
        );
        let kept = pixel(&lace_kept, x, y)[k];
        assert!(
            near(kept, o[k]),
            "channel {k}: kept lace {kept} instead of the cloth, {}",
            o[k]
        );
        let g = pixel(&gauze, x, y)[k];
        let want = 0.4 * o[k] + 0.6 * b[k];
        assert!(
            near(g, want),
            "channel {k}: gauze {g}, the linear blend {want}"
        );
    }
}

/// The opaque forward draws' face order (front faces first, so depth rejects the back faces
/// they hide) changes the cost, not the picture: the default scene with its steel ball made of
/// double-sided glass renders the same with the back faces forced first.
#[test]
fn the_front_faces_first_order_changes_nothing_in_the_image() {
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let glass = weft::bench::plan_bench::default_with_glass_ball();
    let balls = glass
        .materials
        .iter()
        .filter(|m| m.transmission.is_some())
        .count();
    assert_eq!(balls, 1, "the default scene has one steel ball");
    let o = RenderOptions {
        width: 96,
        height: 54,
        read_hdr: true,
        ..Default::default()
    };
    let front_first = renderer.render(&glass, &o).expect("render");
    let back_first = renderer
        .render(
            &glass,
            &RenderOptions {
                force: weft::render::Force {
                    back_faces_first: true,
                    ..weft::render::Force::NONE
                },
                ..o.clone()
            },
        )
        .expect("render");
    assert!(front_first.plan.forward_opaque_draws == 1);
    assert_eq!(
        front_first.hdr, back_first.hdr,
        "the face order changed the image"
    );
}

/// KHR_materials_iridescence end to end: the thin film goes through the transparent pass, and a
/// lamp's share of the centre pixel (the change of the pixel with the lamp's intensity, so the
/// ambient cancels) is ΔI × the twin's `gltf_brdf_cos` with the film (its Fresnel at v·h), over a
/// dielectric and over a metal; a film of factor 0 is the material alone, through the G-buffer.
#[test]
fn a_thin_film_colours_the_lamps_highlight_as_the_twin_says() {
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let film = |base: Material, factor: f32| Material {
        iridescence: Some(scene::Iridescence {
            factor,
            texture: None,
            ior: 1.8,
            thickness_min: 100.0,
            thickness_max: 350.0,
            thickness_texture: None,
        }),
        ..base
    };
    let dielectric = Material {
        base_color: [0.3, 0.3, 0.3, 1.0],
        metallic: 0.0,
        roughness: 0.35,
        ..Default::default()
    };
    let metal = Material {
        base_color: [0.9, 0.6, 0.3, 1.0],
        metallic: 1.0,
        ..dielectric.clone()
    };
    let render = |m: Material, intensity: f32, r: &mut Renderer| {
        let mut s = scene_of(vec![square("square", 0.0, 1.0, 0, 1.0)], vec![m]);
        s.lights[0].intensity = intensity;
        r.render(&s, &options(None)).expect("render")
    };
    for base in [dielectric, metal] {
        let plain = render(base.clone(), 3.0, &mut renderer);
        let zero = render(film(base.clone(), 0.0), 3.0, &mut renderer);
        assert!(zero.plan.runs(Pass::Transparent) && zero.plan.iridescence_draws == 1);
        assert!(zero
            .stats
            .pipelines
            .iter()
            .any(|p| p.contains("iridescence=1")));
        let d = max_relative_difference(&plain.hdr, &zero.hdr);
        assert!(d < 0.02, "a film of factor 0 differs from none by {d}");

        let (i1, i2) = (4.0f32, 1.0f32);
        let a = render(film(base.clone(), 1.0), i1, &mut renderer);
        let b = render(film(base.clone(), 1.0), i2, &mut renderer);
        let (pa, pb) = (pixel(&a, 32, 24), pixel(&b, 32, 24));
        // The point the pixel's centre sees (the film's colour turns fast with the view): the
        // camera's ray through (32.5, 24.5) of 64 x 48 (yfov 0.8, rows downwards) onto z = 0.
        let eye = Vec3::new(0.3, 0.2, 3.0);
        let f = (-eye).normalize();
        let right = f.cross(Vec3::Y).normalize();
        let up = right.cross(f);
        let t = (0.4f32).tan();
        let (x, y) = (32.5 / 64.0 * 2.0 - 1.0, 24.5 / 48.0 * 2.0 - 1.0);
        let ray = f + right * (x * t * 64.0 / 48.0) - up * (y * t);
        let p = eye - ray * (eye.z / ray.z);
        let v = (eye - p).normalize();
        let l = -Vec3::new(0.4, -0.3, -1.0).normalize();
        let s = weft::reference::shading::GltfSurface {
            iridescence: 1.0,
            film_ior: 1.8,
            film_thickness: 350.0,
            ..weft::reference::shading::GltfSurface::core(
                [base.base_color[0], base.base_color[1], base.base_color[2]],
                base.metallic,
                base.roughness,
            )
        };
        let ess = weft::reference::shading::ggx_albedo_lookup(v.z, base.roughness);
        let f = weft::reference::shading::gltf_brdf_cos(
            [0.0, 0.0, 1.0],
            v.to_array(),
            l.to_array(),
            &s,
            [0.0, 0.0],
            ess,
        );
        let no_film = weft::reference::shading::gltf_brdf_cos(
            [0.0, 0.0, 1.0],
            v.to_array(),
            l.to_array(),
            &weft::reference::shading::GltfSurface {
                iridescence: 0.0,
                ..s
            },
            [0.0, 0.0],
            ess,
        );
        for k in 0..3 {
            let want = (i1 - i2) * f[k];
            let got = pa[k] - pb[k];
            println!(
                "metallic {}: channel {k}: the lamp adds {got}, the twin says {want} (without the film {})",
                base.metallic,
                (i1 - i2) * no_film[k]
            );
            // The HDR target's half floats (0.1 % of each of the two pixels; measured here
            // 0.001-0.06 %): 0.3 %. The film moves the channels by 9-44 %.
            assert!(
                (got - want).abs() <= 0.003 * want.abs() + 1e-4,
                "metallic {}: channel {k}: the lamp adds {got}, the twin says {want}",
                base.metallic
            );
        }
    }
}

/// KHR_materials_dispersion: a clear volume before a white stripe on black. Without dispersion
/// the three colours see the stripe through one refracted ray, so every pixel is grey (R = B);
/// dispersed, the red and blue rays refract by different indices and land at different points of
/// the backdrop, so the stripe's edges seen through the glass get colour fringes (R ≠ B).
#[test]
fn dispersion_splits_the_colours_of_what_is_seen_through_a_volume() {
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let unlit = |c: f32| Material {
        base_color: [c, c, c, 1.0],
        unlit: true,
        ..Default::default()
    };
    let glass = |dispersion: f32| {
        let mut m = transmissive([1.0; 3], 0.8, None);
        m.roughness = 0.0;
        if let Some(t) = m.transmission.as_mut() {
            t.dispersion = dispersion;
        }
        m
    };
    let mut fringe = |dispersion: f32| -> f32 {
        let meshes = vec![
            square("black", -1.0, 4.0, 0, 1.0),
            // A stripe: a narrow square (its own x scale) just in front of the black.
            {
                let mut m = square("stripe", -0.99, 1.0, 1, 1.0);
                for v in &mut m.vertices {
                    v.position[0] *= 0.15;
                }
                m
            },
            square("glass", 0.0, 0.8, 2, 1.0),
        ];
        let f = renderer
            .render(
                &scene_of(meshes, vec![unlit(0.0), unlit(1.0), glass(dispersion)]),
                &options(None),
            )
            .expect("render");
        assert_eq!(f.plan.dispersion_draws, (dispersion > 0.0) as usize);
        if dispersion > 0.0 {
            assert!(f.stats.pipelines.iter().any(|p| p.contains("dispersion=1")));
        }
        // The largest red-blue difference across the rows through the glass.
        let mut worst = 0f32;
        for y in 14..34 {
            for x in 14..50 {
                let p = pixel(&f, x, y);
                worst = worst.max((p[0] - p[2]).abs());
            }
        }
        worst
    };
    let plain = fringe(0.0);
    let dispersed = fringe(20.0);
    println!("largest |R - B| through the glass: {plain} without dispersion, {dispersed} with 20");
    // Half floats: 1e-3 of the white; a fringe is a good part of it.
    assert!(plain < 2e-3, "no dispersion, yet |R - B| reaches {plain}");
    assert!(
        dispersed > 0.05,
        "dispersion 20 leaves |R - B| at {dispersed}"
    );
}

/// Over a transparent background (`--background none`), a blended surface with nothing behind it
/// keeps its alpha in the image: straight alpha (the PNG's) equal to the surface's, and the colour
/// of the same surface at alpha 1, where it used to be 0 or 1 by a threshold at 0.5 (Khronos'
/// ClearCoatTest's alpha-blended column lost its ramps). Outside the square: alpha 0.
#[test]
fn a_blended_surface_over_a_transparent_background_keeps_its_alpha() {
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let studio = Arc::new(Environment::studio());
    let dielectric = materials()[0].1.clone();
    let mut render = |alpha: f32| {
        let s = scene_of(
            vec![square("square", 0.0, 1.0, 0, alpha)],
            vec![blend(&dielectric)],
        );
        let mut o = options(Some(&studio));
        if let Some(e) = o.environment.as_mut() {
            e.background = weft::env::Background::None;
        }
        renderer_frame(&mut renderer, &s, &o)
    };
    let solid = render(1.0);
    for alpha in [0.25f32, 0.5, 0.8] {
        let pane = render(alpha);
        let (w, h) = (pane.width, pane.height);
        let at = |f: &weft::render::Frame, x: u32, y: u32| {
            let i = ((y * w + x) * 4) as usize;
            [f.ldr[i], f.ldr[i + 1], f.ldr[i + 2], f.ldr[i + 3]]
        };
        assert_eq!(at(&pane, 0, 0)[3], 0, "a corner outside the square");
        let (mut worst_alpha, mut worst_colour) = (0u8, 0u8);
        for y in h / 2 - 4..h / 2 + 4 {
            for x in w / 2 - 4..w / 2 + 4 {
                let (p, s) = (at(&pane, x, y), at(&solid, x, y));
                assert_eq!(s[3], 255);
                worst_alpha = worst_alpha.max(p[3].abs_diff((alpha * 255.0).round() as u8));
                for c in 0..3 {
                    worst_colour = worst_colour.max(p[c].abs_diff(s[c]));
                }
            }
        }
        eprintln!("alpha {alpha}: image alpha within {worst_alpha}/255, colour within {worst_colour}/255 of the pane at alpha 1");
        // Measured: alpha exact to 1/255 (8-bit rounding), colour within 1-2/255 (the half-float
        // HDR target's rounding divided by alpha); a premultiplied colour would be 25-75 % dark.
        assert!(worst_alpha <= 1, "alpha {alpha}: {worst_alpha}");
        assert!(
            worst_colour <= 3,
            "alpha {alpha}: colour off by {worst_colour}/255"
        );
    }
}
