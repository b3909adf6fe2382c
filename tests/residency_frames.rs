//! Describing simulated frames for rendering.

use crate::common;

use common::scenes;
use dormant::scene::file::SceneFile;
use dormant::scene::SceneAssets;

/// `scenes/forest-walk.toml` rendered through the camera called `camera`.
fn forest_walk(camera: &str) -> SceneFile {
    let path = scenes::shipped("forest-walk");
    let text = std::fs::read_to_string(&path).unwrap();
    let chosen = "camera = \"high\"";
    assert!(text.contains(chosen), "forest-walk.toml chooses its camera with {chosen}");
    SceneFile::parse(&path, text.replace(chosen, &format!("camera = {camera:?}"))).unwrap()
}

#[test]
fn keyframed_camera_moves_between_frames_regression() {
    // Bug: every frame was described with the camera at t = 0.
    let file = forest_walk("follow");
    let assets = SceneAssets::load(&file).unwrap();
    let at = |t: f32| assets.describe(t).camera;
    assert_ne!(at(0.0).eye, at(4.0).eye);
    assert_eq!(at(0.0), at(0.0));
}

#[test]
fn fixed_camera_stays_put() {
    let file = forest_walk("high");
    let assets = SceneAssets::load(&file).unwrap();
    let at = |t: f32| assets.describe(t).camera;
    assert_eq!(at(0.0), at(4.0));
}

#[test]
fn scene_file_sky_reaches_the_description() {
    use dormant::scene::Sky;
    use glam::Vec3;
    let base = std::fs::read_to_string(scenes::shipped("tiny")).unwrap();
    let sky_of = |extra: &str| {
        let file = SceneFile::parse("scenes/tiny.toml", format!("{base}\n{extra}")).unwrap();
        SceneAssets::load(&file).unwrap().describe(0.0).sky
    };
    assert_eq!(sky_of(""), Sky::DAYLIGHT);
    assert_eq!(sky_of("[sky]\ncolor = [0.5, 0.5, 0.5]\nintensity = 2.0"), Sky::constant(Vec3::ONE));
    let gradient = sky_of("[sky]\nzenith = [0.0, 0.0, 1.0]");
    assert_eq!((gradient.zenith, gradient.horizon), (Vec3::Z, Sky::DAYLIGHT.horizon));
}
