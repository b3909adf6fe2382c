//! Where a sequence's motion comes from: a scene file simulated now, a scene file with a
//! trajectory of it, or a trajectory alone with the scene recorded in it.

use std::path::{Path, PathBuf};

use serde::Serialize;

use super::selection::{FrameRange, FrameSelection};
use super::SequenceError;
use crate::accel::{self, Backend};
use std::sync::Arc;

use crate::physics;

use crate::physics::{SimulateOptions, SimulatedFrame};

use crate::physics::trajectory::{Trajectory, TrajectoryError};
use crate::render::AdaptiveSampling;
use crate::residency::{IntegrationSettings, Lookahead, ManagerOptions, SceneManager};
use crate::scene::file::SceneFile;
use crate::scene::{SceneAssets, SceneDescription};

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

/// A simulation ready to be replayed into frames; see the module docs.
pub struct Sequence {
    pub trajectory: Trajectory,
    pub assets: SceneAssets,
    /// The scene without bodies at time 0: the scene managers' template.
    pub template: SceneDescription,
    /// The scene file's `render.frame_step`: the step when a run names none.
    pub frame_step: u32,
    /// The scene file's `render.noise_threshold` and `render.min_spp`: adaptive sampling when
    /// a run names none.
    pub adaptive: AdaptiveSampling,
    /// The scene file's `render.shutter` (motion blur): the shutter when a run names none.
    pub shutter: f32,
    pub physics: PhysicsSource,
    /// Wall-clock ms of each simulated frame's physics step (empty when replayed).
    pub physics_ms: Vec<f64>,
    /// The scene file's text as read (before overrides): the glTF export records it.
    pub(crate) scene_source: String,
    /// The scene file's `render.width` and `render.height`: the glTF camera's aspect ratio.
    pub(crate) render_size: (u32, u32),
}

impl Sequence {
    /// Simulates or reads the trajectory of `source` and loads the scene's assets.
    /// `on_step` sees each simulated frame (nothing when the trajectory is read).
    pub fn load(
        source: SequenceSource,
        on_step: &mut dyn FnMut(SimulatedFrame),
    ) -> Result<Self, SequenceError> {
        match source {
            SequenceSource::Scene { file, options, trajectory: Some(path) } => {
                let expected = options.effective_scene(&file)?.source_hash();
                let trajectory = Trajectory::read(&path, expected).map_err(|e| match e {
                    TrajectoryError::SceneMismatch { .. } => SequenceError::TrajectoryOfAnotherScene {
                        trajectory: path.clone(),
                        scene: file.path().into(),
                    },
                    e => e.into(),
                })?;
                Self::new(&file, trajectory, PhysicsSource::Trajectory, Vec::new())
            }
            SequenceSource::Scene { file, options, trajectory: None } => {
                let mut physics_ms = Vec::new();
                let trajectory = physics::simulate_observed(&file, &options, &mut |step| {
                    physics_ms.push(step.step_ms);
                    on_step(step);
                })?;
                Self::new(&file, trajectory, PhysicsSource::Simulated, physics_ms)
            }
            SequenceSource::Recorded { trajectory, count } => {
                let (file, options, t) = recorded_scene(&trajectory)?;
                if count.is_some_and(|c| options.count != Some(c)) {
                    return Err(SequenceError::CountOverride(trajectory));
                }
                Self::new(&file, t, PhysicsSource::Trajectory, Vec::new())
            }
        }
    }

    fn new(
        file: &SceneFile,
        trajectory: Trajectory,
        physics: PhysicsSource,
        physics_ms: Vec<f64>,
    ) -> Result<Self, SequenceError> {
        let assets = SceneAssets::load(file)?;
        let template = assets.describe(0.0);
        Ok(Self {
            trajectory,
            assets,
            template,
            frame_step: file.spec().render.frame_step.max(1),
            adaptive: AdaptiveSampling {
                noise_threshold: file.spec().render.noise_threshold,
                min_spp: file.spec().render.min_spp,
            },
            shutter: file.spec().render.shutter,
            physics,
            physics_ms,
            scene_source: file.source().to_owned(),
            render_size: (file.spec().render.width, file.spec().render.height),
        })
    }

    /// Frames the trajectory holds.
    pub fn frame_count(&self) -> u32 {
        self.trajectory.frames.len() as u32
    }

    /// Seconds of simulated time at the start of frame `index`.
    pub(crate) fn time_of(&self, index: u32) -> f32 {
        index as f32 * self.trajectory.timestep
    }

    /// Frames `range` (default: all) every `step` (default: the scene's frame step), checked
    /// against the trajectory's length.
    pub fn select(
        &self,
        range: Option<FrameRange>,
        step: Option<u32>,
    ) -> Result<FrameSelection, SequenceError> {
        let total = self.frame_count();
        let range = range.unwrap_or(FrameRange { start: 0, end: total });
        if range.end > total {
            return Err(SequenceError::Range { start: range.start, end: range.end, total });
        }
        Ok(FrameSelection::stepped(range, step.unwrap_or(self.frame_step).max(1)))
    }

    /// `count` frames of `range` (clamped to the trajectory), evenly spaced and ending with
    /// its last.
    pub fn evenly_spaced_in(&self, range: FrameRange, count: u32) -> FrameSelection {
        let end = range.end.min(self.frame_count());
        let n = end.saturating_sub(range.start);
        let k = count.min(n.max(1));
        FrameSelection::list((1..=k).map(|i| range.start + (i * n).div_ceil(k).saturating_sub(1)).collect())
    }

    /// The trajectory's last frame.
    pub fn last_frame(&self) -> FrameSelection {
        FrameSelection::list(vec![self.frame_count().saturating_sub(1)])
    }

    /// What the run knows of its future: the frames `selection` renders and when each island
    /// wakes.
    pub fn lookahead(&self, selection: &FrameSelection) -> Lookahead {
        let events = self
            .trajectory
            .frames
            .iter()
            .enumerate()
            .flat_map(|(i, f)| f.events.iter().map(move |e| (i as u32, e)));
        Lookahead::new(events, selection.frames())
    }

    /// The scene manager's options for rendering `selection` under `settings`: the run's
    /// length and, with lookahead, its future.
    pub fn manager_options(
        &self,
        selection: &FrameSelection,
        settings: IntegrationSettings,
    ) -> ManagerOptions {
        ManagerOptions {
            policy: settings.policy,
            form: settings.form,
            cache: settings.cache,
            planned_frames: Some(selection.count()),
            lookahead: settings.lookahead.then(|| Arc::new(self.lookahead(selection))),
            ..ManagerOptions::default()
        }
    }

    /// A scene manager over a new accelerator of `backend`, loaded with the template.
    pub fn manager(
        &self,
        backend: Backend,
        threads: Option<usize>,
        options: ManagerOptions,
    ) -> Result<SceneManager, SequenceError> {
        let accel = accel::create(backend, threads)?;
        Ok(SceneManager::new(accel, &self.template, &self.trajectory.bodies, options)?)
    }
}

/// A trajectory and the scene recorded in it, checked against each other.
fn recorded_scene(path: &Path) -> Result<(SceneFile, SimulateOptions, Trajectory), SequenceError> {
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
