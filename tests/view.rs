//! `weft view`: the window shows what `weft render` renders (under Xvfb, lavapipe, validation on),
//! the panel is drawn, and a fabric edit made through the panel's code changes the fabric's
//! pixels and no others.

mod common;

use std::path::Path;
use std::process::Command;

use weft::render::{RenderOptions, Renderer};
use weft::view::controls::{self, MaterialUpdate};

/// `xvfb-run` (package xvfb, installed by tools/setup), or None: the window tests then say they
/// are skipped.
fn xvfb_run() -> Option<&'static str> {
    let found = Command::new("sh")
        .args(["-c", "command -v xvfb-run"])
        .output()
        .is_ok_and(|o| o.status.success());
    found.then_some("xvfb-run")
}

/// Runs `weft ARGS` under a fresh Xvfb server, returning its stderr; panics with its output
/// when it fails.
fn weft_in_xvfb(xvfb: &str, args: &[&str]) -> String {
    let out = Command::new(xvfb)
        .args(["-a", "-s", "-screen 0 1024x768x24", common::WEFT])
        .args(args)
        .env("WEFT_DEVICE", common::device())
        .output()
        .expect("running xvfb-run");
    assert!(
        out.status.success(),
        "weft {args:?} under Xvfb failed ({}):\n{}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn weft_render(args: &[&str]) {
    let out = common::weft()
        .arg("render")
        .args(args)
        .output()
        .expect("running weft render");
    assert!(
        out.status.success(),
        "weft render {args:?} failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn rgb(path: &Path) -> image::RgbImage {
    image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgb8()
}

/// Mean FLIP of `test` against `reference`, over the columns from `x0` on.
fn flip_mean(reference: &image::RgbImage, test: &image::RgbImage, x0: u32) -> f64 {
    let (w, h) = reference.dimensions();
    let crop = |img: &image::RgbImage| {
        image::imageops::crop_imm(img, x0, 0, w - x0, h)
            .to_image()
            .into_raw()
    };
    common::flip_mean(w - x0, h, &crop(reference), &crop(test)) as f64
}

fn max_abs_diff(a: &image::RgbImage, b: &image::RgbImage, x0: u32) -> u8 {
    a.enumerate_pixels()
        .filter(|(x, _, _)| *x >= x0)
        .map(|(x, y, p)| {
            let q = b.get_pixel(x, y);
            (0..3).map(|c| p[c].abs_diff(q[c])).max().unwrap_or(0)
        })
        .max()
        .unwrap_or(0)
}

#[test]
fn window_shows_what_render_renders() {
    let Some(xvfb) = xvfb_run() else {
        println!("SKIPPED window_shows_what_render_renders: xvfb-run is not installed (tools/setup installs xvfb and xauth)");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let shot = dir.path().join("view.png");
    let reference = dir.path().join("render.png");
    // The panel hidden: the whole window is the render. Same scene, camera (the scene's) and size.
    weft_in_xvfb(
        xvfb,
        &[
            "view",
            "--validate",
            "--no-panel",
            "--size",
            "320x240",
            "--screenshot",
            shot.to_str().unwrap(),
            "--after",
            "4",
        ],
    );
    weft_render(&[
        "--validate",
        "--size",
        "320x240",
        "-o",
        reference.to_str().unwrap(),
    ]);
    let (a, b) = (rgb(&reference), rgb(&shot));
    assert_eq!(a.dimensions(), b.dimensions(), "the window's size");
    let flip = flip_mean(&a, &b, 0);
    let max = max_abs_diff(&a, &b, 0);
    println!("view vs render, 320x240, panel hidden: mean FLIP {flip:.6}, max |diff| {max}/255");
    // The window shows the same tonemapped target: the only step between the two is a blit from
    // the RGBA8 sRGB target into the BGRA8 sRGB swapchain image, a decode and re-encode of each
    // 8-bit value, which a driver may round by at most one step (the sRGB conversion precision
    // Vulkan requires is about 1 ULP of 8 bits). One step everywhere gives a mean FLIP below
    // 0.01; anything else (a wrong camera, size, exposure, a channel swap, a missing pass)
    // gives tenths.
    assert!(
        max <= 1,
        "the window differs from weft render by {max}/255 somewhere"
    );
    assert!(
        flip < 0.01,
        "mean FLIP {flip} between the window and weft render"
    );
}

#[test]
fn panel_is_drawn_left_of_the_scene() {
    let Some(xvfb) = xvfb_run() else {
        println!("SKIPPED panel_is_drawn_left_of_the_scene: xvfb-run is not installed (tools/setup installs xvfb and xauth)");
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let shot = dir.path().join("view.png");
    let reference = dir.path().join("render.png");
    let stderr = weft_in_xvfb(
        xvfb,
        &[
            "view",
            "--validate",
            "--size",
            "640x360",
            "--screenshot",
            shot.to_str().unwrap(),
            "--after",
            "4",
        ],
    );
    // "the scene WxH from x X0": the viewer renders the scene right of the panel, at that size.
    let tail = stderr
        .split("the scene ")
        .nth(1)
        .unwrap_or_else(|| panic!("no scene area in:\n{stderr}"));
    let (size, rest) = tail.split_once(" from x ").unwrap();
    let x0: u32 = rest
        .trim_end_matches(|c: char| !c.is_ascii_digit())
        .parse()
        .unwrap();
    println!("panel: the scene is {size} from x {x0}");
    assert!(x0 > 100 && x0 < 640, "the panel's width {x0}");
    weft_render(&[
        "--validate",
        "--size",
        size,
        "-o",
        reference.to_str().unwrap(),
    ]);
    let (a, b) = (rgb(&reference), rgb(&shot));
    assert_eq!(a.width() + x0, b.width());
    // Right of the panel: the render of that size, the same bound as above (a blit of identical
    // 8-bit values).
    let right = image::imageops::crop_imm(&b, x0, 0, a.width(), a.height()).to_image();
    let max = max_abs_diff(&a, &right, 0);
    assert!(
        max <= 1,
        "right of the panel the window differs from weft render by {max}/255"
    );
    // Left of it, the panel: egui's dark fill and its widgets, nearly uniform, nothing like the
    // scene (a window without the panel drawn would be the cleared black there, also checked).
    let panel: Vec<[u8; 3]> = (0..b.height())
        .flat_map(|y| (0..x0).map(move |x| (x, y)))
        .map(|(x, y)| b.get_pixel(x, y).0)
        .collect();
    let mean = panel.iter().map(|p| p[0] as f64).sum::<f64>() / panel.len() as f64;
    let lit = panel.iter().filter(|p| p[0] > 100).count();
    println!(
        "panel: mean red {mean:.1}, {lit} of {} pixels brighter than 100 (text, widgets)",
        panel.len()
    );
    // egui's dark theme fills the panel with grey 27; its text and widgets are brighter. A black
    // (undrawn) panel has mean 0 and nothing lit.
    assert!(mean > 15.0 && mean < 80.0, "panel mean {mean}");
    assert!(lit > 100, "no text or widgets drawn in the panel");
}

#[test]
fn no_display_is_a_clean_error() {
    // No DISPLAY at all, and a DISPLAY no X server listens on.
    for display in [None, Some(":4711")] {
        let mut cmd = Command::new(common::WEFT);
        cmd.arg("view").env_remove("WAYLAND_DISPLAY");
        match display {
            Some(d) => cmd.env("DISPLAY", d),
            None => cmd.env_remove("DISPLAY"),
        };
        let out = cmd.output().expect("running weft view");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(
            out.status.code(),
            Some(1),
            "{display:?}: exit code; stderr:\n{stderr}"
        );
        assert!(
            stderr.contains("no display: use weft render"),
            "{display:?}: stderr:\n{stderr}"
        );
        assert!(
            !stderr.contains("panicked"),
            "{display:?}: stderr:\n{stderr}"
        );
    }
}

/// Renders `scene` with `gpu`, returning the 8-bit image and, per pixel, whether a fabric
/// material is drawn there (from the G-buffer's material index).
fn render_with_mask(
    renderer: &mut Renderer,
    scene: &weft::scene::Scene,
    gpu: &weft::render::GpuScene,
    options: &RenderOptions,
) -> (Vec<u8>, Vec<bool>) {
    let frame = renderer.render_frame(scene, gpu, options).unwrap();
    let g = renderer.read_gbuffer().unwrap();
    let mask = (0..(options.width * options.height) as usize)
        .map(|i| {
            g.depth[i] > 0.0
                && scene
                    .materials
                    .get(g.surface[i * 4 + 1].round() as usize)
                    .is_some_and(|m| m.fabric.is_some())
        })
        .collect();
    (frame.ldr, mask)
}

#[test]
fn fabric_edit_changes_the_fabric_and_nothing_else() {
    let mut renderer = Renderer::new(common::context()).unwrap();
    let mut scene = weft::scene::default_scene();
    weft::env::stage(&mut scene, weft::env::LightsMode::Auto, 0.0, false);
    let options = RenderOptions {
        width: 160,
        height: 120,
        read_hdr: false,
        environment: Some(weft::env::EnvLighting::new(std::sync::Arc::new(
            weft::env::Environment::studio(),
        ))),
        ..Default::default()
    };
    let mut gpu = renderer.upload(&scene).unwrap();
    let (before, mask) = render_with_mask(&mut renderer, &scene, &gpu, &options);
    let fabric_pixels = mask.iter().filter(|&&m| m).count();
    assert!(fabric_pixels > 1000, "the default scene shows its cloth");

    let (material, _) = controls::fabric_materials(&scene)[0].clone();
    let original = scene.materials[material].fabric.clone().unwrap();

    // Unchanged parameters: nothing to do.
    assert_eq!(
        controls::set_fabric(&mut scene, material, &original).unwrap(),
        MaterialUpdate::None
    );

    // Edits as the panel makes them: (what changes, the update it needs).
    let mut green = original.clone();
    green.rd_warp = [0.1, 0.6, 0.1];
    green.rd_weft = [0.1, 0.6, 0.1];
    let mut gap = original.clone();
    gap.gap = original.repeat * 0.3;
    for (what, params, expect) in [
        ("thread colours", green, MaterialUpdate::Records),
        ("gap", gap, MaterialUpdate::Weave),
    ] {
        let update = controls::set_fabric(&mut scene, material, &params).unwrap();
        assert_eq!(update, expect, "{what}");
        controls::apply(&renderer, &scene, &mut gpu, update).unwrap();
        let (after, mask_after) = render_with_mask(&mut renderer, &scene, &gpu, &options);
        assert_eq!(
            mask, mask_after,
            "{what}: the fabric covers the same pixels"
        );
        let mut changed_fabric = 0;
        let mut changed_other = 0;
        for (i, m) in mask.iter().enumerate() {
            let differs = before[i * 4..i * 4 + 3] != after[i * 4..i * 4 + 3];
            match (differs, m) {
                (true, true) => changed_fabric += 1,
                (true, false) => changed_other += 1,
                _ => {}
            }
        }
        println!(
            "{what} ({update:?}): {changed_fabric} of {fabric_pixels} fabric pixels changed, {changed_other} others"
        );
        // Deferred shading: every pixel is lit from its own G-buffer texel, and the cloth's
        // parameters reach no other pixel (the shadow map holds depth only), so not one other
        // pixel may change.
        assert_eq!(
            changed_other, 0,
            "{what}: pixels that are not fabric changed"
        );
        // Red thread to green changes every lit fabric pixel; the gap (a third of the pitch
        // instead of a tenth) darkens most of them. Half is far below both and far above noise.
        assert!(
            changed_fabric * 2 > fabric_pixels,
            "{what}: only {changed_fabric} of {fabric_pixels} fabric pixels changed"
        );
        // Back to the original for the next edit.
        let back = controls::set_fabric(&mut scene, material, &original).unwrap();
        controls::apply(&renderer, &scene, &mut gpu, back).unwrap();
    }
}

#[test]
fn dropped_files_load_or_say_why() {
    use weft::env::LightsMode;
    use weft::view::SceneSource;
    let load = |p: &str| {
        controls::load(
            &SceneSource::File(p.into()),
            Default::default(),
            LightsMode::Auto,
            0.0,
            false,
        )
    };
    let e = load("tests/data/env/lebombo_1k.hdr")
        .unwrap_err()
        .to_string();
    assert!(e.contains("not a .gltf or .glb"), "{e}");
    let e = load("tests/malformed/broken-json.gltf")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("broken-json.gltf"),
        "the error names the file: {e}"
    );
    let e = load("no/such/file.glb").unwrap_err().to_string();
    assert!(e.contains("no/such/file.glb"), "{e}");
    // A real file loads, and is staged: a file without lights gets the default key light.
    let box_path = "../shared/realworld/khronos/Box/glTF-Binary/Box.glb";
    if Path::new(box_path).exists() {
        let scene = load(box_path).unwrap();
        assert!(!scene.draws.is_empty());
        assert!(
            !scene.lights.is_empty(),
            "staged with the default key light"
        );
    } else {
        println!("({box_path} not present: the real-file half of this test is skipped)");
    }
}

/// Authoring in the viewer (issue 27 item 5), through the functions its panel calls: SheenChair
/// (no fabric material) has its seat woven with a preset, then with a weaving draft, tuned as the
/// panel's sliders tune it (a sheet, a new exponent), and saved; the saved file is what `weft
/// fabric` writes for the same requests, and loads back with the tuned parameters.
#[test]
fn a_material_is_woven_tuned_and_saved_from_the_viewer() {
    let dir = common::temp_dir("view-authoring");
    let from = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/khronos/SheenChair/glTF");
    for entry in std::fs::read_dir(&from).unwrap() {
        let p = entry.unwrap().path();
        std::fs::copy(&p, dir.join(p.file_name().unwrap())).unwrap();
    }
    let file = dir.join("SheenChair.gltf");
    let source = weft::view::SceneSource::File(file.clone());
    let lights = weft::env::LightsMode::Auto;
    let scene = controls::load(&source, Default::default(), lights, 0.0, false).unwrap();
    assert!(controls::fabric_materials(&scene).is_empty());
    let materials = controls::file_materials(&scene);
    // The file's own materials only (not the staged ground), all of them.
    let doc: serde_json::Value = serde_json::from_slice(&std::fs::read(&file).unwrap()).unwrap();
    assert_eq!(materials.len(), doc["materials"].as_array().unwrap().len());
    assert!(
        scene.materials.len() > materials.len(),
        "the staged ground is there"
    );
    assert!(
        materials.iter().all(|(_, n)| !n.contains("default ground")),
        "{materials:?}"
    );
    let (seat, _) = materials
        .iter()
        .find(|(_, n)| n.to_lowercase().contains("fabric"))
        .cloned()
        .expect("SheenChair has a fabric material");

    // Weave it with a preset: the scene loads again with the woven seat.
    let mut requests = Vec::new();
    let (r, _) = controls::weave_request(seat, "denim-twill", None).unwrap();
    controls::replace_request(&mut requests, r);
    let (scene, applied) =
        controls::load_woven(&source, Default::default(), &requests, lights, 0.0, false).unwrap();
    let woven = scene.materials[seat].fabric.clone().expect("woven");
    assert_eq!(applied.len(), 1);
    assert_eq!(woven.pattern, weft::fabric::WeavePattern::twill());
    // The preset's 0.5 mm pitch, converted by the mesh's UV density.
    let pitch = woven.repeat as f64 / 2.0 * applied[0].density.metres_per_uv;
    assert!((pitch - 0.5e-3).abs() < 1e-6, "pitch {pitch}");

    // Again with a draft: it replaces the first weave of that material.
    let draft = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/drafts/tartan-twill.wif");
    let (r, _) = controls::weave_request(seat, "cotton-plain", Some(&draft)).unwrap();
    controls::replace_request(&mut requests, r);
    assert_eq!(requests.len(), 1);
    let (scene, _) =
        controls::load_woven(&source, Default::default(), &requests, lights, 0.0, false).unwrap();
    let woven = scene.materials[seat].fabric.clone().unwrap();
    assert!(woven.has_thread_colours(), "the tartan's sett");

    // Tuned in the panel: a sheet, a narrower lobe. Becoming a sheet moves the cloth to the
    // transparent pass: the scene is uploaded again; then a new τ only rewrites the records.
    let mut tuned = woven.clone();
    tuned.e_along = 321.0;
    tuned.transmission = Some(0.25);
    let mut live = scene.clone();
    assert_eq!(
        controls::set_fabric(&mut live, seat, &tuned).unwrap(),
        MaterialUpdate::Weave
    );
    assert!(live.materials[seat].blended());
    let mut thinner = tuned.clone();
    thinner.transmission = Some(0.1);
    assert_eq!(
        controls::set_fabric(&mut live, seat, &thinner).unwrap(),
        MaterialUpdate::Records
    );
    let exact = controls::exact_request(&scene, &requests, seat, &tuned).unwrap();
    controls::replace_request(&mut requests, exact);
    let (path, _) = controls::save_woven(&source, &requests).unwrap();
    assert_eq!(path, dir.join("SheenChair-fabric.gltf"));
    let saved = weft::scene::load(&path).expect("the saved file loads");
    let back = saved.materials[seat].fabric.clone().unwrap();
    assert_eq!(back.e_along, 321.0);
    assert_eq!(back.transmission, Some(0.25));
    assert_eq!(back.pattern, tuned.pattern);
    assert_eq!(back.warp_colours, tuned.warp_colours);
    assert!(
        (back.repeat - tuned.repeat).abs() <= 1e-5 * tuned.repeat,
        "{} vs {}",
        back.repeat,
        tuned.repeat
    );
    // The tuned request kept the preset's source (its fallback written again for the new
    // parameters); a fabric the file already had is saved as tuned, the rest of the material
    // untouched.
    assert_eq!(requests[0].source.name(), "cotton-plain");
    let before: serde_json::Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    let source2 = weft::view::SceneSource::File(path.clone());
    let scene2 = controls::load(&source2, Default::default(), lights, 0.0, false).unwrap();
    let mut retuned = scene2.materials[seat].fabric.clone().unwrap();
    retuned.rs = 0.1;
    let exact = controls::exact_request(&scene2, &[], seat, &retuned).unwrap();
    assert_eq!(exact.source.name(), "as tuned");
    let (path2, _) = controls::save_woven(&source2, &[exact]).unwrap();
    assert_eq!(path2, dir.join("SheenChair-fabric-fabric.gltf"));
    let after: serde_json::Value = serde_json::from_slice(&std::fs::read(&path2).unwrap()).unwrap();
    let (m0, m1) = (&before["materials"][seat], &after["materials"][seat]);
    assert_eq!(
        m1["extensions"]["WEFT_materials_fabric"]["rs"],
        serde_json::json!(0.1)
    );
    assert_eq!(m0["pbrMetallicRoughness"], m1["pbrMetallicRoughness"]);
    assert_eq!(
        m0["extensions"]["KHR_materials_sheen"],
        m1["extensions"]["KHR_materials_sheen"]
    );
    // Nothing to save without a weave.
    assert!(controls::save_woven(&source, &[]).is_err());
    let _ = std::fs::remove_dir_all(&dir);
}

/// Ctrl+click's pick: the material at a pixel of the read-back G-buffer, None on the background.
#[test]
fn a_click_picks_the_material_under_it() {
    let mut renderer = Renderer::new(common::context()).unwrap();
    let scene = weft::scene::default_scene();
    let (w, h) = (160u32, 120u32);
    let options = RenderOptions {
        width: w,
        height: h,
        ..Default::default()
    };
    renderer.render(&scene, &options).unwrap();
    let g = renderer.read_gbuffer().unwrap();
    let (cloth, _) = controls::fabric_materials(&scene)[0].clone();
    let mut seen = std::collections::BTreeSet::new();
    let mut background = 0;
    for y in 0..h {
        for x in 0..w {
            match controls::material_at(&g, w, x, y, &scene) {
                Some(m) => {
                    seen.insert(m);
                }
                None => background += 1,
            }
        }
    }
    assert!(seen.contains(&cloth), "the cloth is pickable: {seen:?}");
    assert!(seen.len() >= 2, "{seen:?}");
    assert!(background > 0, "the sky is no material");
    assert_eq!(controls::material_at(&g, w, w, 0, &scene), None);
    assert_eq!(controls::material_at(&g, w, 0, h, &scene), None);
}

/// The viewer plays a file's animation (KHR_animation_pointer drives the quad's base colour from
/// red at 0 s to blue at 1 s): `--time` starts it paused there, and a playing one runs with
/// validation on.
#[test]
fn the_viewer_plays_and_poses_animations() {
    let Some(xvfb) = xvfb_run() else {
        println!("SKIPPED the_viewer_plays_and_poses_animations: xvfb-run is not installed (tools/setup installs xvfb and xauth)");
        return;
    };
    let file =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/malformed/animation-pointer-valid.gltf");
    let dir = tempfile::tempdir().unwrap();
    let centre = |time: Option<&str>, name: &str| {
        let shot = dir.path().join(name);
        let mut args = vec![
            "view",
            "--validate",
            "--no-panel",
            "--size",
            "96x64",
            "--screenshot",
            shot.to_str().unwrap(),
            "--after",
            "4",
            file.to_str().unwrap(),
        ];
        if let Some(t) = time {
            args.extend(["--time", t]);
        }
        weft_in_xvfb(xvfb, &args);
        rgb(&shot).get_pixel(48, 32).0
    };
    let (red, blue) = (centre(Some("0"), "t0.png"), centre(Some("1"), "t1.png"));
    assert!(
        red[0] > 200 && red[2] < 100,
        "paused at 0 s: red, got {red:?}"
    );
    assert!(
        blue[2] > 200 && blue[0] < 100,
        "paused at 1 s: blue, got {blue:?}"
    );
    // Playing: posed every frame (each after the frame before has finished), no validation
    // message; its colour depends on the frames' wall time, so only that it ran.
    let _ = centre(None, "playing.png");
}
