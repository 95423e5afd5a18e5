//! Fuzzes `weft::package::spirv::reflect` with arbitrary bytes: it must return a reflection or an
//! error, never panic (libfuzzer-sys's panic hook aborts). Seeds: glsl/spirv/ and
//! corpus/spirv_reflect/ (replayed by tests/fuzz_spirv.rs on every `cargo test`):
//!
//!     cargo +nightly fuzz run --fuzz-dir tools/fuzz spirv_reflect /tmp/spirv-corpus \
//!         tools/fuzz/corpus/spirv_reflect glsl/spirv -- -max_total_time=600

#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = weft::package::spirv::reflect(data);
});
