//! Scenes on the shared real assets (../shared/assets). Users' checkouts do not have them:
//! every test here skips cleanly when they are absent.

use crate::common;

use std::path::Path;

use common::scenes;
use dormant::physics::{simulate, ColliderChoice, SimulateOptions, Simulation};
use dormant::scene::file::SceneFile;

#[test]
fn the_monastery_benchmark_scene_simulates_a_few_objects() {
    let Some(_) = common::shared_assets() else { return };
    let file = scenes::load("monastery-rain");
    let options = SimulateOptions { count: Some(12), frames: Some(90) };
    let sim = Simulation::new(&options.effective_scene(&file).unwrap()).unwrap();
    let choices = sim.collider_choices();
    assert_eq!(choices.len(), 3);
    assert!(choices.iter().all(|c| *c != ColliderChoice::Primitive), "{choices:?}");
    let t = simulate(&file, &options).unwrap();
    assert_eq!(t.frames.len(), 90);
    assert_eq!(t.bodies.len(), 12);
}

#[test]
fn an_asset_directory_from_the_command_line_overrides_the_scene() {
    let Some(dir) = common::shared_assets() else { return };
    let file = SceneFile::load_with_assets(scenes::shipped("monastery-rain"), Some(&dir)).unwrap();
    assert_eq!(file.resolve("duck.glb"), dir.join("duck.glb"));
    let err = SceneFile::load_with_assets(scenes::shipped("monastery-rain"), Some(Path::new("/nonexistent")))
        .unwrap_err();
    assert!(err.to_string().contains("environment.gltf"), "{err}");
}
