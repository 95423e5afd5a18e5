//! Replays the scene loader's fuzz corpus (tools/fuzz/corpus/scene_loader/: seeds and the minimized
//! inputs of past fuzz runs, crashers among them) through `weft::scene::load_slice` on every
//! `cargo test`, without the fuzzer: each must give a scene or an error, never a panic (counted by
//! a panic hook, since the loader catches panics itself), and a scene must be well formed.

#[path = "../tools/fuzz/well_formed.rs"]
mod well_formed;

use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

#[test]
fn every_corpus_input_loads_or_fails_without_panicking() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/fuzz/corpus/scene_loader");
    let mut inputs: Vec<_> = std::fs::read_dir(&dir)
        .expect("tools/fuzz/corpus/scene_loader")
        .map(|e| e.expect("corpus entry").path())
        .filter(|p| p.is_file())
        .collect();
    inputs.sort();
    assert!(
        inputs.len() >= 24,
        "the corpus has only {} inputs",
        inputs.len()
    );

    let panics = Arc::new(AtomicUsize::new(0));
    let counter = panics.clone();
    let previous = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        counter.fetch_add(1, Ordering::SeqCst);
        eprintln!("panic: {info}");
    }));
    let (mut scenes, mut errors) = (0, 0);
    let mut failures = Vec::new();
    for path in &inputs {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let bytes = std::fs::read(path).unwrap();
        let before = panics.load(Ordering::SeqCst);
        let result = weft::scene::load_slice(&bytes, &name, None);
        if panics.load(Ordering::SeqCst) != before {
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
                if msg.contains(&name) {
                    errors += 1;
                } else {
                    failures.push(format!("{name}: the error does not name the file: {msg}"));
                }
            }
        }
    }
    std::panic::set_hook(previous);
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
