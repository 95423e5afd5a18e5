//! `weft fidelity` end to end on a scenario made here: the default scene as the model, the
//! repository's HDR as the environment, and published thumbnails made from weft's own render
//! (the reference) and a darkened copy (a second engine). The real scenarios and thumbnails live
//! in ../shared/fidelity/ (docs/fidelity.md); this checks the command's plumbing and ranking.

mod common;

use std::path::Path;

use common::weft;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

fn save_webp(img: &image::RgbaImage, path: &Path) {
    let file = std::fs::File::create(path).unwrap();
    img.write_with_encoder(image::codecs::webp::WebPEncoder::new_lossless(file))
        .unwrap();
}

#[test]
fn scores_and_ranks_weft_among_the_engines() {
    let dir = common::temp_dir("fidelity");
    let shared = dir.join("shared");
    let fid = shared.join("fidelity");
    let thumbs = fid.join("thumbnails").join("khronos-Default");
    std::fs::create_dir_all(&thumbs).unwrap();
    std::fs::create_dir_all(shared.join("realworld")).unwrap();
    std::fs::create_dir_all(fid.join("environments")).unwrap();
    std::fs::copy(
        Path::new(ROOT).join("assets/default.glb"),
        shared.join("realworld/default.glb"),
    )
    .unwrap();
    std::fs::copy(
        Path::new(ROOT).join("tests/data/env/lebombo_1k.hdr"),
        fid.join("environments/env.hdr"),
    )
    .unwrap();
    let scenario = serde_json::json!({
        "model": "realworld/default.glb", "eye": [0.0, 1.6, 4.0], "target": [0.0, 0.8, 0.0],
        "vertical_fov_deg": 40.0, "size": [48, 32], "environment": "environments/env.hdr",
        "skybox": false
    });
    std::fs::write(
        fid.join("scenarios.json"),
        serde_json::to_string(&serde_json::json!({ "khronos-Default": scenario })).unwrap(),
    )
    .unwrap();

    // The generator's way of calling a renderer: one JSON argument, twice the scenario's size.
    let full = dir.join("full.png");
    let arg = serde_json::json!({"scenario": scenario, "outputFile": full}).to_string();
    let o = weft()
        .args(["fidelity", "--shared"])
        .arg(&shared)
        .args(["--scenario", &arg])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let full = image::open(&full).unwrap().to_rgba8();
    assert_eq!(full.dimensions(), (96, 64));
    // The background is transparent (skybox false), the model is not.
    assert!(full.pixels().any(|p| p.0[3] == 0) && full.pixels().any(|p| p.0[3] == 255));

    // Thumbnails: the reference is weft's own (so weft scores -inf), "filament" 20 levels darker.
    let reference = weft::fidelity::thumbnail(&full, 48, 32).unwrap();
    save_webp(&reference, &thumbs.join("blender-cycles.webp"));
    let mut dark = reference.clone();
    for p in dark.pixels_mut() {
        for c in &mut p.0[..3] {
            *c = c.saturating_sub(20);
        }
    }
    save_webp(&dark, &thumbs.join("filament.webp"));
    let filament = weft::fidelity::score(&reference, &dark).unwrap();
    assert!(filament.is_finite() && filament < -10.0, "{filament}");

    let out = dir.join("out");
    let o = weft()
        .args(["fidelity", "--shared"])
        .arg(&shared)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let row = stdout
        .lines()
        .find(|l| l.starts_with("Default"))
        .expect(&stdout);
    assert!(
        row.contains("weft   -inf dB") && row.contains("weft 1 of 2"),
        "{row}"
    );
    assert!(row.contains(&format!("{filament:.1}")), "{row}");
    let md = std::fs::read_to_string(out.join("fidelity.md")).unwrap();
    assert!(md.contains("| Default | -inf | filament"), "{md}");
    let sheet = image::open(out.join("sheet.png")).unwrap();
    assert_eq!(sheet.width(), 3 * (256 + 4));

    // --ibl reaches weft's renders: with its Monte Carlo estimate the cloth is not the image the
    // reference was made from, so weft no longer scores -inf.
    let o = weft()
        .args(["fidelity", "--shared"])
        .arg(&shared)
        .arg("--out")
        .arg(dir.join("out-mc"))
        .args(["--ibl", "mc:4"])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{stdout}");
    let row = stdout
        .lines()
        .find(|l| l.starts_with("Default"))
        .expect(&stdout);
    assert!(!row.contains("-inf"), "{row}");
    // A level weft does not know is refused, naming the flag.
    let o = weft()
        .args(["fidelity", "--ibl", "fis:many"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && stderr.contains("--ibl"), "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}
