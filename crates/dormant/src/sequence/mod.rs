//! Sequences: a simulation replayed into frames. This module owns the way from a scene file
//! (or a trajectory) to frames:
//!
//! - [`Sequence`] (here, with its core methods in one block): the trajectory (simulated now,
//!   or read from a file and checked against its scene; `source.rs`), the scene file's render
//!   assets and the frame template; [`Sequence::replay`], the one replay loop, which feeds
//!   every frame's island events to the scene managers and hands each selected frame to the
//!   caller; [`Sequence::describe_frame`], a frame with every present body an instance, the
//!   reference integrated scenes are checked against;
//! - [`FrameSelection`]: which frames are rendered (a range and a step, or a list);
//! - [`FrameRenderer`]: how every frame of a run is rendered;
//! - `render.rs`, the sequence's rendering methods: [`Sequence::render_frame`] and
//!   [`Sequence::render`], the per-frame call into the renderer through a
//!   [`SceneManager`](crate::residency::SceneManager), whose trace time goes back to its cost
//!   model; static-frame reuse; exact temporal reuse, which lives in `render/reuse/` and is
//!   called from there once per frame ([`ReuseMode`], whose [`ReuseMode::decide`] says
//!   whether a run reuses, and [`DEFAULT_REUSE_BYTES`] are re-exported here from it);
//! - [`KeptFrame`]: a frame an earlier run finished (`render --resume`), which the driver
//!   brings the manager through as that run did instead of rendering it;
//! - the sequence's export methods, each beside its format: [`Sequence::export`]
//!   (`export.rs`), the selected frames' poses, camera, lights and mesh sources as plain data
//!   for another renderer (`dormant export`, `scripts/compare-cycles.py`), and
//!   [`Sequence::write_gltf`] (`gltf_export/`), every frame as one animated glTF binary
//!   (`dormant export --gltf`).
//!
//! The CLI, `dormant verify` and the integration benchmarks all replay through here.

mod error;
pub mod export;
mod frame_renderer;
pub mod gltf_export;
mod kept;
pub mod output;
mod render;
mod selection;
mod source;
pub mod stats;

use std::sync::Arc;

pub use crate::render::reuse::decision::{ReuseMode, DEFAULT_REUSE_BYTES};
pub use error::SequenceError;
pub use frame_renderer::{FrameRenderer, SeedMode};
pub(crate) use kept::KeptFrame;
pub(crate) use render::trace_kind;
pub use render::RenderedFrame;
pub use selection::{FrameRange, FrameSelection};
pub(crate) use source::PhysicsSource;
pub use source::SequenceSource;

use crate::accel::{self, Backend};
use crate::physics::trajectory::{ReplayFrame, Trajectory, TrajectoryError};
use crate::physics::{self, SimulatedFrame};
use crate::residency::{IntegrationSettings, Lookahead, ManagerOptions, SceneManager};
use crate::scene::file::spec::RenderDef;
use crate::scene::file::SceneFile;
use crate::scene::{Body, Camera, SceneAssets, SceneDescription};
use source::recorded_scene;

/// What [`Sequence::replay`] calls with each selected frame and the scene managers.
pub(crate) type FrameVisitor<'v, E> = dyn FnMut(&ReplayFrame<'_>, &mut [SceneManager]) -> Result<(), E> + 'v;

/// A simulation ready to be replayed into frames; see the module docs.
pub struct Sequence {
    pub trajectory: Trajectory,
    pub assets: SceneAssets,
    /// The scene without bodies at time 0: the scene managers' template.
    pub template: SceneDescription,
    /// The scene file's `[render]` settings, `None` where it gives none: a run takes each from
    /// its flags, else its preset, else the file, else the built-in default.
    pub render: RenderDef,
    pub physics: PhysicsSource,
    /// Wall-clock ms of each simulated frame's physics step (empty when replayed).
    pub physics_ms: Vec<f64>,
    /// The scene file's text as read (before overrides): the glTF export records it.
    pub(crate) scene_source: String,
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
            render: file.spec().render.clone(),
            physics,
            physics_ms,
            scene_source: file.source().to_owned(),
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

    /// Frames `range` (default: all) every `step` (default: the scene's frame step, else 1), checked
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
        Ok(FrameSelection::stepped(range, step.or(self.render.frame_step).unwrap_or(1).max(1)))
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
    pub(crate) fn lookahead(&self, selection: &FrameSelection) -> Lookahead {
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

    /// Replays the trajectory from its first frame (every island event must be seen) to the
    /// last frame `selection` can select: each frame's island events go to every manager in
    /// `managers` (none for callers that only describe frames), and each selected frame goes
    /// to `on_frame` with the managers.
    pub fn replay<E>(
        &self,
        selection: &FrameSelection,
        managers: &mut [SceneManager],
        on_frame: &mut FrameVisitor<'_, E>,
    ) -> Result<(), E> {
        let mut replay = self.trajectory.replay();
        while let Some(frame) = replay.next_frame() {
            if frame.index >= selection.end() {
                break;
            }
            for manager in managers.iter_mut() {
                manager.observe(frame.events);
                // A slice (`--frames A..B`, A > 0) counts island events from the frame a whole
                // run would have rendered last, so that its rows join into the whole run's
                // table; the events themselves still all reach the manager.
                if selection.skipped_on_grid(frame.index) {
                    manager.forget_event_counts();
                }
            }
            if selection.selects(frame.index) {
                on_frame(&frame, managers)?;
                // The managers were prepared for this frame: the next one changes from here.
                replay.restart_changes();
            }
        }
        Ok(())
    }

    /// The bodies present in `frame`, each at its pose.
    pub(crate) fn bodies_at(&self, frame: &ReplayFrame<'_>) -> Vec<Body> {
        frame
            .present_bodies()
            .map(|b| Body {
                prototype: self.trajectory.bodies[b.0 as usize].prototype,
                transform: frame.poses[b.0 as usize].to_affine(),
            })
            .collect()
    }

    /// `frame` as a render description: the environment as the only static mesh, every
    /// present body (awake or asleep) an instance of its prototype at its pose, and the
    /// camera where its keyframes put it. The reference integrated scenes are checked
    /// against.
    pub fn describe_frame(&self, frame: &ReplayFrame<'_>) -> SceneDescription {
        SceneDescription { bodies: self.bodies_at(frame), ..self.assets.describe(self.time_of(frame.index)) }
    }

    /// The camera of frame `index`: without a shutter, at the frame's instant; with one, at
    /// shutter open and close (`shutter / 2` frame intervals before and after it).
    fn shutter_cameras(&self, index: u32, shutter: f32) -> (Camera, Option<Camera>) {
        let t = self.time_of(index);
        if shutter <= 0.0 {
            return (self.assets.camera_at(t), None);
        }
        let half = 0.5 * shutter * self.trajectory.timestep;
        (self.assets.camera_at(t - half), Some(self.assets.camera_at(t + half)))
    }

    /// Whether frames `a` and `b > a` show the same scene: no body moved, appeared or left in
    /// between (kinematic bodies included), and the camera is where it was. Lights, sky and
    /// materials do not change over a sequence.
    pub(crate) fn unchanged_between(&self, a: u32, b: u32) -> bool {
        let frames = &self.trajectory.frames;
        let still = (a as usize + 1..=b as usize)
            .all(|f| frames.get(f).is_some_and(|f| f.pose_changes.is_empty() && f.state_changes.is_empty()));
        still && self.assets.camera_at(self.time_of(a)) == self.assets.camera_at(self.time_of(b))
    }
}
