//! The workspace's integration tests, built as one test binary (`cargo test --test suite`):
//! each file in tests/ is a module here, named after the behaviour it pins, and `common`
//! holds the fixtures and helpers they share. One binary links the workspace once, where a
//! binary per file linked it 34 times (Cargo.toml sets `autotests = false` so the files are
//! not also built as binaries of their own). Run one file's tests with its module name as the
//! filter: `cargo test --release --test suite render_exact_reuse::`.

mod common;
mod fuzz_harness;
mod trajectory_v2;

// Accelerators: the interface on each backend, packets, long runs, the Embree wrapper.
mod accel_embree;
mod accel_long_run;
mod accel_packets;
mod crosscheck_verdicts;
mod embree_wrapper;

// Scenes, physics and trajectories.
mod animated_gltf;
mod physics_assets;
mod physics_atrium;
mod physics_islands;
mod physics_structures;
mod physics_trajectory;
mod residency_frames;
mod residency_manager;
mod scene_file_errors;
mod scene_file_structures;

// Rendering.
mod render_adaptive;
mod render_denoise;
mod render_exact_reuse;
mod render_filter_and_clamp;
mod render_images;
mod render_materials;
mod render_motion_blur;
mod render_resume;

// The `dormant` binary end to end: commands, outputs, exports and bad input.
mod bench_paper;
mod bench_physics;
mod cli_export;
mod cli_render;
mod cli_settings;
mod cli_stats;
mod cli_verify_bench;
mod cli_video;
mod docs_links;
mod export_gltf;
mod fuzz_regressions;
mod gltf_round_trip;
mod input_errors;
mod setup_rust;
