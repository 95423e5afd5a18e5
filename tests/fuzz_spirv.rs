//! Fuzzing the public SPIR-V reader, `weft::package::spirv::reflect`, as tests/fuzz_mutate.rs and
//! tests/fuzz_corpus.rs fuzz the scene loader: every input must give a reflection or an error,
//! never a panic (counted by a panic hook), and must not take long.
//!
//! - `corpus_replays`: the shipped modules (glsl/spirv/) and tools/fuzz/corpus/spirv_reflect/
//!   (hostile seeds and the inputs of past runs).
//! - `mutated_modules_reflect_or_fail_without_panicking`: a deterministic SPIR-V-aware mutation
//!   fuzzer over those seeds: words set to interesting values (0, 1, the id bound, u32::MAX ...),
//!   instruction word counts and opcodes changed, instructions deleted, duplicated, swapped and
//!   spliced in from another module, type operands pointed at other types (cycles included),
//!   truncations and bit flips. 3000 mutations on every `cargo test`; a long run:
//!   `WEFT_FUZZ_ITERATIONS=1000000 WEFT_FUZZ_SEED=2 cargo test --release --test fuzz_spirv -- --nocapture`.
//!   Crashing inputs are written to `target/tmp/fuzz-spirv-crashes/`.
//!
//! The coverage-guided twin is tools/fuzz/fuzz_targets/spirv_reflect.rs (cargo-fuzz).

mod common;

use std::path::Path;
use std::time::{Duration, Instant};

use weft::package::spirv::reflect;

use common::fuzz::{files, iterations_and_seed, Panics, Rng};

fn seeds() -> Vec<(String, Vec<u8>)> {
    let mut out = files("glsl/spirv", |p| p.extension().is_some_and(|e| e == "spv"));
    out.extend(files("tools/fuzz/corpus/spirv_reflect", |_| true));
    out
}

fn words(bytes: &[u8]) -> Vec<u32> {
    bytes
        .chunks(4)
        .map(|c| {
            let mut w = [0u8; 4];
            w[..c.len()].copy_from_slice(c);
            u32::from_le_bytes(w)
        })
        .collect()
}

fn bytes(words: &[u32]) -> Vec<u8> {
    words.iter().flat_map(|w| w.to_le_bytes()).collect()
}

/// The start of every instruction after the 5-word header, as far as the word counts lead.
fn instructions(w: &[u32]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = 5;
    while i < w.len() {
        let n = (w[i] >> 16) as usize;
        if n == 0 || i + n > w.len() {
            break;
        }
        out.push((i, n));
        i += n;
    }
    out
}

/// Opcodes the reader looks at (and a few it does not).
const OPCODES: &[u32] = &[
    10, 15, 16, 17, 19, 20, 21, 22, 23, 24, 25, 26, 27, 28, 29, 30, 32, 41, 42, 43, 44, 48, 49, 50,
    51, 54, 59, 71, 72, 331, 5341, 0, 1, 0xFFFF,
];

fn mutate(rng: &mut Rng, seed: &[u8], other: &[u8]) -> Vec<u8> {
    let mut w = words(seed);
    let bound = w.get(3).copied().unwrap_or(100);
    let interesting = |rng: &mut Rng| -> u32 {
        [
            0,
            1,
            2,
            3,
            4,
            16,
            64,
            0xFFFF,
            0x1_0000,
            0x7FFF_FFFF,
            0x8000_0000,
            u32::MAX,
            bound,
            bound.wrapping_add(1),
            (rng.below(bound.max(1) as usize)) as u32,
        ][rng.below(15)]
    };
    let ins = instructions(&w);
    match rng.below(10) {
        // A word anywhere (the header too) set to an interesting value.
        0 | 1 if !w.is_empty() => {
            let i = rng.below(w.len());
            w[i] = interesting(rng);
        }
        // An operand of an instruction pointed at another instruction's result id (type
        // operands at other types, themselves included: cycles).
        2 if ins.len() > 1 => {
            let (a, n) = ins[rng.below(ins.len())];
            let (b, m) = ins[rng.below(ins.len())];
            if n > 1 && m > 1 {
                w[a + 1 + rng.below(n - 1)] = w[b + 1 + rng.below(m - 1)];
            }
        }
        // A word count.
        3 if !ins.is_empty() => {
            let (a, _) = ins[rng.below(ins.len())];
            let n = [0u32, 1, 2, 3, 0xFFFF][rng.below(5)];
            w[a] = (w[a] & 0xFFFF) | (n << 16);
        }
        // An opcode.
        4 if !ins.is_empty() => {
            let (a, _) = ins[rng.below(ins.len())];
            w[a] = (w[a] & 0xFFFF_0000) | OPCODES[rng.below(OPCODES.len())];
        }
        // An instruction deleted, or duplicated.
        5 if !ins.is_empty() => {
            let (a, n) = ins[rng.below(ins.len())];
            if rng.chance(2) {
                w.drain(a..a + n);
            } else {
                let copy: Vec<u32> = w[a..a + n].to_vec();
                let at = ins[rng.below(ins.len())].0;
                w.splice(at..at, copy);
            }
        }
        // Two instructions swapped (a use before its definition).
        6 if ins.len() > 1 => {
            let (a, n) = ins[rng.below(ins.len())];
            let (b, m) = ins[rng.below(ins.len())];
            if a + n <= b {
                let first: Vec<u32> = w[a..a + n].to_vec();
                let second: Vec<u32> = w[b..b + m].to_vec();
                w.splice(b..b + m, first);
                w.splice(a..a + n, second);
            }
        }
        // An instruction of another module spliced in.
        7 => {
            let o = words(other);
            let theirs = instructions(&o);
            if !theirs.is_empty() && !ins.is_empty() {
                let (b, m) = theirs[rng.below(theirs.len())];
                let at = ins[rng.below(ins.len())].0;
                w.splice(at..at, o[b..b + m].iter().copied());
            }
        }
        // Truncated (to any byte length).
        8 => {
            let mut b = bytes(&w);
            b.truncate(rng.below(b.len() + 1));
            return b;
        }
        // Bit flips.
        _ => {
            let mut b = bytes(&w);
            for _ in 0..1 + rng.below(8) {
                if !b.is_empty() {
                    let i = rng.below(b.len());
                    b[i] ^= 1 << rng.below(8);
                }
            }
            return b;
        }
    }
    bytes(&w)
}

/// Runs `reflect` on each input, counting panics with a hook; returns the problems.
fn run(inputs: impl Iterator<Item = (String, Vec<u8>)>, crash_dir: Option<&Path>) -> Report {
    let panics = Panics::count();
    let mut report = Report::default();
    for (name, input) in inputs {
        let before = panics.so_far();
        let t = Instant::now();
        let result = std::panic::catch_unwind(|| reflect(&input));
        let took = t.elapsed();
        if took > report.slowest.0 {
            report.slowest = (took, name.clone());
        }
        report.executions += 1;
        match result {
            Ok(Ok(_)) if panics.so_far() == before => report.reflected += 1,
            Ok(Err(_)) if panics.so_far() == before => report.errors += 1,
            _ => {
                if let Some(dir) = crash_dir {
                    std::fs::create_dir_all(dir).unwrap();
                    std::fs::write(dir.join(format!("{name}.spv")), &input).unwrap();
                }
                report.crashes.push(name);
            }
        }
    }
    panics.end();
    report
}

#[derive(Default)]
struct Report {
    executions: usize,
    reflected: usize,
    errors: usize,
    crashes: Vec<String>,
    slowest: (Duration, String),
}

#[test]
fn corpus_replays() {
    let seeds = seeds();
    assert!(seeds.len() >= 16, "only {} seeds", seeds.len());
    let shipped = files("glsl/spirv", |p| p.extension().is_some_and(|e| e == "spv")).len();
    let r = run(seeds.into_iter(), None);
    assert!(r.crashes.is_empty(), "crashed: {:?}", r.crashes);
    assert!(
        r.reflected >= shipped && r.errors >= 4,
        "every shipped module reflects and the hostile seeds fail: {} reflected, {} errors",
        r.reflected,
        r.errors
    );
}

#[test]
fn mutated_modules_reflect_or_fail_without_panicking() {
    let (iterations, seed) = iterations_and_seed();
    let seeds = seeds();
    let crash_dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("fuzz-spirv-crashes");
    let mut rng = Rng::for_seed(seed);
    let start = Instant::now();
    let inputs = (0..iterations).map(|i| {
        let (name, bytes) = &seeds[rng.below(seeds.len())];
        let other = seeds[rng.below(seeds.len())].1.clone();
        let mut input = mutate(&mut rng, bytes, &other);
        // Mutants of mutants, to get further from the seeds.
        while rng.chance(3) {
            input = mutate(&mut rng, &input, &other);
        }
        (format!("seed{seed}-iteration{i}-from-{name}"), input)
    });
    let r = run(inputs, Some(&crash_dir));
    println!(
        "{} executions in {:.1} s: {} reflected, {} errors, {} crashes; slowest {:?} ({})",
        r.executions,
        start.elapsed().as_secs_f64(),
        r.reflected,
        r.errors,
        r.crashes.len(),
        r.slowest.0,
        r.slowest.1
    );
    assert!(
        r.crashes.is_empty(),
        "crashed: {:?}",
        &r.crashes[..r.crashes.len().min(10)]
    );
    assert!(
        r.reflected > 0 && r.errors > 0,
        "the mutants reach both outcomes"
    );
    assert!(
        r.slowest.0 < Duration::from_secs(1),
        "an input took {:?}: {}",
        r.slowest.0,
        r.slowest.1
    );
}
