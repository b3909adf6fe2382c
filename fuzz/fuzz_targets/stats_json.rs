//! Fuzz target `stats_json`: see `tests/fuzz_harness/mod.rs` (`stats_json`) and docs/fuzzing.md.
#![no_main]

#[path = "../../tests/fuzz_harness/mod.rs"]
mod harness;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let _ = harness::stats_json(data);
});
