//! Options of a simulation run: the overrides a command line can apply to a scene, and the
//! scene they give (whose hash a trajectory of it carries).

use super::PhysicsError;
use std::num::NonZeroU32;

use crate::scene::file::SceneFile;
use crate::scene::limits::{MAX_BODIES, MAX_FRAMES};

/// Overrides a command line can apply to a scene before simulating it.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SimulateOptions {
    /// Total dynamic objects, spread over the spawners and structures in proportion to their
    /// bodies (see [`SceneFile::with_total_count`]).
    pub count: Option<u32>,
    /// Frames to simulate instead of `scene.frames`.
    pub frames: Option<u32>,
}

impl SimulateOptions {
    /// The scene as it will be simulated: overrides applied and folded into
    /// [`SceneFile::source_hash`], which is the hash a trajectory of it carries.
    pub fn effective_scene(&self, file: &SceneFile) -> Result<SceneFile, PhysicsError> {
        let mut file = file.clone();
        if let Some(count) = self.count {
            if count == 0 || count as u64 > MAX_BODIES {
                let message = format!("must be from 1 to {MAX_BODIES}, got {count}");
                return Err(PhysicsError::Option { option: "--count", message });
            }
            file = file.with_total_count(count)?;
        }
        if let Some(frames) = self.frames {
            let frames = NonZeroU32::new(frames).filter(|f| f.get() <= MAX_FRAMES).ok_or_else(|| {
                PhysicsError::Option {
                    option: "--frame-count",
                    message: format!("must be from 1 to {MAX_FRAMES}, got {frames}"),
                }
            })?;
            file = file.with_frames(frames);
        }
        Ok(file)
    }
}
