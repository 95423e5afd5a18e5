//! The plan decides what a frame runs; the recorded frame shows what ran; and what the plan skips
//! changes nothing in the image.

mod common;

use glam::Vec3;
use weft::fabric::FabricParams;
use weft::render::{Pass, Plan, RenderOptions, Renderer};
use weft::scene::{self, Light, LightKind, Scene};

fn options() -> RenderOptions {
    RenderOptions {
        width: 96,
        height: 54,
        ..Default::default()
    }
}

fn without_fabric(mut scene: Scene) -> Scene {
    for m in &mut scene.materials {
        m.fabric = None;
    }
    scene
}

fn only_directional(mut scene: Scene) -> Scene {
    scene.lights.retain(|l| l.kind == LightKind::Directional);
    scene
}

#[test]
fn a_scene_with_no_fabric_runs_no_weave_pass() {
    let scene = without_fabric(scene::default_scene());
    let plan = Plan::new(&scene, &options());
    assert!(!plan.runs(Pass::Weave));
    assert!(plan.weaves.is_empty() && !plan.features.far_field_mixture);
    let mut renderer = Renderer::new(common::context()).unwrap();
    let frame = renderer.render(&scene, &options()).unwrap();
    assert_eq!(frame.stats.passes, vec!["gbuffer", "lighting", "tonemap"]);
    assert_eq!(
        (frame.stats.weave_textures, frame.stats.weave_dispatches),
        (0, 0)
    );
}

#[test]
fn materials_with_the_same_weave_share_one_texture() {
    let mut scene = scene::default_scene();
    let cloth = scene
        .materials
        .iter()
        .position(|m| m.fabric.is_some())
        .unwrap();
    // A second cloth that differs only in colour and exponents, and a third with another weave.
    let mut blue = scene.materials[cloth].clone();
    blue.name = "blue cloth".into();
    let f = blue.fabric.as_mut().unwrap();
    f.rd_warp = [0.05, 0.1, 0.5];
    f.rd_weft = [0.05, 0.1, 0.5];
    f.e_along = 50.0;
    let mut twill = scene.materials[cloth].clone();
    twill.name = "twill cloth".into();
    twill.fabric = Some(FabricParams {
        pattern: weft::fabric::WeavePattern::twill(),
        ..Default::default()
    });
    scene.materials.push(blue);
    scene.materials.push(twill);
    // Give the two new materials something to draw.
    for material in [scene.materials.len() - 2, scene.materials.len() - 1] {
        let mut mesh = scene.meshes[0].clone();
        mesh.material = material;
        scene.meshes.push(mesh);
        scene.draws.push(weft::scene::Draw::new(
            scene.meshes.len() - 1,
            glam::Mat4::from_translation(Vec3::X * 10.0),
        ));
    }
    let plan = Plan::new(&scene, &options());
    assert_eq!(plan.weaves.len(), 2, "{:?}", plan.weaves);
    assert_eq!(plan.weaves[0].materials.len(), 2);
    let mut renderer = Renderer::new(common::context()).unwrap();
    let frame = renderer.render(&scene, &options()).unwrap();
    assert_eq!(frame.stats.weave_textures, 2);
}

#[test]
fn only_directional_lights_compile_no_point_light_code_and_skipping_changes_nothing() {
    let scene = only_directional(scene::default_scene());
    let plan = Plan::new(&scene, &options());
    assert_eq!(plan.light_types_mask(), 1);
    let mut renderer = Renderer::new(common::context()).unwrap();
    let planned = renderer.render(&scene, &options()).unwrap();
    assert!(
        planned
            .stats
            .pipelines
            .iter()
            .any(|p| p.starts_with("lighting[") && p.contains("light_types=1,")),
        "{:?}",
        planned.stats.pipelines
    );
    let forced = renderer
        .render(
            &scene,
            &RenderOptions {
                all_features: true,
                ..options()
            },
        )
        .unwrap();
    assert!(forced
        .stats
        .pipelines
        .iter()
        .any(|p| p.starts_with("lighting[") && p.contains("light_types=7,")));
    let max_diff = planned
        .hdr
        .iter()
        .zip(&forced.hdr)
        .map(|(a, b)| (a - b).abs())
        .fold(0f32, f32::max);
    assert_eq!(
        max_diff, 0.0,
        "compiling out absent light types changed the image"
    );
    assert_eq!(planned.ldr, forced.ldr);
}

#[test]
fn lights_out_of_range_are_culled_and_change_nothing() {
    let scene = scene::default_scene();
    let mut with_far_lights = scene.clone();
    for i in 0..8 {
        with_far_lights.lights.push(Light {
            name: format!("far lamp {i}"),
            kind: LightKind::Point,
            color: [1.0; 3],
            intensity: 1000.0,
            range: Some(1.0),
            position: Vec3::new(50.0 + i as f32, 5.0, 0.0),
            direction: Vec3::NEG_Y,
            shadow: None,
        });
    }
    let mut renderer = Renderer::new(common::context()).unwrap();
    let a = renderer.render(&scene, &options()).unwrap();
    let b = renderer.render(&with_far_lights, &options()).unwrap();
    assert_eq!(
        a.hdr, b.hdr,
        "lights whose range cannot reach the scene must add nothing"
    );
}
