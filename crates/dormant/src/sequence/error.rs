//! What can stop a sequence: bad input (scene, trajectory, frame range) or a failed render.

use std::path::PathBuf;

use crate::accel::AccelError;
use crate::physics::trajectory::TrajectoryError;
use crate::physics::PhysicsError;
use crate::render::denoise::DenoiseError;
use crate::render::RenderError;
use crate::scene::file::SceneError;

#[derive(Debug, thiserror::Error)]
pub enum SequenceError {
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error(transparent)]
    Physics(#[from] PhysicsError),
    #[error(transparent)]
    Trajectory(#[from] TrajectoryError),
    #[error(
        "{}: scene: the trajectory does not record its scene (format version 1); pass the SCENE file too",
        .0.display()
    )]
    SceneNotRecorded(PathBuf),
    #[error("{}: the scene recorded in it: {source}", .path.display())]
    RecordedScene {
        path: PathBuf,
        #[source]
        source: SceneError,
    },
    #[error(
        "{}: scene: the recorded scene does not hash to the trajectory's scene_hash (damaged file)",
        .0.display()
    )]
    RecordedSceneHash(PathBuf),
    /// `--trajectory` given with a SCENE (and overrides) it was not simulated from.
    #[error(
        "{}: it was simulated from another scene than {} (or with other --count/--frame-count \
         overrides): simulate the scene again, or render the trajectory alone, which records its scene",
        .trajectory.display(), .scene.display()
    )]
    TrajectoryOfAnotherScene { trajectory: PathBuf, scene: PathBuf },
    #[error("--count: {} was simulated with its own object count; simulate again to change it", .0.display())]
    CountOverride(PathBuf),
    /// A frame range past the trajectory's end (callers name the flag that gave it).
    #[error("{start}..{end}: the trajectory has {total} frames (0..{total})")]
    Range { start: u32, end: u32, total: u32 },
    /// A frame kept from an earlier run (`render --resume`) whose recorded state the replay
    /// does not reach (callers name the statistics file it came from).
    #[error(
        "frame {frame}: the kept statistics record {what} = {recorded}, replaying them gives {replayed}"
    )]
    KeptMismatch { frame: u32, what: &'static str, recorded: String, replayed: String },
    #[error(transparent)]
    Render(#[from] RenderError),
    #[error(transparent)]
    Accel(#[from] AccelError),
    #[error(transparent)]
    Denoise(#[from] DenoiseError),
}

impl SequenceError {
    /// Whether the input (scene, trajectory, options) was at fault rather than the run.
    pub fn is_input(&self) -> bool {
        // A trajectory that cannot be read is input too, like a missing scene file, and so is
        // a reuse budget too small for the frames asked for.
        match self {
            SequenceError::Render(e) => matches!(e, RenderError::ReuseBudget { .. }),
            SequenceError::Accel(_) | SequenceError::Denoise(_) => false,
            _ => true,
        }
    }
}
