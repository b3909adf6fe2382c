//! Every class of bad input in docs/errors.md, through the real binary: the exit code, a
//! message naming the file (or flag), the field and the cause, no panic, and no partial
//! output file. One test per row of the table; `the_error_table_names_every_test` keeps the
//! table and this file in step.

use crate::common;

use std::path::Path;
use std::process::Command;
use std::sync::OnceLock;

use common::cli::{dormant, exits_with, simulate_tiny, succeeds};
use common::repo;
use common::scenes::{self, BOXES};
use tempfile::TempDir;

/// Runs `cmd`, expects exit `code` and a message holding every one of `needles`, no panic,
/// and (when given) an output directory with no file in it; returns stderr.
fn expect_exit(cmd: &mut Command, code: i32, needles: &[&str], out: Option<&Path>) -> String {
    let stderr = exits_with(cmd, code);
    assert!(!stderr.contains("panicked"), "{cmd:?} panicked: {stderr}");
    for needle in needles {
        assert!(stderr.contains(needle), "{cmd:?}: expected {needle:?} in: {stderr}");
    }
    if let Some(out) = out {
        let left: Vec<_> =
            std::fs::read_dir(out).into_iter().flatten().flatten().map(|e| e.file_name()).collect();
        assert!(left.is_empty(), "{cmd:?} left files behind: {left:?}");
    }
    stderr
}

/// `render SCENE` of one small frame into `dir/out`.
fn render_scene(dir: &Path, scene: &Path) -> Command {
    let mut cmd = dormant();
    cmd.args(["render", "--frames", "0..1", "--size", "16x9", "--spp", "1", "--out"])
        .arg(dir.join("out"))
        .arg(scene);
    cmd
}

// ---------------------------------------------------------------------------------------------
// Scene files

/// `BOXES` with `from` replaced by `to`, written as `dir/bad.toml`, rendered: exit 2 naming
/// the file, its line and every one of `needles`.
fn expect_scene_error(from: &str, to: &str, line: usize, needles: &[&str]) {
    assert!(BOXES.contains(from), "{from:?}");
    let dir = TempDir::new().unwrap();
    let scene = dir.path().join("bad.toml");
    std::fs::write(&scene, BOXES.replace(from, to)).unwrap();
    let at = format!("bad.toml:{line}");
    let mut all = vec![at.as_str()];
    all.extend_from_slice(needles);
    expect_exit(&mut render_scene(dir.path(), &scene), 2, &all, Some(&dir.path().join("out")));
}

#[test]
fn scene_toml_syntax_error_names_line_and_column() {
    expect_scene_error("frames = 10", "frames = = 10", 3, &["bad.toml:3:", "frames"]);
}

#[test]
fn scene_value_of_the_wrong_type_names_the_field() {
    expect_scene_error("frames = 10", "frames = \"ten\"", 3, &["scene.frames", "expected u32"]);
}

#[test]
fn scene_value_out_of_range_names_the_field() {
    expect_scene_error("count = 4", "count = 0", 15, &["spawners[0].count", "at least 1"]);
    expect_scene_error("[0.5, 0.5, 0.5]", "[0.5, nan, 0.5]", 11, &["prototypes[0].half_extents", "finite"]);
}

#[test]
fn scene_unknown_key_is_rejected() {
    expect_scene_error("count = 4", "count = 4\ncolour = \"red\"", 16, &["colour"]);
}

#[test]
fn scene_adaptive_sampling_out_of_range_names_the_field() {
    let render = "[render]\nnoise_threshold = -0.5\n\n[environment]";
    expect_scene_error("[environment]", render, 6, &["render.noise_threshold", "must not be negative"]);
    let render = "[render]\nnoise_threshold = 0.05\nmin_spp = 0\n\n[environment]";
    expect_scene_error("[environment]", render, 7, &["render.min_spp", "at least 1"]);
    // Above the run's --spp (1 in `render_scene`): named as the scene's field.
    let dir = TempDir::new().unwrap();
    let scene = dir.path().join("bad.toml");
    let render = "[render]\nnoise_threshold = 0.05\nmin_spp = 4\n\n[environment]";
    std::fs::write(&scene, BOXES.replace("[environment]", render)).unwrap();
    let needles = ["render.min_spp 4", "--spp (1)"];
    expect_exit(&mut render_scene(dir.path(), &scene), 2, &needles, Some(&dir.path().join("out")));
}

#[test]
fn scene_dangling_reference_names_the_missing_name() {
    expect_scene_error(
        "prototypes = [\"box\"]",
        "prototypes = [\"crate\"]",
        14,
        &["spawners[0].prototypes[0]", "crate"],
    );
}

#[test]
fn scene_missing_asset_names_the_path() {
    expect_scene_error(
        "generator = \"ground\"",
        "gltf = \"nowhere.glb\"",
        6,
        &["environment.gltf", "nowhere.glb"],
    );
}

#[test]
fn scene_huge_count_is_refused_before_allocating() {
    expect_scene_error("count = 4", "count = 4000000000", 15, &["spawners[0].count", "at most 2000000"]);
}

#[test]
fn scene_bodies_beyond_the_machine_are_refused() {
    let two = BOXES.replace("count = 4", "count = 1500000") + &BOXES[BOXES.find("[[spawners]]").unwrap()..];
    let two = two.replace("count = 4", "count = 1500000");
    let dir = TempDir::new().unwrap();
    let scene = dir.path().join("bad.toml");
    std::fs::write(&scene, two).unwrap();
    let needles = ["bad.toml:13", "spawners", "3000000 bodies", "2000000"];
    expect_exit(&mut render_scene(dir.path(), &scene), 2, &needles, Some(&dir.path().join("out")));
    let grid =
        "[[structures]]\nname = \"g\"\nkind = \"grid\"\nprototype = \"box\"\norigin = [0.0, 0.0, 9.0]\n\
                counts = [100000, 100000, 100000]\n";
    std::fs::write(&scene, format!("{BOXES}\n{grid}")).unwrap();
    let needles = ["bad.toml:23", "structures[0].counts", "2000000"];
    expect_exit(&mut render_scene(dir.path(), &scene), 2, &needles, Some(&dir.path().join("out")));
}

#[test]
fn scene_image_size_beyond_the_machine_is_refused() {
    let text = format!("{BOXES}\n[render]\nwidth = 16384\nheight = 16384\n");
    let dir = TempDir::new().unwrap();
    let scene = dir.path().join("bad.toml");
    std::fs::write(&scene, text).unwrap();
    // Simulate: render's --size would override the scene's size.
    let mut cmd = dormant();
    cmd.args(["--quiet", "simulate", "--out"]).arg(dir.path().join("out/t.traj")).arg(&scene);
    expect_exit(&mut cmd, 2, &["bad.toml:19", "render.width", "8192x8192"], Some(&dir.path().join("out")));
}

#[test]
fn scene_shutter_outside_zero_to_one_names_the_field() {
    let last = "region = { min = [0.0, 1.0, 0.0], max = [2.0, 1.0, 2.0] }";
    for shutter in ["-0.5", "1.5"] {
        let with = format!("{last}\n\n[render]\nshutter = {shutter}");
        expect_scene_error(last, &with, 19, &["render.shutter", shutter, "from 0 (no motion blur) to 1"]);
    }
}

#[test]
fn scene_file_missing_or_unreadable_names_the_path() {
    let dir = TempDir::new().unwrap();
    let missing = dir.path().join("absent.toml");
    expect_exit(&mut render_scene(dir.path(), &missing), 2, &["absent.toml"], Some(&dir.path().join("out")));
    let not_utf8 = dir.path().join("binary.toml");
    std::fs::write(&not_utf8, [0xff, 0xfe, 0x00, 0x80]).unwrap();
    expect_exit(&mut render_scene(dir.path(), &not_utf8), 2, &["binary.toml"], Some(&dir.path().join("out")));
}

// ---------------------------------------------------------------------------------------------
// glTF assets, through a scene file's environment

/// One triangle: three VEC3 positions (36 bytes), then three u16 indices (6 bytes, padded).
fn triangle_bin(positions: [f32; 9]) -> Vec<u8> {
    let mut bytes: Vec<u8> = positions.iter().flat_map(|v| v.to_le_bytes()).collect();
    bytes.extend([0u16, 1, 2].iter().flat_map(|i| i.to_le_bytes()));
    bytes.extend([0, 0]);
    bytes
}

const TRIANGLE: [f32; 9] = [-5.0, 0.0, -5.0, 5.0, 0.0, -5.0, 0.0, 0.0, 5.0];

/// A glTF document over `env.bin`; `position_count` is the POSITION accessor's count and
/// `extra` more top-level members (each followed by a comma).
fn gltf_json(position_count: u64, extra: &str) -> String {
    format!(
        r#"{{ {extra}
  "asset": {{ "version": "2.0" }},
  "scene": 0, "scenes": [{{ "nodes": [0] }}], "nodes": [{{ "mesh": 0 }}],
  "meshes": [{{ "primitives": [{{ "attributes": {{ "POSITION": 0 }}, "indices": 1 }}] }}],
  "buffers": [{{ "uri": "env.bin", "byteLength": 44 }}],
  "bufferViews": [{{ "buffer": 0, "byteOffset": 0, "byteLength": 36 }},
                  {{ "buffer": 0, "byteOffset": 36, "byteLength": 6 }}],
  "accessors": [{{ "bufferView": 0, "componentType": 5126, "count": {position_count}, "type": "VEC3",
                   "min": [-5.0, 0.0, -5.0], "max": [5.0, 0.0, 5.0] }},
                {{ "bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR" }}]
}}"#
    )
}

/// A scene whose environment is `env.gltf` with `json` (and `env.bin` holding `bin`, when
/// given), rendered: exit `code`, and every one of `needles` in the message.
fn expect_gltf_outcome(json: &str, bin: Option<Vec<u8>>, code: i32, needles: &[&str]) -> String {
    let dir = TempDir::new().unwrap();
    std::fs::write(dir.path().join("env.gltf"), json).unwrap();
    if let Some(bin) = bin {
        std::fs::write(dir.path().join("env.bin"), bin).unwrap();
    }
    let scene = dir.path().join("scene.toml");
    std::fs::write(&scene, BOXES.replace("generator = \"ground\"", "gltf = \"env.gltf\"")).unwrap();
    let out = (code != 0).then(|| dir.path().join("out"));
    expect_exit(&mut render_scene(dir.path(), &scene), code, needles, out.as_deref())
}

#[test]
fn gltf_that_loads_renders() {
    expect_gltf_outcome(&gltf_json(3, ""), Some(triangle_bin(TRIANGLE)), 0, &[]);
}

#[test]
fn gltf_malformed_names_the_file() {
    expect_gltf_outcome("{ \"asset\": ", None, 2, &["env.gltf", "environment.gltf"]);
    expect_gltf_outcome("glTF\u{2}\0\0\0garbage", None, 2, &["env.gltf"]);
}

#[test]
fn gltf_missing_buffer_names_it() {
    expect_gltf_outcome(&gltf_json(3, ""), None, 2, &["env.gltf", "buffers[0]", "env.bin"]);
}

#[test]
fn gltf_missing_image_renders_magenta_with_a_warning() {
    let textured = r#""materials": [{ "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } } }],
  "textures": [{ "source": 0 }], "images": [{ "uri": "missing.png" }],"#;
    let json = gltf_json(3, textured).replace(r#""indices": 1 }"#, r#""indices": 1, "material": 0 }"#);
    let stderr = expect_gltf_outcome(&json, Some(triangle_bin(TRIANGLE)), 0, &[]);
    assert!(stderr.contains("missing.png"), "the warning names the image: {stderr}");
}

#[test]
fn gltf_unsupported_required_extension_is_refused() {
    let ext = r#""extensionsUsed": ["KHR_draco_mesh_compression"], "extensionsRequired": ["KHR_draco_mesh_compression"],"#;
    let needles = ["env.gltf", "extensionsRequired[0]", "KHR_draco_mesh_compression"];
    expect_gltf_outcome(&gltf_json(3, ext), Some(triangle_bin(TRIANGLE)), 2, &needles);
}

#[test]
fn gltf_nan_vertices_are_refused() {
    let mut nan = TRIANGLE;
    nan[4] = f32::NAN;
    expect_gltf_outcome(
        &gltf_json(3, ""),
        Some(triangle_bin(nan)),
        2,
        &["env.gltf", "meshes[0]", "non-finite"],
    );
}

#[test]
fn gltf_huge_counts_are_refused_without_allocating() {
    let needles = ["env.gltf", "accessors[0]"];
    expect_gltf_outcome(&gltf_json(4_000_000_000, ""), Some(triangle_bin(TRIANGLE)), 2, &needles);
}

// ---------------------------------------------------------------------------------------------
// Trajectories

/// A 20-frame trajectory of scenes/tiny.toml, simulated once for all tests.
fn tiny_trajectory() -> &'static [u8] {
    static BYTES: OnceLock<Vec<u8>> = OnceLock::new();
    BYTES.get_or_init(|| {
        let dir = TempDir::new().unwrap();
        std::fs::read(simulate_tiny(dir.path(), &["--frame-count", "20"])).unwrap()
    })
}

/// Renders the trajectory `bytes` (written as `dir/t.traj`) with `scene` when given.
fn expect_trajectory_error(bytes: &[u8], scene: Option<&Path>, needles: &[&str]) {
    let dir = TempDir::new().unwrap();
    let path = dir.path().join("t.traj");
    std::fs::write(&path, bytes).unwrap();
    let mut cmd = dormant();
    cmd.args(["--quiet", "render", "--size", "16x9", "--spp", "1", "--trajectory"]).arg(&path);
    cmd.arg("--out").arg(dir.path().join("out"));
    if let Some(scene) = scene {
        cmd.arg(scene);
    }
    expect_exit(&mut cmd, 2, needles, Some(&dir.path().join("out")));
}

#[test]
fn trajectory_truncated_names_the_byte_offset() {
    let bytes = tiny_trajectory();
    expect_trajectory_error(&bytes[..bytes.len() / 2], None, &["t.traj", "at byte"]);
}

#[test]
fn trajectory_corrupt_fails_its_checksum() {
    let mut bytes = tiny_trajectory().to_vec();
    let middle = bytes.len() / 2;
    bytes[middle] ^= 0x55;
    expect_trajectory_error(&bytes, None, &["t.traj", "checksum"]);
}

#[test]
fn trajectory_of_another_version_is_refused() {
    let mut bytes = tiny_trajectory().to_vec();
    bytes[8..12].copy_from_slice(&99u32.to_le_bytes());
    expect_trajectory_error(&bytes, None, &["t.traj", "version 99"]);
}

#[test]
fn trajectory_of_another_scene_is_refused() {
    let scene = scenes::shipped("monastery-rain");
    expect_trajectory_error(
        tiny_trajectory(),
        Some(&scene),
        &["t.traj", "another scene than", "monastery-rain.toml"],
    );
}

#[test]
fn trajectory_that_is_not_one_is_refused() {
    expect_trajectory_error(
        b"[scene]\nname = \"not a trajectory\"\n",
        None,
        &["t.traj", "not a dormant trajectory"],
    );
    expect_trajectory_error(b"", None, &["t.traj"]);
}

// ---------------------------------------------------------------------------------------------
// Command-line values

fn expect_usage_error(args: &[&str], needles: &[&str]) {
    let dir = TempDir::new().unwrap();
    let mut cmd = dormant();
    cmd.args(args).arg("--out").arg(dir.path().join("out"));
    expect_exit(&mut cmd, 2, needles, Some(&dir.path().join("out")));
}

#[test]
fn cli_frames_malformed_empty_or_beyond_the_scene() {
    let tiny = scenes::shipped("tiny");
    let tiny = tiny.to_str().unwrap();
    expect_usage_error(&["render", tiny, "--frames", "ten"], &["--frames", "ten"]);
    expect_usage_error(&["render", tiny, "--frames", "9..3"], &["--frames", "9..3"]);
    expect_usage_error(&["render", tiny, "--frames", "400..900"], &["--frames", "480"]);
    expect_usage_error(&["render", "--frames", "0..2"], &["--frames"]);
}

#[test]
fn cli_size_malformed_or_beyond_the_machine() {
    expect_usage_error(&["render", "--size", "big"], &["--size", "WIDTHxHEIGHT"]);
    expect_usage_error(&["render", "--size", "0x5"], &["--size", "from 1 to 16384"]);
    expect_usage_error(&["render", "--size", "16384x16384"], &["--size", "8192x8192"]);
}

#[test]
fn cli_spp_out_of_range() {
    expect_usage_error(&["render", "--spp", "0"], &["--spp"]);
    expect_usage_error(&["render", "--spp", "100000"], &["--spp", "65536"]);
}

#[test]
fn cli_noise_threshold_negative_or_not_a_number() {
    expect_usage_error(
        &["render", "--noise-threshold", "-0.1"],
        &["--noise-threshold -0.1", "0 (off) or more"],
    );
    expect_usage_error(&["render", "--noise-threshold", "NaN"], &["--noise-threshold NaN"]);
    expect_usage_error(&["render", "--noise-threshold", "low"], &["--noise-threshold"]);
}

#[test]
fn cli_min_spp_above_spp_or_without_adaptive_sampling() {
    let adaptive = ["render", "--noise-threshold", "0.05", "--spp", "16"];
    expect_usage_error(&[&adaptive[..], &["--min-spp", "32"]].concat(), &["--min-spp 32", "--spp (16)"]);
    expect_usage_error(&[&adaptive[..], &["--min-spp", "0"]].concat(), &["--min-spp 0"]);
    expect_usage_error(&["render", "--min-spp", "4"], &["--min-spp", "--noise-threshold"]);
}

#[test]
fn cli_aov_unknown() {
    expect_usage_error(&["render", "--aov", "albedo,glossy"], &["--aov", "glossy", "spp"]);
}

#[test]
fn cli_shutter_outside_zero_to_one() {
    let tiny = scenes::shipped("tiny");
    let tiny = tiny.to_str().unwrap();
    let range = "from 0 (no motion blur) to 1";
    expect_usage_error(&["render", tiny, "--shutter", "-0.5"], &["--shutter -0.5", range]);
    expect_usage_error(&["render", tiny, "--shutter", "1.5"], &["--shutter 1.5", range]);
    expect_usage_error(&["render", "--shutter", "0.5"], &["--shutter needs a SCENE file or --trajectory"]);
    // These write no files.
    expect_exit(dormant().args(["verify", tiny, "--shutter", "2"]), 2, &["--shutter 2", range], None);
    let bench = ["bench", "integration", tiny, "--shutter", "-1"];
    expect_exit(dormant().args(bench), 2, &["--shutter -1", range], None);
}

#[test]
fn cli_filter_width_or_clamp_indirect_out_of_range() {
    let width = "must be a number above 0 and at most 16 pixels";
    expect_usage_error(&["render", "--filter-width", "0"], &["--filter-width", "width 0", width]);
    expect_usage_error(
        &["render", "--filter", "gaussian", "--filter-width", "100"],
        &["--filter-width", "100"],
    );
    expect_usage_error(&["render", "--filter", "mitchell"], &["--filter", "mitchell", "blackman-harris"]);
    let clamp = "must be a number, 0 (off) or more";
    expect_usage_error(&["render", "--clamp-indirect=-1"], &["--clamp-indirect -1", clamp]);
    expect_usage_error(&["render", "--clamp-indirect", "NaN"], &["--clamp-indirect NaN", clamp]);
}

#[test]
fn cli_export_without_a_sequence() {
    let dir = TempDir::new().unwrap();
    let out = dir.path().join("e.json");
    expect_exit(
        dormant().args(["export", "--out"]).arg(&out),
        2,
        &["export needs a SCENE file or --trajectory"],
        Some(dir.path()),
    );
}

#[test]
fn cli_export_gltf_with_frames_or_without_an_output() {
    let dir = TempDir::new().unwrap();
    let tiny = scenes::shipped("tiny");
    expect_exit(
        dormant()
            .arg("export")
            .arg(&tiny)
            .args(["--frames", "0..10", "--gltf"])
            .arg(dir.path().join("e.glb")),
        2,
        &["--frames: the glTF export has every frame"],
        Some(dir.path()),
    );
    expect_exit(dormant().arg("export").arg(&tiny), 2, &["--out <FILE>"], Some(dir.path()));
}

#[test]
fn cli_threads_out_of_range() {
    expect_usage_error(&["--threads", "0", "render"], &["--threads"]);
    expect_usage_error(&["--threads", "many", "render"], &["--threads"]);
}

#[test]
fn cli_counts_beyond_the_machine() {
    let tiny = scenes::shipped("tiny");
    let tiny = tiny.to_str().unwrap();
    expect_usage_error(&["simulate", tiny, "--count", "0"], &["--count", "from 1"]);
    expect_usage_error(&["simulate", tiny, "--count", "3000000"], &["--count", "2000000"]);
    expect_usage_error(&["simulate", tiny, "--frame-count", "2000000"], &["--frame-count", "1000000"]);
}

#[test]
fn cli_simd_path_unknown_or_unsupported() {
    let dir = TempDir::new().unwrap();
    let out = dir.path().join("out");
    let mut cmd = dormant();
    cmd.env("DORMANT_SIMD", "sse9").args(["render", "--size", "8x8", "--spp", "1", "--out"]).arg(&out);
    expect_exit(&mut cmd, 2, &["DORMANT_SIMD=sse9", "unknown SIMD path", "portable"], Some(&out));
    let mut cmd = dormant();
    cmd.env("DORMANT_SIMD", "sse9").arg("info");
    expect_exit(&mut cmd, 2, &["DORMANT_SIMD=sse9"], None);
    // Every supported path is accepted, and `info` names the one that runs.
    let info = dormant().arg("info").output().unwrap();
    let info: serde_json::Value = serde_json::from_slice(&info.stdout).unwrap();
    for path in info["simd_paths_supported"].as_array().unwrap() {
        let path = path.as_str().unwrap();
        let out = dormant().env("DORMANT_SIMD", path).arg("info").output().unwrap();
        assert!(out.status.success(), "{path}: {}", String::from_utf8_lossy(&out.stderr));
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(v["simd_path"], path);
    }
}

#[test]
fn cli_output_path_not_writable_is_a_runtime_error() {
    let dir = TempDir::new().unwrap();
    let file = dir.path().join("not-a-dir");
    std::fs::write(&file, b"").unwrap();
    let mut cmd = dormant();
    cmd.args(["--quiet", "render", "--size", "8x8", "--spp", "1", "--out"]).arg(file.join("sub"));
    expect_exit(&mut cmd, 1, &["not-a-dir"], None);
    let mut cmd = dormant();
    cmd.args(["--quiet", "simulate", "--out"]).arg(file.join("t.traj")).arg(scenes::shipped("tiny"));
    expect_exit(&mut cmd, 1, &["not-a-dir"], None);
    // A directory that does not exist yet is created, as for `render --out`.
    let traj = dir.path().join("new/dir/t.traj");
    succeeds(
        dormant()
            .args(["--quiet", "simulate", "--frame-count", "2", "--out"])
            .arg(&traj)
            .arg(scenes::shipped("tiny")),
    );
    assert!(traj.is_file());
}

// ---------------------------------------------------------------------------------------------

/// docs/errors.md names each test of this file once, and only tests of this file.
#[test]
fn the_error_table_names_every_test() {
    let table = std::fs::read_to_string(repo("docs/errors.md")).unwrap();
    let source = std::fs::read_to_string(repo("tests/input_errors.rs")).unwrap();
    let tests: Vec<&str> = source
        .split("#[test]\nfn ")
        .skip(1)
        .map(|rest| &rest[..rest.find('(').unwrap()])
        .filter(|name| *name != "the_error_table_names_every_test")
        .collect();
    for name in &tests {
        assert!(table.contains(&format!("`{name}`")), "docs/errors.md has no row for {name}");
    }
    for word in table.split('`').skip(1).step_by(2) {
        let is_test = word.starts_with("scene_")
            || word.starts_with("gltf_")
            || word.starts_with("trajectory_")
            || word.starts_with("cli_");
        if is_test && word.chars().all(|c| c.is_ascii_lowercase() || c == '_' || c.is_ascii_digit()) {
            assert!(tests.contains(&word), "docs/errors.md names {word}, which is not a test here");
        }
    }
}

#[test]
fn a_truncated_glb_given_as_the_scene_says_truncated_and_names_the_file_once() {
    let dir = TempDir::new().unwrap();
    let whole = common::animated::falling_cubes().glb();
    let glb = dir.path().join("cut.glb");
    std::fs::write(&glb, &whole[..whole.len() / 2]).unwrap();
    let stderr = expect_exit(&mut render_scene(dir.path(), &glb), 2, &["cut.glb", "truncated"], None);
    assert_eq!(stderr.matches("cut.glb").count(), 1, "the file named once: {stderr}");
}
