//! Replays the scene loader's fuzz corpus (tools/fuzz/corpus/scene_loader/: seeds and the minimized
//! inputs of past fuzz runs, crashers among them) through `weft::scene::load_slice` on every
//! `cargo test`, without the fuzzer: each must give a scene or an error, never a panic (counted by
//! a panic hook, since the loader catches panics itself), and a scene must be well formed.

mod common;

#[path = "../tools/fuzz/well_formed.rs"]
mod well_formed;

use common::fuzz::{self, Panics};

#[test]
fn every_corpus_input_loads_or_fails_without_panicking() {
    let inputs = fuzz::files("tools/fuzz/corpus/scene_loader", |_| true);
    assert!(
        inputs.len() >= 24,
        "the corpus has only {} inputs",
        inputs.len()
    );

    let panics = Panics::count();
    let (mut scenes, mut errors) = (0, 0);
    let mut failures = Vec::new();
    for (name, bytes) in &inputs {
        let before = panics.so_far();
        let result = weft::scene::load_slice(bytes, name, None);
        if panics.so_far() != before {
            failures.push(format!(
                "{name}: panicked ({:?})",
                result.err().map(|e| e.to_string())
            ));
            continue;
        }
        match result {
            Ok(scene) => match well_formed::check(&scene) {
                Ok(()) => scenes += 1,
                Err(problem) => failures.push(format!("{name}: not well formed: {problem}")),
            },
            Err(e) => {
                let msg = e.to_string();
                if msg.contains(name.as_str()) {
                    errors += 1;
                } else {
                    failures.push(format!("{name}: the error does not name the file: {msg}"));
                }
            }
        }
    }
    panics.end();
    assert!(
        failures.is_empty(),
        "{} of {} corpus inputs fail:\n{}",
        failures.len(),
        inputs.len(),
        failures.join("\n")
    );
    println!(
        "fuzz corpus: {} inputs replayed: {scenes} scenes, {errors} errors, no panics",
        inputs.len()
    );
}
