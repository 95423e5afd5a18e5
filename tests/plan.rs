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
    // The default precision reads the summed-area tables: the weave pass dispatches nothing.
    // The mip chains are built by the first frame that reads them (RGBA16F here): two weaves,
    // one dispatch per level each.
    assert_eq!(frame.stats.weave_dispatches, 0);
    let chains = renderer
        .render(
            &scene,
            &RenderOptions {
                weave_precision: weft::render::WeavePrecision::Rgba16f,
                ..options()
            },
        )
        .unwrap();
    assert_eq!(chains.stats.weave_textures, 2);
    assert!(
        chains.stats.weave_dispatches >= 2 * 7,
        "{}",
        chains.stats.weave_dispatches
    );
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
                force: weft::render::Force {
                    light_types: true,
                    ..Default::default()
                },
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

fn shadows_scene() -> Scene {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes/shadows.glb");
    scene::load(std::path::Path::new(path)).expect("shadows.glb")
}

/// Largest absolute difference of two frames' linear radiance.
fn max_hdr_diff(a: &weft::render::Frame, b: &weft::render::Frame) -> f32 {
    a.hdr
        .iter()
        .zip(&b.hdr)
        .map(|(x, y)| (x - y).abs())
        .fold(0f32, f32::max)
}

fn lighting_pipeline(frame: &weft::render::Frame) -> String {
    frame
        .stats
        .pipelines
        .iter()
        .find(|p| p.starts_with("lighting["))
        .cloned()
        .unwrap_or_default()
}

#[test]
fn a_light_without_shadows_creates_no_shadow_map() {
    // The default scene's lights do not ask for shadows.
    let scene = scene::default_scene();
    assert!(scene.lights.iter().all(|l| l.shadow.is_none()));
    let plan = Plan::new(&scene, &options());
    assert!(plan.shadows.is_empty() && !plan.runs(Pass::Shadow) && !plan.shadow_sampling);
    let mut renderer = Renderer::new(common::context()).unwrap();
    let frame = renderer.render(&scene, &options()).unwrap();
    assert!(!frame.stats.passes.contains(&"shadow"));
    assert_eq!((frame.stats.shadow_maps, frame.stats.shadow_draws), (0, 0));
    assert!(lighting_pipeline(&frame).contains("shadows=0"));

    // In the shadow scene only the sun and the spot ask; the point light gets no map.
    let scene = shadows_scene();
    let plan = Plan::new(&scene, &options());
    let names: Vec<&str> = plan.shadows.iter().map(|s| s.name.as_str()).collect();
    let asking: Vec<&str> = scene
        .lights
        .iter()
        .filter(|l| l.shadow.is_some())
        .map(|l| l.name.as_str())
        .collect();
    assert_eq!(names, asking);
    assert!(scene
        .lights
        .iter()
        .any(|l| l.kind == LightKind::Point && l.shadow.is_none()));
    let frame = renderer.render(&scene, &options()).unwrap();
    assert_eq!(
        frame.stats.passes,
        vec!["weave", "gbuffer", "shadow", "lighting", "tonemap"]
    );
    assert_eq!(frame.stats.shadow_maps, 2);
    // Every draw but the one that asks not to cast, into each map.
    let casters = scene.draws.iter().filter(|d| d.cast_shadows).count();
    assert!(casters < scene.draws.len());
    assert_eq!(frame.stats.shadow_draws, 2 * casters);
}

#[test]
fn shadows_only_darken_and_the_non_caster_casts_nothing() {
    let scene = shadows_scene();
    let mut unshadowed = scene.clone();
    for l in &mut unshadowed.lights {
        l.shadow = None;
    }
    let mut renderer = Renderer::new(common::context()).unwrap();
    let lit = renderer.render(&unshadowed, &options()).unwrap();
    let shadowed = renderer.render(&scene, &options()).unwrap();
    let pixels = lit.hdr.len() / 4;
    let mut darker = 0;
    for i in 0..pixels {
        for c in 0..3 {
            let (a, b) = (lit.hdr[4 * i + c], shadowed.hdr[4 * i + c]);
            assert!(
                b <= a * (1.0 + 1e-6) + 1e-9,
                "pixel {i}: shadowed {b} > lit {a}"
            );
        }
        if shadowed.hdr[4 * i] < 0.8 * lit.hdr[4 * i] {
            darker += 1;
        }
    }
    // The sun's and the spot's shadows of the ball and the box cover a good part of the cloth.
    assert!(
        darker * 20 > pixels,
        "{darker} of {pixels} pixels in shadow"
    );

    // Without the non-casting steel ball the image is the same: it casts nothing.
    let steel = scene
        .draws
        .iter()
        .position(|d| !d.cast_shadows)
        .expect("a non-casting draw");
    let mut without = scene.clone();
    let mut moved = scene.clone();
    without.draws.remove(steel);
    // (Removing it also removes its own pixels; compare only where neither frame sees it: the
    // pixels where the image with it equals the one without it must be all but the ball's.)
    moved.draws[steel].cast_shadows = true;
    let a = renderer.render(&without, &options()).unwrap();
    let b = renderer.render(&scene, &options()).unwrap();
    let c = renderer.render(&moved, &options()).unwrap();
    let differ = |x: &weft::render::Frame, y: &weft::render::Frame| {
        (0..pixels)
            .filter(|&i| (0..3).any(|k| x.hdr[4 * i + k] != y.hdr[4 * i + k]))
            .count()
    };
    // Casting, the steel ball darkens cloth pixels beyond its own silhouette.
    assert!(
        differ(&a, &c) > differ(&a, &b),
        "{} vs {}",
        differ(&a, &c),
        differ(&a, &b)
    );
}

#[test]
fn nothing_receiving_runs_no_shadow_pass_and_forcing_it_changes_nothing() {
    let mut scene = shadows_scene();
    for d in &mut scene.draws {
        d.receive_shadows = false;
    }
    let plan = Plan::new(&scene, &options());
    assert!(plan.shadows.is_empty() && !plan.runs(Pass::Shadow) && !plan.shadow_sampling);
    let mut renderer = Renderer::new(common::context()).unwrap();
    let planned = renderer.render(&scene, &options()).unwrap();
    let forced = renderer
        .render(
            &scene,
            &RenderOptions {
                force: weft::render::Force {
                    shadows: true,
                    ..Default::default()
                },
                ..options()
            },
        )
        .unwrap();
    assert_eq!(forced.stats.shadow_maps, 2);
    assert!(lighting_pipeline(&forced).contains("shadows=1"));
    assert!(lighting_pipeline(&planned).contains("shadows=0"));
    assert_eq!(max_hdr_diff(&planned, &forced), 0.0);
    assert_eq!(planned.ldr, forced.ldr);

    // Shadow sampling compiled in with no light asking changes nothing either.
    let scene = scene::default_scene();
    let planned = renderer.render(&scene, &options()).unwrap();
    let forced = renderer
        .render(
            &scene,
            &RenderOptions {
                force: weft::render::Force {
                    shadows: true,
                    ..Default::default()
                },
                ..options()
            },
        )
        .unwrap();
    assert!(lighting_pipeline(&forced).contains("shadows=1"));
    assert_eq!(forced.stats.shadow_maps, 0);
    assert_eq!(max_hdr_diff(&planned, &forced), 0.0);
}

#[test]
fn range_culling_changes_nothing() {
    // 256 point lights of 0.6 m range over the default scene: most pixels are out of reach of
    // most lights.
    let scene = weft::bench::with_local_point_lights(&scene::default_scene(), 256, 0.6);
    let plan = Plan::new(&scene, &options());
    assert!(plan.range_culling);
    let mut renderer = Renderer::new(common::context()).unwrap();
    let culled = renderer.render(&scene, &options()).unwrap();
    let all = renderer
        .render(
            &scene,
            &RenderOptions {
                force: weft::render::Force {
                    no_range_culling: true,
                    ..Default::default()
                },
                ..options()
            },
        )
        .unwrap();
    let mut dark = scene.clone();
    dark.lights.clear();
    let unlit = renderer.render(&dark, &options()).unwrap();
    assert!(
        max_hdr_diff(&culled, &unlit) > 0.05,
        "the local lights must light something"
    );
    assert!(lighting_pipeline(&culled).contains("range_culling=2"));
    assert!(lighting_pipeline(&all).contains("range_culling=0"));
    // Culled by tile and by slice of view distance (render::tiles): the lists are sliced here.
    assert_eq!(culled.stats.light_slices, weft::render::tiles::SLICES);
    assert_eq!(all.stats.light_slices, 1);
    assert_eq!(max_hdr_diff(&culled, &all), 0.0);
}

fn gbuffer_pipeline(frame: &weft::render::Frame) -> String {
    frame
        .stats
        .pipelines
        .iter()
        .find(|p| p.starts_with("gbuffer["))
        .cloned()
        .unwrap_or_default()
}

#[test]
fn no_vertex_colours_compile_no_colour_code_and_forcing_it_changes_nothing() {
    let scene = scene::default_scene();
    let plan = Plan::new(&scene, &options());
    assert_eq!(plan.vertex_color_meshes, 0);
    assert!(!plan.vertex_colors);
    let mut renderer = Renderer::new(common::context()).unwrap();
    let planned = renderer.render(&scene, &options()).unwrap();
    let forced = renderer
        .render(
            &scene,
            &RenderOptions {
                force: weft::render::Force {
                    vertex_colors: true,
                    ..Default::default()
                },
                ..options()
            },
        )
        .unwrap();
    assert!(gbuffer_pipeline(&planned).contains("vertex_colors=0"));
    assert!(gbuffer_pipeline(&forced).contains("vertex_colors=1"));
    assert_eq!(max_hdr_diff(&planned, &forced), 0.0);
    assert_eq!(planned.ldr, forced.ldr);

    // A drawn mesh with colours turns the code on; an undrawn one does not.
    let mut coloured = scene.clone();
    let n = coloured.meshes[0].vertices.len();
    coloured.meshes[0].colors = vec![[1.0, 0.5, 0.25, 1.0]; n];
    let plan = Plan::new(&coloured, &options());
    assert_eq!((plan.vertex_color_meshes, plan.vertex_colors), (1, true));
    coloured.draws.retain(|d| d.mesh != 0);
    let plan = Plan::new(&coloured, &options());
    assert_eq!((plan.vertex_color_meshes, plan.vertex_colors), (0, false));
}

#[test]
fn no_unlit_material_compiles_no_unlit_code_and_forcing_it_changes_nothing() {
    let scene = scene::default_scene();
    let plan = Plan::new(&scene, &options());
    assert_eq!(plan.unlit_materials, 0);
    assert!(!plan.unlit);
    let mut renderer = Renderer::new(common::context()).unwrap();
    let planned = renderer.render(&scene, &options()).unwrap();
    let forced = renderer
        .render(
            &scene,
            &RenderOptions {
                force: weft::render::Force {
                    unlit: true,
                    ..Default::default()
                },
                ..options()
            },
        )
        .unwrap();
    assert!(lighting_pipeline(&planned).contains("unlit=0"));
    assert!(lighting_pipeline(&forced).contains("unlit=1"));
    assert_eq!(max_hdr_diff(&planned, &forced), 0.0);
    assert_eq!(planned.ldr, forced.ldr);
    let mut flat = scene.clone();
    flat.materials[0].unlit = true;
    assert!(Plan::new(&flat, &options()).unlit);
}

#[test]
fn no_mask_material_compiles_no_discard_and_forcing_it_changes_nothing() {
    let scene = shadows_scene();
    let plan = Plan::new(&scene, &options());
    assert_eq!(
        (plan.mask_draws, plan.alpha_mask, plan.mask_casters),
        (0, false, 0)
    );
    let mut renderer = Renderer::new(common::context()).unwrap();
    let planned = renderer.render(&scene, &options()).unwrap();
    let forced = renderer
        .render(
            &scene,
            &RenderOptions {
                force: weft::render::Force {
                    alpha_mask: true,
                    ..Default::default()
                },
                ..options()
            },
        )
        .unwrap();
    assert!(gbuffer_pipeline(&planned).contains("alpha_mask=0"));
    assert!(gbuffer_pipeline(&forced).contains("alpha_mask=1"));
    assert!(!planned
        .stats
        .pipelines
        .iter()
        .any(|p| p.starts_with("shadow_mask")));
    assert_eq!(max_hdr_diff(&planned, &forced), 0.0);
    assert_eq!(planned.ldr, forced.ldr);
}

/// A Khronos sample model of tests/data/khronos ("SheenChair/glTF/SheenChair.gltf").
fn khronos(path: &str) -> Scene {
    scene::load(std::path::Path::new(&format!(
        "{}/tests/data/khronos/{path}",
        env!("CARGO_MANIFEST_DIR")
    )))
    .unwrap_or_else(|e| panic!("{path}: {e}"))
}

const CHAIR: &str = "SheenChair/glTF/SheenChair.gltf";
const ANISOTROPY: &str = "AnisotropyRotationTest/glTF-Binary/AnisotropyRotationTest.glb";

/// The built-in studio environment, as `weft render` lights a scene by default.
fn studio() -> Option<weft::env::EnvLighting> {
    Some(weft::env::EnvLighting::new(std::sync::Arc::new(
        weft::env::Environment::studio(),
    )))
}

#[test]
fn a_pipeline_per_kind_of_material_with_only_the_scenes_code_changes_nothing() {
    // The G-buffer draws fabric and glTF materials with a pipeline each (the other kind's code
    // compiled out), samples only the texture slots some material has a texture in, and the
    // lighting shades each kind of pixel (background, fabric, glTF) with a pipeline of its own
    // over the G-buffer's stencil, with only the glTF extensions the scene has: against one
    // pipeline of each pass with all of it (Force::material_kinds), under the studio at fis:8,
    // the same image bit for bit. The scenes: the default (fabric and untextured glTF), SheenChair
    // (textures, sheen), AnisotropyRotationTest (anisotropy), and the default with its fabric
    // shaded as glTF.
    let base = RenderOptions {
        width: 96,
        height: 64,
        environment: studio(),
        ..Default::default()
    };
    let cases: [(&str, Scene, RenderOptions, &[&str]); 4] = [
        (
            "default",
            scene::default_scene(),
            base.clone(),
            &["woven", "glTF"],
        ),
        ("SheenChair", khronos(CHAIR), base.clone(), &["glTF"]),
        (
            "AnisotropyRotationTest",
            khronos(ANISOTROPY),
            base.clone(),
            &["glTF"],
        ),
        (
            "default, fabric as glTF",
            scene::default_scene(),
            RenderOptions {
                fabric_as_pbr: true,
                ..base.clone()
            },
            &["woven", "glTF"],
        ),
    ];
    let mut renderer = Renderer::new(common::context()).unwrap();
    for (name, scene, options, kinds) in cases {
        let plan = Plan::new(&scene, &options);
        assert!(plan.material_kinds, "{name}");
        let planned = renderer.render(&scene, &options).unwrap();
        let forced = renderer
            .render(
                &scene,
                &RenderOptions {
                    force: weft::render::Force {
                        material_kinds: true,
                        ..Default::default()
                    },
                    ..options.clone()
                },
            )
            .unwrap();
        let gbuffers: Vec<&String> = planned
            .stats
            .pipelines
            .iter()
            .filter(|p| p.starts_with("gbuffer["))
            .collect();
        assert_eq!(gbuffers.len(), kinds.len(), "{name}: {gbuffers:?}");
        for k in kinds {
            assert!(
                gbuffers.iter().any(|p| p.ends_with(&format!(", {k}]"))),
                "{name}: no {k} pipeline in {gbuffers:?}"
            );
        }
        assert!(
            !gbuffer_pipeline(&forced).contains("woven"),
            "{name}: {}",
            gbuffer_pipeline(&forced)
        );
        // The lighting pass: a pipeline per kind of pixel (the background's, and each kind of
        // surface the G-buffer holds), each drawn where the G-buffer's stencil is its kind.
        let lightings: Vec<&String> = planned
            .stats
            .pipelines
            .iter()
            .filter(|p| p.starts_with("lighting["))
            .collect();
        // (A device without D32_SFLOAT_S8_UINT has no stencil: one pipeline of the scene's kinds.)
        let surfaces = if options.fabric_as_pbr {
            1
        } else {
            kinds.len()
        };
        if renderer.context().info().depth_stencil {
            assert_eq!(lightings.len(), 1 + surfaces, "{name}: {lightings:?}");
            assert!(lightings.iter().any(|p| p.contains("pixel_kinds=1,")));
        } else {
            assert_eq!(lightings.len(), 1, "{name}: {lightings:?}");
        }
        assert!(lighting_pipeline(&forced).contains("pixel_kinds=7"));
        assert!(lighting_pipeline(&forced).contains("gltf_features=3"));
        assert_eq!(max_hdr_diff(&planned, &forced), 0.0, "{name}");
    }
    // What each scene compiles in.
    let slots = |s: &Scene| Plan::new(s, &base).texture_slots;
    assert_eq!(slots(&scene::default_scene()), 0);
    assert_ne!(slots(&khronos(CHAIR)), 0);
    assert_eq!(Plan::new(&scene::default_scene(), &base).gltf_features, 0);
    assert_eq!(
        Plan::new(&khronos(CHAIR), &base).gltf_features,
        weft::render::plan::GLTF_SHEEN
    );
    assert_eq!(
        Plan::new(&khronos(ANISOTROPY), &base).gltf_features,
        weft::render::plan::GLTF_ANISOTROPY
    );
}

/// The fabric lobes' albedo tables are planned only where the woven model reads them: at the
/// approx and fis levels of environment light, not at mc, not with the fabric shaded as glTF or
/// by a comparison model, not without an environment.
#[test]
fn lobe_albedo_tables_only_where_the_woven_model_reads_them() {
    use weft::env::{EnvLighting, Environment, IblLevel};
    let scene = scene::default_scene();
    let env = |level| {
        let mut e = EnvLighting::new(std::sync::Arc::new(Environment::uniform([1.0; 3])));
        e.level = level;
        Some(e)
    };
    let tables = |o: RenderOptions| {
        Plan::new(&scene, &o)
            .environment
            .map_or(0, |e| e.lobe_albedo_tables)
    };
    let fabrics = scene
        .materials
        .iter()
        .filter(|m| m.fabric.is_some())
        .count();
    assert!(fabrics > 0);
    let with = |level| RenderOptions {
        environment: env(level),
        ..options()
    };
    assert_eq!(tables(with(IblLevel::Fis(8))), fabrics);
    assert_eq!(tables(with(IblLevel::Approx)), fabrics);
    assert_eq!(tables(with(IblLevel::MonteCarlo(4))), 0);
    assert_eq!(tables(options()), 0);
    assert_eq!(
        tables(RenderOptions {
            fabric_as_pbr: true,
            ..with(IblLevel::Fis(8))
        }),
        0
    );
    assert_eq!(
        tables(RenderOptions {
            shading: weft::records::Shading::Phong,
            ..with(IblLevel::Fis(8))
        }),
        0
    );
    let plain = without_fabric(scene.clone());
    assert_eq!(
        Plan::new(&plain, &with(IblLevel::Fis(8)))
            .environment
            .map_or(usize::MAX, |e| e.lobe_albedo_tables),
        0
    );
}

/// The pooling of the fabric lobes' samples is planned only at fis where the woven model shades
/// fabric; compiled in where it has nothing to pool (no fabric, or the fabric at mc) it changes
/// nothing, and where it pools it changes the cloth's lobes only: the same image off the cloth.
#[test]
fn lobe_pooling_only_at_fis_on_woven_fabric_and_forcing_it_changes_nothing() {
    use weft::env::{EnvLighting, IblLevel};
    let scene = scene::default_scene();
    let lit = |level, pooled| RenderOptions {
        width: 160,
        height: 90,
        environment: Some({
            let mut e = EnvLighting::new(weft::spec::studio());
            e.level = level;
            e.pool = if pooled { weft::env::DEFAULT_POOL } else { 0 };
            e
        }),
        ..options()
    };
    let pooled =
        |s: &Scene, o: &RenderOptions| Plan::new(s, o).environment.is_some_and(|e| e.pool > 0);
    assert!(pooled(&scene, &lit(IblLevel::Fis(8), true)));
    assert!(!pooled(&scene, &lit(IblLevel::Fis(8), false)));
    assert!(!pooled(&scene, &lit(IblLevel::Approx, true)));
    assert!(!pooled(&scene, &lit(IblLevel::MonteCarlo(4), true)));
    assert!(!pooled(
        &scene,
        &RenderOptions {
            fabric_as_pbr: true,
            ..lit(IblLevel::Fis(8), true)
        }
    ));
    let plain = without_fabric(scene.clone());
    assert!(!pooled(&plain, &lit(IblLevel::Fis(8), true)));

    let mut renderer = Renderer::new(common::context()).unwrap();
    let force = |o: RenderOptions| RenderOptions {
        force: weft::render::Force {
            pool: true,
            ..Default::default()
        },
        ..o
    };
    // Nothing to pool: no woven pixel, or the woven model at mc.
    for (s, level) in [
        (&plain, IblLevel::Fis(8)),
        (&scene, IblLevel::MonteCarlo(4)),
    ] {
        let planned = renderer.render(s, &lit(level, true)).unwrap();
        let forced = renderer.render(s, &force(lit(level, true))).unwrap();
        assert!(lighting_pipeline(&planned).contains("pool=0"));
        assert!(lighting_pipeline(&forced).contains("pool=1"));
        assert_eq!(max_hdr_diff(&planned, &forced), 0.0, "{}", level.name());
        assert_eq!(planned.ldr, forced.ldr);
    }
    // Pooling at fis:8 moves the cloth's pixels a little and nothing else.
    let on = renderer
        .render(&scene, &lit(IblLevel::Fis(8), true))
        .unwrap();
    let off = renderer
        .render(&scene, &lit(IblLevel::Fis(8), false))
        .unwrap();
    assert!(lighting_pipeline(&on).contains("pool=1"));
    assert!(lighting_pipeline(&off).contains("pool=0"));
    // The lobe sums draw runs only where the lighting pools.
    let lobes_draw = |f: &weft::render::Frame| {
        f.stats
            .pipelines
            .iter()
            .any(|p| p.starts_with("fabric lobes["))
    };
    assert!(lobes_draw(&on));
    assert!(!lobes_draw(&off));
    let plain_on = renderer
        .render(&plain, &lit(IblLevel::Fis(8), true))
        .unwrap();
    let plain_off = renderer
        .render(&plain, &lit(IblLevel::Fis(8), false))
        .unwrap();
    assert_eq!(max_hdr_diff(&plain_on, &plain_off), 0.0);
    let (mut moved, mut sum, mut mean_on, mut mean_off) = (0usize, 0.0f64, 0.0f64, 0.0f64);
    for (a, b) in on.hdr.chunks_exact(4).zip(off.hdr.chunks_exact(4)) {
        assert!(a.iter().all(|x| x.is_finite()));
        let d: f32 = (0..3).map(|c| (a[c] - b[c]).abs()).sum();
        if d > 0.0 {
            moved += 1;
        }
        sum += d as f64;
        mean_on += (a[0] + a[1] + a[2]) as f64;
        mean_off += (b[0] + b[1] + b[2]) as f64;
    }
    assert!(moved > 0, "pooling changed no pixel");
    // The two estimate the same integral: the image's mean within 1 % (measured 0.02 %: ratio
    // 0.99979 on lavapipe).
    assert!(
        (mean_on / mean_off - 1.0).abs() < 0.01,
        "pooled mean {mean_on} against alone {mean_off}"
    );
    println!(
        "pooling moved {moved} pixels, mean |change| {:.2e}, mean ratio {:.5}",
        sum / moved as f64,
        mean_on / mean_off
    );
}

#[test]
fn the_depth_prepass_runs_where_pixels_outnumber_triangles_and_changes_nothing() {
    let has_prepass = |frame: &weft::render::Frame| {
        frame
            .stats
            .pipelines
            .iter()
            .any(|p| p == "gbuffer depth pre-pass")
    };
    let sized = |width, height, force| RenderOptions {
        width,
        height,
        force,
        ..options()
    };
    let none = weft::render::Force::default();
    let mut renderer = Renderer::new(common::context()).unwrap();

    // The default scene (26370 triangles) at 640x360, 8.7 pixels a triangle: the cloth and the
    // three glTF draws pre-passed; without it (forced) the same image bit for bit, every hidden
    // fragment shaded.
    let scene = scene::default_scene();
    let large = sized(640, 360, none);
    assert_eq!(Plan::new(&scene, &large).depth_prepass, 4);
    let planned = renderer.render(&scene, &large).unwrap();
    let skipped = renderer
        .render(
            &scene,
            &sized(
                640,
                360,
                weft::render::Force {
                    no_depth_prepass: true,
                    ..none
                },
            ),
        )
        .unwrap();
    assert!(has_prepass(&planned) && !has_prepass(&skipped));
    assert!(gbuffer_pipeline(&planned).contains(", depth >="));
    assert!(!gbuffer_pipeline(&skipped).contains("depth >="));
    assert_eq!(max_hdr_diff(&planned, &skipped), 0.0);
    assert_eq!(planned.ldr, skipped.ldr);

    // Fewer than PREPASS_PIXELS_PER_TRIANGLE pixels a triangle (320x180: 2.2 for the default
    // scene, 1.4 for SheenChair): not planned, and run anyway (forced) it changes nothing.
    for scene in [scene::default_scene(), khronos(CHAIR)] {
        let small = sized(320, 180, none);
        assert_eq!(Plan::new(&scene, &small).depth_prepass, 0);
        let planned = renderer.render(&scene, &small).unwrap();
        let forced = renderer
            .render(
                &scene,
                &sized(
                    320,
                    180,
                    weft::render::Force {
                        depth_prepass: true,
                        ..none
                    },
                ),
            )
            .unwrap();
        assert!(!has_prepass(&planned) && has_prepass(&forced));
        assert_eq!(max_hdr_diff(&planned, &forced), 0.0);
        assert_eq!(planned.ldr, forced.ldr);
    }

    // A cut-out cloth's depth depends on its cut-out: it is left out, the glTF draws are not.
    let mut cut = scene::default_scene();
    for m in &mut cut.materials {
        if m.fabric.is_some() {
            m.alpha_cutoff = Some(0.5);
        }
    }
    assert_eq!(Plan::new(&cut, &large).depth_prepass, 3);
}

#[test]
fn fxaa_on_the_edge_blocks_alone_changes_nothing() {
    // Where the G-buffer's depth has a stencil, FXAA draws twice: the pixels off an edge copied
    // and marked, then the edge search where no mark is (llvmpipe skips the 4 x 4 blocks without
    // an edge). Against one draw of the search over every pixel (Force::fxaa_everywhere), the
    // same image byte for byte; and FXAA changed it (the comparison is not of two unsmoothed
    // images). The scenes: the default (the cloth's fine weave, a metal ball) under the studio,
    // and SheenChair (textures, thin legs).
    let base = RenderOptions {
        width: 160,
        height: 96,
        environment: studio(),
        antialias: weft::render::Antialias::Fxaa,
        ..Default::default()
    };
    let mut renderer = Renderer::new(common::context()).unwrap();
    let stencil = renderer.context().info().depth_stencil;
    for (name, scene) in [
        ("default", scene::default_scene()),
        ("SheenChair", khronos(CHAIR)),
    ] {
        let plan = Plan::new(&scene, &base);
        assert!(
            plan.runs(Pass::Antialias) && plan.antialias_edge_blocks,
            "{name}"
        );
        assert!(plan
            .to_string()
            .contains("only on the 4x4 blocks with an edge"));
        let planned = renderer.render(&scene, &base).unwrap();
        let forced = renderer
            .render(
                &scene,
                &RenderOptions {
                    force: weft::render::Force {
                        fxaa_everywhere: true,
                        ..Default::default()
                    },
                    ..base.clone()
                },
            )
            .unwrap();
        let none = renderer
            .render(
                &scene,
                &RenderOptions {
                    antialias: weft::render::Antialias::None,
                    ..base.clone()
                },
            )
            .unwrap();
        let aa: Vec<&String> = planned
            .stats
            .pipelines
            .iter()
            .filter(|p| p.starts_with("antialias["))
            .collect();
        if stencil {
            assert_eq!(
                aa,
                ["antialias[fxaa, off edges]", "antialias[fxaa, edge blocks]"],
                "{name}"
            );
        } else {
            assert_eq!(aa, ["antialias[fxaa]"], "{name}");
        }
        assert!(
            forced
                .stats
                .pipelines
                .iter()
                .any(|p| p == "antialias[fxaa]"),
            "{name}: {:?}",
            forced.stats.pipelines
        );
        let smoothed = planned
            .ldr
            .chunks(4)
            .zip(none.ldr.chunks(4))
            .filter(|(a, b)| a != b)
            .count();
        assert!(smoothed > 50, "{name}: FXAA changed only {smoothed} pixels");
        let differ = planned
            .ldr
            .chunks(4)
            .zip(forced.ldr.chunks(4))
            .filter(|(a, b)| a != b)
            .count();
        assert_eq!(
            differ, 0,
            "{name}: {differ} pixels differ from FXAA everywhere"
        );
    }
}

#[test]
fn occlusion_where_a_surface_is_alone_changes_nothing() {
    // The occlusion pass draws its estimates and blur against a half-resolution copy of depth,
    // where a surface is (llvmpipe skips the empty 4 x 4 blocks); the empty texels keep the
    // targets' clear. Against both drawn over every pixel (Force::occlusion_everywhere), the
    // same image: the lit HDR and the occlusion debug view, byte for byte; and the occlusion
    // darkened something (the comparison is not of two unoccluded images). The scenes: the
    // default (a quarter of it sky) and SheenChair (mostly empty around the chair).
    let base = RenderOptions {
        width: 160,
        height: 96,
        environment: studio(),
        occlusion: weft::render::Occlusion::DEFAULT,
        ..Default::default()
    };
    let mut renderer = Renderer::new(common::context()).unwrap();
    for (name, scene) in [
        ("default", scene::default_scene()),
        ("SheenChair", khronos(CHAIR)),
    ] {
        let plan = Plan::new(&scene, &base);
        assert!(plan.runs(Pass::Occlusion), "{name}");
        assert!(plan.occlusion.as_ref().unwrap().covered_only, "{name}");
        assert!(plan.to_string().contains("drawn only where a surface is"));
        let forced_options = RenderOptions {
            force: weft::render::Force {
                occlusion_everywhere: true,
                ..Default::default()
            },
            ..base.clone()
        };
        for view in [
            weft::render::DebugView::None,
            weft::render::DebugView::Occlusion,
        ] {
            let planned = renderer
                .render(
                    &scene,
                    &RenderOptions {
                        debug_view: view,
                        ..base.clone()
                    },
                )
                .unwrap();
            let forced = renderer
                .render(
                    &scene,
                    &RenderOptions {
                        debug_view: view,
                        ..forced_options.clone()
                    },
                )
                .unwrap();
            assert!(
                forced
                    .stats
                    .pipelines
                    .iter()
                    .any(|p| p.ends_with("everywhere")),
                "{name}: {:?}",
                forced.stats.pipelines
            );
            assert!(!planned
                .stats
                .pipelines
                .iter()
                .any(|p| p.ends_with("everywhere")));
            assert_eq!(max_hdr_diff(&planned, &forced), 0.0, "{name} {view:?}");
            assert_eq!(planned.ldr, forced.ldr, "{name} {view:?}");
            if view == weft::render::DebugView::Occlusion {
                let occluded = planned.ldr.chunks(4).filter(|p| p[0] < 250).count();
                assert!(occluded > 100, "{name}: only {occluded} pixels occluded");
            }
        }
    }
}

/// Where nothing reads the HDR image (no HDR readback, no transparent pass blending over it), the
/// lighting pass applies the exposure and the tone curve itself and no tonemap pass runs; the
/// image is the tonemap pass's to the last bit of the 8-bit target: the tonemap pass reads the
/// radiance back from the half-float HDR target, the folded curve takes the shader's f32, so a
/// pixel may round to the neighbouring 8-bit value (measured at 160x90: 1/255 at most, in 1.6-6.7 %
/// of the pixels), never further.
#[test]
fn the_lighting_pass_tone_maps_where_nothing_reads_the_hdr_image_and_it_changes_nothing() {
    use weft::render::{DebugView, Force, ToneCurve};
    let scene = scene::default_scene();
    let mut renderer = Renderer::new(common::context()).unwrap();
    let mut checked = 0;
    for (tonemap, exposure, debug_view, environment) in [
        (ToneCurve::PbrNeutral, 0.0, DebugView::None, studio()),
        (ToneCurve::Agx, 1.5, DebugView::None, None),
        (ToneCurve::Aces, -1.0, DebugView::None, studio()),
        (ToneCurve::None, 0.5, DebugView::None, None),
        (ToneCurve::PbrNeutral, 2.0, DebugView::Normals, None),
    ] {
        let folded = RenderOptions {
            width: 160,
            height: 90,
            read_hdr: false,
            tonemap,
            exposure,
            debug_view,
            environment,
            ..options()
        };
        let plan = Plan::new(&scene, &folded);
        assert!(
            plan.tone_in_lighting && !plan.runs(Pass::Tonemap),
            "{tonemap:?}"
        );
        let a = renderer.render(&scene, &folded).unwrap();
        assert!(!a.stats.passes.contains(&"tonemap"), "{:?}", a.stats.passes);
        // tonemap.frag's CURVE (4: a debug view's passthrough), plus one.
        let curve = if debug_view == DebugView::None {
            tonemap.code()
        } else {
            4
        } + 1;
        assert!(
            lighting_pipeline(&a).contains(&format!("tone_curve={curve}")),
            "{}",
            lighting_pipeline(&a)
        );
        let separate = RenderOptions {
            force: Force {
                tonemap_pass: true,
                ..Force::NONE
            },
            ..folded.clone()
        };
        assert!(!Plan::new(&scene, &separate).tone_in_lighting);
        let b = renderer.render(&scene, &separate).unwrap();
        assert!(b.stats.passes.contains(&"tonemap"));
        assert!(lighting_pipeline(&b).contains("tone_curve=0"));
        assert_eq!(a.ldr.len(), b.ldr.len());
        let max = a
            .ldr
            .iter()
            .zip(&b.ldr)
            .map(|(x, y)| x.abs_diff(*y))
            .max()
            .unwrap();
        let moved = a
            .ldr
            .chunks_exact(4)
            .zip(b.ldr.chunks_exact(4))
            .filter(|(x, y)| x != y)
            .count();
        eprintln!(
            "{tonemap:?} {exposure} EV {debug_view:?}: {moved} of {} pixels moved, by at most {max}/255",
            a.ldr.len() / 4
        );
        assert!(max <= 1, "{tonemap:?} {debug_view:?}: {max}/255");
        // Rounding moves a few pixels; another curve or exposure would move most of them.
        assert!(
            moved * 4 < a.ldr.len() / 4,
            "{tonemap:?}: {moved} pixels moved"
        );
        checked += 1;
    }
    assert_eq!(checked, 5);
    // The HDR image read back (`weft render --exr`), or blended draws over it: the pass runs.
    let hdr = RenderOptions {
        read_hdr: true,
        ..options()
    };
    assert!(Plan::new(&scene, &hdr).runs(Pass::Tonemap));
    let mut blended = scene.clone();
    blended.materials[0].blend = true;
    let folded = RenderOptions {
        read_hdr: false,
        ..options()
    };
    assert!(Plan::new(&blended, &folded).runs(Pass::Transparent));
    assert!(Plan::new(&blended, &folded).runs(Pass::Tonemap));
}
