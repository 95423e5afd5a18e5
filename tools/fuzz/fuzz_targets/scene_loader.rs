//! Fuzzes `weft::scene::load_slice` with arbitrary bytes (as .gltf JSON or .glb): it must return a
//! scene or an error, never panic (libfuzzer-sys's panic hook aborts even inside the loader's own
//! `catch_unwind`, so a caught panic is still a crash here), and a scene it returns must be one the
//! renderer can draw without NaN (checked by `well_formed`).

#![no_main]

use libfuzzer_sys::fuzz_target;

#[path = "../well_formed.rs"]
mod well_formed;

fuzz_target!(|data: &[u8]| {
    if let Ok(scene) = weft::scene::load_slice(data, "fuzz input", None) {
        if let Err(problem) = well_formed::check(&scene) {
            panic!("the loader returned a scene the renderer cannot draw: {problem}");
        }
    }
});
