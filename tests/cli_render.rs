//! The `dormant` binary end to end: the default render, `info`, and bad output paths.

use crate::common;

use std::path::Path;

use common::cli::{dormant, exits_with, read_json, read_stats, simulate_tiny, succeeds};
use common::scenes;

fn png_is_not_uniform(path: &Path) -> bool {
    let img = image::open(path).unwrap().to_rgb8();
    let first = *img.get_pixel(0, 0);
    img.pixels().any(|p| *p != first)
}

#[test]
fn default_scene_renders_a_non_uniform_png() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("demo");
    succeeds(dormant().args(["render", "--size", "160x90", "--spp", "2", "--quiet", "--out"]).arg(&out));
    let png = out.join("frame_0000.png");
    assert!(png.is_file());
    assert!(png_is_not_uniform(&png));
    let leftovers: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .filter_map(Result::ok)
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty());
}

#[cfg(feature = "embree")]
#[test]
fn info_reports_embree_4_library_and_header() {
    let output = succeeds(dormant().arg("info"));
    let info: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    let lib = info["embree"]["library_version"].as_str().unwrap();
    let header = info["embree"]["header_version"].as_str().unwrap();
    assert!(lib.starts_with("4."), "{lib}");
    assert_eq!(lib.split('.').next(), header.split('.').next());
    assert!(info["backends"].as_array().unwrap().iter().any(|b| b == "embree"));
}

#[test]
fn unwritable_output_directory_fails_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("not-a-dir");
    std::fs::write(&file, b"").unwrap();
    let stderr = exits_with(
        dormant().args(["render", "--size", "8x8", "--spp", "1", "--out"]).arg(file.join("sub")),
        1,
    );
    assert!(stderr.contains("not-a-dir"), "{stderr}");
}

#[test]
fn failed_frame_write_leaves_no_partial_file() {
    let dir = tempfile::tempdir().unwrap();
    // The frame's path is taken by a directory, so the final rename fails.
    std::fs::create_dir_all(dir.path().join("frame_0000.png")).unwrap();
    exits_with(dormant().args(["render", "--size", "8x8", "--spp", "1", "--out"]).arg(dir.path()), 1);
    let names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, vec!["frame_0000.png".to_string()], "left behind: {names:?}");
}

#[test]
fn usage_errors_exit_2() {
    for args in [
        &["render", "--size", "0x5"][..],
        &["render", "--spp", "0"],
        &["render", "--backend", "optix"],
        &["frobnicate"],
    ] {
        exits_with(dormant().args(args), 2);
    }
}

#[test]
fn trajectory_frames_render_the_same_split_whole_or_from_the_trajectory_alone() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scenes::shipped("tiny");
    let traj = simulate_tiny(dir.path(), &[]);
    let render = |frames: &str, out: &Path, scene_file: Option<&Path>| {
        let mut cmd = dormant();
        cmd.args(["render", "--quiet", "--size", "48x27", "--spp", "2", "--frames", frames, "--trajectory"])
            .arg(&traj)
            .arg("--out")
            .arg(out);
        match scene_file {
            Some(scene) => cmd.arg(scene),
            // The trajectory alone, from another directory: the scene is recorded in it.
            None => cmd.current_dir(dir.path()),
        };
        succeeds(&mut cmd);
    };
    let (whole, split, alone) =
        (dir.path().join("whole"), dir.path().join("split"), dir.path().join("alone"));
    render("200..202", &whole, Some(&scene));
    render("200..201", &split, Some(&scene));
    render("201..202", &split, Some(&scene));
    render("200..202", &alone, None);
    for name in ["frame_0200.png", "frame_0201.png"] {
        let a = std::fs::read(whole.join(name)).unwrap();
        assert_eq!(a, std::fs::read(split.join(name)).unwrap(), "{name} differs split");
        assert_eq!(a, std::fs::read(alone.join(name)).unwrap(), "{name} differs from the trajectory alone");
    }
    assert!(png_is_not_uniform(&whole.join("frame_0200.png")));
}

#[test]
fn trajectory_of_another_scene_is_an_input_error() {
    let dir = tempfile::tempdir().unwrap();
    let traj = simulate_tiny(dir.path(), &[]);
    let mut render = dormant();
    render
        .args(["render", "--trajectory"])
        .arg(&traj)
        .arg("--out")
        .arg(dir.path())
        .arg(scenes::shipped("forest-walk"));
    assert!(exits_with(&mut render, 2).contains("tiny.traj"));
}

#[test]
fn json_is_a_global_flag_before_or_after_the_command() {
    let dir = tempfile::tempdir().unwrap();
    let (before, after) = (dir.path().join("before.json"), dir.path().join("after.json"));
    succeeds(dormant().arg("--json").arg(&before).arg("info"));
    succeeds(dormant().arg("info").arg("--json").arg(&after));
    assert_eq!(read_json(&before), read_json(&after));
    assert!(read_json(&before)["backends"].is_array(), "{:#}", read_json(&before));
}

#[test]
fn render_of_a_trajectory_alone_reports_its_integration_policy() {
    // Bug: `render --trajectory F` without SCENE wrote "integration": null in its JSON although
    // the policy applies.
    let dir = tempfile::tempdir().unwrap();
    let traj = simulate_tiny(dir.path(), &[]);
    let json = dir.path().join("render.json");
    succeeds(
        dormant()
            .args(["render", "--quiet", "--size", "16x9", "--spp", "1", "--frames", "10..11"])
            .args(["--frame-step", "1", "--integration", "never", "--trajectory"])
            .arg(&traj)
            .arg("--out")
            .arg(dir.path().join("out"))
            .arg("--json")
            .arg(&json),
    );
    let report = read_json(&json);
    assert_eq!(report["integration"], "never", "{report:#}");
    assert_eq!(report["frames"].as_array().map(Vec::len), Some(1));
}

#[test]
fn frame_flags_without_a_sequence_are_input_errors() {
    let dir = tempfile::tempdir().unwrap();
    for flags in [["--frames", "0..2"], ["--frame-step", "2"]] {
        let stderr = exits_with(dormant().arg("render").args(flags).arg("--out").arg(dir.path()), 2);
        assert!(stderr.contains(flags[0]) && stderr.contains("SCENE"), "{stderr}");
    }
}

#[test]
fn static_frames_reuse_the_previous_image_byte_for_byte() {
    let dir = tempfile::tempdir().unwrap();
    // Six crates dropped onto the ground: at rest (bit for bit) from about frame 70 on.
    let scene = scenes::copy_data("settle", dir.path());
    let render = |reuse: &str| {
        let out = dir.path().join(format!("reuse-{reuse}"));
        succeeds(
            dormant()
                .args(["render", "--quiet", "--size", "48x27", "--spp", "2", "--frames", "130..150"])
                .args(["--aov", "albedo", "--exr", "--seed", "fixed", "--reuse", reuse, "--out"])
                .arg(&out)
                .arg(&scene),
        );
        out
    };
    let (on, off) = (render("on"), render("off"));
    for f in 130..150 {
        for ext in ["png", "exr", "albedo.png", "albedo.exr"] {
            let name = format!("frame_{f:04}.{ext}");
            let a = std::fs::read(on.join(&name)).unwrap();
            assert_eq!(a, std::fs::read(off.join(&name)).unwrap(), "{name} differs with reuse");
        }
    }
    // Every frame after the first shows the same scene: reused, nothing traced.
    assert_eq!(read_stats(&on)["summary"]["totals"]["reused_frames"], 19);
    assert_eq!(read_stats(&off)["summary"]["totals"]["reused_frames"], 0);
}

#[test]
fn seed_offsets_give_independent_renders_of_one_frame() {
    let dir = tempfile::tempdir().unwrap();
    let render = |name: &str, offset: &str| {
        let out = dir.path().join(name);
        succeeds(
            dormant()
                .args([
                    "render",
                    "--quiet",
                    "--size",
                    "32x18",
                    "--spp",
                    "8",
                    "--seed-offset",
                    offset,
                    "--out",
                ])
                .arg(&out),
        );
        std::fs::read(out.join("frame_0000.png")).unwrap()
    };
    let (a, again, b) = (render("a", "0"), render("again", "0"), render("b", "7"));
    assert_eq!(a, again, "one offset, one image");
    assert_ne!(a, b, "another offset, the same noise");
}
