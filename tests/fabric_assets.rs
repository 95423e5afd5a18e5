//! `weft fabric` and `weft render --fabric` (weft::assets) on the repository's own scenes:
//! the output passes the Khronos glTF Validator with no errors, loads back with the fabric on the
//! chosen materials and nowhere else, leaves every other part of the file as it was (JSON minus
//! the added keys; a .glb's BIN chunk and a .gltf's external buffer byte for byte), converts the
//! pitch with the mesh's UV density and node scale, and renders with the weave (lavapipe,
//! validation on).

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use serde_json::{json, Value};
use weft::assets::{self, Container, MaterialRef, Overrides, Request, Source};
use weft::fabric::{presets, WeavePattern, EXTENSION_NAME};
use weft::scene;

use common::{temp_dir, weft};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");
const VALIDATOR_VERSION: &str = "2.0.0-dev.3.10";

fn asset(name: &str) -> PathBuf {
    Path::new(ROOT).join("assets").join(name)
}

fn request(materials: &[&str], preset: &str, pitch: Option<&str>) -> Request {
    Request {
        materials: materials.iter().map(|m| MaterialRef::parse(m)).collect(),
        source: Source::parse(preset).unwrap(),
        overrides: Overrides {
            pitch_m: pitch.map(|p| assets::parse_length(p).unwrap()),
            ..Default::default()
        },
    }
}

/// Transforms the file at `path` in memory.
fn transform(path: &Path, requests: &[Request]) -> weft::Result<(Vec<u8>, Vec<assets::Applied>)> {
    let bytes = std::fs::read(path).unwrap();
    assets::transform(&bytes, &path.display().to_string(), path.parent(), requests)
}

/// The validator's directory, installed on first use (the test's set-up, as tools/setup does);
/// None, with the reason printed, only when node or npm is missing.
fn validator() -> Option<PathBuf> {
    static DIR: OnceLock<Option<PathBuf>> = OnceLock::new();
    DIR.get_or_init(|| {
        let have = |tool: &str| {
            Command::new(tool)
                .arg("--version")
                .output()
                .is_ok_and(|o| o.status.success())
        };
        if !have("node") || !have("npm") {
            println!("SKIPPED: node/npm are not installed, so the Khronos glTF Validator cannot run (apt-get install nodejs npm; tools/setup installs the validator)");
            return None;
        }
        let dir = Path::new(ROOT).join("target/gltf-validator");
        let package = dir.join("node_modules/gltf-validator/package.json");
        let installed = std::fs::read_to_string(&package)
            .is_ok_and(|t| t.contains(&format!("\"version\": \"{VALIDATOR_VERSION}\"")));
        if !installed {
            std::fs::create_dir_all(&dir).unwrap();
            let out = Command::new("npm")
                .args(["install", "--silent", "--no-audit", "--no-fund", "--prefix"])
                .arg(&dir)
                .arg(format!("gltf-validator@{VALIDATOR_VERSION}"))
                .output()
                .unwrap();
            assert!(
                out.status.success(),
                "npm install gltf-validator failed: {}",
                String::from_utf8_lossy(&out.stderr)
            );
        }
        Some(dir.join("node_modules/gltf-validator"))
    })
    .clone()
}

/// The validator's report on `file`: (errors, the printed summary).
fn validate(dir: &Path, file: &Path) -> (u64, String) {
    let out = Command::new("node")
        .arg(Path::new(ROOT).join("tools/gltf-validator/validate.cjs"))
        .arg(file)
        .env("WEFT_GLTF_VALIDATOR", dir)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    let report: Value = text
        .lines()
        .last()
        .and_then(|l| serde_json::from_str(l).ok())
        .unwrap_or_else(|| {
            panic!(
                "no report from the validator on {}: {text}{}",
                file.display(),
                String::from_utf8_lossy(&out.stderr)
            )
        });
    let errors = report["issues"]["numErrors"].as_u64().expect("numErrors");
    let summary: String = text
        .lines()
        .filter(|l| !l.starts_with('{'))
        .collect::<Vec<_>>()
        .join("\n");
    (errors, summary)
}

#[test]
fn output_passes_the_khronos_validator_with_no_errors() {
    let Some(dir) = validator() else { return };
    let out = temp_dir("fabric-assets-validator");
    let cases: &[(&str, &str, &[&str], &str)] = &[
        ("default.gltf", "d.gltf", &["ball", "floor"], "denim-twill"),
        ("default.glb", "d.glb", &["0"], "silk-satin"),
        ("scenes/spheres.glb", "s.glb", &["0", "1"], "cotton-plain"),
        ("scenes/twill_satin.glb", "t.glb", &["0"], "polyester-plain"),
    ];
    for (input, output, materials, preset) in cases {
        let path = out.join(output);
        let o = weft()
            .arg("fabric")
            .arg(asset(input))
            .arg("-o")
            .arg(&path)
            .arg("--material")
            .arg(materials.join(","))
            .args(["--preset", preset])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let (errors, summary) = validate(&dir, &path);
        println!("{summary}");
        assert_eq!(errors, 0, "{summary}");
        // The input was valid too: the count is not 0 because the validator ran on nothing.
        assert!(summary.contains("0 error(s)"), "{summary}");
        assert!(summary.contains("WEFT_materials_fabric"), "{summary}");
    }
}

#[test]
fn output_loads_back_with_the_fabric_on_the_chosen_materials_only() {
    let (bytes, applied) = transform(
        &asset("default.glb"),
        &[request(&["ball", "3"], "denim-twill", Some("1mm"))],
    )
    .unwrap();
    assert_eq!(applied.len(), 2);
    let scene = scene::load_slice(&bytes, "out.glb", None).unwrap();
    let original = scene::default_scene();
    for (i, m) in scene.materials.iter().enumerate() {
        match m.name.as_str() {
            "ball" | "polished steel" => {
                let f = m.fabric.as_ref().expect("fabric on a chosen material");
                assert_eq!(f.pattern, WeavePattern::twill());
                let a = applied.iter().find(|a| a.index == i).unwrap();
                assert_eq!(f.repeat, a.params.repeat);
                assert_eq!(f.rd_warp, presets::by_name("denim-twill").unwrap().rd_warp);
                // The fallback: dielectric, the far-field albedo as base colour.
                assert_eq!(m.metallic, 0.0);
                let albedo = assets::far_field_albedo(&a.params);
                for (got, want) in m.base_color.iter().zip(albedo) {
                    assert!((*got as f64 - want).abs() < 1e-5, "{got} vs {want}");
                }
            }
            // The cloth keeps its own fabric, the floor stays without.
            _ => assert_eq!(m.fabric, original.materials[i].fabric, "{}", m.name),
        }
    }
    let warnings: Vec<String> = scene.warnings.iter().map(|w| w.0.clone()).collect();
    assert!(
        warnings.iter().all(|w| !w.contains(EXTENSION_NAME)),
        "{warnings:?}"
    );
}

/// Removes `materials[i].<path>` for every chosen material and the names from extensionsUsed.
fn strip_added(doc: &mut Value, chosen: &[usize]) {
    for &i in chosen {
        let m = &mut doc["materials"][i];
        if let Some(e) = m.get_mut("extensions").and_then(Value::as_object_mut) {
            e.remove(EXTENSION_NAME);
            e.remove(assets::SHEEN_EXTENSION);
            if e.is_empty() {
                m.as_object_mut().unwrap().remove("extensions");
            }
        }
        if let Some(p) = m
            .get_mut("pbrMetallicRoughness")
            .and_then(Value::as_object_mut)
        {
            p.remove("baseColorFactor");
            p.remove("metallicFactor");
            if p.is_empty() {
                m.as_object_mut().unwrap().remove("pbrMetallicRoughness");
            }
        }
    }
    if let Some(used) = doc.get_mut("extensionsUsed").and_then(Value::as_array_mut) {
        used.retain(|e| e != EXTENSION_NAME && e != assets::SHEEN_EXTENSION);
    }
}

#[test]
fn everything_else_in_the_file_is_unchanged() {
    // .glb: JSON minus the added keys equal; BIN chunk byte for byte.
    let input = std::fs::read(asset("scenes/spheres.glb")).unwrap();
    let (out, applied) = transform(
        &asset("scenes/spheres.glb"),
        &[request(&["1", "2"], "cotton-plain", None)],
    )
    .unwrap();
    let before = Container::split(&input, "in").unwrap();
    let after = Container::split(&out, "out").unwrap();
    assert!(after.glb);
    assert!(before.bin.is_some());
    assert!(before.bin == after.bin, "the BIN chunk changed");
    let chosen: Vec<usize> = applied.iter().map(|a| a.index).collect();
    assert_eq!(chosen, vec![1, 2]);
    // The keys it adds are there, in extensionsUsed and not required.
    let used = after.json["extensionsUsed"].as_array().unwrap();
    assert!(
        used.contains(&json!(EXTENSION_NAME)) && used.contains(&json!(assets::SHEEN_EXTENSION))
    );
    let required = after
        .json
        .get("extensionsRequired")
        .cloned()
        .unwrap_or(json!([]));
    assert_eq!(
        required,
        before
            .json
            .get("extensionsRequired")
            .cloned()
            .unwrap_or(json!([]))
    );
    for &i in &chosen {
        assert!(after.json["materials"][i]["extensions"][EXTENSION_NAME].is_object());
    }
    let (mut a, mut b) = (after.json.clone(), before.json.clone());
    strip_added(&mut a, &chosen);
    strip_added(&mut b, &chosen);
    assert_eq!(a, b);
    // A material that was not chosen is the same to the last key (not only after stripping).
    assert_eq!(after.json["materials"][0], before.json["materials"][0]);

    // .gltf written to another folder: JSON likewise, the external buffer copied beside it.
    let dir = temp_dir("fabric-assets-unchanged");
    let path = dir.join("sub").join("copy.gltf");
    let o = weft()
        .arg("fabric")
        .arg(asset("default.gltf"))
        .arg("-o")
        .arg(&path)
        .args([
            "--material",
            "floor",
            "--preset",
            "polyester-plain",
            "--pitch",
            "0.5cm",
        ])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        stdout.contains("cells per UV unit") && stdout.contains("world pitch 5.000 mm"),
        "{stdout}"
    );
    assert_eq!(
        std::fs::read(dir.join("sub/default.bin")).unwrap(),
        std::fs::read(asset("default.bin")).unwrap()
    );
    let mut a: Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    let mut b: Value =
        serde_json::from_slice(&std::fs::read(asset("default.gltf")).unwrap()).unwrap();
    strip_added(&mut a, &[0]);
    strip_added(&mut b, &[0]);
    assert_eq!(a, b);
    // And it loads from there (its URI resolves).
    let s = scene::load(&path).unwrap();
    assert!(s.materials[0].fabric.is_some());
}

#[test]
fn pitch_follows_uv_density_and_node_scale() {
    let input = std::fs::read(asset("default.gltf")).unwrap();
    let base = asset(".");
    let run = |doc: &Value, pitch: &str| {
        let bytes = serde_json::to_vec(doc).unwrap();
        let (_, applied) = assets::transform(
            &bytes,
            "test.gltf",
            Some(&base),
            &[request(&["floor"], "cotton-plain", Some(pitch))],
        )
        .unwrap();
        applied.into_iter().next().unwrap()
    };
    let doc: Value = serde_json::from_slice(&input).unwrap();
    let a = run(&doc, "2mm");
    // The floor is a plane whose UV unit spans 1 m (tools/make_default_scene.py): 500 cells of 2 mm.
    assert!(
        (a.density.metres_per_uv - 1.0).abs() < 1e-4,
        "{:?}",
        a.density
    );
    assert!(
        (a.cells_per_uv() - 500.0).abs() < 0.05,
        "{}",
        a.cells_per_uv()
    );
    assert!((a.density.metres_per_uv / a.cells_per_uv() - 2e-3).abs() < 1e-9);
    // Units: 0.2 cm is 2 mm.
    assert!((run(&doc, "0.2cm").cells_per_uv() - a.cells_per_uv()).abs() < 1e-3);
    // The floor's node scaled by 3: three times the world per UV unit, three times the cells.
    let mut scaled = doc.clone();
    let node = scaled["nodes"]
        .as_array_mut()
        .unwrap()
        .iter_mut()
        .find(|n| {
            n.get("mesh").and_then(Value::as_u64) == Some(0)
                || n.get("name") == Some(&json!("floor"))
        })
        .expect("the floor's node");
    assert!(node.get("matrix").is_none(), "the test scales a TRS node");
    node["scale"] = json!([3.0, 3.0, 3.0]);
    let b = run(&scaled, "2mm");
    assert!(
        (b.density.metres_per_uv - 3.0).abs() < 1e-3,
        "{:?}",
        b.density
    );
    assert!((b.cells_per_uv() / a.cells_per_uv() - 3.0).abs() < 1e-3);

    // A material only a KHR_materials_variants variant puts on the floor is measured there.
    let mut variants = doc.clone();
    let mut velvet = variants["materials"][0].clone();
    velvet["name"] = json!("velvet");
    variants["materials"].as_array_mut().unwrap().push(velvet);
    let velvet_index = variants["materials"].as_array().unwrap().len() - 1;
    variants["extensions"]["KHR_materials_variants"] = json!({"variants": [{"name": "soft"}]});
    variants["extensionsUsed"]
        .as_array_mut()
        .unwrap()
        .push(json!("KHR_materials_variants"));
    variants["meshes"][0]["primitives"][0]["extensions"] = json!({"KHR_materials_variants":
        {"mappings": [{"material": velvet_index, "variants": [0]}]}});
    let bytes = serde_json::to_vec(&variants).unwrap();
    let (_, applied) = assets::transform(
        &bytes,
        "variants.gltf",
        Some(&base),
        &[request(&["velvet"], "cotton-plain", Some("2mm"))],
    )
    .unwrap();
    assert_eq!(applied[0].density, a.density);
    assert!(applied[0]
        .notes
        .iter()
        .any(|n| n.contains("KHR_materials_variants")));
}

#[test]
fn user_errors_are_clear_and_name_the_material_and_key() {
    let path = asset("default.gltf");
    let err = |requests: &[Request]| transform(&path, requests).unwrap_err().to_string();
    let e = err(&[request(&["curtain"], "cotton-plain", None)]);
    assert!(e.contains("'curtain'") && e.contains("'floor'"), "{e}");
    let e = err(&[request(&["9"], "cotton-plain", None)]);
    assert!(e.contains("no material 9"), "{e}");
    let e = err(&[request(&["floor", "0"], "cotton-plain", None)]);
    assert!(e.contains("twice"), "{e}");
    let e = err(&[request(&["floor"], "from-sheen", None)]);
    assert!(
        e.contains("'floor'") && e.contains("KHR_materials_sheen"),
        "{e}"
    );
    // A pitch that cannot be a repeat.
    let e = err(&[request(&["floor"], "cotton-plain", Some("1e-9mm"))]);
    assert!(e.contains("'floor'") && e.contains("unit"), "{e}");

    // A material whose mesh has no UVs.
    let mut doc: Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    let floor_mesh = doc["meshes"]
        .as_array_mut()
        .unwrap()
        .iter_mut()
        .find(|m| m["primitives"][0]["material"] == json!(0))
        .unwrap();
    floor_mesh["primitives"][0]["attributes"]
        .as_object_mut()
        .unwrap()
        .remove("TEXCOORD_0");
    let bytes = serde_json::to_vec(&doc).unwrap();
    let e = assets::transform(
        &bytes,
        "nouv.gltf",
        path.parent(),
        &[request(&["floor"], "cotton-plain", None)],
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("'floor'") && e.contains("TEXCOORD_0"), "{e}");

    // from-sheen on a wrongly typed sheen key.
    let mut doc: Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    doc["materials"][0]["extensions"] =
        json!({"KHR_materials_sheen": {"sheenColorFactor": [1, 0]}});
    let bytes = serde_json::to_vec(&doc).unwrap();
    let e = assets::transform(
        &bytes,
        "sheen.gltf",
        path.parent(),
        &[request(&["floor"], "from-sheen", None)],
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("'floor'") && e.contains("sheenColorFactor"),
        "{e}"
    );

    // On the command line: one line, non-zero exit, nothing written.
    let dir = temp_dir("fabric-assets-errors");
    for (args, needle) in [
        (vec!["--material", "floor", "--preset", "tweed"], "tweed"),
        (
            vec![
                "--material",
                "floor",
                "--preset",
                "denim-twill",
                "--pitch",
                "0.8",
            ],
            "no unit",
        ),
        (
            vec![
                "--material",
                "floor",
                "--preset",
                "denim-twill",
                "--pitch",
                "2ft",
            ],
            "'ft'",
        ),
        (
            vec!["--material", "curtain", "--preset", "denim-twill"],
            "'curtain'",
        ),
        (
            vec![
                "--material",
                "floor",
                "--preset",
                "denim-twill",
                "--rd",
                "1,2",
            ],
            "--rd",
        ),
    ] {
        let out = dir.join("x.gltf");
        let o = weft()
            .arg("fabric")
            .arg(&path)
            .arg("-o")
            .arg(&out)
            .args(&args)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{args:?} succeeded");
        assert!(stderr.contains(needle), "{args:?}: {stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
        assert!(!out.exists());
    }
}

#[test]
fn from_sheen_maps_and_says_what_it_mapped() {
    let path = asset("default.gltf");
    let mut doc: Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    doc["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"] = json!([0.5, 0.1, 0.05, 1.0]);
    doc["materials"][0]["extensions"] = json!({"KHR_materials_sheen": {"sheenColorFactor": [1.0, 0.3, 0.1], "sheenRoughnessFactor": 0.5}});
    let bytes = serde_json::to_vec(&doc).unwrap();
    let (out, applied) = assets::transform(
        &bytes,
        "sheen.gltf",
        path.parent(),
        &[request(&["floor"], "from-sheen", None)],
    )
    .unwrap();
    let a = &applied[0];
    assert_eq!(a.params.rd_warp, [0.5, 0.1, 0.05]);
    assert!(a.params.e_along > a.params.e_across);
    let text = a.to_string();
    assert!(
        text.contains("sheenRoughnessFactor 0.5") && text.contains("not mapped"),
        "{text}"
    );
    // The sheen itself is kept as the fallback; nothing else in the material changes.
    let after: Value = serde_json::from_slice(&out).unwrap();
    let mut m = after["materials"][0].clone();
    m["extensions"]
        .as_object_mut()
        .unwrap()
        .remove(EXTENSION_NAME);
    assert_eq!(m, doc["materials"][0]);
}

#[test]
fn render_fabric_flag_renders_the_weave() {
    // The same transform in memory, then the GPU: the floor's G-buffer shows warp-up and weft-up
    // cells where it had no fabric before (lavapipe, validation on).
    let (scene, applied) = assets::load_with_fabric(
        None,
        &["floor=cotton-plain@5cm".to_string()],
        &Default::default(),
    )
    .unwrap();
    assert_eq!(applied[0].name, "floor");
    let mut renderer = weft::render::Renderer::new(common::context()).expect("renderer");
    let options = weft::render::RenderOptions {
        width: 240,
        height: 180,
        ..Default::default()
    };
    let mut fractions = Vec::new();
    for scene in [scene::default_scene(), scene] {
        renderer.render(&scene, &options).expect("render");
        let g = renderer.read_gbuffer().expect("gbuffer");
        let (mut floor, mut fabric, mut warp, mut weft_up) = (0, 0, 0, 0);
        for i in 0..(options.width * options.height) as usize {
            if g.depth[i] <= 0.0 || g.surface[i * 4 + 1].round() as usize != 0 {
                continue;
            }
            floor += 1;
            // Threads on top (the fabric target is all zero for a material without fabric or
            // sheen, as the default floor).
            if g.fabric[i * 4] + g.fabric[i * 4 + 1] > 0.05 {
                fabric += 1;
                warp += (g.fabric[i * 4] > 0.8) as usize;
                weft_up += (g.fabric[i * 4 + 1] > 0.8) as usize;
            }
        }
        println!("floor pixels {floor}: fabric {fabric}, warp-up {warp}, weft-up {weft_up}");
        fractions.push((floor, fabric, warp, weft_up));
    }
    let (floor0, fabric0, _, _) = fractions[0];
    let (floor1, fabric1, warp, weft_up) = fractions[1];
    assert!(floor0 > 1000 && floor1 == floor0, "{fractions:?}");
    assert_eq!(fabric0, 0, "the floor had no fabric");
    assert_eq!(fabric1, floor1, "every floor pixel is fabric");
    // A plain weave near the camera: both threads on top in a good share of the pixels.
    assert!(warp > floor1 / 20 && weft_up > floor1 / 20, "{fractions:?}");

    // And through the command line, which prints what it did.
    let dir = temp_dir("fabric-assets-render");
    let o = weft()
        .args([
            "render",
            "--validate",
            "--size",
            "96x72",
            "--fabric",
            "floor=cotton-plain@5cm",
            "-o",
        ])
        .arg(dir.join("r.png"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(
        stderr.contains("cells per UV unit") && stderr.contains("world pitch 5.00 cm"),
        "{stderr}"
    );
    assert!(dir.join("r.png").exists());
}

#[test]
fn a_weaving_draft_gives_the_weave_and_the_thread_colours() {
    // tests/data/drafts/twill-2-2-denim.wif: a 2/2 twill, indigo warp (79,157,431 of 999), natural
    // weft (900,880,820 of 999), the way a weaving program writes it.
    let draft = Path::new(ROOT).join("tests/data/drafts/twill-2-2-denim.wif");
    let dir = temp_dir("fabric-assets-draft");
    let out = dir.join("out.glb");
    // `weft fabric` on the default scene's ball with a draft, more flags, and an output.
    let fabric = |draft: &Path, more: &[&str], out: &Path| {
        weft()
            .args(["fabric", "--material", "ball", "--preset", "cotton-plain"])
            .args(more)
            .arg("--draft")
            .arg(draft)
            .arg("-o")
            .arg(out)
            .arg(asset("default.glb"))
            .output()
            .unwrap()
    };
    let o = fabric(&draft, &[], &out);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(
        stderr.contains("16 warp threads x 12 picks, weave repeat 4 x 4 cells"),
        "{stderr}"
    );
    let scene = scene::load(&out).unwrap();
    let ball = scene.materials.iter().find(|m| m.name == "ball").unwrap();
    let f = ball.fabric.as_ref().expect("fabric on the ball");
    assert_eq!(f.pattern.to_rows(), ["||--", "-||-", "--||", "|--|"]);
    // sRGB on the palette's 0..999 scale, decoded to linear.
    let lin = |v: f64| {
        let c = v / 999.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    for (got, want) in f.rd_warp.iter().zip([79.0, 157.0, 431.0].map(lin)) {
        assert!((*got as f64 - want).abs() < 1e-4, "warp {:?}", f.rd_warp);
    }
    for (got, want) in f.rd_weft.iter().zip([900.0, 880.0, 820.0].map(lin)) {
        assert!((*got as f64 - want).abs() < 1e-4, "weft {:?}", f.rd_weft);
    }

    // --pattern and --draft together are refused; a draft that does not parse names the file.
    let o = fabric(&draft, &["--pattern", "plain"], &dir.join("x.glb"));
    assert!(!o.status.success());
    let bad = dir.join("bad.wif");
    std::fs::write(&bad, "[WIF]\nVersion=1.1\n[WEAVING]\nShafts=2\n[WARP]\nThreads=2\n[WEFT]\nThreads=2\n[THREADING]\n1=1\n2=3\n[LIFTPLAN]\n1=1\n2=2\n").unwrap();
    let o = fabric(&bad, &[], &dir.join("y.glb"));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        stderr.contains("bad.wif")
            && stderr.contains("[THREADING] line 11")
            && stderr.contains("shaft 3 is out of range"),
        "{stderr}"
    );
    assert!(!dir.join("y.glb").exists(), "nothing written on an error");

    // The same draft through --fabric's MATERIAL=PRESET@PITCH:DRAFT form, in memory.
    let spec = format!("red cloth=cotton-plain@4mm:{}", draft.display());
    let (scene, applied) = assets::load_with_fabric(None, &[spec], &Default::default()).unwrap();
    assert_eq!(applied[0].name, "red cloth");
    let cloth = scene
        .materials
        .iter()
        .find(|m| m.name == "red cloth")
        .unwrap();
    assert_eq!(
        cloth.fabric.as_ref().unwrap().pattern.to_rows(),
        ["||--", "-||-", "--||", "|--|"]
    );
    let e = assets::load_with_fabric(
        None,
        &["red cloth=cotton-plain:missing.wif".to_string()],
        &Default::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("missing.wif"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_sheet_from_the_flag_or_from_khr_materials_diffuse_transmission() {
    let path = asset("default.gltf");
    let mut doc: Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    doc["materials"][0]["extensions"] =
        json!({"KHR_materials_diffuse_transmission": {"diffuseTransmissionFactor": 0.35}});
    let bytes = serde_json::to_vec(&doc).unwrap();
    let run = |request: Request| {
        let (out, applied) =
            assets::transform(&bytes, "sheet.gltf", path.parent(), &[request]).unwrap();
        let after: Value = serde_json::from_slice(&out).unwrap();
        let written = after["materials"][0]["extensions"][EXTENSION_NAME]["transmission"].clone();
        (
            applied[0].params.transmission,
            written,
            applied[0].to_string(),
        )
    };
    // The file says its surface lets diffuse light through: a sheet with that factor.
    let (t, written, text) = run(request(&["floor"], "cotton-plain", None));
    assert_eq!(t, Some(0.35));
    assert_eq!(written, json!(0.35));
    assert!(
        text.contains("KHR_materials_diffuse_transmission"),
        "{text}"
    );
    // Without it: not a sheet, unless --sheet (the preset's τ) or --transmission.
    doc["materials"][0]
        .as_object_mut()
        .unwrap()
        .remove("extensions");
    let bytes = serde_json::to_vec(&doc).unwrap();
    let run = |request: Request| {
        let (out, applied) =
            assets::transform(&bytes, "plain.gltf", path.parent(), &[request]).unwrap();
        let after: Value = serde_json::from_slice(&out).unwrap();
        let written = after["materials"][0]["extensions"][EXTENSION_NAME]
            .get("transmission")
            .cloned();
        (applied[0].params.transmission, written)
    };
    assert_eq!(run(request(&["floor"], "silk-satin", None)), (None, None));
    let mut sheet = request(&["floor"], "silk-satin", None);
    sheet.overrides.sheet = Some(true);
    assert_eq!(run(sheet), (Some(0.45), Some(json!(0.45))));
    let mut given = request(&["floor"], "silk-satin", None);
    given.overrides.transmission = Some(0.1);
    assert_eq!(run(given).0, Some(0.1));
    // And the written file loads back as a sheet.
    let mut sheet = request(&["floor"], "denim-twill", None);
    sheet.overrides.sheet = Some(true);
    let (out, _) = assets::transform(&bytes, "plain.gltf", path.parent(), &[sheet]).unwrap();
    let scene = scene::load_slice(&out, "sheet.gltf", path.parent()).expect("loads back");
    let m = &scene.materials[0];
    assert!(m.is_sheet() && m.blended(), "{:?}", m.fabric);
}
