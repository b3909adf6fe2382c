//! Exact temporal reuse (`--reuse exact`, the default) against rendering every frame in full
//! (`--reuse off`): every file a frame writes (image, AOVs, EXR) is the same bytes, on both
//! backends, in both forms of sleeping islands, with motion blur and adaptive sampling, and
//! later frames really trace only part of their samples. Decisions of `--integration auto`
//! follow measured times, so the runs pin them with `never` or `always`.

use crate::common;

use std::path::{Path, PathBuf};

use common::cli::{dormant, exits_with, read_stats, succeeds};
use common::scenes;

/// Renders `scene` with `--reuse reuse` and `flags` into `dir/name-reuse`.
fn render(dir: &Path, name: &str, reuse: &str, scene: &Path, flags: &[&str]) -> PathBuf {
    let out = dir.join(format!("{name}-{reuse}"));
    succeeds(
        dormant()
            .args(["render", "--quiet", "--seed", "fixed", "--reuse", reuse])
            .args(flags)
            .arg("--out")
            .arg(&out)
            .arg(scene),
    );
    out
}

/// The frame files of `dir` (all but the statistics and the `traced` AOV, which says what
/// was traced and so differs by design), sorted.
fn frame_files(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| n.starts_with("frame_") && !n.contains(".traced."))
        .collect();
    names.sort();
    names
}

/// Renders `scene` with `flags` both ways and asserts every frame file is byte-identical;
/// returns the share of camera samples the exact run traced.
fn assert_exact_matches_full(name: &str, scene: &Path, flags: &[&str]) -> f64 {
    let dir = tempfile::tempdir().unwrap();
    let off = render(dir.path(), name, "off", scene, flags);
    let exact = render(dir.path(), name, "exact", scene, flags);
    let files = frame_files(&off);
    assert!(!files.is_empty());
    assert_eq!(files, frame_files(&exact), "{name}: the runs wrote different files");
    for file in &files {
        let same = std::fs::read(off.join(file)).unwrap() == std::fs::read(exact.join(file)).unwrap();
        assert!(same, "{name}: {file} differs between --reuse off and exact");
    }
    let totals = &read_stats(&exact)["summary"]["totals"];
    let traced = totals["samples_traced"].as_f64().unwrap();
    traced / (traced + totals["samples_reused"].as_f64().unwrap())
}

/// tiny.toml at a small size, with the frames where boxes fall and settle.
fn tiny(name: &str, flags: &[&str]) -> f64 {
    let mut all = vec!["--size", "64x36", "--frames", "0..48"];
    all.extend_from_slice(flags);
    assert_exact_matches_full(name, &scenes::shipped("tiny"), &all)
}

#[test]
fn exact_reuse_writes_the_full_renders_bytes_path_traced_with_aovs_and_exr() {
    let share =
        tiny("path", &["--spp", "4", "--aov", "albedo", "--aov", "normal", "--aov", "depth", "--exr"]);
    assert!(share < 0.9, "exact reuse traced {share} of the samples");
}

#[test]
fn exact_reuse_writes_the_full_renders_bytes_on_the_rust_bvh() {
    let share =
        tiny("bvh", &["--spp", "4", "--backend", "bvh", "--aov", "albedo", "--integration", "always"]);
    assert!(share < 0.9, "exact reuse traced {share} of the samples");
}

#[test]
fn exact_reuse_writes_the_full_renders_bytes_with_baked_islands() {
    let flags = ["--spp", "2", "--integration", "always", "--integrate-as", "baked"];
    tiny("baked", &flags);
    let mut bvh = flags.to_vec();
    bvh.extend(["--backend", "bvh"]);
    tiny("baked-bvh", &bvh);
}

#[test]
fn exact_reuse_writes_the_full_renders_bytes_shaded_and_never_integrating() {
    tiny("shaded", &["--spp", "2", "--mode", "shaded", "--integration", "never"]);
}

#[test]
fn exact_reuse_writes_the_full_renders_bytes_with_motion_blur() {
    tiny("blur", &["--spp", "2", "--shutter", "0.5"]);
    tiny("blur-bvh", &["--spp", "2", "--shutter", "0.5", "--backend", "bvh"]);
}

#[test]
fn exact_reuse_writes_the_full_renders_bytes_with_adaptive_sampling() {
    // Per sample: stored and retraced samples decide together where a pixel stops. The
    // albedo pass is shaded beside the image where a pixel is traced whole and traced on its
    // own, at the pixel's sample count, where its passes' horizon came or the count changed.
    let adaptive = ["--noise-threshold", "0.1", "--min-spp", "4", "--aov", "spp", "--aov", "albedo"];
    let share = tiny("adaptive", &[&["--spp", "16"], &adaptive[..]].concat());
    assert!(share < 0.9, "exact reuse traced {share} of the samples");
    // Per pixel (1 MiB holds 64 samples per pixel only as pixels): a due pixel is traced whole.
    tiny("adaptive-pixels", &[&["--spp", "64", "--reuse-mib", "1"], &adaptive[..]].concat());
}

#[test]
fn a_change_index_rebuilt_window_by_window_keeps_the_full_renders_bytes() {
    // 1 MiB leaves the change index 128 KiB, a few hundred change boxes: the falling boxes'
    // frames take several windows, each index built when rendering reaches it.
    let share = tiny("windows", &["--spp", "4", "--reuse-mib", "1"]);
    assert!(share < 0.95, "exact reuse traced {share} of the samples");
}

#[test]
fn a_budget_without_room_for_samples_reuses_whole_pixels_exactly() {
    // 64x36 pixels need 45 KiB per pixel but 576 KiB per sample at 256 spp: 1 MiB holds
    // pixels only. Two passes: the store traces both at once for the pixels due.
    let dir = tempfile::tempdir().unwrap();
    let flags = [
        "--size",
        "64x36",
        "--frames",
        "0..24",
        "--spp",
        "256",
        "--mode",
        "shaded",
        "--reuse-mib",
        "1",
        "--aov",
        "albedo",
        "--aov",
        "depth",
    ];
    let out = render(dir.path(), "pixels", "exact", &scenes::shipped("tiny"), &flags);
    let frames = read_stats(&out)["frames"].as_array().unwrap().clone();
    assert!(frames.iter().all(|f| f["reuse_granularity"] == "pixel"), "{frames:?}");
    let off = render(dir.path(), "pixels", "off", &scenes::shipped("tiny"), &flags);
    for file in frame_files(&off) {
        assert_eq!(
            std::fs::read(off.join(&file)).unwrap(),
            std::fs::read(out.join(&file)).unwrap(),
            "{file}"
        );
    }
}

#[test]
fn exact_reuse_writes_the_full_renders_bytes_on_a_small_demolition() {
    // A few hundred bodies: the first structures fall around frame 150.
    let flags = [
        "--count",
        "300",
        "--size",
        "96x54",
        "--spp",
        "2",
        "--frames",
        "150..170",
        "--integration",
        "always",
    ];
    let share = assert_exact_matches_full("demolition", &scenes::shipped("demolition"), &flags);
    assert!(share < 0.8, "exact reuse traced {share} of the samples");
}

#[test]
fn a_reuse_budget_of_zero_or_too_small_is_an_input_error_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    for (mib, size) in [("0", "64x36"), ("1", "1920x1080")] {
        let out = dir.path().join(format!("budget-{mib}"));
        let stderr = exits_with(
            dormant()
                .args(["render", "--quiet", "--frames", "0..3", "--size", size, "--reuse-mib", mib, "--out"])
                .arg(&out)
                .arg(scenes::shipped("tiny")),
            2,
        );
        assert!(stderr.contains("--reuse-mib"), "{stderr}");
        assert!(!out.exists(), "--reuse-mib {mib} left {}", out.display());
    }
}

#[test]
fn camera_rays_traced_only_as_packet_neighbours_of_due_samples_are_counted_apart() {
    let flags = ["--size", "64x36", "--frames", "0..48", "--spp", "4"];
    let dir = tempfile::tempdir().unwrap();
    let neighbours = |out: &Path| {
        let frames = read_stats(out)["frames"].as_array().unwrap().clone();
        for f in &frames {
            assert!(f["neighbour_rays"].as_u64().unwrap() <= f["rays"].as_u64().unwrap(), "{f}");
            if !f["full_frame"].is_null() {
                assert_eq!(f["neighbour_rays"], 0, "a frame traced in full has no neighbours: {f}");
            }
        }
        let total: u64 = frames.iter().map(|f| f["neighbour_rays"].as_u64().unwrap()).sum();
        assert_eq!(read_stats(out)["summary"]["totals"]["neighbour_rays"], total);
        total
    };
    let exact = render(dir.path(), "tiny", "exact", &scenes::shipped("tiny"), &flags);
    assert!(neighbours(&exact) > 0, "later frames trace some packets with lanes that are not due");
    let off = render(dir.path(), "tiny", "off", &scenes::shipped("tiny"), &flags);
    assert_eq!(neighbours(&off), 0);
}

#[test]
fn a_camera_that_moves_every_frame_traces_every_frame_without_horizon_queries() {
    // forest-walk's "follow" camera is key-framed: every frame is traced in full, and since
    // the next frame is always full, no sample's horizon is worth finding.
    let flags = ["--camera", "follow", "--size", "48x27", "--spp", "1", "--frames", "0..6"];
    assert_exact_matches_full("follow", &scenes::shipped("forest-walk"), &flags);
    let dir = tempfile::tempdir().unwrap();
    let out = render(dir.path(), "follow", "exact", &scenes::shipped("forest-walk"), &flags);
    let frames = read_stats(&out)["frames"].as_array().unwrap().clone();
    assert!(frames[1..].iter().all(|f| f["full_frame"] == "camera_moved"), "{frames:?}");
    assert!(frames.iter().all(|f| f["horizon_ms"] == 0.0), "{frames:?}");
}

#[test]
fn an_unknown_camera_is_an_input_error_naming_the_cameras() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("nope");
    let stderr = exits_with(
        dormant()
            .args(["render", "--quiet", "--camera", "nope", "--frames", "0..2", "--out"])
            .arg(&out)
            .arg(scenes::shipped("forest-walk")),
        2,
    );
    assert!(!out.exists());
    assert!(stderr.contains("--camera") && stderr.contains("follow"), "{stderr}");
}
