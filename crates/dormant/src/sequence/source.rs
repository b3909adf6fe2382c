//! Where a sequence's motion comes from: a scene file simulated now, a scene file with a
//! trajectory of it, or a trajectory alone with the scene recorded in it ([`SequenceSource`],
//! which `Sequence::load` takes).

use std::path::{Path, PathBuf};

use serde::Serialize;

use super::SequenceError;
use crate::physics::trajectory::Trajectory;
use crate::physics::SimulateOptions;
use crate::scene::file::SceneFile;

/// What a sequence is made from.
pub enum SequenceSource {
    /// A scene file with command-line overrides: simulated now, or replayed from
    /// `trajectory`, which must have been simulated from the same scene and overrides.
    Scene { file: Box<SceneFile>, options: SimulateOptions, trajectory: Option<PathBuf> },
    /// A trajectory alone: the scene recorded in it. `count`, if given, must be the count it
    /// was simulated with.
    Recorded { trajectory: PathBuf, count: Option<u32> },
}

impl SequenceSource {
    /// A scene file with overrides, simulated now or replayed from `trajectory`.
    pub fn scene(file: SceneFile, options: SimulateOptions, trajectory: Option<PathBuf>) -> Self {
        SequenceSource::Scene { file: Box::new(file), options, trajectory }
    }
}

/// Where the frames' motion came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PhysicsSource {
    /// Simulated in this run, before rendering: the step times are known.
    Simulated,
    /// Replayed from a trajectory file: no physics time.
    Trajectory,
}

/// A trajectory and the scene recorded in it, checked against each other.
pub(super) fn recorded_scene(path: &Path) -> Result<(SceneFile, SimulateOptions, Trajectory), SequenceError> {
    let trajectory = Trajectory::read_unchecked(path)?;
    let Some(recorded) = &trajectory.scene else {
        return Err(SequenceError::SceneNotRecorded(path.to_path_buf()));
    };
    let file = recorded
        .scene_file()
        .map_err(|source| SequenceError::RecordedScene { path: path.to_path_buf(), source })?;
    let options = recorded.options.clone();
    if options.effective_scene(&file)?.source_hash() != trajectory.scene_hash {
        return Err(SequenceError::RecordedSceneHash(path.to_path_buf()));
    }
    Ok((file, options, trajectory))
}
