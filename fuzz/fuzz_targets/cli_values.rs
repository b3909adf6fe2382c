//! Fuzz target `cli_values`: see `tests/fuzz_harness/mod.rs` (`cli_values`) and docs/fuzzing.md.
#![no_main]

#[path = "../../tests/fuzz_harness/mod.rs"]
mod harness;

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let _ = harness::cli_values(data);
});
