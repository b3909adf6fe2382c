//! Fuzz target `gltf_json`: see `tests/fuzz_harness/mod.rs` (`gltf_json`) and docs/fuzzing.md.
#![no_main]

#[path = "../../tests/fuzz_harness/mod.rs"]
mod harness;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let _ = harness::gltf_json(data);
});
