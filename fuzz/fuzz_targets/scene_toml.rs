//! Fuzz target `scene_toml`: see `tests/fuzz_harness/mod.rs` (`scene_toml`) and docs/fuzzing.md.
#![no_main]

#[path = "../../tests/fuzz_harness/mod.rs"]
mod harness;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let _ = harness::scene_toml(data);
});
