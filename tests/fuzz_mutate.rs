//! A bounded, deterministic, structure-aware mutation fuzzer for `weft::scene::load_slice`, for
//! machines without cargo-fuzz (the coverage-guided target is tools/fuzz/; see
//! docs/robustness.md). It mutates the fuzz corpus and the malformed-file catalogue: byte flips,
//! interesting bytes, truncations, deletions, duplications, splices of two inputs, and, knowing the
//! formats, JSON value replacements, subtree swaps and deletions (inside a .glb's JSON chunk too,
//! rebuilding the container), .glb header and chunk lengths, and NaN, Inf and huge floats in the
//! binary chunk. Every input must give a scene or an error, never a panic (counted by a panic hook,
//! as the loader catches panics itself); a scene must be well formed.
//!
//! `cargo test --release --test fuzz_mutate` runs 3000 mutations (a few seconds). For a long run:
//! `WEFT_FUZZ_ITERATIONS=500000 WEFT_FUZZ_SEED=7 cargo test --release --test fuzz_mutate -- --nocapture`.
//! Crashing inputs are written to `target/tmp/fuzz-mutate-crashes/`.

mod common;

#[path = "../tools/fuzz/well_formed.rs"]
mod well_formed;

use std::path::Path;
use std::time::{Duration, Instant};

use serde_json::{json, Value};

use common::fuzz::{self, Panics, Rng};

fn seeds() -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    for dir in ["tools/fuzz/corpus/scene_loader", "tests/malformed"] {
        out.extend(fuzz::files(dir, |p| {
            p.extension().is_none_or(|e| e != "md")
        }));
    }
    out
}

/// A .glb split into its JSON text and binary chunk, or None for anything else.
fn split_glb(bytes: &[u8]) -> Option<(Vec<u8>, Option<Vec<u8>>)> {
    let u32_at = |at: usize| {
        bytes
            .get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
    };
    if !bytes.starts_with(b"glTF") {
        return None;
    }
    let json_len = u32_at(12)?;
    let json = bytes.get(20..20 + json_len)?.to_vec();
    let bin_at = 20 + json_len;
    let bin = u32_at(bin_at)
        .and_then(|len| bytes.get(bin_at + 8..bin_at + 8 + len))
        .map(<[u8]>::to_vec);
    Some((json, bin))
}

fn make_glb(json: &[u8], bin: Option<&[u8]>) -> Vec<u8> {
    let mut text = json.to_vec();
    while text.len() % 4 != 0 {
        text.push(b' ');
    }
    let mut chunks = Vec::new();
    chunks.extend_from_slice(&(text.len() as u32).to_le_bytes());
    chunks.extend_from_slice(b"JSON");
    chunks.extend_from_slice(&text);
    if let Some(bin) = bin {
        chunks.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        chunks.extend_from_slice(b"BIN\0");
        chunks.extend_from_slice(bin);
    }
    let mut glb = b"glTF".to_vec();
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&((12 + chunks.len()) as u32).to_le_bytes());
    glb.extend_from_slice(&chunks);
    glb
}

/// Every path to a value in a JSON document (keys and array indices).
fn paths(v: &Value, path: &mut Vec<Value>, out: &mut Vec<Vec<Value>>) {
    out.push(path.clone());
    match v {
        Value::Object(map) => {
            for (k, child) in map {
                path.push(json!(k));
                paths(child, path, out);
                path.pop();
            }
        }
        Value::Array(items) => {
            for (i, child) in items.iter().enumerate() {
                path.push(json!(i));
                paths(child, path, out);
                path.pop();
            }
        }
        _ => {}
    }
}

fn at<'v>(v: &'v mut Value, path: &[Value]) -> Option<&'v mut Value> {
    let mut v = v;
    for k in path {
        v = match k {
            Value::String(k) => v.get_mut(k.as_str())?,
            _ => v.get_mut(k.as_u64()? as usize)?,
        };
    }
    Some(v)
}

fn interesting_value(rng: &mut Rng, original: &Value) -> Value {
    let numbers = [
        json!(0),
        json!(-1),
        json!(1),
        json!(2),
        json!(3),
        json!(7),
        json!(255),
        json!(65535),
        json!(4294967295u64),
        json!(4294967296u64),
        json!(9007199254740993u64),
        json!(-2147483648i64),
        json!(0.5),
        json!(-0.0),
        json!(1e-45),
        json!(3.4e38),
        json!(1e39),
        json!(-1e308),
        json!(1e308),
    ];
    match rng.below(8) {
        0..=3 => numbers[rng.below(numbers.len())].clone(),
        4 => match original {
            Value::Number(n) => {
                let x = n.as_f64().unwrap_or(0.0);
                let scaled = [x + 1.0, x - 1.0, x * 2.0, -x, x * 1e20, x / 3.0][rng.below(6)];
                serde_json::Number::from_f64(scaled).map_or(json!(0), Value::Number)
            }
            Value::Array(a) if !a.is_empty() => {
                let mut a = a.clone();
                let k = rng.below(a.len());
                a.truncate(k);
                Value::Array(a)
            }
            other => other.clone(),
        },
        5 => [
            json!(null),
            json!(true),
            json!(false),
            json!([]),
            json!({}),
            json!([0, 0]),
            json!([1.0, 2.0, 3.0, 4.0, 5.0]),
        ][rng.below(7)]
        .clone(),
        6 => [
            json!(""),
            json!("POSITION"),
            json!("image/png"),
            json!("data:application/octet-stream;base64,AAAA"),
            json!("data:image/png;base64,iVBORw0KGgo="),
            json!("../../../../etc/passwd"),
            json!("plain"),
            json!("KHR_draco_mesh_compression"),
            json!("\u{0}\u{ffff}"),
        ][rng.below(9)]
        .clone(),
        _ => [json!(["|-", "-|"]), json!([[]]), json!({"a": [{}]})][rng.below(3)].clone(),
    }
}

/// Mutates a JSON document in place: 1 to 4 replacements, swaps, duplications and deletions.
fn mutate_json(rng: &mut Rng, doc: &mut Value) {
    for _ in 0..1 + rng.below(4) {
        let mut all = Vec::new();
        paths(doc, &mut Vec::new(), &mut all);
        let a = all[rng.below(all.len())].clone();
        match rng.below(6) {
            0..=2 => {
                if let Some(slot) = at(doc, &a) {
                    let original = slot.clone();
                    *slot = interesting_value(rng, &original);
                }
            }
            3 => {
                // Swap with (a copy of) another subtree.
                let b = all[rng.below(all.len())].clone();
                if let Some(other) = at(doc, &b).map(|v| v.clone()) {
                    if let Some(slot) = at(doc, &a) {
                        *slot = other;
                    }
                }
            }
            4 => {
                // Duplicate an array element many times, or delete a key.
                if let Some(slot) = at(doc, &a) {
                    match slot {
                        Value::Array(items) if !items.is_empty() => {
                            let k = rng.below(items.len());
                            let item = items[k].clone();
                            for _ in 0..1 + rng.below(64) {
                                items.push(item.clone());
                            }
                        }
                        Value::Object(map) if !map.is_empty() => {
                            let key = map.keys().nth(rng.below(map.len())).cloned().unwrap();
                            map.remove(&key);
                        }
                        _ => {}
                    }
                }
            }
            _ => {
                if let Some((last, parent)) = a.split_last() {
                    if let Some(Value::Array(items)) = at(doc, parent) {
                        if let Some(i) = last.as_u64() {
                            if (i as usize) < items.len() {
                                items.remove(i as usize);
                            }
                        }
                    }
                }
            }
        }
    }
}

fn mutate_bytes(rng: &mut Rng, data: &mut Vec<u8>, other: &[u8]) {
    for _ in 0..1 + rng.below(3) {
        let len = data.len();
        match rng.below(7) {
            0 if len > 0 => {
                for _ in 0..1 + rng.below(8) {
                    let i = rng.below(len);
                    data[i] ^= 1 << rng.below(8);
                }
            }
            1 if len > 0 => {
                let i = rng.below(len);
                data[i] = [
                    0u8, 0xff, 0x7f, 0x80, b'"', b'{', b'[', b',', b'-', b'9', b'e', b'\\',
                ][rng.below(12)];
            }
            2 => data.truncate(rng.below(len + 1)),
            3 if len > 0 => {
                let a = rng.below(len);
                let b = (a + 1 + rng.below(64)).min(len);
                data.drain(a..b);
            }
            4 if len > 0 => {
                let a = rng.below(len);
                let b = (a + 1 + rng.below(256)).min(len);
                let piece = data[a..b].to_vec();
                let at = rng.below(len + 1);
                data.splice(at..at, piece);
            }
            5 => {
                // Splice: this input's head, another's tail.
                let cut = rng.below(len + 1);
                let from = rng.below(other.len() + 1);
                data.truncate(cut);
                data.extend_from_slice(&other[from..]);
            }
            _ if len >= 4 => {
                // A little-endian u32 or f32 somewhere: lengths, counts, floats.
                let i = rng.below(len - 3) & !3;
                let v: [u8; 4] = [
                    0u32.to_le_bytes(),
                    u32::MAX.to_le_bytes(),
                    0x7fff_ffffu32.to_le_bytes(),
                    f32::NAN.to_le_bytes(),
                    f32::INFINITY.to_le_bytes(),
                    f32::MAX.to_le_bytes(),
                    1e-45f32.to_le_bytes(),
                    12u32.to_le_bytes(),
                ][rng.below(8)];
                data[i..i + 4].copy_from_slice(&v);
            }
            _ => {}
        }
    }
}

/// One mutated input from `seed` (and `other`, for splices).
fn mutate(rng: &mut Rng, seed: &[u8], other: &[u8]) -> Vec<u8> {
    let structured = rng.below(3) != 0;
    if structured {
        if let Some((json_text, bin)) = split_glb(seed) {
            let mut bin = bin;
            let json_text = match serde_json::from_slice::<Value>(&json_text) {
                Ok(mut doc) if rng.chance(2) => {
                    mutate_json(rng, &mut doc);
                    serde_json::to_vec(&doc).unwrap()
                }
                _ => json_text,
            };
            if let Some(b) = bin.as_mut() {
                if rng.chance(2) {
                    mutate_bytes(rng, b, other);
                }
            }
            let mut glb = make_glb(&json_text, bin.as_deref());
            if rng.chance(8) {
                // Lie in the header or a chunk length.
                let at = [
                    8usize,
                    12,
                    20 + json_text.len() + (4 - json_text.len() % 4) % 4,
                ][rng.below(3)];
                if at + 4 <= glb.len() {
                    let v = [0u32, 4, 11, 12, u32::MAX, glb.len() as u32 + 1][rng.below(6)];
                    glb[at..at + 4].copy_from_slice(&v.to_le_bytes());
                }
            }
            return glb;
        }
        if let Ok(mut doc) = serde_json::from_slice::<Value>(seed) {
            mutate_json(rng, &mut doc);
            return serde_json::to_vec_pretty(&doc).unwrap();
        }
    }
    let mut data = seed.to_vec();
    mutate_bytes(rng, &mut data, other);
    data
}

#[test]
fn mutated_scenes_load_or_fail_without_panicking() {
    let (iterations, seed) = fuzz::iterations_and_seed();
    let seeds = seeds();
    assert!(seeds.len() > 50, "only {} seeds", seeds.len());
    let crash_dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("fuzz-mutate-crashes");

    let panics = Panics::count();

    let mut rng = Rng::for_seed(seed);
    let start = Instant::now();
    let (mut scenes, mut errors) = (0usize, 0usize);
    let mut crashes = Vec::new();
    let mut slowest = (Duration::ZERO, String::new());
    for i in 0..iterations {
        let (name, bytes) = &seeds[rng.below(seeds.len())];
        let other = &seeds[rng.below(seeds.len())].1;
        // Mutants of mutants, now and then, to get further from the seeds.
        let mut input = mutate(&mut rng, bytes, other);
        if rng.chance(4) {
            input = mutate(&mut rng, &input, other);
        }
        let before = panics.so_far();
        let t = Instant::now();
        let result = weft::scene::load_slice(&input, "mutant", None);
        let took = t.elapsed();
        if took > slowest.0 {
            slowest = (took, format!("iteration {i}, from {name}"));
        }
        let problem = if panics.so_far() != before {
            Some(format!(
                "panicked: {:?}",
                result.as_ref().err().map(|e| e.to_string())
            ))
        } else {
            match &result {
                Ok(scene) => well_formed::check(scene)
                    .err()
                    .map(|p| format!("not well formed: {p}")),
                Err(_) => None,
            }
        };
        match (problem, result.is_ok()) {
            (Some(problem), _) => {
                std::fs::create_dir_all(&crash_dir).unwrap();
                let file = crash_dir.join(format!("seed{seed}-iteration{i}.bin"));
                std::fs::write(&file, &input).unwrap();
                crashes.push(format!(
                    "iteration {i} (from {name}, saved as {}): {problem}",
                    file.display()
                ));
            }
            (None, true) => scenes += 1,
            (None, false) => errors += 1,
        }
    }
    panics.end();
    let secs = start.elapsed().as_secs_f64();
    println!(
        "fuzz_mutate: seed {seed}, {iterations} executions in {secs:.1} s ({:.0}/s): {scenes} scenes, {errors} errors, {} crashes; slowest input {:.0} ms ({})",
        iterations as f64 / secs,
        crashes.len(),
        slowest.0.as_secs_f64() * 1e3,
        slowest.1
    );
    assert!(
        crashes.is_empty(),
        "{} crashing inputs:\n{}",
        crashes.len(),
        crashes.join("\n")
    );
}
