//! Fuzz target `trajectory`: see `tests/fuzz_harness/mod.rs` (`trajectory`) and docs/fuzzing.md.
#![no_main]

#[path = "../../tests/fuzz_harness/mod.rs"]
mod harness;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let _ = harness::trajectory(data);
});
