//! Animated glTF in (issue 40): a rigid-body bake from another tool becomes a trajectory with
//! its rests found from the motion, and renders; malformed animations are input errors that
//! name the file, the animation and the channel.

use crate::common;

use std::path::{Path, PathBuf};

use common::animated::{falling_cubes, scene_toml, time, AnimatedFile, APPEARS, FRAMES, LANDING};
use common::cli::{dormant, exits_with, succeeds};
use dormant::physics::trajectory::Trajectory;
use dormant::physics::{simulate, BodyId, BodyState, IslandEvent, SimulateOptions};
use dormant::scene::file::SceneFile;

/// Writes `file` as `dir/cubes.glb` and a scene file for it (with `extra` in `[animation]`);
/// returns the scene file's path.
fn write_scene(dir: &Path, file: &AnimatedFile, extra: &str) -> PathBuf {
    file.write(&dir.join("cubes.glb"));
    let scene = dir.join("cubes.toml");
    std::fs::write(&scene, scene_toml(extra)).unwrap();
    scene
}

fn trajectory_of(file: &AnimatedFile, extra: &str) -> Trajectory {
    let dir = tempfile::TempDir::new().unwrap();
    let scene = SceneFile::load(write_scene(dir.path(), file, extra)).unwrap();
    simulate(&scene, &SimulateOptions::default()).unwrap()
}

/// (frame, bodies) of every `Slept` event, and the number of `Woke` events.
fn rests(t: &Trajectory) -> (Vec<(usize, Vec<u32>)>, usize) {
    let mut slept = Vec::new();
    let mut woke = 0;
    for (f, frame) in t.frames.iter().enumerate() {
        for e in &frame.events {
            match e {
                IslandEvent::Slept { bodies, .. } => slept.push((f, bodies.iter().map(|b| b.0).collect())),
                IslandEvent::Woke { .. } => woke += 1,
            }
        }
    }
    (slept, woke)
}

#[test]
fn bodies_that_stop_together_rest_as_one_island_from_the_frame_they_stop() {
    let t = trajectory_of(&falling_cubes(), "");
    assert_eq!(t.frames.len(), FRAMES as usize);
    assert_eq!(t.prototypes, ["cube"]);
    assert_eq!(t.bodies.len(), 4, "the ground is environment; left, right, spinner and late are bodies");
    assert_eq!(t.timestep, (1.0 / common::animated::FPS) as f32);
    let (slept, woke) = rests(&t);
    assert_eq!(slept, [(APPEARS as usize, vec![3]), (LANDING as usize, vec![0, 1])]);
    assert_eq!(woke, 0);
    assert_eq!(t.bodies[3].spawn_frame, APPEARS);
}

#[test]
fn replayed_poses_are_the_keys_as_stored_and_resting_bodies_hold_the_first_pose_of_their_rest() {
    let t = trajectory_of(&falling_cubes(), "");
    let mut replay = t.replay();
    while let Some(frame) = replay.next_frame() {
        let i = frame.index;
        let y = (3.0 - 5.0 * time(i) * time(i)).max(0.5);
        assert_eq!(frame.poses[0].translation.to_array(), [-1.5, y, 0.0], "frame {i}");
        assert_eq!(frame.states[2], BodyState::Awake, "the spinner never rests (frame {i})");
        let late = if i < APPEARS { BodyState::Absent } else { BodyState::Asleep };
        assert_eq!(frame.states[3], late, "frame {i}");
        let left = if i < LANDING { BodyState::Awake } else { BodyState::Asleep };
        assert_eq!(frame.states[BodyId(0).0 as usize], left, "frame {i}");
    }
}

#[test]
fn float_noise_below_the_rest_tolerance_still_rests_and_a_tolerance_of_zero_does_not() {
    let mut file = falling_cubes();
    // The left cube drifts by 2e-6 a frame once landed, as bodies in Blender's bakes do.
    let drift: Vec<f32> = (0..FRAMES)
        .flat_map(|i| {
            let t = time(i);
            let settled = i.saturating_sub(LANDING) as f32 * 2e-6;
            [-1.5 + settled, (3.0 - 5.0 * t * t).max(0.5), 0.0]
        })
        .collect();
    file.set_output(0, &drift);
    let (slept, _) = rests(&trajectory_of(&file, ""));
    assert_eq!(slept, [(APPEARS as usize, vec![3]), (LANDING as usize, vec![0, 1])]);
    let (slept, _) = rests(&trajectory_of(&file, "rest_tolerance = 0.0"));
    assert_eq!(slept, [(APPEARS as usize, vec![3]), (LANDING as usize, vec![1])]);
}

#[test]
fn an_animated_scene_renders_and_a_glb_without_a_frame_rate_renders_at_24_fps_unless_fps_says_otherwise() {
    let dir = tempfile::TempDir::new().unwrap();
    let scene = write_scene(dir.path(), &falling_cubes(), "");
    let out = dir.path().join("frames");
    succeeds(
        dormant()
            .args(["--quiet", "render"])
            .arg(&scene)
            .args(["--frames", "16..19", "--size", "32x18", "--spp", "1", "--out"])
            .arg(&out),
    );
    let mut images: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|name| name.starts_with("frame_"))
        .collect();
    images.sort();
    assert_eq!(images, ["frame_0016.png", "frame_0017.png", "frame_0018.png"]);
    // A bake from another tool records no rate: 24 fps, said in one line.
    let glb = dir.path().join("cubes.glb");
    let at_24 = dir.path().join("at-24");
    let line = succeeds_saying_once(
        dormant()
            .arg("render")
            .arg(&glb)
            .args(["--frames", "17..18", "--size", "32x18", "--spp", "1", "--out"])
            .arg(&at_24),
        "records no frame rate",
    );
    assert!(line.contains("cubes.glb") && line.contains("24 fps") && line.contains("--fps"), "{line}");
    assert_eq!(
        std::fs::read(at_24.join("frame_0017.png")).unwrap(),
        std::fs::read(out.join("frame_0017.png")).unwrap()
    );
    // A scene file states the rate itself.
    let no_rate = dir.path().join("no-rate.toml");
    std::fs::write(&no_rate, "[scene]\nname = \"cubes\"\n\n[animation]\ngltf = \"cubes.glb\"\n").unwrap();
    let stderr = exits_with(dormant().args(["--quiet", "render"]).arg(&no_rate).args(["--out"]).arg(&out), 2);
    assert!(stderr.contains("no-rate.toml") && stderr.contains("animation.fps"), "{stderr}");
    // The command line may give the rate too.
    let from_glb = dir.path().join("from-glb");
    succeeds(
        dormant()
            .args(["--quiet", "render"])
            .arg(&glb)
            .args(["--fps", "24", "--frames", "17..18", "--size", "32x18", "--spp", "1", "--out"])
            .arg(&from_glb),
    );
    assert_eq!(
        std::fs::read(from_glb.join("frame_0017.png")).unwrap(),
        std::fs::read(out.join("frame_0017.png")).unwrap()
    );
    let stderr = exits_with(
        dormant().args(["--quiet", "render"]).arg(&scene).args(["--fps", "24", "--out"]).arg(&out),
        2,
    );
    assert!(
        stderr.contains("--fps") && stderr.contains("a scene file gives `fps` in [animation]"),
        "{stderr}"
    );
}

/// `file` broken by `break_it`, simulated: exits 2 with a message naming the file and
/// containing every one of `expected`.
fn refused(break_it: impl FnOnce(&mut AnimatedFile), expected: &[&str]) {
    let dir = tempfile::TempDir::new().unwrap();
    let mut file = falling_cubes();
    break_it(&mut file);
    let scene = write_scene(dir.path(), &file, "");
    let stderr = exits_with(
        dormant().args(["--quiet", "simulate"]).arg(&scene).arg("--out").arg(dir.path().join("t.traj")),
        2,
    );
    assert!(stderr.contains("cubes.glb"), "{stderr}");
    for e in expected {
        assert!(stderr.contains(e), "expected {e:?} in: {stderr}");
    }
    assert!(!dir.path().join("t.traj").exists());
}

#[test]
fn malformed_animations_are_input_errors_naming_the_file_animation_and_channel() {
    let channel0 = "animations[0] (\"bake\").channels[0]";
    // One key's output dropped: 48 times, 47 values.
    refused(
        |f| {
            let output = f.output_accessor(0);
            f.json["accessors"][output]["count"] = 47.into();
        },
        &[channel0, "47 output values for 48 input times"],
    );
    refused(
        |f| {
            f.channel(1, "scale", "LINEAR", &[0.0, 0.5, 0.5], &[1.0; 9]);
        },
        &["animations[0] (\"bake\").channels[4]", "not increasing at key 2"],
    );
    refused(
        |f| {
            f.channel(4, "translation", "LINEAR", &[0.0, 1.0], &[0.0, f32::NAN, 0.0, 0.0, 0.0, 0.0]);
        },
        &["channels[4]", "output value 0 is not finite"],
    );
    refused(|f| f.json["animations"][0]["channels"][0]["target"]["node"] = 99.into(), &["node"]);
    refused(
        |f| f.json["animations"][0]["samplers"][0]["interpolation"] = "QUADRATIC".into(),
        &["interpolation"],
    );
    refused(
        |f| {
            f.channel(1, "translation", "LINEAR", &[0.0], &[0.0, 0.0, 0.0]);
        },
        &["channels[4]", "animates the translation of nodes[1] a second time"],
    );
}

#[test]
fn the_specular_layer_reads_from_khr_materials_specular_and_from_dormants_own_extras() {
    let mut file = falling_cubes();
    file.json["extensionsUsed"] = serde_json::json!(["KHR_materials_specular"]);
    file.json["materials"][0]["extensions"] =
        serde_json::json!({"KHR_materials_specular": {"specularFactor": 0.25}});
    file.json["materials"][1]["extras"] = serde_json::json!({"dormant": {"specular": 0.0}});
    let asset = dormant::scene::gltf::load_gltf_slice(&file.glb(), Path::new("cubes.glb")).unwrap();
    let specular: Vec<f32> = asset.materials.iter().map(|m| m.specular).collect();
    assert_eq!(specular, [0.25, 0.0]);
}

/// The sun and lights a render of `file` (with no scene file lights) is lit by.
fn lit_by(file: &AnimatedFile) -> dormant::scene::SceneDescription {
    let dir = tempfile::TempDir::new().unwrap();
    let scene = SceneFile::load(write_scene(dir.path(), file, "")).unwrap();
    dormant::scene::SceneAssets::load(&scene).unwrap().describe(0.0)
}

/// Adds KHR_lights_punctual `lights` to `file`, each on a node of its own at the root.
fn with_lights(file: &mut AnimatedFile, lights: serde_json::Value) {
    let count = lights.as_array().unwrap().len();
    file.json["extensionsUsed"] = serde_json::json!(["KHR_lights_punctual"]);
    file.json["extensions"] = serde_json::json!({ "KHR_lights_punctual": { "lights": lights } });
    for i in 0..count {
        let nodes = file.json["nodes"].as_array_mut().unwrap();
        nodes.push(serde_json::json!({ "extensions": { "KHR_lights_punctual": { "light": i } } }));
        let node = nodes.len() - 1;
        file.json["scenes"][0]["nodes"].as_array_mut().unwrap().push(serde_json::json!(node));
    }
}

#[test]
fn a_blender_bakes_sun_in_lux_is_the_sun_at_its_strength_in_blender() {
    // Blender's exporter writes a sun of strength 3 W/m² as 3 * 683 = 2049 lux, and a point
    // light of 1000 W as 1000 / (4 pi) * 683 candela.
    let mut file = falling_cubes();
    let candela = 1000.0 / (4.0 * std::f32::consts::PI) * 683.0;
    with_lights(
        &mut file,
        serde_json::json!([
            { "type": "directional", "intensity": 2049.0 },
            { "type": "point", "intensity": candela }
        ]),
    );
    let desc = lit_by(&file);
    assert!((desc.sun.irradiance - glam::Vec3::splat(3.0)).abs().max_element() < 1e-5, "{:?}", desc.sun);
    // The node's -Z is where its light travels: the sun is up the node's +Z.
    assert!((desc.sun.direction - glam::Vec3::Z).length() < 1e-5, "{:?}", desc.sun);
    assert_eq!(desc.lights.len(), 1, "the sun is not a second directional light: {:?}", desc.lights);
    match desc.lights[0] {
        dormant::scene::Light::Point { intensity, .. } => {
            // Cycles' point light of P watts has a radiant intensity of P / (4 pi) W/sr.
            let expected = 1000.0 / (4.0 * std::f32::consts::PI);
            assert!((intensity - glam::Vec3::splat(expected)).abs().max_element() < 1e-3, "{intensity}");
        }
        ref other => panic!("expected the point light, got {other:?}"),
    }
}

#[test]
fn a_bake_without_lights_is_lit_by_the_default_sky_and_sun_and_says_so() {
    let desc = lit_by(&falling_cubes());
    assert!(desc.lights.is_empty());
    let default = dormant::scene::default_scene();
    assert_eq!(desc.sun.irradiance, default.sun.irradiance);
    // The one line, from the binary.
    let dir = tempfile::TempDir::new().unwrap();
    let scene = write_scene(dir.path(), &falling_cubes(), "");
    succeeds_saying_once(
        dormant()
            .arg("render")
            .arg(&scene)
            .args(["--frames", "0..1", "--size", "32x18", "--spp", "1", "--mode", "shaded", "--out"])
            .arg(dir.path().join("out")),
        "no lights in the file",
    );
}

/// Runs `cmd`, which must succeed and print exactly one stderr line containing `needle`;
/// returns that line.
fn succeeds_saying_once(cmd: &mut std::process::Command, needle: &str) -> String {
    let out = cmd.output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{cmd:?}: {stderr}");
    let lines: Vec<&str> = stderr.lines().filter(|l| l.contains(needle)).collect();
    assert_eq!(lines.len(), 1, "{cmd:?}: one line with {needle:?} in: {stderr}");
    lines[0].to_string()
}
