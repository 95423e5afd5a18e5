//! Modules specialised before a CPU driver sees them (src/vk/specialize.rs): every pipeline's
//! specialised module passes `spirv-val` and is smaller, and specialising changes no pixel.
//!
//! `spirv-opt` and `spirv-val` come from the `spirv-tools` package (tools/setup installs it).

mod common;

use std::collections::BTreeSet;
use std::process::Command;

use common::{temp_dir, weft};
use weft::vk::shaders;
use weft::vk::specialize::{specialize, MIN_BYTES};

/// Every module of the package's pipelines (`Renderer::pipelines`: the default scene's, the
/// cloth under the environment, the transparent pass with and without the woven model, a debug
/// view, the probes...) specialised for its pipeline's constants is valid SPIR-V for Vulkan 1.3
/// and smaller than the module it came from; the large modules of the default frame shrink to
/// less than half.
#[test]
fn every_pipelines_specialised_module_passes_spirv_val_and_is_smaller() {
    let mut renderer = weft::render::Renderer::new(common::context()).unwrap();
    let pipelines = renderer.pipelines().unwrap();
    let dir = temp_dir("specialize-val");
    let mut checked = BTreeSet::new();
    let mut halved = BTreeSet::new();
    let mut failures = Vec::new();
    for (i, p) in pipelines.iter().enumerate() {
        for name in &p.shaders {
            let shader = shaders::ALL
                .iter()
                .find(|s| s.name == *name)
                .expect("a pipeline's shader is one of the package's");
            if shader.spirv.len() < MIN_BYTES || p.constants.is_empty() {
                continue;
            }
            let Some(out) = specialize(shader.name, shader.spirv, &p.constants) else {
                failures.push(format!(
                    "{name} of {}: not specialised (is spirv-opt installed? tools/setup)",
                    p.name
                ));
                continue;
            };
            let path = dir.join(format!("{i}-{name}.spv"));
            std::fs::write(&path, out.as_slice()).unwrap();
            let val = Command::new("spirv-val")
                .args(["--target-env", "vulkan1.3"])
                .arg(&path)
                .output()
                .expect("spirv-val runs (install spirv-tools with tools/setup)");
            if !val.status.success() {
                failures.push(format!(
                    "{name} of {}: spirv-val: {}{}",
                    p.name,
                    String::from_utf8_lossy(&val.stdout),
                    String::from_utf8_lossy(&val.stderr)
                ));
            }
            if out.len() >= shader.spirv.len() {
                failures.push(format!(
                    "{name} of {}: {} bytes specialised, {} before",
                    p.name,
                    out.len(),
                    shader.spirv.len()
                ));
            }
            if 2 * out.len() < shader.spirv.len() {
                halved.insert(*name);
            }
            checked.insert(*name);
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    for big in [
        "gbuffer.frag",
        "lighting_woven.frag",
        "forward.frag",
        "forward_gltf.frag",
    ] {
        assert!(
            checked.contains(big),
            "{big} was among the pipelines: {checked:?}"
        );
        assert!(halved.contains(big), "{big} at least halves: {halved:?}");
    }
}

/// The same image bit for bit with and without specialising, and from weft's cache: the default
/// scene (the woven G-buffer and lighting modules) and a file with blended materials (the
/// transparent pass's module).
#[test]
fn specialising_changes_no_pixel() {
    let dir = temp_dir("specialize-pixels");
    let blend = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/khronos/AlphaBlendModeTest/glTF-Binary/AlphaBlendModeTest.glb"
    );
    for (scene, tag) in [(None, "default"), (Some(blend), "blend")] {
        let render = |what: &str, optimizer: Option<&str>| -> (Vec<u8>, String) {
            let out_png = dir.join(format!("{tag}-{what}.png"));
            let mut c = weft();
            c.arg("render");
            if let Some(s) = scene {
                c.arg(s);
            }
            c.args(["--size", "256x144", "--stats", "-o"])
                .arg(&out_png)
                .env("WEFT_CACHE_DIR", dir.join("cache"));
            if let Some(o) = optimizer {
                c.env("WEFT_SPIRV_OPT", o);
            }
            let out = c.output().unwrap();
            assert!(
                out.status.success(),
                "{tag} {what}: {}",
                String::from_utf8_lossy(&out.stderr)
            );
            let stats = String::from_utf8_lossy(&out.stdout)
                .lines()
                .find(|l| l.starts_with("modules"))
                .unwrap_or_default()
                .to_string();
            (std::fs::read(&out_png).unwrap(), stats)
        };
        // "modules    N specialised before the driver by spirv-opt (M of them from weft's
        // cache; ...)": (N, M).
        let counts = |stats: &str| -> (u32, u32) {
            let n = stats.split_whitespace().nth(1).and_then(|w| w.parse().ok());
            let m = stats
                .split('(')
                .nth(1)
                .and_then(|r| r.split_whitespace().next())
                .and_then(|w| w.parse().ok());
            (n.expect(stats), m.expect(stats))
        };
        let (plain, stats) = render("off", Some("off"));
        assert_eq!(counts(&stats), (0, 0), "{tag}: WEFT_SPIRV_OPT=off: {stats}");
        let (made, stats) = render("made", None);
        let (n, m) = counts(&stats);
        assert!(n > 0 && m == 0, "{tag}: the first run specialises: {stats}");
        let (cached, stats) = render("cached", None);
        assert_eq!(
            counts(&stats),
            (n, n),
            "{tag}: the second run takes them all from the cache: {stats}"
        );
        assert!(plain == made, "{tag}: specialised modules change the image");
        assert!(plain == cached, "{tag}: cached modules change the image");
    }
}
