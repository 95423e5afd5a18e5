//! Image regression (project issue 5): every case of `regression/cases.rs` is rendered on lavapipe
//! with the validation layer on and compared with its golden `tests/golden/<case>.png` (FLIP and
//! per-channel differences); some are also compared with the CPU reference rasterizer
//! (`weft::reference::raster`) or with their own mirror image. Every case's images and figures go
//! to `target/regression/` with one `index.html`; the test fails afterwards, naming each case
//! that is out of bounds.
//!
//! `WEFT_BLESS=1` (what `tools/bless` sets) writes the goldens and `tests/golden/VERSION` instead
//! of comparing with them. docs/regression.md explains the suite, the page and the bounds.

#[path = "regression/cases.rs"]
mod cases;
mod common;
#[path = "regression/metrics.rs"]
mod metrics;
#[path = "regression/report.rs"]
mod report;

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use cases::{Case, HEIGHT, WIDTH};
use metrics::{compare, mirror_x};
use report::{write_index, write_png, Row, Shown};
use weft::reference::raster::{self, RasterOptions};
use weft::reference::shading;
use weft::render::{RenderOptions, Renderer};
use weft::scene::Scene;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn golden_dir() -> PathBuf {
    root().join("tests/golden")
}

/// Where the images and the index page go (git-ignored with the rest of target/):
/// `target/regression`, or `target/$WEFT_REGRESSION_REPORT` (tools/test's second pass, with
/// 128-bit vectors, keeps its own page beside the first).
fn report_dir() -> PathBuf {
    let name = std::env::var("WEFT_REGRESSION_REPORT")
        .ok()
        .filter(|n| !n.is_empty() && !n.contains(['/', '\\']) && n != "..")
        .unwrap_or_else(|| "regression".to_string());
    root().join("target").join(name)
}

/// The device and driver an image was rendered with, as tests/golden/VERSION records them. One
/// line each; the test compares all of them, since each can change the images (the Mesa release,
/// LLVM, and llvmpipe's vector width, which is in the device name).
fn version_lines(info: &weft::vk::DeviceInfo) -> Vec<String> {
    vec![
        format!("device: {}", info.name),
        format!("driver: {}", info.driver_name),
        format!("driver_info: {}", info.driver_info),
    ]
}

fn read_version() -> Option<Vec<String>> {
    let text = std::fs::read_to_string(golden_dir().join("VERSION")).ok()?;
    Some(
        text.lines()
            .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
            .map(str::to_owned)
            .collect(),
    )
}

fn write_version(lines: &[String]) {
    let mut text = String::from(
        "# The device and driver tests/golden/*.png were rendered with; written by tools/bless, checked by\n\
         # tests/regression.rs (lavapipe output is identical only for the same Mesa, LLVM and vector width).\n",
    );
    for l in lines {
        text.push_str(l);
        text.push('\n');
    }
    std::fs::write(golden_dir().join("VERSION"), text).expect("write tests/golden/VERSION");
}

fn read_png(path: &Path) -> Option<(u32, u32, Vec<u8>)> {
    let img = image::open(path).ok()?.to_rgba8();
    Some((img.width(), img.height(), img.into_raw()))
}

fn load_scene(
    cache: &mut HashMap<(&'static str, Option<&'static str>), Scene>,
    path: &'static str,
    variant: Option<&'static str>,
    known: &[&str],
) -> Scene {
    cache
        .entry((path, variant))
        .or_insert_with(|| {
            let options = weft::scene::LoadOptions {
                variant: variant.map(str::to_owned),
                ..Default::default()
            };
            let scene = weft::scene::load_with(&root().join(path), &options)
                .unwrap_or_else(|e| panic!("{path}: {e}"));
            assert!(
                scene
                    .warnings
                    .iter()
                    .all(|w| known.iter().any(|k| w.0.contains(k))),
                "{path} loads with warnings: {:?}",
                scene.warnings
            );
            scene
        })
        .clone()
}

#[test]
fn image_regression() {
    let started = Instant::now();
    let bless = std::env::var("WEFT_BLESS").is_ok_and(|v| v == "1");
    let dir = report_dir();
    std::fs::create_dir_all(&dir).expect("create target/regression");
    // Images of cases that no longer exist would only confuse whoever opens the folder.
    for entry in std::fs::read_dir(&dir)
        .expect("read target/regression")
        .flatten()
    {
        let path = entry.path();
        if path.extension().is_some_and(|e| e == "png" || e == "html") {
            let _ = std::fs::remove_file(path);
        }
    }
    std::fs::create_dir_all(golden_dir()).expect("create tests/golden");

    let ctx = common::context();
    let info = ctx.info().clone();
    let version = version_lines(&info);
    let mut renderer = Renderer::new(ctx).expect("renderer");

    // The goldens hold on any CPU's lavapipe within their bounds (cases.rs: GOLDEN, measured
    // across vector widths and CPU vendors), so another device or driver is not a failure by
    // itself; it is named on the page, and beside any failure, since a different Mesa or LLVM
    // release may move images further than the bounds were measured for.
    let version_note = if bless {
        write_version(&version);
        None
    } else {
        match read_version() {
            None => Some("tests/golden/VERSION is missing: there are no goldens; make them with tools/bless (after looking at the images)".to_string()),
            Some(golden) if golden != version => {
                // Name only what differs, without the keys: "goldens were made with llvmpipe
                // (LLVM 15.0.6, 256 bits), this is llvmpipe (LLVM 15.0.6, 128 bits)".
                let value = |l: &String| l.split_once(": ").map_or(l.clone(), |(_, v)| v.to_string());
                let differ = |a: &[String], b: &[String]| {
                    let d: Vec<String> = a.iter().filter(|l| !b.contains(l)).map(value).collect();
                    if d.is_empty() { "(nothing recorded)".to_string() } else { d.join(" on ") }
                };
                Some(format!(
                    "goldens were made with {}, this is {}",
                    differ(&golden, &version),
                    differ(&version, &golden)
                ))
            }
            Some(_) => None,
        }
    };
    let goldens_missing = !bless && read_version().is_none();

    let mut scenes = HashMap::new();
    let mut rows = Vec::new();
    for case in cases::cases() {
        rows.push(run_case(&case, &mut renderer, &mut scenes, bless, &dir));
    }

    let header = format!(
        "{} on {} ({}, {}) in {:.1} s.{}",
        if bless {
            "Goldens blessed (written)"
        } else {
            "Compared with the goldens"
        },
        info.name,
        info.driver_name,
        info.driver_info,
        started.elapsed().as_secs_f64(),
        version_note
            .as_ref()
            .map(|p| format!(" <b>{p}</b>"))
            .unwrap_or_default()
    );
    write_index(&dir, &header, &rows);
    for row in &rows {
        for s in &row.shown {
            println!(
                "{:<26} {:<22} {}",
                row.case.name,
                s.title,
                s.figures.summary(&s.tolerance)
            );
        }
    }
    println!("index: {}", dir.join("index.html").display());

    // The bounds must still catch a real change, not only "the CPU changed": small deliberate
    // changes of a shading input, each compared with its case's golden under that case's bound,
    // must fail it (docs/regression.md, "What the bounds absorb").
    let mut caught_nothing = Vec::new();
    if !bless {
        for (name, change, apply) in perturbations() {
            let case = cases::cases()
                .into_iter()
                .find(|c| c.name == name)
                .expect("a perturbation names a case");
            let Some((w, h, golden)) = read_png(&golden_dir().join(format!("{name}.png"))) else {
                continue;
            };
            let mut scene = load_scene(&mut scenes, case.scene, case.variant, case.warnings);
            apply(&mut scene);
            let (_, _, width, height, ldr, _) = render_case(&case, &mut renderer, scene);
            assert_eq!((w, h), (width, height), "{name}: golden size");
            let figures = compare(&golden, &ldr, width, height, case.golden.abs).figures;
            let violations = case.golden.violations(&figures);
            println!(
                "{name:<26} {change:<40} {} -> {}",
                figures.summary(&case.golden),
                if violations.is_empty() {
                    "NOT CAUGHT"
                } else {
                    "caught"
                }
            );
            if violations.is_empty() {
                caught_nothing.push(format!("{name} with {change}"));
            }
        }
    }

    if goldens_missing {
        panic!("{}", version_note.unwrap_or_default());
    }
    let failures: Vec<String> = rows
        .iter()
        .filter(|r| !r.passed())
        .map(|r| {
            let mut why: Vec<String> = r
                .note
                .iter()
                .filter(|n| n.starts_with("FAIL"))
                .cloned()
                .collect();
            why.extend(
                r.shown
                    .iter()
                    .filter(|s| !s.violations.is_empty())
                    .map(|s| format!("{}: {}", s.title, s.violations.join("; "))),
            );
            format!("  {}: {}", r.case.name, why.join(" | "))
        })
        .collect();
    assert!(
        caught_nothing.is_empty(),
        "the golden bounds let real changes through: {}",
        caught_nothing.join(", ")
    );
    assert!(
        failures.is_empty(),
        "{} of {} regression cases failed (images and figures: {}):\n{}{}",
        failures.len(),
        rows.len(),
        dir.join("index.html").display(),
        failures.join("\n"),
        version_note
            .map(|n| format!("\n(note: {n}; if the images are right, re-bless with tools/bless after looking at them)"))
            .unwrap_or_default()
    );
}

/// A change of a shading input: the case it is rendered as, what it is, and how.
type Perturbation = (&'static str, &'static str, fn(&mut Scene));

/// Small changes a person would call a regression, for the check that the golden bounds catch
/// them: a fabric's diffuse colour 2 % darker, a base colour 2 % darker, a light turned 5°.
fn perturbations() -> Vec<Perturbation> {
    fn darker_fabric(scene: &mut Scene) {
        for m in &mut scene.materials {
            if let Some(f) = &mut m.fabric {
                for c in 0..3 {
                    f.rd_warp[c] *= 0.98;
                    f.rd_weft[c] *= 0.98;
                }
            }
        }
    }
    fn darker_base_colour(scene: &mut Scene) {
        for m in &mut scene.materials {
            for c in 0..3 {
                m.base_color[c] *= 0.98;
            }
        }
    }
    fn light_turned(scene: &mut Scene) {
        // Every light about the vertical axis through the origin, by 5°.
        let turn = glam::Mat3::from_rotation_y(5f32.to_radians());
        for l in &mut scene.lights {
            l.direction = turn * l.direction;
            l.position = turn * l.position;
        }
    }
    vec![
        ("default", "fabric diffuse 2 % darker", darker_fabric),
        ("far", "fabric diffuse 2 % darker", darker_fabric),
        ("closeup", "fabric diffuse 2 % darker", darker_fabric),
        ("env-cloth", "fabric diffuse 2 % darker", darker_fabric),
        (
            "khronos-sheen-chair",
            "base colour 2 % darker",
            darker_base_colour,
        ),
        ("spheres", "base colour 2 % darker", darker_base_colour),
        ("default", "lights turned 5°", light_turned),
        ("shadows", "lights turned 5°", light_turned),
        ("many-lights", "lights turned 5°", light_turned),
    ]
}

/// The mean linear radiance over `block × block` pixels, tone-mapped and sRGB-encoded as the
/// tonemap pass does (RGBA8).
fn block_means(hdr: &[f32], width: u32, height: u32, block: u32, exposure_ev: f32) -> Vec<u8> {
    let (bw, bh) = (width / block, height / block);
    let mut out = Vec::with_capacity((bw * bh * 4) as usize);
    for by in 0..bh {
        for bx in 0..bw {
            let mut sum = [0.0f64; 3];
            for y in by * block..(by + 1) * block {
                for x in bx * block..(bx + 1) * block {
                    let i = ((y * width + x) * 4) as usize;
                    for c in 0..3 {
                        sum[c] += hdr[i + c] as f64;
                    }
                }
            }
            let n = (block * block) as f64;
            let mean = [
                (sum[0] / n) as f32,
                (sum[1] / n) as f32,
                (sum[2] / n) as f32,
            ];
            let display = shading::tonemap(mean, 2f32.powf(exposure_ev));
            out.extend_from_slice(&[
                shading::srgb_encode(display[0]),
                shading::srgb_encode(display[1]),
                shading::srgb_encode(display[2]),
                255,
            ]);
        }
    }
    out
}

/// Renders a case's scene (already loaded, maybe changed) as the case says: posed, lit, framed.
/// Returns the LDR image and, for a frame (not `weft compare`'s figure), the frame.
fn render_case(
    case: &Case,
    renderer: &mut Renderer,
    mut scene: Scene,
) -> (
    Scene,
    RenderOptions,
    u32,
    u32,
    Vec<u8>,
    Option<weft::render::Frame>,
) {
    if let Some((index, time)) = case.pose {
        scene
            .pose(index, time)
            .unwrap_or_else(|e| panic!("case {}: {e}", case.name));
    }
    let environment = case.env.map(|e| {
        let env = if e.map == "studio" {
            weft::env::Environment::studio()
        } else {
            weft::env::Environment::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join(e.map))
                .unwrap_or_else(|err| panic!("case {}: {err}", case.name))
        };
        weft::env::stage(&mut scene, e.lights, e.rotation, e.map != "studio");
        let mut l = weft::env::EnvLighting::new(std::sync::Arc::new(env));
        l.rotation = e.rotation;
        l
    });
    let options = RenderOptions {
        environment,
        width: WIDTH,
        height: HEIGHT,
        camera: case.camera,
        debug_view: case.debug_view,
        accuracy: case.accuracy,
        weave_precision: case.weave_precision,
        shading: case.shading,
        antialias: case.antialias,
        occlusion: case.occlusion,
        camera_override: case.look.map(|(eye, target, fov)| {
            scene
                .look_at_camera(eye.into(), target.into(), fov.to_radians())
                .unwrap_or_else(|e| panic!("case {}: {e}", case.name))
        }),
        ..Default::default()
    };
    // A figure case renders weft compare's figure (four panels at the case size, labelled).
    if case.figure {
        let fig = weft::compare::figure(renderer, &scene, &options)
            .unwrap_or_else(|e| panic!("case {}: {e}", case.name));
        (scene, options, fig.width, fig.height, fig.rgba, None)
    } else {
        let frame = renderer
            .render(&scene, &options)
            .unwrap_or_else(|e| panic!("case {}: {e}", case.name));
        let ldr = frame.ldr.clone();
        (scene, options, WIDTH, HEIGHT, ldr, Some(frame))
    }
}

fn run_case(
    case: &Case,
    renderer: &mut Renderer,
    scenes: &mut HashMap<(&'static str, Option<&'static str>), Scene>,
    bless: bool,
    dir: &Path,
) -> Row {
    let scene = load_scene(scenes, case.scene, case.variant, case.warnings);
    let start = Instant::now();
    let (scene, options, width, height, ldr, frame) = render_case(case, renderer, scene);
    let render_ms = start.elapsed().as_secs_f64() * 1e3;
    let file = |suffix: &str| format!("{}-{suffix}.png", case.name);
    write_png(&dir.join(file("actual")), width, height, &ldr);

    let mut row = Row {
        case: case.clone(),
        render_ms,
        note: None,
        shown: Vec::new(),
    };
    let golden_path = golden_dir().join(format!("{}.png", case.name));
    if bless {
        write_png(&golden_path, width, height, &ldr);
        row.note = Some(format!("blessed: wrote tests/golden/{}.png", case.name));
    }
    match read_png(&golden_path) {
        None => {
            row.note = Some(format!(
                "FAIL: no golden tests/golden/{}.png: look at target/regression/{}, then make it with tools/bless",
                case.name,
                file("actual")
            ));
        }
        Some((w, h, _)) if (w, h) != (width, height) => {
            row.note = Some(format!(
                "FAIL: golden tests/golden/{}.png is {w}x{h}, the case renders {width}x{height}: re-bless with tools/bless",
                case.name
            ));
        }
        Some((_, _, golden)) => {
            write_png(&dir.join(file("expected")), width, height, &golden);
            let cmp = compare(&golden, &ldr, width, height, case.golden.abs);
            write_png(&dir.join(file("difference")), width, height, &cmp.error_map);
            row.shown.push(Shown {
                title: "GPU vs golden",
                violations: case.golden.violations(&cmp.figures),
                figures: cmp.figures,
                tolerance: case.golden,
                images: [file("expected"), file("actual"), file("difference")],
                captions: ["expected (golden)", "actual (lavapipe)", "FLIP error"],
            });
        }
    }

    let Some(frame) = frame else {
        return row;
    };
    if let Some(tol) = case.cpu {
        let camera = match case.camera {
            Some(i) => scene.cameras[i].clone(),
            None => scene.camera(None).expect("a camera"),
        };
        let start = Instant::now();
        let cpu = raster::render(
            &scene,
            &RasterOptions {
                width: WIDTH,
                height: HEIGHT,
                camera,
                exposure: options.exposure,
                subdivisions: tol.subdivisions,
                pieces: tol.pieces,
                shading: case.shading,
            },
        )
        .unwrap_or_else(|e| panic!("case {}: CPU reference: {e}", case.name));
        println!(
            "{:<26} CPU reference in {:.0} ms",
            case.name,
            start.elapsed().as_secs_f64() * 1e3
        );
        write_png(&dir.join(file("cpu")), WIDTH, HEIGHT, &cpu.ldr);
        let cmp = compare(&cpu.ldr, &frame.ldr, WIDTH, HEIGHT, tol.full.abs);
        write_png(
            &dir.join(file("cpu-difference")),
            WIDTH,
            HEIGHT,
            &cmp.error_map,
        );
        row.shown.push(Shown {
            title: "GPU vs CPU reference",
            violations: tol.full.violations(&cmp.figures),
            figures: cmp.figures,
            tolerance: tol.full,
            images: [file("cpu"), file("actual"), file("cpu-difference")],
            captions: ["CPU reference (raster.rs)", "GPU (lavapipe)", "FLIP error"],
        });
        // The same in means over blocks of pixels (of the linear radiance, tone-mapped after):
        // the two weave filters differ in shape, not in what they average, so this isolates
        // everything else (camera, geometry, lights, BRDF).
        let b = cases::CPU_BLOCK;
        let (bw, bh) = (WIDTH / b, HEIGHT / b);
        let cpu_blocks = block_means(&cpu.hdr, WIDTH, HEIGHT, b, options.exposure);
        let gpu_blocks = block_means(&frame.hdr, WIDTH, HEIGHT, b, options.exposure);
        write_png(&dir.join(file("cpu-blocks")), bw, bh, &cpu_blocks);
        write_png(&dir.join(file("blocks")), bw, bh, &gpu_blocks);
        let cmp = compare(&cpu_blocks, &gpu_blocks, bw, bh, tol.blocks.abs);
        write_png(
            &dir.join(file("cpu-blocks-difference")),
            bw,
            bh,
            &cmp.error_map,
        );
        row.shown.push(Shown {
            title: "GPU vs CPU reference, block means",
            violations: tol.blocks.violations(&cmp.figures),
            figures: cmp.figures,
            tolerance: tol.blocks,
            images: [
                file("cpu-blocks"),
                file("blocks"),
                file("cpu-blocks-difference"),
            ],
            captions: [
                "CPU reference, block means",
                "GPU, block means",
                "FLIP error",
            ],
        });
    }

    if let Some(tol) = case.mirror {
        let mirrored = mirror_x(&frame.ldr, WIDTH);
        write_png(&dir.join(file("mirrored")), WIDTH, HEIGHT, &mirrored);
        let cmp = compare(&frame.ldr, &mirrored, WIDTH, HEIGHT, tol.abs);
        write_png(
            &dir.join(file("mirror-difference")),
            WIDTH,
            HEIGHT,
            &cmp.error_map,
        );
        row.shown.push(Shown {
            title: "GPU vs its mirror image",
            violations: tol.violations(&cmp.figures),
            figures: cmp.figures,
            tolerance: tol,
            images: [file("actual"), file("mirrored"), file("mirror-difference")],
            captions: ["GPU (lavapipe)", "mirrored left to right", "FLIP error"],
        });
    }
    row
}
