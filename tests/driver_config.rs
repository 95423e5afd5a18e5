//! Driver configurations that must not crash weft (issue 23).
//!
//! Mesa 22.3's lavapipe, asked for 128-bit vectors (`LP_NATIVE_VECTOR_WIDTH=128`) on a CPU with
//! AVX, runs its draw module's vertex shader eight vertices at a time while it sizes the vertex
//! buffer for counts rounded to four: a heap overflow inside the driver, which aborts the process
//! at some later `malloc` or `free`, or not at all (docs/regression.md, "Driver configurations").
//! weft works around it in `src/vk/context.rs` (`consistent_lavapipe_cpu`). These renders are
//! the configurations that overflowed, each in a child process so that an abort is a failure of
//! this test and not of the harness. glibc's heap checker (`libc_malloc_debug.so.0` with
//! `MALLOC_CHECK_=3`) turns the intermittent abort into a certain one: without the workaround,
//! `--lights default` aborted in 3 of 3 runs under it on this project's machine (Intel Xeon, Mesa
//! 22.3.6), and 0 of 3 with it.
//!
//! The same lavapipe asked for 512-bit vectors crashes in LLVM at its first image blit (every mip
//! chain: the environment's cube, a file's textures), and at any other width but 128 and 256
//! bits at once; weft runs such a width at 128 or 256 bits and says so (session 43). Without
//! that every render below died (SIGSEGV) on an AVX-512 EPYC.

mod common;

use std::path::Path;

const MALLOC_DEBUG: &str = "/usr/lib/x86_64-linux-gnu/libc_malloc_debug.so.0";

/// `weft render ARGS` at 128-bit vectors, validated, under the heap checker where this system
/// has it; returns (exit status success, stderr).
fn render_at_128_bits(args: &[&str], out: &Path) -> (bool, String) {
    render_at_width("128", args, out)
}

/// `weft render ARGS` with `LP_NATIVE_VECTOR_WIDTH=BITS`, as [`render_at_128_bits`].
fn render_at_width(bits: &str, args: &[&str], out: &Path) -> (bool, String) {
    let mut c = common::weft();
    c.env("LP_NATIVE_VECTOR_WIDTH", bits)
        .env_remove("GALLIUM_OVERRIDE_CPU_CAPS")
        .args(["render", "--validate"])
        .args(args)
        .arg("-o")
        .arg(out);
    if Path::new(MALLOC_DEBUG).exists() {
        c.env("LD_PRELOAD", MALLOC_DEBUG).env("MALLOC_CHECK_", "3");
    } else {
        eprintln!("{MALLOC_DEBUG} is absent: the renders run without glibc's heap checker, so an overflow shows only when it happens to abort");
    }
    let output = c.output().expect("the weft binary runs");
    (
        output.status.success(),
        String::from_utf8_lossy(&output.stderr).into_owned(),
    )
}

#[test]
fn renders_at_128_bit_vectors_do_not_corrupt_the_heap() {
    let dir = common::temp_dir("driver-128");
    let cases: [(&str, &[&str]); 5] = [
        ("default", &["--size", "32x18"]),
        (
            "lights-default",
            &["--size", "32x18", "--lights", "default"],
        ),
        ("studio", &["--size", "32x18", "--env", "studio"]),
        (
            "supersampled",
            &["--size", "32x18", "--accuracy", "supersampled:4"],
        ),
        (
            "analytic",
            &["--size", "32x18", "--weave-precision", "analytic"],
        ),
    ];
    let mut failures = Vec::new();
    for (name, args) in cases {
        let out = dir.join(format!("{name}.png"));
        let (ok, stderr) = render_at_128_bits(args, &out);
        if !ok || !out.exists() {
            failures.push(format!("{name} ({args:?}): {}", stderr.trim()));
        } else {
            // A picture, not an empty file: the driver ran the frame to the end.
            let img = image::open(&out).expect("the render wrote a PNG");
            assert_eq!((img.width(), img.height()), (32, 18), "{name}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    assert!(
        failures.is_empty(),
        "renders at LP_NATIVE_VECTOR_WIDTH=128 failed:\n{}",
        failures.join("\n")
    );
}

#[test]
fn renders_at_other_vector_widths_run_at_256_or_128_bits_and_say_so() {
    let dir = common::temp_dir("driver-512");
    let textured = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/khronos/AlphaBlendModeTest/glTF-Binary/AlphaBlendModeTest.glb");
    let textured = textured.to_str().unwrap();
    // The default scene (the environment's radiance cube: mips by blits) and a file's textures
    // (their mips by blits) without the environment.
    let cases: [(&str, Vec<&str>); 2] = [
        ("default", vec!["--size", "32x18"]),
        (
            "textures",
            vec!["--size", "32x18", "--env", "none", textured],
        ),
    ];
    for (name, args) in cases {
        let out = dir.join(format!("{name}.png"));
        let (ok, stderr) = render_at_width("512", &args, &out);
        assert!(ok && out.exists(), "{name} at 512 bits failed:\n{stderr}");
        assert!(
            stderr.contains("LP_NATIVE_VECTOR_WIDTH=512") && stderr.contains("256 bits"),
            "{name}: no word of the cap:\n{stderr}"
        );
        let img = image::open(&out).expect("the render wrote a PNG");
        assert_eq!((img.width(), img.height()), (32, 18), "{name}");
    }
    // Any other width crashed every render (64, 192 among them): run at 128 or 256 bits.
    for (bits, kept) in [("64", "128 bits"), ("192", "128 bits")] {
        let out = dir.join(format!("{bits}.png"));
        let (ok, stderr) = render_at_width(bits, &["--size", "32x18"], &out);
        assert!(ok && out.exists(), "{bits} bits failed:\n{stderr}");
        assert!(
            stderr.contains(&format!("LP_NATIVE_VECTOR_WIDTH={bits}")) && stderr.contains(kept),
            "{bits}: no word of the width weft keeps:\n{stderr}"
        );
    }
    // At one of the two widths nothing is said.
    let out = dir.join("256.png");
    let (ok, stderr) = render_at_width("256", &["--size", "32x18", "--env", "none"], &out);
    assert!(ok, "{stderr}");
    assert!(!stderr.contains("LP_NATIVE_VECTOR_WIDTH"), "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}
