//! `dormant render`'s settings rule: a flag given on the command line, else `--preset`'s value,
//! else the scene file's `[render]`, else the built-in default; stats.json records the values
//! and where each came from (docs/scene-format.md, "Settings").

use std::path::{Path, PathBuf};

use crate::common;

use common::cli::{dormant, exits_with, read_json, read_stats, succeeds};
use common::scenes;
use serde_json::Value;

/// tiny.toml with its `[render]` table replaced by `render` (TOML lines), written into `dir`.
fn tiny_with_render(dir: &Path, render: &str) -> PathBuf {
    let text = std::fs::read_to_string(scenes::shipped("tiny")).unwrap();
    let start = text.find("[render]").expect("tiny.toml has a [render] table");
    let rest = &text[start + "[render]".len()..];
    let end = rest.find("\n[").map_or(text.len(), |e| start + "[render]".len() + e);
    let scene = format!("{}[render]\n{render}\n{}", &text[..start], &text[end..]);
    let path = dir.join("tiny-settings.toml");
    std::fs::write(&path, scene).unwrap();
    path
}

/// Renders the first frame of `scene` with `flags` into `dir/name`; returns stats.json's `run`.
fn render_first_frame(scene: &Path, dir: &Path, name: &str, flags: &[&str]) -> Value {
    let out = dir.join(name);
    succeeds(
        dormant()
            .args(["--quiet", "render", "--frames", "0..1"])
            .args(flags)
            .arg("--out")
            .arg(&out)
            .arg(scene),
    );
    read_stats(&out)["run"].clone()
}

/// The width and height of a PNG.
fn png_size(path: &Path) -> (u32, u32) {
    let image = image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    (image.width(), image.height())
}

/// `run`'s size, spp and mode, and where each came from.
fn size_spp_mode(run: &Value) -> ((u64, u64, u64, &str), [&str; 3]) {
    let from =
        |k: &str| run["settings_from"][k].as_str().unwrap_or_else(|| panic!("settings_from.{k}: {run}"));
    let values = (
        run["width"].as_u64().unwrap(),
        run["height"].as_u64().unwrap(),
        run["spp"].as_u64().unwrap(),
        run["mode"].as_str().unwrap(),
    );
    (values, [from("size"), from("spp"), from("mode")])
}

#[test]
fn a_scene_files_size_and_samples_take_effect() {
    let dir = tempfile::tempdir().unwrap();
    let scene =
        tiny_with_render(dir.path(), "width = 48\nheight = 27\nsamples_per_pixel = 3\nframe_step = 2");
    let run = render_first_frame(&scene, dir.path(), "scene", &[]);
    assert_eq!(size_spp_mode(&run), ((48, 27, 3, "path"), ["scene", "scene", "default"]));
    assert_eq!(run["frame_step"], 2, "{run}");
    assert_eq!(run["settings_from"]["frame_step"], "scene", "{run}");
    assert_eq!(run["settings_from"]["shutter"], "default", "{run}");
    assert_eq!(png_size(&dir.path().join("scene/frame_0000.png")), (48, 27));
}

#[test]
fn a_flag_overrides_the_scene_file_and_the_preset() {
    let dir = tempfile::tempdir().unwrap();
    let scene = tiny_with_render(dir.path(), "width = 48\nheight = 27\nsamples_per_pixel = 3");
    let flags = ["--size", "32x18", "--spp", "2", "--mode", "ao", "--preset", "preview"];
    let run = render_first_frame(&scene, dir.path(), "flags", &flags);
    assert_eq!(size_spp_mode(&run), ((32, 18, 2, "ao"), ["flag", "flag", "flag"]));
    assert_eq!(png_size(&dir.path().join("flags/frame_0000.png")), (32, 18));
}

#[test]
fn a_preset_sits_between_the_flags_and_the_scene_file() {
    let dir = tempfile::tempdir().unwrap();
    let scene = tiny_with_render(
        dir.path(),
        "width = 48\nheight = 27\nsamples_per_pixel = 3\nframe_step = 4\nnoise_threshold = 0.1\nmin_spp = 2",
    );
    // preview: shaded, 320x180, 1 spp, every frame, adaptive sampling off (the scene's
    // min_spp 2 above 1 spp is then no error); a flag still wins over it.
    let run = render_first_frame(&scene, dir.path(), "preview", &["--preset", "preview", "--spp", "2"]);
    assert_eq!(size_spp_mode(&run), ((320, 180, 2, "shaded"), ["preset", "flag", "preset"]));
    assert_eq!((&run["frame_step"], &run["noise_threshold"]), (&Value::from(1), &Value::from(0.0)), "{run}");
    assert_eq!(run["settings_from"]["frame_step"], "preset", "{run}");
    assert_eq!(run["settings_from"]["noise_threshold"], "preset", "{run}");
    // final: the scene file's own settings.
    let run = render_first_frame(&scene, dir.path(), "final", &["--preset", "final"]);
    assert_eq!(size_spp_mode(&run), ((48, 27, 3, "path"), ["scene", "scene", "default"]));
    assert_eq!(run["frame_step"], 4, "{run}");
    assert_eq!(run["settings_from"]["noise_threshold"], "scene", "{run}");
}

#[test]
fn the_built_in_scene_takes_the_flags_else_the_defaults() {
    let dir = tempfile::tempdir().unwrap();
    let report = dir.path().join("still.json");
    let out = dir.path().join("still");
    succeeds(dormant().args(["render", "--size", "40x24", "--json"]).arg(&report).arg("--out").arg(&out));
    let json = read_json(&report);
    assert_eq!(
        (&json["width"], &json["height"], &json["spp"]),
        (&Value::from(40), &Value::from(24), &Value::from(16))
    );
    assert_eq!(json["settings_from"]["size"], "flag", "{json}");
    assert_eq!(json["settings_from"]["spp"], "default", "{json}");
    assert_eq!(json["settings_from"]["mode"], "default", "{json}");
    assert_eq!(png_size(&out.join("frame_0000.png")), (40, 24));
}

#[test]
fn a_scene_file_with_a_width_and_no_height_is_an_input_error() {
    let dir = tempfile::tempdir().unwrap();
    let scene = tiny_with_render(dir.path(), "width = 48");
    let out = dir.path().join("out");
    let stderr = exits_with(dormant().args(["render", "--out"]).arg(&out).arg(&scene), 2);
    assert!(stderr.contains("render.height") && stderr.contains("tiny-settings.toml"), "{stderr}");
    assert!(!out.exists(), "a bad scene file left {}", out.display());
}

#[test]
fn a_scene_min_spp_above_the_runs_samples_names_where_each_came_from() {
    let dir = tempfile::tempdir().unwrap();
    let scene = tiny_with_render(dir.path(), "samples_per_pixel = 4\nnoise_threshold = 0.1\nmin_spp = 8");
    let out = dir.path().join("out");
    let stderr = exits_with(dormant().args(["render", "--out"]).arg(&out).arg(&scene), 2);
    assert!(
        stderr.contains("render.min_spp 8") && stderr.contains("render.samples_per_pixel (4)"),
        "{stderr}"
    );
    assert!(!out.exists(), "a refused run left {}", out.display());
}
