//! The directory a scene file's relative asset paths resolve against, fixed when the file is
//! parsed.

use std::path::{Path, PathBuf};

#[derive(Clone, Debug, PartialEq)]
pub(super) struct AssetDir {
    dir: PathBuf,
    /// Given when loading (by a command line) rather than by the file.
    overridden: bool,
}

impl AssetDir {
    /// `given` (the override from loading), else `scene_assets` (the file's `scene.assets`,
    /// relative to the scene file), else the scene file's directory.
    pub(crate) fn new(scene_path: &Path, scene_assets: Option<&str>, given: Option<&Path>) -> Self {
        let base = scene_path.parent().unwrap_or_else(|| Path::new(""));
        let dir = match (given, scene_assets) {
            (Some(dir), _) => dir.to_path_buf(),
            (None, Some(dir)) => base.join(dir),
            (None, None) => base.to_path_buf(),
        };
        Self { dir, overridden: given.is_some() }
    }

    pub(crate) fn path(&self) -> &Path {
        &self.dir
    }

    pub(crate) fn is_overridden(&self) -> bool {
        self.overridden
    }

    /// `relative` resolved against the directory (absolute paths are kept).
    pub(crate) fn resolve(&self, relative: &str) -> PathBuf {
        self.dir.join(relative)
    }
}
