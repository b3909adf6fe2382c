//! The scene fixtures: the scenes the repository ships (`scenes/`), the scenes made for the
//! tests (`tests/data/`), and [`BOXES`], the small scene file tests edit as text.

use std::path::{Path, PathBuf};

use dormant::scene::file::SceneFile;

/// `scenes/NAME.toml`, a scene the repository ships (tiny, atrium, forest-walk, demolition,
/// monastery-rain, far-assets, ...).
pub fn shipped(name: &str) -> PathBuf {
    super::repo(&format!("scenes/{name}.toml"))
}

/// The shipped scene `name` ([`shipped`]), loaded.
pub fn load(name: &str) -> SceneFile {
    SceneFile::load(shipped(name)).unwrap()
}

/// `tests/data/NAME.toml`, a scene made for the tests:
/// - `settle`: six crates dropped onto the ground, at rest (bit for bit) from about frame 70
///   on (static-frame reuse);
/// - `motion`: a dark slider crossing the view at 0.4 units a frame and a crate at rest
///   (motion blur).
pub fn data(name: &str) -> PathBuf {
    super::repo(&format!("tests/data/{name}.toml"))
}

/// The test scene `name` ([`data`]) copied into `dir` as `NAME.toml`, which is returned.
pub fn copy_data(name: &str, dir: &Path) -> PathBuf {
    let path = dir.join(format!("{name}.toml"));
    std::fs::copy(data(name), &path).unwrap();
    path
}

/// A scene file of four boxes over the ground (`tests/data/boxes.toml`), for tests that
/// replace a piece of it and expect an error naming a line. Its lines, which those tests
/// count on: `[scene]` 1, `frames = 10` 3, `[environment]` 5, `generator = "ground"` 6,
/// `[[prototypes]]` 8, `half_extents = [0.5, 0.5, 0.5]` 11, `[[spawners]]` 13,
/// `prototypes = ["box"]` 14, `count = 4` 15, `region = { min = [0.0, 1.0, 0.0],
/// max = [2.0, 1.0, 2.0] }` 16 (the last).
pub const BOXES: &str = include_str!("../data/boxes.toml");
