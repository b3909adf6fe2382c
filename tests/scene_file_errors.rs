//! Bad scene input: every error names the file and the field (and the line when the field
//! is written), and none panics.

use crate::common;

use common::scene_errors::{expect_error, parse};
use common::scenes::{self, BOXES};
use dormant::scene::file::spec::Shape;
use dormant::scene::file::{SceneError, SceneFile};

#[test]
fn the_good_scene_parses() {
    let file = parse(BOXES).unwrap();
    assert_eq!(file.spec().spawners[0].count, 4);
}

#[test]
fn references_resolve_to_indices() {
    let text = BOXES
        .replace(
            "[[spawners]]",
            "[[prototypes]]\nname = \"ball\"\nshape = \"sphere\"\nradius = 0.25\n\n[[spawners]]",
        )
        .replace("prototypes = [\"box\"]", "prototypes = [\"ball\", \"box\"]");
    let cameras = "[[cameras]]\nname = \"a\"\nposition = [0.0, 1.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\n\n\
                   [[cameras]]\nname = \"b\"\nposition = [0.0, 2.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\n\n\
                   [render]\ncamera = \"b\"\n";
    let file = parse(&format!("{text}\n{cameras}")).unwrap();
    let spec = file.spec();
    assert_eq!(spec.spawners[0].prototypes, vec![1, 0]);
    assert_eq!(spec.spawners[0].seed, 0, "a spawner's seed defaults to its index");
    assert_eq!(spec.prototypes[1].shape, Shape::Sphere { radius: 0.25 });
    assert_eq!(spec.render.camera, Some(1));
    assert_eq!(spec.render_camera().map(|c| c.name.as_str()), Some("b"));
}

#[test]
fn malformed_toml_names_the_line() {
    let text = BOXES.replace("frames = 10", "frames = = 10");
    let err = expect_error(&text, "frames", Some(3));
    assert!(matches!(err, SceneError::Syntax { .. }));
}

#[test]
fn unknown_keys_are_rejected() {
    let text = BOXES.replace("count = 4", "count = 4\ncolour = \"red\"");
    let err = expect_error(&text, "colour", Some(16));
    assert!(matches!(err, SceneError::Syntax { .. }));
    let text = BOXES.replace("[environment]", "[environmnet]");
    parse(&text).unwrap_err();
}

#[test]
fn nan_and_infinite_values_are_rejected() {
    let text = BOXES.replace("frames = 10", "frames = 10\n[physics]\ntimestep = nan");
    expect_error(&text, "physics.timestep", Some(5));
    let text = BOXES.replace("[0.5, 0.5, 0.5]", "[0.5, inf, 0.5]");
    expect_error(&text, "prototypes[0].half_extents", Some(11));
    let text = BOXES.replace("max = [2.0, 1.0, 2.0]", "max = [2.0, -inf, 2.0]");
    expect_error(&text, "spawners[0].region.max", Some(16));
}

#[test]
fn zero_and_negative_counts_are_rejected() {
    let err = expect_error(&BOXES.replace("count = 4", "count = 0"), "spawners[0].count", Some(15));
    assert!(matches!(err, SceneError::Invalid { .. }));
    expect_error(&BOXES.replace("count = 4", "count = -3"), "count", Some(15));
    expect_error(&BOXES.replace("frames = 10", "frames = 0"), "scene.frames", Some(3));
    expect_error(&BOXES.replace("[0.5, 0.5, 0.5]", "[0.5, -0.5, 0.5]"), "half_extents", Some(11));
}

#[test]
fn dangling_references_are_rejected() {
    expect_error(
        &BOXES.replace("prototypes = [\"box\"]", "prototypes = [\"crate\"]"),
        "spawners[0].prototypes[0]",
        Some(14),
    );
}

#[test]
fn missing_files_are_named() {
    let err = SceneFile::load("/nonexistent/scene.toml").unwrap_err();
    assert!(matches!(err, SceneError::Io { .. }));
    assert!(err.to_string().contains("/nonexistent/scene.toml"));
    let text = BOXES.replace("generator = \"ground\"", "gltf = \"missing.glb\"");
    expect_error(&text, "environment.gltf", Some(6));
}

#[test]
fn malformed_gltf_is_an_error_naming_file_and_field() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("broken.glb"), b"glTF\x02\x00\x00\x00garbage").unwrap();
    let text = BOXES.replace("generator = \"ground\"", "gltf = \"broken.glb\"");
    let scene = dir.path().join("scene.toml");
    std::fs::write(&scene, text).unwrap();
    let file = SceneFile::load(&scene).unwrap();
    let err = dormant::scene::file::environment_mesh(&file).unwrap_err();
    let message = err.to_string();
    assert!(matches!(err, SceneError::Asset { .. }), "{message}");
    assert!(message.contains("scene.toml:6") && message.contains("environment.gltf"), "{message}");
    assert!(message.contains("broken.glb"), "{message}");
    let err = dormant::physics::Simulation::new(&file).err().expect("simulation refuses the scene");
    assert!(err.to_string().contains("broken.glb"), "{err}");
}

#[test]
fn every_shipped_scene_parses() {
    let dir = common::repo("scenes");
    let mut n = 0;
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            // Benchmark scenes need ../shared/assets; they must fail cleanly without it.
            match SceneFile::load(&path) {
                Ok(_) => n += 1,
                Err(e) => assert!(e.to_string().contains("not found"), "{}: {e}", path.display()),
            }
        }
    }
    assert!(n >= 3, "atrium, forest-walk and tiny parse");
}

#[test]
fn count_override_spreads_over_spawners() {
    let file = scenes::load("atrium");
    let total: u32 = file.spec().spawners.iter().map(|s| s.count).sum();
    assert_eq!(total, 8000, "the default is the paper's experiment");
    let small = file.clone().with_total_count(100).unwrap();
    assert_eq!(small.spec().spawners.iter().map(|s| s.count).sum::<u32>(), 100);
    assert!(small.spec().spawners.iter().all(|s| s.count >= 1 && s.waves <= s.count));
    assert!(file.with_total_count(3).is_err(), "fewer objects than spawners");
}

#[test]
fn sky_table_is_checked() {
    let both = format!("{BOXES}\n[sky]\ncolor = [1.0, 1.0, 1.0]\nzenith = [0.1, 0.2, 0.9]\n");
    expect_error(&both, "sky.color", None);
    let negative = format!("{BOXES}\n[sky]\nhorizon = [0.5, -0.1, 0.5]\n");
    expect_error(&negative, "sky.horizon", None);
    let unknown = format!("{BOXES}\n[sky]\ncolour = [1.0, 1.0, 1.0]\n");
    expect_error(&unknown, "colour", None);
}
