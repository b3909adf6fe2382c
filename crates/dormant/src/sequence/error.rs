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
    /// Exact temporal reuse needs more memory than its budget allows (callers name the flag).
    #[error(
        "{budget_mib} MiB is too small for exact reuse of {width}x{height} frames with these passes: \
         it needs {needed_mib} MiB (one value per pixel and pass); raise the budget or turn reuse off"
    )]
    ReuseBudget { budget_mib: usize, needed_mib: usize, width: u32, height: u32 },
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
        // A trajectory that cannot be read is input too, like a missing scene file.
        !matches!(self, SequenceError::Render(_) | SequenceError::Accel(_) | SequenceError::Denoise(_))
    }
}
