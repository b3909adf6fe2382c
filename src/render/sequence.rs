//! Image sequences of a simulation: replays a trajectory through a [`SceneManager`], which
//! keeps one accelerator in step (integrating sleeping islands), and renders the selected
//! frames. The trace stage's time goes back to the manager's cost model.

use super::emitters::Emitters;
use super::{
    render_frame, Aov, AovIntegrator, Film, Integrator, RenderError, RenderScene, RenderSettings, RenderStats,
};
use crate::integrate::{FrameState, FrameStats, SceneAssets, SceneManager};
use crate::physics::{BodyState, ReplayFrame, Trajectory};
use crate::scene::{Body, SceneDescription};

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
    /// Whether frame `index` is rendered.
    pub fn selects(&self, index: u32) -> bool {
        (self.start..self.end).contains(&index) && index % self.step.max(1) == 0
    }

    /// Frames this selects.
    pub fn frame_count(&self) -> u32 {
        (self.start..self.end).filter(|&f| self.selects(f)).count() as u32
    }

    fn settings(&self, frame: u32) -> RenderSettings {
        RenderSettings { width: self.width, height: self.height, spp: self.spp, frame }
    }
}

/// The simulation a sequence shows: its trajectory, the scene file's assets, and the scene
/// without bodies ([`crate::integrate::describe_scene`]).
#[derive(Clone, Copy)]
pub struct SequenceScene<'a> {
    pub trajectory: &'a Trajectory,
    pub assets: &'a SceneAssets,
    pub template: &'a SceneDescription,
}

/// One rendered frame of a sequence.
pub struct SequenceFrame<'a> {
    pub index: u32,
    pub film: &'a Film,
    pub render: RenderStats,
    /// The manager's per-stage statistics, trace included.
    pub stats: &'a FrameStats,
    /// The requested AOV passes, in request order.
    pub aovs: Vec<(Aov, Film)>,
}

/// Replays `trajectory` from its first frame (every island event must be seen), renders the
/// frames `options` selects with `integrator`, and hands each to `on_frame`. The accelerator
/// is first brought up to date at `options.start`, so a slice of a sequence renders the same
/// images as a whole run, up to float noise (integrated and instanced bodies are hit alike).
pub fn render_sequence<E: From<RenderError>>(
    scene: &SequenceScene<'_>,
    manager: &mut SceneManager,
    integrator: &dyn Integrator,
    aovs: &[Aov],
    options: &SequenceOptions,
    on_frame: &mut dyn FnMut(SequenceFrame<'_>) -> Result<(), E>,
) -> Result<(), E> {
    let mut replay = scene.trajectory.replay();
    while let Some(frame) = replay.next_frame() {
        if frame.index >= options.end {
            break;
        }
        manager.observe(frame.events);
        if !options.selects(frame.index) {
            continue;
        }
        let rendered = render_managed_frame(scene, manager, &frame, integrator, aovs, options)?;
        on_frame(SequenceFrame {
            index: frame.index,
            film: &rendered.film,
            render: rendered.render,
            stats: manager.last_frame(),
            aovs: rendered.aovs,
        })?;
    }
    Ok(())
}

/// What [`render_managed_frame`] produced; the manager keeps the frame's statistics
/// ([`SceneManager::last_frame`]).
pub struct ManagedFrame {
    pub film: Film,
    pub render: RenderStats,
    pub aovs: Vec<(Aov, Film)>,
}

/// One frame of a sequence through `manager`, whose island events up to this frame must have
/// been observed: prepares the accelerator, renders the image and `aovs`, and reports the
/// trace time back to the manager.
pub fn render_managed_frame(
    scene: &SequenceScene<'_>,
    manager: &mut SceneManager,
    frame: &ReplayFrame<'_>,
    integrator: &dyn Integrator,
    aovs: &[Aov],
    options: &SequenceOptions,
) -> Result<ManagedFrame, RenderError> {
    let SequenceScene { trajectory, assets, template } = *scene;
    manager.prepare(FrameState { index: frame.index, states: frame.states, poses: frame.poses })?;
    // Emissive prototypes are light-sampled where their bodies are this frame.
    let bodies: Vec<Body> = if Emitters::prototypes_emit(template) {
        (0..frame.states.len())
            .filter(|&b| frame.states[b] != BodyState::Absent && frame.poses[b].translation.is_finite())
            .map(|b| Body {
                prototype: trajectory.bodies[b].prototype,
                transform: frame.poses[b].to_affine(),
            })
            .collect()
    } else {
        Vec::new()
    };
    let settings = options.settings(frame.index);
    let (film, render, aov_films) = {
        let mut render_scene = RenderScene::with_objects(template, &*manager, &bodies)?;
        render_scene.camera = assets.camera_at(frame.index as f32 * trajectory.timestep);
        let query = manager.query()?;
        let (film, render) = render_frame(&render_scene, query, integrator, &settings)?;
        let mut aov_films = Vec::with_capacity(aovs.len());
        for &aov in aovs {
            aov_films.push((aov, render_frame(&render_scene, query, &AovIntegrator(aov), &settings)?.0));
        }
        (film, render, aov_films)
    };
    manager.record_trace(render.seconds * 1e3, render.rays);
    Ok(ManagedFrame { film, render, aovs: aov_films })
}
