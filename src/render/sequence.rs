//! Image sequences of a simulation: replays a trajectory through a [`SceneManager`], which
//! keeps one accelerator in step (integrating sleeping islands), and renders the selected
//! frames. The trace stage's time goes back to the manager's cost model.

use super::{render_frame, Film, Integrator, RenderError, RenderScene, RenderSettings, RenderStats};
use crate::integrate::{FrameState, FrameStats, SceneAssets, SceneManager};
use crate::physics::Trajectory;
use crate::scene::SceneDescription;

/// Which frames to render, and how.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SequenceOptions {
    /// First frame (inclusive) and last (exclusive).
    pub start: u32,
    pub end: u32,
    /// Render every `step`-th frame (counted from frame 0, so split ranges line up).
    pub step: u32,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
}

impl SequenceOptions {
    /// Frames this selects.
    pub fn frame_count(&self) -> u32 {
        (self.start..self.end).filter(|f| f % self.step.max(1) == 0).count() as u32
    }
}

/// One rendered frame of a sequence.
pub struct SequenceFrame<'a> {
    pub index: u32,
    pub film: &'a Film,
    pub render: RenderStats,
    /// The manager's per-stage statistics, trace included.
    pub stats: &'a FrameStats,
}

/// Replays `trajectory` from its first frame (every island event must be seen), renders the
/// frames `options` selects with `integrator`, and hands each to `on_frame`. The accelerator
/// is first brought up to date at `options.start`, so a slice of a sequence renders the same
/// images as a whole run, up to float noise (integrated and instanced bodies are hit alike).
pub fn render_sequence<E: From<RenderError>>(
    trajectory: &Trajectory,
    assets: &SceneAssets,
    template: &SceneDescription,
    manager: &mut SceneManager,
    integrator: &dyn Integrator,
    options: &SequenceOptions,
    on_frame: &mut dyn FnMut(SequenceFrame<'_>) -> Result<(), E>,
) -> Result<(), E> {
    let step = options.step.max(1);
    let mut replay = trajectory.replay();
    while let Some(frame) = replay.next_frame() {
        if frame.index >= options.end {
            break;
        }
        manager.observe(frame.events);
        if frame.index % step != 0 || frame.index < options.start {
            continue;
        }
        let state = FrameState { index: frame.index, states: frame.states, poses: frame.poses };
        manager.prepare(state).map_err(RenderError::from)?;
        let settings = RenderSettings {
            width: options.width,
            height: options.height,
            spp: options.spp,
            frame: frame.index,
        };
        let (film, render) = {
            let mut scene = RenderScene::with_objects(template, &*manager)?;
            scene.camera = assets.camera_at(frame.index as f32 * trajectory.timestep);
            render_frame(&scene, manager.query().map_err(RenderError::from)?, integrator, &settings)?
        };
        let stats = manager.record_trace(render.seconds * 1e3, render.rays);
        on_frame(SequenceFrame { index: frame.index, film: &film, render, stats })?;
    }
    Ok(())
}
