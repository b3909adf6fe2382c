//! Trajectories: a simulation's frames as changes (body states and poses that changed, island
//! events), in a versioned binary file that carries the scene's hash. Rendering can replay
//! one instead of simulating.
//!
//! Format (little endian), version 3:
//! ```text
//! magic "DORMTRAJ" | version u32 | scene_hash u64 | timestep f32
//! scene:      u8 recorded [0, 1]; if 1: path, asset_dir, source (each u32 len, utf-8),
//!             count and frames overrides (each u8 present, u32 value)
//! prototypes: u32 n, then n x (u32 len, utf-8 name)
//! bodies:     u32 n, then n x (prototype u32, kind u8 [0 dynamic, 1 kinematic], spawn_frame u32)
//! frames:     u32 n, then per frame, what changed since the frame before:
//!   states  u32 n, n x (body u32, state u8 [0 absent, 1 awake, 2 asleep])
//!   poses   u32 n, n x (body u32, translation 3 x f32, rotation xyzw 4 x f32)
//!   events  u32 n, n x (tag u8 [0 slept, 1 woke], island u64,
//!                       slept only: u32 m, m x (body u32, translation, rotation))
//! checksum u64: FNV-1a 64 of every byte before it
//! ```
//! Before the first frame every body is absent at the origin (translation zero, identity
//! rotation). A frame lists the bodies whose state changed, and the poses of bodies awake at
//! its end or fallen asleep during it that differ bit for bit from the body's last recorded
//! pose, each in ascending body order; every other body keeps its state and pose. A sleeping
//! body's pose is constant until its island wakes, so a settled world costs a few bytes a
//! frame.
//!
//! Version 2 stored, per frame, a state byte for every body (`body_count x u8` in place of
//! `states`) and the pose of every body awake at the frame's end or fallen asleep during it.
//! Version 1 is version 2 without the `scene` section. Both still read: their frames are
//! turned into changes as they are read, and replay to the same states and poses.

mod decode;
mod encode;
mod replay;

use std::path::{Path, PathBuf};

use super::body::{BodyId, BodyInfo, BodyPose, BodyState};
use super::island::IslandEvent;
use super::options::SimulateOptions;
use crate::scene::file::{SceneError, SceneFile};

pub use replay::Replay;
pub use replay::ReplayFrame;
pub(crate) use replay::{pose_bits, FrameRecorder};

const MAGIC: &[u8; 8] = b"DORMTRAJ";

/// A trajectory file that cannot be written, read or trusted. Errors about the contents name
/// the file, the field and the byte offset where it starts.
#[derive(Debug, thiserror::Error)]
pub enum TrajectoryError {
    #[error("{}: {source}", .file.display())]
    Io {
        file: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{}: magic at byte 0: not a dormant trajectory (bad magic)", .file.display())]
    NotATrajectory { file: PathBuf },
    #[error("{}: version at byte 8: trajectory format version {found}, this build reads versions 1 to {expected}", .file.display())]
    Version { file: PathBuf, found: u32, expected: u32 },
    #[error("{}: scene_hash at byte 12: trajectory was made from another scene (hash {found:016x}, expected {expected:016x})", .file.display())]
    SceneMismatch { file: PathBuf, found: u64, expected: u64 },
    #[error("{}: {field} at byte {offset}: {message}", .file.display())]
    Corrupt { file: PathBuf, offset: usize, field: String, message: String },
}

/// The scene file a trajectory was simulated from, recorded in it so that the trajectory alone
/// can be rendered (`dormant render --trajectory FILE`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RecordedScene {
    /// Where the scene file was (names it in messages).
    pub path: PathBuf,
    /// The absolute directory its relative asset paths resolved against.
    pub asset_dir: PathBuf,
    /// The scene file's text.
    pub source: String,
    /// The overrides it was simulated with.
    pub options: SimulateOptions,
}

impl RecordedScene {
    /// Records `file` (as read, before `options` apply).
    pub(crate) fn new(file: &SceneFile, options: &SimulateOptions) -> Self {
        let absolute = |p: PathBuf| std::path::absolute(&p).unwrap_or(p);
        Self {
            path: file.path().to_path_buf(),
            asset_dir: absolute(file.asset_dir().to_path_buf()),
            source: file.source().to_string(),
            options: options.clone(),
        }
    }

    /// The scene file again, its assets resolved where they were when it was simulated.
    pub fn scene_file(&self) -> Result<SceneFile, SceneError> {
        SceneFile::parse_with_assets(&self.path, self.source.as_str(), Some(&self.asset_dir))
    }
}

/// One simulated frame as a trajectory records it: what changed during it. [`Replay`]
/// applies the changes to give every body's state and pose at the frame's end.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TrajectoryFrame {
    /// Bodies whose state changed, ascending, with their state at the frame's end.
    pub(crate) state_changes: Vec<(BodyId, BodyState)>,
    /// Bodies awake at the frame's end or fallen asleep during it whose pose differs bit for
    /// bit from their last recorded pose, ascending, with the new pose.
    pub(crate) pose_changes: Vec<(BodyId, BodyPose)>,
    pub events: Vec<IslandEvent>,
}

/// A recorded simulation.
#[derive(Clone, Debug, PartialEq)]
pub struct Trajectory {
    /// Hash of the scene (and overrides) that produced it.
    pub scene_hash: u64,
    /// Simulated seconds per frame.
    pub timestep: f32,
    /// The scene it was simulated from; `None` in version-1 files.
    pub scene: Option<RecordedScene>,
    /// Prototype names, indexed by [`BodyInfo::prototype`].
    pub prototypes: Vec<String>,
    pub bodies: Vec<BodyInfo>,
    pub frames: Vec<TrajectoryFrame>,
}

impl Trajectory {
    pub(crate) const FORMAT_VERSION: u32 = 3;

    /// Encodes the trajectory in the current format; identical trajectories give identical
    /// bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        encode::encode(self)
    }

    /// Decodes and checks a trajectory of any readable version: format, checksum, ranges,
    /// and the island event invariants (no `Woke` without an earlier `Slept`, each body in at
    /// most one sleeping island). `file` names the source in errors.
    pub fn from_bytes(bytes: &[u8], file: &Path) -> Result<Self, TrajectoryError> {
        decode::decode(bytes, file)
    }

    /// Writes the trajectory atomically: a temporary file in the same directory, then a
    /// rename, so readers never see a half-written file.
    pub fn write_atomic(&self, path: &Path) -> Result<(), TrajectoryError> {
        crate::atomic_file::write_atomic(path, &self.to_bytes())
            .map_err(|source| TrajectoryError::Io { file: path.to_path_buf(), source })
    }

    /// Reads a trajectory and checks that it was made from the scene with
    /// `expected_scene_hash` (see [`super::SimulateOptions::effective_scene`]).
    pub fn read(path: &Path, expected_scene_hash: u64) -> Result<Self, TrajectoryError> {
        let t = Self::read_unchecked(path)?;
        if t.scene_hash != expected_scene_hash {
            return Err(TrajectoryError::SceneMismatch {
                file: path.to_path_buf(),
                found: t.scene_hash,
                expected: expected_scene_hash,
            });
        }
        Ok(t)
    }

    /// Reads a trajectory without checking which scene made it.
    pub fn read_unchecked(path: &Path) -> Result<Self, TrajectoryError> {
        let bytes =
            std::fs::read(path).map_err(|source| TrajectoryError::Io { file: path.to_path_buf(), source })?;
        Self::from_bytes(&bytes, path)
    }

    /// Walks the frames with every body's current state and pose filled in.
    pub fn replay(&self) -> Replay<'_> {
        Replay::new(&self.frames, self.bodies.len())
    }

    /// Every body's state after the last frame (all absent without frames).
    pub fn states_at_end(&self) -> Vec<BodyState> {
        let mut states = vec![BodyState::Absent; self.bodies.len()];
        for &(body, state) in self.frames.iter().flat_map(|f| &f.state_changes) {
            states[body.0 as usize] = state;
        }
        states
    }
}
