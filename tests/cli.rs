//! The command line as a user meets it: errors are one clear sentence and a non-zero exit.

mod common;

use common::{temp_dir, weft, weft_without_gpu};

#[test]
fn no_vulkan_driver_says_what_to_install() {
    let dir = temp_dir("cli-nodriver");
    let out = weft()
        .args(["render", "-o"])
        .arg(dir.join("x.png"))
        .env("VK_ICD_FILENAMES", "/nonexistent")
        .env("VK_DRIVER_FILES", "/nonexistent")
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("No Vulkan driver found") && err.contains("apt-get install"),
        "{err}"
    );
    assert_eq!(
        err.trim().lines().count(),
        1,
        "one sentence, not a backtrace: {err}"
    );
    assert!(!dir.join("x.png").exists());
}

#[test]
fn missing_scene_file_is_named() {
    let out = weft()
        .args(["render", "/nonexistent/scene.gltf"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("/nonexistent/scene.gltf"), "{err}");
}

#[test]
fn non_gltf_file_is_named() {
    let dir = temp_dir("cli-notgltf");
    let path = dir.join("notes.gltf");
    std::fs::write(&path, "this is not glTF").unwrap();
    let out = weft().arg("render").arg(&path).output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("notes.gltf") && err.contains("glTF"), "{err}");
}

#[test]
fn bad_size_is_explained() {
    let out = weft().args(["render", "--size", "big"]).output().unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("WIDTHxHEIGHT"));
    let out = weft()
        .args(["render", "--size", "100000x100000"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("between 1 and"));
}

#[test]
fn render_writes_png_and_exr() {
    let dir = temp_dir("cli-render");
    let png = dir.join("out.png");
    let exr = dir.join("out.exr");
    let out = weft()
        .args([
            "render",
            "--validate",
            "--size",
            "128x72",
            "--timings",
            "--stats",
            "-o",
        ])
        .arg(&png)
        .arg("--exr")
        .arg(&exr)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("lighting")
            && stdout.contains("weave -> gbuffer -> occlusion -> lighting -> tonemap")
            && stdout.contains("(the PNG and the EXR encoded and written)")
            && stdout.contains("specialised before the driver"),
        "{stdout}"
    );
    let img = image::open(&png).unwrap().to_rgba8();
    assert_eq!(img.dimensions(), (128, 72));
    let hdr = image::open(&exr).unwrap().to_rgba32f();
    assert_eq!(hdr.dimensions(), (128, 72));
    assert!(hdr.as_raw().iter().all(|v| v.is_finite()));
}

// `weft plan --json` of the default scene with `args`: it succeeds, and its JSON.
fn plan_json(args: &[&str]) -> serde_json::Value {
    let out = weft().args(["plan", "--json"]).args(args).output().unwrap();
    assert!(
        out.status.success(),
        "weft plan --json {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

#[test]
fn plan_prints_the_default_scene() {
    let v = plan_json(&[]);
    // Lit by the built-in studio by default: its preprocessing comes first, the occlusion of its
    // light before the lighting; edge anti-aliasing last (weft render's default), and not with
    // --aa none.
    assert_eq!(
        v["passes"],
        serde_json::json!([
            "environment",
            "weave",
            "gbuffer",
            "occlusion",
            "lighting",
            "antialias"
        ])
    );
    // The tone curve compiled in (the others are not in the pipeline): nothing reads the HDR
    // image without --exr, so the lighting pass applies it and no tonemap pass runs.
    assert_eq!(v["tone_curve"], "pbr-neutral");
    assert_eq!(v["tone_in_lighting"], true);
    let v = plan_json(&["--tonemap", "agx"]);
    assert_eq!(v["tone_curve"], "agx");
    let v = plan_json(&["--debug-view", "normals"]);
    assert_eq!(v["tone_curve"], "passthrough");
    let v = plan_json(&["--aa", "none"]);
    assert_eq!(
        v["passes"],
        serde_json::json!(["environment", "weave", "gbuffer", "occlusion", "lighting"])
    );
    assert_eq!(v["supersample"], 1);
    assert!(
        v["occlusion"]["radius"].as_f64().is_some_and(|r| r > 0.0),
        "{v}"
    );
    // --occlusion none, or no environment: no occlusion pass.
    for args in [["--occlusion", "none"], ["--env", "none"]] {
        let n = plan_json(&args);
        let passes = n["passes"].as_array().expect("a list");
        assert!(
            !passes.contains(&serde_json::json!("occlusion")),
            "{args:?}: {n}"
        );
        assert!(n["occlusion"].is_null(), "{args:?}: {n}");
    }
    // --aa ss3: nine frames of the same passes, without the FXAA pass.
    let v3 = plan_json(&["--aa", "ss3"]);
    assert_eq!(v3["passes"], v["passes"]);
    assert_eq!(v3["supersample"], 3);
    let out = weft().args(["plan", "--aa", "ss9"]).output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("ssN") && err.contains("from 2 to 8"), "{err}");
    // A draft tried on the cloth: its thread colours are planned.
    assert_eq!(v["features"]["thread_colours"], false);
    let vt = plan_json(&[
        "--fabric",
        &format!(
            "red cloth=cotton-plain@8mm:{}/tests/data/drafts/tartan-twill.wif",
            env!("CARGO_MANIFEST_DIR")
        ),
    ]);
    assert_eq!(vt["features"]["thread_colours"], true);
    assert_eq!(v["environment"]["name"], "built-in studio");
    assert_eq!(v["environment"]["ibl"], "fis:8");
    assert!(v["lights"]["directional"].as_u64().unwrap() >= 1);
    // Without an environment there is nothing to preprocess.
    let v = plan_json(&["--env", "none"]);
    assert_eq!(
        v["passes"],
        serde_json::json!(["weave", "gbuffer", "lighting", "antialias"])
    );
    assert!(v["environment"].is_null());
}

#[test]
fn compare_writes_the_labelled_figure_and_rejects_unknown_shading() {
    let dir = temp_dir("cli-compare");
    let png = dir.join("figure.png");
    let out = weft()
        .args(["compare", "--validate", "--size", "160x90", "-o"])
        .arg(&png)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("Gouraud, Phong, Ashikhmin-Shirley, Fabric model"),
        "{err}"
    );
    // Four 160-px panels with 4-px margins in a row, a label strip under them.
    let img = image::open(&png).unwrap();
    assert_eq!(img.width(), 4 + 4 * (160 + 4));
    assert!(img.height() > 90 + 8, "{}", img.height());

    let out = weft()
        .args(["render", "--shading", "flat", "-o"])
        .arg(dir.join("x.png"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("unknown shading 'flat'") && err.contains("gouraud"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn relative_paths_start_where_the_user_is() {
    // A user's own folder: the scene, the environment and the output named relative to it.
    let dir = temp_dir("cli-relative");
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    std::fs::copy(root.join("assets/scenes/spheres.glb"), dir.join("mine.glb")).unwrap();
    std::fs::copy(
        root.join("tests/data/env/lebombo_1k.hdr"),
        dir.join("room.hdr"),
    )
    .unwrap();
    let out = weft()
        .current_dir(&dir)
        .args([
            "render", "mine.glb", "--env", "room.hdr", "--size", "64x36", "-o", "out.png",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(dir.join("out.png").exists());
    // A missing environment map is named, with what to do.
    let out = weft()
        .current_dir(&dir)
        .args(["render", "mine.glb", "--env", "missing.hdr", "-o", "x.png"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("missing.hdr") && err.contains("does not exist"),
        "{err}"
    );
    assert!(!dir.join("x.png").exists());
    // The scripts never change directory before the binary sees its arguments.
    for script in ["tools/weft", "tools/test"] {
        let text = std::fs::read_to_string(root.join(script)).unwrap();
        assert!(
            text.contains("--manifest-path") || script == "tools/test",
            "{script}"
        );
    }
    let weft_script = std::fs::read_to_string(root.join("tools/weft")).unwrap();
    assert!(
        !weft_script
            .lines()
            .any(|l| l.trim_start().starts_with("cd ")),
        "tools/weft must not cd"
    );
}

#[test]
fn bad_environment_flags_are_refused_clearly() {
    for (flag, value, expect) in [
        ("--background", "sky", "unknown background"),
        ("--ibl", "fis:0", "unknown IBL level"),
        ("--lights", "some", "unknown --lights"),
        ("--env-intensity", "-1", "out of range"),
    ] {
        let out = weft()
            .args(["render", flag, value, "--size", "32x18", "-o"])
            .arg(temp_dir("cli-badenv").join("never.png"))
            .output()
            .unwrap();
        assert!(!out.status.success(), "{flag} {value}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(expect), "{flag} {value}: {err}");
    }
    // A broken HDR (a PNG renamed) is named.
    let dir = temp_dir("cli-brokenhdr");
    std::fs::write(dir.join("bad.hdr"), b"#?RADIANCE\nnot really").unwrap();
    let out = weft()
        .args(["render", "--size", "32x18", "--env"])
        .arg(dir.join("bad.hdr"))
        .arg("-o")
        .arg(dir.join("o.png"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.hdr") && err.contains("cannot"), "{err}");
}

/// Bad values of the render flags are refused by the argument parser, before any Vulkan work:
/// with no Vulkan driver at all, the error is still the flag's, not "No Vulkan driver found".
#[test]
fn bad_flag_values_fail_before_any_gpu_work() {
    let cases: &[(&[&str], &str)] = &[
        (&["--frames", "0"], "--frames"),
        (&["--size", "big"], "WIDTHxHEIGHT"),
        (&["--size", "0x10"], "between 1 and"),
        (&["--size", "100000x100000"], "between 1 and"),
        (&["--accuracy", "supersampled:0"], "unknown accuracy"),
        (&["--weave-precision", "rgba32"], "rgba16f"),
        (&["--debug-view", "normal"], "roughness-metallic"),
        (&["--shading", "flat"], "unknown shading 'flat'"),
        (&["--eye", "1,2", "--target", "0,0,0"], "--eye '1,2'"),
        (&["--eye", "0,0,5", "--target", "0,nan,0"], "--target"),
    ];
    for (args, expect) in cases {
        let out = weft()
            .arg("render")
            .args(*args)
            .args(["-o", "/nonexistent/never-written.png"])
            .env("VK_ICD_FILENAMES", "/nonexistent")
            .env("VK_DRIVER_FILES", "/nonexistent")
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: bad input: {err}");
        assert!(
            err.starts_with("error: invalid value"),
            "{args:?}: clap's message: {err}"
        );
        assert!(err.contains(expect), "{args:?}: {err}");
        assert!(
            !err.contains("Vulkan"),
            "{args:?}: refused before Vulkan: {err}"
        );
    }
}

/// `--help` lists the values each choice flag takes, spelled as the flags accept them.
#[test]
fn help_lists_the_values_of_every_choice() {
    let out = weft().args(["render", "--help"]).output().unwrap();
    assert!(out.status.success());
    let help = String::from_utf8_lossy(&out.stdout);
    for values in [
        "[possible values: nearest, filtered-params, mixture, supersampled:N]",
        "[possible values: rgba8, rgba16f, analytic, sat]",
        "[possible values: none, albedo, normals, tangents, roughness-metallic, coverage, thread-dir, depth, occlusion]",
        "[possible values: gtao, gtao:R, gtao-screen, gtao-screen:R, gtao-nobounce, gtao-nobounce:R, none]",
        "[possible values: gouraud, phong, ashikhmin-shirley, fabric]",
    ] {
        assert!(help.contains(values), "{values} missing from:\n{help}");
    }
    // And every listed spelling is accepted (a plan needs no GPU).
    for (flag, value) in [
        ("--accuracy", "supersampled:4"),
        ("--accuracy", "filtered-params"),
        ("--weave-precision", "analytic"),
        ("--debug-view", "thread-dir"),
        ("--debug-view", "occlusion"),
        ("--occlusion", "gtao:0.25"),
        ("--occlusion", "gtao-screen"),
        ("--occlusion", "none"),
        ("--shading", "ashikhmin-shirley"),
    ] {
        let out = weft().args(["plan", flag, value]).output().unwrap();
        assert!(
            out.status.success(),
            "{flag} {value}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

/// An I/O error prints the OS's message once: `Error::Io` keeps it as its source only, and
/// weft prints the chain (it used to be in the message and the source both).
#[test]
fn os_message_appears_once() {
    let dir = temp_dir("cli-osmessage");
    let file = dir.join("a-file");
    std::fs::write(&file, "in the way").unwrap();
    let out = weft()
        .args(["shaders", "--out"])
        .arg(file.join("package"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    let os = std::io::Error::from_raw_os_error(20).to_string(); // ENOTDIR
    assert_eq!(err.matches(&os).count(), 1, "{err}");
    assert!(err.contains("a-file"), "{err}");
    let _ = std::fs::remove_dir_all(dir);
}

/// Every file in `dir` with its bytes, to show that a refused command changed nothing.
fn snapshot(dir: &std::path::Path) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            let bytes = std::fs::read(e.path()).unwrap_or_default();
            (e.file_name().to_string_lossy().into_owned(), bytes)
        })
        .collect();
    v.sort();
    v
}

/// Outputs may not be inputs, nor each other (project issue 30, defects 1 and 4): one check,
/// before any work, for every output of every command. Checked with no Vulkan driver: the
/// refusal comes first, and nothing in the folder changes.
#[test]
fn outputs_that_collide_with_inputs_or_each_other_are_refused_before_any_work() {
    let dir = temp_dir("cli-collide");
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    for f in std::fs::read_dir(root.join("tests/data/khronos/SimpleSkin/glTF")).unwrap() {
        let f = f.unwrap();
        std::fs::copy(f.path(), dir.join(f.file_name())).unwrap();
    }
    std::fs::copy(
        root.join("tests/data/env/lebombo_1k.hdr"),
        dir.join("room.hdr"),
    )
    .unwrap();
    let before = snapshot(&dir);
    // The scene again, through the folder's parent.
    let around = format!(
        "../{}/SimpleSkin.gltf",
        dir.file_name().unwrap().to_string_lossy()
    );
    let long = format!("{}.png", "n".repeat(300));
    let reads = "a file this command reads";
    let cases: Vec<(Vec<&str>, &str)> = vec![
        // The scene itself, by its name and by other spellings of it.
        (
            vec!["render", "SimpleSkin.gltf", "-o", "SimpleSkin.gltf"],
            reads,
        ),
        (
            vec!["render", "SimpleSkin.gltf", "-o", "./SimpleSkin.gltf"],
            reads,
        ),
        (vec!["render", "SimpleSkin.gltf", "-o", &around], reads),
        // A buffer the scene refers to, and the environment map.
        (
            vec!["render", "SimpleSkin.gltf", "-o", "skinGeometry.bin"],
            "skinGeometry.bin', a file this command reads",
        ),
        (
            vec![
                "render",
                "SimpleSkin.gltf",
                "--env",
                "room.hdr",
                "-o",
                "room.hdr",
            ],
            reads,
        ),
        (
            vec![
                "render",
                "SimpleSkin.gltf",
                "-o",
                "x.png",
                "--exr",
                "SimpleSkin.gltf",
            ],
            "--exr 'SimpleSkin.gltf'",
        ),
        // The two outputs of one render.
        (
            vec!["render", "SimpleSkin.gltf", "-o", "o.png", "--exr", "o.png"],
            "are the same file",
        ),
        (
            vec!["render", "-o", "o.png", "--exr", "./o.png"],
            "are the same file",
        ),
        // Other commands: the same check.
        (
            vec!["compare", "SimpleSkin.gltf", "-o", "SimpleSkin.gltf"],
            reads,
        ),
        (vec!["sheet", ".", "-o", "SimpleSkin.gltf"], reads),
        (
            vec!["view", "SimpleSkin.gltf", "--screenshot", "SimpleSkin.gltf"],
            reads,
        ),
        (
            vec![
                "fabric",
                "SimpleSkin.gltf",
                "-o",
                "SimpleSkin.gltf",
                "--material",
                "0",
                "--preset",
                "denim-twill",
            ],
            reads,
        ),
        // Names no file system takes, and directories.
        (vec!["render", "-o", &long], "at most 255"),
        (vec!["render", "-o", "."], "names no file"),
        (vec!["render", "-o", "sub/"], "names no file"),
    ];
    for (args, expect) in &cases {
        let o = weft_without_gpu()
            .current_dir(&dir)
            .args(args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        // (The scene's own warnings may come first.)
        assert!(
            err.lines()
                .any(|l| l.starts_with("error: ") && l.contains(expect)),
            "{args:?}: {err}"
        );
        assert!(
            !err.contains("Vulkan") && !err.contains("panicked"),
            "{args:?}: {err}"
        );
        assert_eq!(snapshot(&dir), before, "{args:?} changed the folder");
    }
    // The scene file was not replaced: still the same glTF, byte for byte.
    assert_eq!(
        std::fs::read(dir.join("SimpleSkin.gltf")).unwrap(),
        std::fs::read(root.join("tests/data/khronos/SimpleSkin/glTF/SimpleSkin.gltf")).unwrap()
    );
}

/// A failed single render leaves nothing behind (defect 7): its outputs are checked before the
/// render, and written all or none.
#[test]
fn a_failed_render_leaves_none_of_its_outputs() {
    let dir = temp_dir("cli-leftover");
    let o = weft()
        .current_dir(&dir)
        .args([
            "render",
            "--size",
            "16x9",
            "-o",
            "left.png",
            "--exr",
            "/nonexistent/o.exr",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("'/nonexistent' does not exist"), "{err}");
    assert!(
        !dir.join("left.png").exists(),
        "the PNG of a failed render was left"
    );
    assert!(snapshot(&dir).is_empty(), "{:?}", snapshot(&dir));
}

/// Degenerate sizes: a 1 x 1 image is 4 bytes, a quarter of the smallest readback buffer; it
/// panicked in the PNG encoder and left a 0-byte temporary file (defect 2).
#[test]
fn one_pixel_renders_write_one_pixel() {
    let dir = temp_dir("cli-onepixel");
    for size in ["1x1", "2x1", "1x3"] {
        let o = weft()
            .current_dir(&dir)
            .args([
                "render", "--size", size, "-o", "one.png", "--exr", "one.exr",
            ])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(0), "{size}: {err}");
        let (w, h) = weft::render::parse_size(size).unwrap();
        assert_eq!(
            image::open(dir.join("one.png"))
                .unwrap()
                .to_rgba8()
                .dimensions(),
            (w, h)
        );
        let hdr = image::open(dir.join("one.exr")).unwrap().to_rgba32f();
        assert_eq!(hdr.dimensions(), (w, h));
        assert!(hdr.as_raw().iter().all(|v| v.is_finite()));
        let names: Vec<String> = snapshot(&dir).into_iter().map(|(n, _)| n).collect();
        assert_eq!(
            names,
            ["one.exr", "one.png"],
            "{size}: something left behind"
        );
    }
}

/// A long file name the file system takes (250 bytes) is written: the temporary file's name,
/// which adds the process and thread ids, is kept under the limit too.
#[test]
fn the_longest_file_names_are_written() {
    let dir = temp_dir("cli-longname");
    let name = format!("{}.png", "l".repeat(246));
    assert_eq!(name.len(), 250);
    let o = weft()
        .current_dir(&dir)
        .args(["render", "--size", "8x8", "-o", &name])
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(dir.join(&name).is_file());
}

/// Non-finite numbers are refused where a flag enters, whatever uses it later (defect 6:
/// `--env-rotation NaN` with `--env none` placed the default key light at NaN).
#[test]
fn non_finite_number_flags_are_refused_before_any_gpu_work() {
    for (flag, value) in [
        ("--env-rotation", "NaN"),
        ("--env-rotation", "inf"),
        ("--env-intensity", "nan"),
        ("--exposure", "-inf"),
        ("--fov", "NaN"),
        ("--time", "inf"),
    ] {
        for extra in [&["--env", "none"][..], &[][..]] {
            let o = weft_without_gpu()
                .args(["render", flag, value, "-o", "/nonexistent/never.png"])
                .args(extra)
                .output()
                .unwrap();
            let err = String::from_utf8_lossy(&o.stderr);
            assert_eq!(o.status.code(), Some(1), "{flag} {value} {extra:?}: {err}");
            assert!(
                err.starts_with("error: invalid value")
                    && err.contains(&format!("{flag} {value} is not a finite number")),
                "{flag} {value}: {err}"
            );
        }
    }
    // In a batch, the same refusal is bad input (exit 2).
    let o = weft_without_gpu()
        .args([
            "render",
            "--frames-range",
            "0..1",
            "--dolly",
            "nan",
            "-o",
            "/nonexistent/f%d.png",
        ])
        .output()
        .unwrap();
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// `weft sheet --columns 0` is refused (it was accepted, and a sheet of one column made).
#[test]
fn sheet_columns_must_be_at_least_one() {
    let o = weft_without_gpu()
        .args([
            "sheet",
            "assets",
            "--columns",
            "0",
            "-o",
            "/nonexistent/s.png",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    assert!(err.contains("--columns") && err.contains("0"), "{err}");
    assert!(!err.contains("Vulkan"), "{err}");
}

/// `--tonemap` chooses the curve, the PNG says which (text chunk `weft:display`), and an unknown
/// name is refused with the choices.
#[test]
fn tonemap_is_chosen_and_written_into_the_png() {
    let dir = temp_dir("cli-tonemap");
    let text_of = |png: &std::path::Path| -> Vec<(String, String)> {
        let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(png).unwrap()));
        let reader = decoder.read_info().unwrap();
        reader
            .info()
            .uncompressed_latin1_text
            .iter()
            .map(|t| (t.keyword.clone(), t.text.clone()))
            .collect()
    };
    for (curve, exposure) in [
        ("pbr-neutral", "0"),
        ("aces", "0.5"),
        ("agx", "-1"),
        ("none", "0"),
    ] {
        let png = dir.join(format!("{curve}.png"));
        let out = weft()
            .args([
                "render",
                "--size",
                "32x18",
                "--tonemap",
                curve,
                "--exposure",
                exposure,
                "-o",
            ])
            .arg(&png)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let text = text_of(&png);
        // (weft render anti-aliases edges unless told --aa none.)
        let want = format!("tonemap {curve}, exposure {exposure} EV, aa fxaa");
        assert!(
            text.iter().any(|(k, v)| k == "weft:display" && *v == want),
            "{curve}: {text:?}"
        );
        assert!(text
            .iter()
            .any(|(k, v)| k == "Software" && v.starts_with("weft ")));
    }
    let out = weft()
        .args(["render", "--size", "32x18", "--tonemap", "filmic", "-o"])
        .arg(dir.join("x.png"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("unknown tone curve 'filmic'")
            && err.contains("pbr-neutral, aces, agx or none"),
        "{err}"
    );
}

#[test]
fn without_a_depth_stencil_format_the_frame_is_the_same() {
    // A device without D32_SFLOAT_S8_UINT (WEFT_NO_STENCIL=1 stands in for one) keeps a D32 depth
    // and shades every pixel with one lighting pipeline of the scene's kinds instead of one per
    // kind over the stencil: the same PNG, byte for byte, validation on.
    let dir = temp_dir("cli-no-stencil");
    let render = |name: &str, no_stencil: bool| {
        let png = dir.join(name);
        let mut cmd = weft();
        if no_stencil {
            cmd.env("WEFT_NO_STENCIL", "1");
        }
        let out = cmd
            .args(["render", "--validate", "--size", "160x90", "--stats", "-o"])
            .arg(&png)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let stdout = String::from_utf8_lossy(&out.stdout).to_string();
        (
            std::fs::read(&png).unwrap(),
            stdout.matches("lighting[").count(),
        )
    };
    let (split, split_pipelines) = render("split.png", false);
    let (one, one_pipelines) = render("one.png", true);
    assert_eq!(split_pipelines, 3, "background, fabric, glTF");
    assert_eq!(one_pipelines, 1);
    assert!(split == one, "the two paths' PNGs differ");
}

/// Bytes held by weft's entries (`KIND-HEX.bin`) in a cache directory.
fn cache_bytes(dir: &std::path::Path) -> (usize, u64) {
    std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().ends_with(".bin"))
        .fold((0, 0), |(n, b), e| (n + 1, b + e.metadata().unwrap().len()))
}

#[test]
fn the_cache_on_disk_stays_within_its_limit_and_can_be_cleared() {
    let dir = temp_dir("cli-cache");
    let cache = dir.join("cache");
    let png = dir.join("x.png");
    // weft with this test's cache directory and, when given, its size limit.
    let cache_command = |args: &[&str], limit: Option<&str>| {
        let mut c = weft();
        c.args(args).env("WEFT_CACHE_DIR", &cache);
        if let Some(limit) = limit {
            c.env("WEFT_CACHE_MAX_SIZE", limit);
        }
        c.output().unwrap()
    };
    let render = |env: &str, limit: Option<u64>| {
        let args = [
            "render",
            "--size",
            "64x36",
            "--env",
            env,
            "-o",
            png.to_str().unwrap(),
        ];
        let out = cache_command(&args, limit.map(|l| l.to_string()).as_deref());
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    };
    let lebombo = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/env/lebombo_1k.hdr");
    // No limit to speak of: the studio's run fills the cache with what it made.
    render("studio", None);
    let (studio_entries, studio_bytes) = cache_bytes(&cache);
    assert!(
        studio_entries >= 2 && studio_bytes > 1 << 20,
        "{studio_entries} {studio_bytes}"
    );
    // A second environment's preprocessing does not fit beside the first in a limit a little over
    // the first run's: the least recently used go, and what this run made stays.
    let limit = studio_bytes + studio_bytes / 8;
    render(lebombo, Some(limit));
    let (_, bytes) = cache_bytes(&cache);
    assert!(bytes <= limit, "{bytes} bytes over the limit of {limit}");
    let names: Vec<String> = std::fs::read_dir(&cache)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(
        names
            .iter()
            .filter(|n| n.starts_with("environment-"))
            .count(),
        1,
        "only the latest environment fits: {names:?}"
    );
    // The cache read back as a run would use it: the same entry again, nothing removed.
    render(lebombo, Some(limit));
    assert_eq!(cache_bytes(&cache).1, bytes);

    // `weft cache` says where it is, its limit and what it holds; --clear removes weft's files
    // and nothing else.
    std::fs::write(cache.join("notes.txt"), "the user's").unwrap();
    let out = cache_command(&["cache"], Some("512M"));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    assert!(
        text.contains(&cache.display().to_string())
            && text.contains("limit 512.0 MiB")
            && text.contains("| environment | 1 |"),
        "{text}"
    );
    let out = cache_command(&["cache", "--clear"], None);
    assert!(out.status.success());
    assert_eq!(cache_bytes(&cache), (0, 0));
    assert!(cache.join("notes.txt").exists());
    // A limit that is not a size is said, and the cache keeps its default.
    let out = cache_command(&["cache"], Some("lots"));
    assert!(out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("WEFT_CACHE_MAX_SIZE") && err.contains("512M"),
        "{err}"
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("limit 1.00 GiB"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_reader_that_stops_early_is_not_a_crash() {
    // `weft fabric --list-presets | head -1`: the pipe is closed before weft writes to it.
    for args in [&["fabric", "--list-presets"][..], &["cache"][..]] {
        let mut child = weft_without_gpu()
            .args(args)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stdout.take());
        let out = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            !err.contains("panicked") && !err.contains("Broken pipe"),
            "{args:?}: {err}"
        );
        assert!(out.status.success(), "{args:?}: {:?} {err}", out.status);
    }
}
