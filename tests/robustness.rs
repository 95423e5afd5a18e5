//! Bad input, faults and load (project issue 8): a renderer that panics or writes NaN on a bad file
//! is not trusted.
//!
//! - The catalogue `tests/malformed/` (written by `tools/make_malformed.py`; its README.md table is
//!   what this file reads): every entry either fails with its expected message, naming the file,
//!   and `weft` exits with 1 (never 101, never "panicked"), or loads into a well-formed scene and
//!   renders on lavapipe, validation on, to finite HDR and LDR images.
//! - Ten million triangles, made at run time: rendered by the CLI in bounded time and memory.
//! - Faults: output to a missing, read-only or full directory, or over a directory; an existing
//!   output file survives every failed write byte for byte. An allocation the device cannot make.
//! - Load: 100 frames in one process keep resident memory flat (measured in a child process, so
//!   the other tests' allocations do not count).
//!
//! docs/robustness.md records the figures these tests print.

mod common;

#[path = "../tools/fuzz/well_formed.rs"]
mod well_formed;

use std::cell::Cell;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use weft::render::{self, RenderOptions, Renderer};
use weft::scene::{self, Scene};

use common::{weft, TempDir};

// --- helpers --------------------------------------------------------------------------------------

fn malformed_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests")
        .join("malformed")
}

thread_local! {
    static PANICS: Cell<usize> = const { Cell::new(0) };
}

/// Runs `f`, failing if anything panicked on this thread meanwhile: the loader catches panics of
/// the gltf crate and turns them into errors, but a panic on user input is still a bug.
fn without_panic<T>(what: &str, f: impl FnOnce() -> T) -> T {
    static HOOK: std::sync::Once = std::sync::Once::new();
    HOOK.call_once(|| {
        let default = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            PANICS.with(|p| p.set(p.get() + 1));
            default(info);
        }));
    });
    let before = PANICS.with(Cell::get);
    let result = f();
    assert_eq!(PANICS.with(Cell::get), before, "{what} panicked");
    result
}

/// Resident memory of process `pid` ("self" for this one) in KiB: VmRSS, or VmHWM for the peak.
fn proc_kib(pid: &str, field: &str) -> Option<u64> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let line = status.lines().find(|l| l.starts_with(field))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// Runs a command to completion, sampling its peak resident memory (KiB) while it runs.
fn run_measured(mut cmd: Command, limit: Duration) -> (Output, Duration, u64) {
    let start = Instant::now();
    let mut child = cmd
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn weft");
    let pid = child.id().to_string();
    // Drain the pipes on threads, so a chatty child cannot block on a full pipe.
    let mut stdout = child.stdout.take().expect("piped");
    let mut stderr = child.stderr.take().expect("piped");
    let out_thread = std::thread::spawn(move || {
        let mut v = Vec::new();
        std::io::Read::read_to_end(&mut stdout, &mut v).ok();
        v
    });
    let err_thread = std::thread::spawn(move || {
        let mut v = Vec::new();
        std::io::Read::read_to_end(&mut stderr, &mut v).ok();
        v
    });
    let mut peak = 0;
    let status = loop {
        if let Some(hwm) = proc_kib(&pid, "VmHWM:") {
            peak = peak.max(hwm);
        }
        if let Some(status) = child.try_wait().expect("wait") {
            break status;
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            panic!("{cmd:?} ran longer than {limit:?}: killed");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let elapsed = start.elapsed();
    let output = Output {
        status,
        stdout: out_thread.join().unwrap(),
        stderr: err_thread.join().unwrap(),
    };
    (output, elapsed, peak)
}

// --- the catalogue --------------------------------------------------------------------------------

#[derive(Debug)]
enum Expect {
    /// Loading (or preparing the render options) fails with a message holding this fragment.
    Error(String),
    /// Loads, and renders; when given, one of the warnings holds the fragment, else there are none.
    Renders { warning: Option<String> },
}

#[derive(Debug)]
struct Entry {
    file: String,
    expect: Expect,
    args: Vec<String>,
}

/// Entries the test builds at run time (too large to commit).
const GENERATED: &[&str] = &["ten-million-triangles.glb"];

/// The rows of tests/malformed/README.md: | `file` | what is wrong | expected | `arguments` |
fn catalogue() -> Vec<Entry> {
    let text = std::fs::read_to_string(malformed_dir().join("README.md"))
        .expect("tests/malformed/README.md");
    let unquote = |s: &str| s.trim().trim_matches('`').to_owned();
    let entries: Vec<Entry> = text
        .lines()
        .filter(|l| l.starts_with("| `"))
        .map(|line| {
            let cells: Vec<&str> = line.trim().trim_matches('|').split('|').collect();
            assert_eq!(cells.len(), 4, "malformed catalogue row: {line}");
            let expected = cells[2].trim();
            let expect = if let Some(fragment) = expected.strip_prefix("error:") {
                Expect::Error(unquote(fragment))
            } else if let Some(rest) = expected.strip_prefix("renders") {
                let warning = rest
                    .trim()
                    .strip_prefix(", warning:")
                    .or_else(|| rest.trim().strip_prefix("warning:"));
                assert!(
                    warning.is_some() || rest.trim().is_empty(),
                    "unknown outcome '{expected}' in: {line}"
                );
                Expect::Renders {
                    warning: warning.map(unquote),
                }
            } else {
                panic!("unknown outcome '{expected}' in: {line}");
            };
            let args = unquote(cells[3])
                .split_whitespace()
                .map(str::to_owned)
                .collect();
            Entry {
                file: unquote(cells[0]),
                expect,
                args,
            }
        })
        .collect();
    assert!(
        entries.len() >= 40,
        "only {} catalogue entries parsed",
        entries.len()
    );
    entries
}

/// What `weft render FILE ARGS` does before the GPU: load, then the options (mirrors the command
/// line's `SceneSpec::load`, src/cli/mod.rs).
/// Renders at 64x36 unless the entry sets --size.
fn prepare(path: &Path, args: &[String]) -> weft::Result<(Scene, RenderOptions)> {
    let variant = args
        .iter()
        .position(|a| a == "--variant")
        .and_then(|i| args.get(i + 1).cloned());
    let scene = scene::load_with(
        path,
        &scene::LoadOptions {
            variant,
            ..Default::default()
        },
    )?;
    let mut options = RenderOptions {
        width: 64,
        height: 36,
        ..Default::default()
    };
    let (mut eye, mut target, mut fov) = (None, None, 40f32);
    let mut it = args.iter();
    while let Some(arg) = it.next() {
        let (flag, inline) = match arg.split_once('=') {
            Some((f, v)) => (f, Some(v.to_owned())),
            None => (arg.as_str(), None),
        };
        let value = inline
            .or_else(|| it.next().cloned())
            .unwrap_or_else(|| panic!("{flag} needs a value"));
        match flag {
            "--size" => (options.width, options.height) = render::parse_size(&value)?,
            "--camera" => options.camera = Some(value.parse().expect("--camera takes an index")),
            "--eye" => eye = Some(render::parse_vec3("--eye", &value)?),
            "--target" => target = Some(render::parse_vec3("--target", &value)?),
            "--fov" => fov = value.parse().expect("--fov takes degrees"),
            "--variant" => {} // taken by the load above
            other => panic!("the catalogue uses {other}, which this test does not know"),
        }
    }
    options.validate()?;
    if let (Some(eye), Some(target)) = (eye, target) {
        options.camera_override = Some(scene.look_at_camera(eye, target, fov.to_radians())?);
    }
    scene.camera(options.camera)?;
    Ok((scene, options))
}

#[test]
fn the_catalogue_lists_every_file_and_stays_small() {
    let entries = catalogue();
    let listed: std::collections::BTreeSet<&str> =
        entries.iter().map(|e| e.file.as_str()).collect();
    assert_eq!(listed.len(), entries.len(), "a file is listed twice");
    let mut total = 0;
    for f in std::fs::read_dir(malformed_dir()).unwrap() {
        let f = f.unwrap();
        let name = f.file_name().to_string_lossy().into_owned();
        total += f.metadata().unwrap().len();
        if name != "README.md" {
            assert!(
                listed.contains(name.as_str()),
                "{name} is not in tests/malformed/README.md"
            );
        }
    }
    for e in &entries {
        assert!(
            GENERATED.contains(&e.file.as_str()) || malformed_dir().join(&e.file).is_file(),
            "{} is listed but missing: run tools/make_malformed.py",
            e.file
        );
    }
    assert!(
        total < 2 << 20,
        "tests/malformed holds {total} bytes; keep it under 2 MiB"
    );
    println!(
        "catalogue: {} entries ({} made at run time), {total} bytes on disk",
        entries.len(),
        GENERATED.len()
    );
}

#[test]
fn every_entry_loads_or_fails_with_its_message_naming_the_file() {
    let mut failures = Vec::new();
    let (mut errors, mut renders) = (0, 0);
    for e in catalogue()
        .iter()
        .filter(|e| !GENERATED.contains(&e.file.as_str()))
    {
        let path = malformed_dir().join(&e.file);
        let result = without_panic(&e.file, || prepare(&path, &e.args));
        match (&e.expect, result) {
            (Expect::Error(fragment), Err(err)) => {
                let msg = err.to_string();
                if msg.contains(fragment.as_str()) && (msg.contains(&e.file) || !e.args.is_empty())
                {
                    errors += 1;
                } else {
                    failures.push(format!(
                        "{}: error lacks `{fragment}` or the file name: {msg}",
                        e.file
                    ));
                }
            }
            (Expect::Error(fragment), Ok(_)) => {
                failures.push(format!("{}: loaded, expected error `{fragment}`", e.file))
            }
            (Expect::Renders { .. }, Err(err)) => {
                failures.push(format!("{}: expected to load: {err}", e.file))
            }
            (Expect::Renders { warning }, Ok((scene, _))) => {
                if let Err(problem) = well_formed::check(&scene) {
                    failures.push(format!("{}: not well formed: {problem}", e.file));
                }
                let warnings: Vec<String> = scene.warnings.iter().map(|w| w.to_string()).collect();
                match warning {
                    Some(w) if !warnings.iter().any(|m| m.contains(w.as_str())) => {
                        failures.push(format!("{}: no warning holds `{w}`: {warnings:?}", e.file))
                    }
                    None if !warnings.is_empty() => {
                        failures.push(format!("{}: unexpected warnings {warnings:?}", e.file))
                    }
                    _ => renders += 1,
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} catalogue entries misbehave:\n{}",
        failures.len(),
        failures.join("\n")
    );
    println!("loader: {errors} entries fail with their expected message, {renders} load (and are rendered by another test)");
}

/// Runs `weft` on one catalogue entry; Some(problem) if it misbehaves.
fn cli_problem(e: &Entry, dir: &Path) -> Option<String> {
    let path = malformed_dir().join(&e.file);
    let png = dir.join(format!("{}.png", e.file));
    let out = match &e.expect {
        // Fails before any GPU work.
        Expect::Error(_) => weft()
            .arg("render")
            .arg(&path)
            .args(&e.args)
            .arg("-o")
            .arg(&png)
            .output(),
        // `plan` loads and prints the warnings without rendering (the renders are checked
        // in process, by the next test).
        Expect::Renders { .. } => weft().arg("plan").arg(&path).args(&e.args).output(),
    }
    .expect("run weft");
    let stderr = String::from_utf8_lossy(&out.stderr);
    let code = out.status.code();
    if stderr.contains("panicked") || code == Some(101) {
        return Some(format!("panicked (exit {code:?}): {stderr}"));
    }
    match &e.expect {
        Expect::Error(fragment) => {
            let first = stderr.lines().next().unwrap_or("");
            if code != Some(1) {
                Some(format!("exit {code:?}, expected 1: {stderr}"))
            } else if !first.starts_with("error: ") || !stderr.contains(fragment.as_str()) {
                Some(format!("stderr lacks `error: ... {fragment}`: {stderr}"))
            } else if e.args.is_empty() && !stderr.contains(&e.file) {
                Some(format!("the message does not name the file: {stderr}"))
            } else if png.exists() {
                Some("wrote an image despite the error".into())
            } else {
                None
            }
        }
        Expect::Renders { warning } => {
            let printed = |w: &String| stderr.contains("warning: ") && stderr.contains(w.as_str());
            if code != Some(0) {
                Some(format!("`weft plan` exit {code:?}: {stderr}"))
            } else if warning.as_ref().is_some_and(|w| !printed(w)) {
                Some(format!(
                    "`weft plan` did not print warning {warning:?}: {stderr}"
                ))
            } else {
                None
            }
        }
    }
}

#[test]
fn the_cli_exits_1_with_one_clear_message_and_never_panics() {
    let dir = TempDir::new("robustness-cli");
    let entries = catalogue();
    let entries: Vec<&Entry> = entries
        .iter()
        .filter(|e| !GENERATED.contains(&e.file.as_str()))
        .collect();
    // Four threads: each entry is a process start and a load (no GPU for the failing ones).
    let failures: Vec<String> = std::thread::scope(|s| {
        let handles: Vec<_> = entries
            .chunks(entries.len().div_ceil(4))
            .map(|chunk| {
                let dir = &dir;
                s.spawn(move || {
                    let problems = chunk
                        .iter()
                        .map(|e| cli_problem(e, dir).map(|p| format!("{}: {p}", e.file)));
                    problems.flatten().collect::<Vec<_>>()
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().unwrap())
            .collect()
    });
    assert!(
        failures.is_empty(),
        "{} entries misbehave in the CLI:\n{}",
        failures.len(),
        failures.join("\n")
    );
    println!(
        "cli: {} catalogue entries run through `weft`, none panicked",
        entries.len()
    );
}

#[test]
fn every_renderable_entry_renders_finite_images_with_validation_on() {
    let dir = TempDir::new("robustness-render");
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let mut failures = Vec::new();
    let mut rendered = 0;
    for e in catalogue().iter().filter(|e| {
        matches!(e.expect, Expect::Renders { .. }) && !GENERATED.contains(&e.file.as_str())
    }) {
        let (scene, options) = prepare(&malformed_dir().join(&e.file), &e.args)
            .expect("loads (checked by another test)");
        let frame = without_panic(&e.file, || {
            renderer
                .upload(&scene)
                .and_then(|gpu| renderer.render_frame(&scene, &gpu, &options))
        });
        let frame = match frame {
            Ok(f) => f,
            Err(err) => {
                failures.push(format!("{}: {err}", e.file));
                continue;
            }
        };
        let pixels = (options.width * options.height) as usize;
        if frame.ldr.len() != pixels * 4 || frame.hdr.len() != pixels * 4 {
            failures.push(format!("{}: image of the wrong size", e.file));
        }
        if let Some(i) = frame.hdr.iter().position(|v| !v.is_finite()) {
            failures.push(format!(
                "{}: HDR value {} at pixel {}",
                e.file,
                frame.hdr[i],
                i / 4
            ));
            continue;
        }
        // Through the writers, and back: what a user gets on disk.
        let png = dir.join(format!("{}.png", e.file));
        let exr = dir.join(format!("{}.exr", e.file));
        render::write_png(&png, frame.width, frame.height, &frame.ldr).expect("write png");
        render::write_exr(&exr, frame.width, frame.height, &frame.hdr).expect("write exr");
        let back = image::open(&exr).expect("read exr").to_rgba32f();
        assert!(back.as_raw().iter().all(|v| v.is_finite()));
        assert_eq!(
            image::open(&png).expect("read png").to_rgba8().as_raw(),
            &frame.ldr
        );
        rendered += 1;
    }
    assert!(
        failures.is_empty(),
        "{} entries do not render cleanly:\n{}",
        failures.len(),
        failures.join("\n")
    );
    println!("render: {rendered} catalogue entries rendered on lavapipe with validation on, HDR and LDR finite");
}

#[test]
fn the_cli_renders_a_repaired_scene_and_prints_its_warnings() {
    let dir = TempDir::new("robustness-cli-render");
    let png = dir.join("out.png");
    let exr = dir.join("out.exr");
    let out = weft()
        .args(["render", "--validate", "--size", "96x54", "-o"])
        .arg(&png)
        .arg("--exr")
        .arg(&exr)
        .arg(malformed_dir().join("nan-normals.gltf"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert!(
        stderr.contains("warning: ")
            && stderr.contains("2 normal(s)")
            && !stderr.contains("panicked"),
        "{stderr}"
    );
    assert!(image::open(&exr)
        .unwrap()
        .to_rgba32f()
        .as_raw()
        .iter()
        .all(|v| v.is_finite()));
    assert_eq!(image::open(&png).unwrap().to_rgba8().dimensions(), (96, 54));
}

// --- ten million triangles ------------------------------------------------------------------------

/// A .glb of `copies` x 2 x (n-1)^2 triangles: an n x n vertex grid (positions only) and one index
/// buffer repeating the grid's triangles `copies` times.
fn big_glb(n: u32, copies: u32) -> Vec<u8> {
    let mut bin = Vec::new();
    for y in 0..n {
        for x in 0..n {
            for c in [
                x as f32 / (n - 1) as f32 * 2.0 - 1.0,
                y as f32 / (n - 1) as f32 * 2.0 - 1.0,
                0.0f32,
            ] {
                bin.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    let positions_len = bin.len();
    let mut grid = Vec::with_capacity(((n - 1) * (n - 1) * 6) as usize);
    for y in 0..n - 1 {
        for x in 0..n - 1 {
            let i = y * n + x;
            grid.extend_from_slice(&[i, i + 1, i + n + 1, i, i + n + 1, i + n]);
        }
    }
    let grid_bytes: Vec<u8> = grid.iter().flat_map(|i| i.to_le_bytes()).collect();
    for _ in 0..copies {
        bin.extend_from_slice(&grid_bytes);
    }
    let indices = grid.len() as u64 * u64::from(copies);
    let json = serde_json::json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"name": "big", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": n * n, "type": "VEC3", "min": [-1.0, -1.0, 0.0], "max": [1.0, 1.0, 0.0]},
            {"bufferView": 1, "componentType": 5125, "count": indices, "type": "SCALAR"},
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": positions_len},
            {"buffer": 0, "byteOffset": positions_len, "byteLength": bin.len() - positions_len},
        ],
        "buffers": [{"byteLength": bin.len()}],
    });
    common::glb(&serde_json::to_vec(&json).unwrap(), &bin)
}

#[test]
fn ten_million_triangles_render_in_bounded_time_and_memory() {
    let dir = TempDir::new("robustness-ten-million");
    let path = dir.join("ten-million-triangles.glb");
    // 1001 x 1001 vertices: 2 million triangles, drawn 5 times over by one index buffer.
    let glb = big_glb(1001, 5);
    std::fs::write(&path, &glb).unwrap();
    let file_mib = glb.len() >> 20;
    drop(glb);
    let png = dir.join("out.png");
    let exr = dir.join("out.exr");
    let mut cmd = weft();
    cmd.args(["render", "--validate", "--stats", "--size", "320x180", "-o"])
        .arg(&png)
        .arg("--exr")
        .arg(&exr)
        .arg(&path);
    let (out, elapsed, peak_kib) = run_measured(cmd, Duration::from_secs(120));
    let stderr = String::from_utf8_lossy(&out.stderr);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    // The file's ten million, plus the two of the ground the default lighting adds (the file
    // has no lights).
    assert!(stdout.contains("(10000002 triangles)"), "{stdout}");
    assert!(image::open(&exr)
        .unwrap()
        .to_rgba32f()
        .as_raw()
        .iter()
        .all(|v| v.is_finite()));
    println!(
        "ten million triangles ({file_mib} MiB .glb): rendered at 320x180 with validation in {:.1} s, peak resident memory {} MiB",
        elapsed.as_secs_f64(),
        peak_kib >> 10
    );
    // Measured 5.8 s and 591 MiB on lavapipe with validation (docs/robustness.md): time is allowed
    // ten times that (two cores shared with other work), memory a little over three times.
    assert!(elapsed < Duration::from_secs(60), "took {elapsed:?}");
    assert!(
        peak_kib < 2 << 20,
        "peak resident memory {} MiB",
        peak_kib >> 10
    );
}

// --- faults ---------------------------------------------------------------------------------------

/// A small gradient, and its PNG bytes as `write_png` makes them.
fn gradient(w: u32, h: u32) -> Vec<u8> {
    (0..w * h)
        .flat_map(|i| [(i % w * 255 / w) as u8, (i / w * 255 / h) as u8, 128, 255])
        .collect()
}

/// Pixels that do not compress: a PNG of them is about 4 bytes per pixel.
fn noise(w: u32, h: u32) -> Vec<u8> {
    let mut x = 0x9E37_79B9_7F4A_7C15u64;
    (0..w * h * 4)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 24) as u8
        })
        .collect()
}

/// Writes an image over `existing` expecting failure; checks the message and that `existing` and
/// its directory are exactly as before (no temporary file left).
fn assert_failed_write_keeps(
    existing: &Path,
    fragment: &str,
    write: impl Fn(&Path) -> weft::Result<()>,
) {
    let dir = existing.parent().unwrap();
    let before = std::fs::read(existing).unwrap();
    let listing = |d: &Path| {
        let mut v: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    };
    let files = listing(dir);
    let err = write(existing)
        .expect_err("the write must fail")
        .to_string();
    assert!(
        err.contains(fragment) && err.contains(&existing.display().to_string()),
        "{err}"
    );
    assert_eq!(
        std::fs::read(existing).unwrap(),
        before,
        "the existing file changed"
    );
    assert_eq!(
        listing(dir),
        files,
        "the failed write left something behind"
    );
    println!("fault: {err}");
}

#[test]
fn output_to_a_missing_directory_is_a_clear_error() {
    let dir = TempDir::new("robustness-missing-dir");
    let path = dir.join("no/such/dir/out.png");
    let err = render::write_png(&path, 4, 4, &gradient(4, 4))
        .expect_err("must fail")
        .to_string();
    assert!(
        err.contains("does not exist") && err.contains("no/such/dir/out.png"),
        "{err}"
    );

    // And through the CLI, after a real render.
    let out = weft()
        .args(["render", "--validate", "--size", "32x18", "-o"])
        .arg(&path)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("error: could not write")
            && stderr.contains("does not exist")
            && !stderr.contains("panicked"),
        "{stderr}"
    );
}

#[test]
fn a_write_that_fails_leaves_the_existing_file_byte_for_byte() {
    let dir = TempDir::new("robustness-in-the-way");
    let existing = dir.join("out.png");
    render::write_png(&existing, 8, 8, &gradient(8, 8)).unwrap();
    // Something in the way of the temporary file (works whoever runs the test, root included).
    let tmp = dir.join(render::temp_name("out.png".as_ref()));
    std::fs::create_dir(&tmp).unwrap();
    std::fs::write(tmp.join("keep"), b"x").unwrap();
    assert_failed_write_keeps(&existing, "is in the way", |p| {
        render::write_png(p, 64, 64, &gradient(64, 64))
    });
    std::fs::remove_dir_all(&tmp).unwrap();
    // A directory where the image should go: the rename fails, the directory is untouched.
    let target = dir.join("dir.png");
    std::fs::create_dir(&target).unwrap();
    std::fs::write(target.join("inside"), b"kept").unwrap();
    let err = render::write_png(&target, 8, 8, &gradient(8, 8))
        .expect_err("must fail")
        .to_string();
    assert!(
        err.contains("could not replace") && err.contains("dir.png"),
        "{err}"
    );
    assert_eq!(std::fs::read(target.join("inside")).unwrap(), b"kept");
    assert_eq!(
        std::fs::read_dir(&*dir).unwrap().count(),
        2,
        "a temporary file was left behind"
    );
}

#[test]
fn output_to_a_read_only_directory_is_a_clear_error_and_keeps_the_old_file() {
    use std::os::unix::fs::PermissionsExt;
    let dir = TempDir::new("robustness-read-only");
    let ro = dir.join("ro");
    std::fs::create_dir(&ro).unwrap();
    let existing = ro.join("out.png");
    render::write_png(&existing, 8, 8, &gradient(8, 8)).unwrap();
    std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o555)).unwrap();
    // Root ignores permission bits; the immutable attribute stops root too, where it is allowed.
    let writable = |d: &Path| {
        std::fs::File::create(d.join("probe"))
            .is_ok_and(|_| std::fs::remove_file(d.join("probe")).is_ok())
    };
    let mut immutable = false;
    if writable(&ro) {
        immutable = Command::new("chattr")
            .arg("+i")
            .arg(&ro)
            .status()
            .is_ok_and(|s| s.success());
        if !immutable || writable(&ro) {
            let _ = Command::new("chattr").arg("-i").arg(&ro).status();
            println!("fault: read-only directory skipped: running as root without chattr +i");
            return;
        }
    }
    let result = std::panic::catch_unwind(|| {
        assert_failed_write_keeps(&existing, "is not writable", |p| {
            render::write_png(p, 64, 64, &gradient(64, 64))
        });
        assert_failed_write_keeps(&existing, "is not writable", |p| {
            render::write_exr(p, 4, 4, &[0.5; 64])
        });
    });
    if immutable {
        let _ = Command::new("chattr").arg("-i").arg(&ro).status();
    }
    std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o755)).unwrap();
    if let Err(p) = result {
        std::panic::resume_unwind(p);
    }
}

/// A 256 KiB tmpfs, unmounted when dropped (None where mounting is not allowed).
struct TinyDisk(PathBuf);

impl TinyDisk {
    fn mount(dir: &Path) -> Option<TinyDisk> {
        let at = dir.join("disk");
        std::fs::create_dir(&at).ok()?;
        let ok = Command::new("mount")
            .args(["-t", "tmpfs", "-o", "size=256k", "weft-test"])
            .arg(&at)
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success());
        ok.then(|| TinyDisk(at))
    }
}

impl Drop for TinyDisk {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(&self.0).status();
    }
}

#[test]
fn output_to_a_full_disk_is_a_clear_error_and_keeps_the_old_file() {
    let dir = TempDir::new("robustness-full-disk");
    let Some(disk) = TinyDisk::mount(&dir) else {
        println!("fault: full disk skipped: cannot mount a tmpfs here (needs root)");
        return;
    };
    let existing = disk.0.join("out.png");
    render::write_png(&existing, 16, 16, &gradient(16, 16)).unwrap();
    // Fill the disk, then free 16 KiB: the new image (about 64 KiB) starts, and fails part way.
    let filler = disk.0.join("filler");
    let mut f = std::fs::File::create(&filler).unwrap();
    let block = vec![0u8; 4096];
    while f.write_all(&block).and_then(|_| f.sync_all()).is_ok() {}
    let len = f.metadata().unwrap().len();
    f.set_len(len.saturating_sub(16 << 10)).unwrap();
    drop(f);
    assert_failed_write_keeps(&existing, "is full", |p| {
        render::write_png(p, 128, 128, &noise(128, 128))
    });
    drop(disk);
}

#[test]
fn an_allocation_the_device_cannot_make_is_a_clear_error() {
    // 16384 x 16384 (the largest size weft accepts) needs about 14 GiB of render targets. With the
    // address space limited to 6 GiB lavapipe's allocation fails, as a GPU's would with too little
    // memory: one sentence naming the target and the fix, exit 1. (Not run without the limit:
    // the frame would take over 20 GiB of this machine's memory.)
    if std::env::var("WEFT_DEVICE").is_ok_and(|d| d != "cpu") {
        // A GPU driver needs more address space than lavapipe just to start.
        println!("fault: out-of-memory test skipped: it runs on lavapipe (WEFT_DEVICE=cpu)");
        return;
    }
    let dir = TempDir::new("robustness-oom");
    let out = Command::new("sh")
        .arg("-c")
        .arg("ulimit -v 6000000 && exec \"$0\" \"$@\"")
        .arg(common::WEFT)
        .args(["render", "--size", "16384x16384", "-o"])
        .arg(dir.join("big.png"))
        .env("WEFT_DEVICE", common::device())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("error: allocating GPU memory for '") && stderr.contains("--size"),
        "{stderr}"
    );
    assert!(
        !stderr.contains("panicked") && !dir.join("big.png").exists(),
        "{stderr}"
    );
    println!("fault: {}", stderr.lines().last().unwrap_or(""));
}

// --- load -----------------------------------------------------------------------------------------

/// Resident memory may grow by less than this over 90 frames, from frame 10 to 100 or from frame
/// 100 to 190, whichever grew less (lavapipe's and the allocator's caches have settled by frame
/// 10; a leak of one 128x72 RGBA16F readback per frame would add 6.6 MiB over 90 frames, of the
/// frame's uniform buffer and descriptor pool far less, so this catches leaks of whole images, not
/// of small objects — the figures are in docs/robustness.md). A leak grows in both stretches;
/// the lesser of the two leaves out a single step in one of them (a malloc arena a late thread
/// touches: +9.8 MiB once in a CI run at 128-bit vectors under the heap checker, where nine runs
/// here grew by 0 to 4 KiB).
const GROWTH_BOUND_KIB: u64 = 8 << 10;

#[test]
#[ignore = "run by many_frames_keep_resident_memory_flat in a process of its own"]
fn many_frames_child() {
    if std::env::var_os("WEFT_ROBUSTNESS_CHILD").is_none() {
        return;
    }
    let mut renderer = Renderer::new(common::context()).expect("renderer");
    let scene = scene::default_scene();
    let gpu = renderer.upload(&scene).expect("upload");
    let options = RenderOptions {
        width: 128,
        height: 72,
        ..Default::default()
    };
    let mut rss = Vec::new();
    for i in 0..190 {
        let frame = renderer
            .render_frame(&scene, &gpu, &options)
            .unwrap_or_else(|e| panic!("frame {i}: {e}"));
        assert!(
            frame.hdr.iter().all(|v| v.is_finite()),
            "frame {i}: non-finite HDR"
        );
        rss.push(proc_kib("self", "VmRSS:").expect("VmRSS"));
    }
    println!(
        "RSS_KIB frame1={} frame10={} frame100={} frame190={}",
        rss[0], rss[9], rss[99], rss[189]
    );
}

#[test]
fn many_frames_keep_resident_memory_flat() {
    let out = Command::new(std::env::current_exe().unwrap())
        .args([
            "--exact",
            "many_frames_child",
            "--ignored",
            "--nocapture",
            "--test-threads=1",
        ])
        .env("WEFT_ROBUSTNESS_CHILD", "1")
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let line = stdout
        .lines()
        .find_map(|l| l.find("RSS_KIB").map(|at| &l[at..]))
        .unwrap_or_else(|| panic!("no figures: {stdout}"));
    let kib = |key: &str| -> u64 {
        line.split_whitespace()
            .find_map(|w| w.strip_prefix(key))
            .and_then(|v| v.parse().ok())
            .expect("figure")
    };
    let (first, tenth, hundredth, last) = (
        kib("frame1="),
        kib("frame10="),
        kib("frame100="),
        kib("frame190="),
    );
    println!(
        "load: 190 frames of the default scene at 128x72, validation on: resident {} MiB after frame 1, {} KiB after frame 10, {} KiB after frame 100 ({:+} KiB), {} KiB after frame 190 ({:+} KiB)",
        first >> 10,
        tenth,
        hundredth,
        hundredth as i64 - tenth as i64,
        last,
        last as i64 - hundredth as i64
    );
    let growth = hundredth
        .saturating_sub(tenth)
        .min(last.saturating_sub(hundredth));
    assert!(
        growth < GROWTH_BOUND_KIB,
        "resident memory grew by {} KiB over frames 10-100 and {} KiB over frames 100-190",
        hundredth as i64 - tenth as i64,
        last as i64 - hundredth as i64
    );
}

/// Threads writing one target at once: each write goes through a temporary file of its own
/// (the name has the thread's number as well as the process id), so every write succeeds, the
/// target ends as one complete image and no temporary file is left. With the process id alone
/// the threads removed and renamed each other's temporary files.
#[test]
fn threads_writing_one_target_do_not_collide() {
    let dir = TempDir::new("robustness-threads");
    let target = dir.join("shared.png");
    let images: Vec<Vec<u8>> = (0..4u8)
        .map(|t| {
            gradient(32, 32)
                .iter()
                .map(|v| v.wrapping_add(t * 40))
                .collect()
        })
        .collect();
    std::thread::scope(|scope| {
        for img in &images {
            let target = &target;
            scope.spawn(move || {
                for _ in 0..20 {
                    render::write_png(target, 32, 32, img).expect("every write succeeds");
                }
            });
        }
    });
    let got = image::open(&target).unwrap().to_rgba8().into_raw();
    assert!(
        images.contains(&got),
        "the target is one of the written images"
    );
    assert_eq!(
        std::fs::read_dir(&*dir).unwrap().count(),
        1,
        "a temporary file was left behind"
    );
    // Text goes the same way (the shader package and the bench's CSV).
    render::write_file(&dir.join("a.csv"), b"x,y\n").unwrap();
    assert_eq!(std::fs::read(dir.join("a.csv")).unwrap(), b"x,y\n");
    assert_eq!(std::fs::read_dir(&*dir).unwrap().count(), 2);
}

// --- outputs, round two (project issue 30) --------------------------------------------------------

fn listing(d: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// A frame's PNG and EXR are written all or none (a single render wrote the PNG first and left
/// it when the EXR failed): a failure of either leaves neither, and an existing PNG as it was.
#[test]
fn a_frame_is_written_whole_or_not_at_all() {
    let dir = TempDir::new("robustness-frame-whole");
    let png = dir.join("f.png");
    let ldr = gradient(4, 4);
    let hdr = [0.5f32; 64];
    // The EXR's directory is missing: no PNG.
    let e = render::write_frame(
        &png,
        Some(&dir.join("no/f.exr")),
        4,
        4,
        &ldr,
        &hdr,
        &Default::default(),
    )
    .expect_err("the EXR cannot be written")
    .to_string();
    assert!(e.contains("does not exist"), "{e}");
    assert!(listing(&dir).is_empty(), "{:?}", listing(&dir));
    // An HDR value the EXR writer refuses, over an existing PNG: the old PNG stays, byte for byte.
    render::write_png(&png, 4, 4, &gradient(4, 4)).unwrap();
    let old = std::fs::read(&png).unwrap();
    let mut bad = hdr;
    bad[5] = f32::NAN;
    let e = render::write_frame(
        &png,
        Some(&dir.join("f.exr")),
        4,
        4,
        &noise(4, 4),
        &bad,
        &Default::default(),
    )
    .expect_err("NaN refused")
    .to_string();
    assert!(e.contains("non-finite"), "{e}");
    assert_eq!(std::fs::read(&png).unwrap(), old);
    assert_eq!(listing(&dir), ["f.png"]);
    // Both good: both there, and nothing else.
    render::write_frame(
        &png,
        Some(&dir.join("f.exr")),
        4,
        4,
        &ldr,
        &hdr,
        &Default::default(),
    )
    .unwrap();
    assert_eq!(listing(&dir), ["f.exr", "f.png"]);
    // A pixel buffer of the wrong length is an error, not the encoder's panic (1 x 1 frames were
    // read back as 16 bytes), and leaves no temporary file.
    let e = render::write_png(&dir.join("one.png"), 1, 1, &[0u8; 16])
        .expect_err("16 bytes for 1 pixel")
        .to_string();
    assert!(e.contains("holds 16 values, not the 4"), "{e}");
    assert_eq!(listing(&dir), ["f.exr", "f.png"]);
    // A staged file dropped before its commit (an error or a panic between) is removed.
    let staged = render::stage_png(&dir.join("later.png"), 4, 4, &ldr).unwrap();
    assert_eq!(listing(&dir).len(), 3, "the temporary file while staged");
    drop(staged);
    assert_eq!(listing(&dir), ["f.exr", "f.png"]);
}

/// The one output check (render, batch, sheet, compare, view, fabric): entries are compared by
/// what a rename replaces, so every spelling of an input is caught, a link to its directory
/// included, and an input named through a link protects the file it resolves to.
#[test]
fn outputs_are_compared_with_inputs_by_the_file_they_name() {
    use render::OutputPath;
    let dir = TempDir::new("robustness-check-outputs");
    let scene = dir.join("s.gltf");
    std::fs::write(&scene, b"{}").unwrap();
    std::fs::create_dir(dir.join("sub")).unwrap();
    std::os::unix::fs::symlink(&*dir, dir.join("sub/up")).unwrap();
    std::os::unix::fs::symlink(&scene, dir.join("link.gltf")).unwrap();
    let check = |outs: &[(&str, PathBuf)]| {
        let outs: Vec<OutputPath> = outs.iter().map(|(f, p)| OutputPath::new(*f, p)).collect();
        render::check_outputs(&[scene.as_path()], &outs).map_err(|e| e.to_string())
    };
    for spelling in [
        scene.clone(),
        dir.join("sub/../s.gltf"),
        dir.join("sub/up/s.gltf"),
        dir.join("./s.gltf"),
    ] {
        let e = check(&[("-o", spelling.clone())]).expect_err("the input");
        assert!(e.contains("a file this command reads"), "{spelling:?}: {e}");
    }
    // An input named through a link: the file the link resolves to is what the command reads.
    let linked = render::check_outputs(
        &[dir.join("link.gltf").as_path()],
        &[OutputPath::new("-o", dir.join("s.gltf"))],
    );
    assert!(linked.is_err());
    // Two spellings of one output.
    let e = check(&[
        ("-o", dir.join("a.png")),
        ("--exr", dir.join("sub/up/a.png")),
    ])
    .expect_err("one file");
    assert!(e.contains("are the same file"), "{e}");
    // Names and places no file system takes.
    let e = check(&[("-o", dir.join("x".repeat(256)))]).expect_err("256 bytes");
    assert!(
        e.contains("256 bytes long") && e.contains("at most 255"),
        "{e}"
    );
    assert!(check(&[("-o", dir.join("x".repeat(255)))]).is_ok());
    let e = check(&[("-o", dir.join("s.gltf/x.png"))]).expect_err("under a file");
    assert!(e.contains("is not a directory"), "{e}");
    let e = check(&[("-o", dir.join("sub"))]).expect_err("a directory");
    assert!(e.contains("is a directory"), "{e}");
    // Distinct outputs beside the input are fine.
    assert!(check(&[("-o", dir.join("a.png")), ("--exr", dir.join("a.exr"))]).is_ok());
    // The batch classes: every such refusal is bad input (exit 2), and so is a name the file
    // system refuses at write time (ENAMETOOLONG), which used to be "retry" (75).
    let e = render::write_png(&dir.join("y".repeat(300)), 4, 4, &gradient(4, 4)).unwrap_err();
    assert_eq!(
        weft::batch::ExitClass::of_error(&e),
        weft::batch::ExitClass::BadInput,
        "{e}"
    );
}
