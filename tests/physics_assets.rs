//! Scenes on the shared real assets (../shared/assets). Users' checkouts do not have them:
//! every test here skips cleanly when they are absent.

mod common;

use std::path::{Path, PathBuf};

use dormant::physics::{simulate, ColliderChoice, SimulateOptions, Simulation};
use dormant::scene::file::SceneFile;

fn monastery_scene() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/monastery-rain.toml")
}

#[test]
fn the_monastery_benchmark_scene_simulates_a_few_objects() {
    let Some(_) = common::shared_assets() else { return };
    let file = SceneFile::load(monastery_scene()).unwrap();
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
    let file = SceneFile::load_with_assets(monastery_scene(), Some(&dir)).unwrap();
    assert_eq!(file.resolve("duck.glb"), dir.join("duck.glb"));
    let err = SceneFile::load_with_assets(monastery_scene(), Some(Path::new("/nonexistent"))).unwrap_err();
    assert!(err.to_string().contains("environment.gltf"), "{err}");
}
