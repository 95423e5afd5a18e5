//! weft's cache on disk (issue 29 item 4, src/cache.rs): a second run takes the environment's
//! preprocessing from disk and renders the same image; a damaged or foreign entry is not used
//! (the run computes what it needs and renders the same image), and is replaced.
//!
//! One test in this binary, so that the cache directory it sets (`WEFT_CACHE_DIR`) is its own.

mod common;

use std::path::Path;

use weft::render::{Frame, RenderOptions, Renderer};

fn render(scene: &weft::scene::Scene, options: &RenderOptions) -> Frame {
    // A renderer (and device) per run, as a process would have: its pipeline cache is written
    // when it ends.
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    renderer.render(scene, options).expect("render")
}

fn entries(dir: &Path, kind: &str) -> Vec<std::path::PathBuf> {
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .map(|d| {
            d.flatten()
                .map(|e| e.path())
                .filter(|p| {
                    p.file_name()
                        .is_some_and(|n| n.to_string_lossy().starts_with(&format!("{kind}-")))
                })
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

#[test]
fn a_second_run_reuses_the_cache_and_damage_is_never_used() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let cache = dir.path().join("weft-cache");
    // The only test in this binary: no other thread reads the environment meanwhile.
    std::env::set_var("WEFT_CACHE_DIR", &cache);
    let scene = weft::scene::default_scene();
    let options = RenderOptions {
        width: 160,
        height: 90,
        environment: Some(weft::env::EnvLighting::new(std::sync::Arc::new(
            weft::env::Environment::studio(),
        ))),
        ..Default::default()
    };

    let first = render(&scene, &options);
    assert!(!first.stats.environment_from_disk);
    let env_files = entries(&cache, "environment");
    assert_eq!(env_files.len(), 1, "{env_files:?}");
    assert_eq!(entries(&cache, "pipelines").len(), 1);

    // From disk: the same image, bit for bit.
    let second = render(&scene, &options);
    assert!(second.stats.environment_from_disk);
    assert_eq!(first.ldr, second.ldr);
    assert_eq!(first.hdr, second.hdr);

    // Damaged on disk (one byte of its payload): not used, computed again, the same image, and
    // the entry made whole again.
    let mut bytes = std::fs::read(&env_files[0]).unwrap();
    let n = bytes.len();
    bytes[n - 1000] ^= 0x40;
    std::fs::write(&env_files[0], &bytes).unwrap();
    let third = render(&scene, &options);
    assert!(!third.stats.environment_from_disk);
    assert_eq!(first.ldr, third.ldr);
    assert!(render(&scene, &options).stats.environment_from_disk);

    // Cut short, and replaced by something else entirely: the same.
    for damage in [bytes[..n / 2].to_vec(), b"not a cache file".to_vec()] {
        std::fs::write(&env_files[0], &damage).unwrap();
        let f = render(&scene, &options);
        assert!(!f.stats.environment_from_disk);
        assert_eq!(first.ldr, f.ldr);
    }

    // A pipeline cache entry damaged (its last byte), or garbage: the device starts with an
    // empty pipeline cache and renders the same. (Whether a sound record's Vulkan header is this
    // device's is src/vk/context.rs's unit test.)
    let pipelines = entries(&cache, "pipelines");
    let mut damaged = std::fs::read(&pipelines[0]).unwrap();
    let last = damaged.len() - 1;
    damaged[last] ^= 0xff;
    for bad in [damaged, vec![0u8; 64]] {
        std::fs::write(&pipelines[0], &bad).unwrap();
        let f = render(&scene, &options);
        assert_eq!(first.ldr, f.ldr);
    }

    // The world light (`--occlusion gtao`): traced beside the pipelines the first time, read
    // from disk the second (its key is known before the environment's SH is), the same image;
    // damaged on disk, traced again, the same image.
    let world = RenderOptions {
        occlusion: weft::render::Occlusion::DEFAULT,
        ..options.clone()
    };
    assert!(weft::render::Plan::new(&scene, &world)
        .occlusion
        .is_some_and(|o| o.world.is_some()));
    let traced = render(&scene, &world);
    assert!(!traced.stats.world_light_from_disk);
    let world_files = entries(&cache, "world-light");
    assert_eq!(world_files.len(), 1, "{world_files:?}");
    let read = render(&scene, &world);
    assert!(read.stats.world_light_from_disk);
    assert_eq!(traced.ldr, read.ldr);
    assert_eq!(traced.hdr, read.hdr);
    assert_ne!(traced.ldr, first.ldr, "the occlusion is drawn");
    let mut bytes = std::fs::read(&world_files[0]).unwrap();
    let n = bytes.len();
    bytes[n / 2] ^= 0x10;
    std::fs::write(&world_files[0], &bytes).unwrap();
    let again = render(&scene, &world);
    assert!(!again.stats.world_light_from_disk);
    assert_eq!(traced.ldr, again.ldr);
    assert!(render(&scene, &world).stats.world_light_from_disk);

    // Turned off: nothing read or written.
    std::env::set_var("WEFT_CACHE_DIR", "off");
    let off = render(&scene, &options);
    assert!(!off.stats.environment_from_disk);
    assert_eq!(first.ldr, off.ldr);
    let off = render(&scene, &world);
    assert!(!off.stats.world_light_from_disk);
    assert_eq!(traced.ldr, off.ldr);

    // Another sky for the same uploaded scene (a viewer turning the environment): its rays are
    // shaded again, not traced (no "world rays" in the frame's timings), and the image is the
    // one a fresh renderer traces for that sky.
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let gpu = renderer.upload(&scene).expect("upload");
    let named = |f: &Frame, name: &str| f.timings.iter().any(|t| t.name == name);
    let first_sky = renderer.render_frame(&scene, &gpu, &world).expect("render");
    assert!(named(&first_sky, "world rays"));
    let mut turned = world.clone();
    turned.environment.as_mut().expect("lit").rotation = 90.0;
    let again = renderer
        .render_frame(&scene, &gpu, &turned)
        .expect("render");
    assert!(!named(&again, "world rays") && named(&again, "world light"));
    assert_eq!(again.ldr, render(&scene, &turned).ldr);
    assert_ne!(again.ldr, first_sky.ldr, "the sky turned");

    // A material's colour rewritten on the uploaded scene (`weft view`'s live edits): the world
    // light is shaded again with it (the kept rays, whose cut-outs did not change, not traced
    // again), and the image is a fresh renderer's of the edited scene.
    let mut edited = scene.clone();
    let glossy = edited
        .materials
        .iter_mut()
        .find(|m| m.fabric.is_none() && m.metallic < 0.5)
        .expect("the default scene's floor");
    glossy.base_color = [0.1, 0.6, 0.2, 1.0];
    let mut gpu = gpu;
    renderer
        .update_material_records(&edited, &mut gpu)
        .expect("records");
    let recoloured = renderer
        .render_frame(&edited, &gpu, &turned)
        .expect("render");
    assert!(!named(&recoloured, "world rays") && named(&recoloured, "world light"));
    assert_eq!(recoloured.ldr, render(&edited, &turned).ldr);
    renderer.context().check_validation().unwrap();
}
