//! Running a whole scene into a [`Trajectory`].

use super::simulation::Simulation;
use super::trajectory::Trajectory;
use super::PhysicsError;
use std::num::NonZeroU32;

use crate::scene::file::SceneFile;

/// Overrides a command line can apply to a scene before simulating it.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SimulateOptions {
    /// Total dynamic objects, spread over the spawners in proportion to their counts.
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
            if count == 0 {
                return Err(PhysicsError::Option { option: "--count", message: "must be at least 1".into() });
            }
            file = file.with_total_count(count)?;
        }
        if let Some(frames) = self.frames {
            let frames = NonZeroU32::new(frames).ok_or_else(|| PhysicsError::Option {
                option: "--frames",
                message: "must be at least 1".into(),
            })?;
            file = file.with_frames(frames);
        }
        Ok(file)
    }
}

/// One simulated frame, as [`simulate_observed`] reports it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SimulatedFrame {
    pub index: u32,
    /// Frames the whole run simulates.
    pub frames: u32,
    /// Wall-clock milliseconds of this frame's physics step.
    pub step_ms: f64,
}

/// Simulates `file` with `options` and records every frame.
pub fn simulate(file: &SceneFile, options: &SimulateOptions) -> Result<Trajectory, PhysicsError> {
    simulate_observed(file, options, &mut |_| {})
}

/// [`simulate`], calling `on_frame` after each frame (for progress and per-frame timings).
pub fn simulate_observed(
    file: &SceneFile,
    options: &SimulateOptions,
    on_frame: &mut dyn FnMut(SimulatedFrame),
) -> Result<Trajectory, PhysicsError> {
    let recorded = super::trajectory::RecordedScene::new(file, options);
    let file = options.effective_scene(file)?;
    let mut sim = Simulation::new(&file)?;
    let frames = file.spec().scene.frames;
    let mut records = Vec::with_capacity(frames as usize);
    for f in 0..frames {
        let t0 = std::time::Instant::now();
        records.push(sim.step());
        on_frame(SimulatedFrame { index: f, frames, step_ms: t0.elapsed().as_secs_f64() * 1e3 });
        if (f + 1) % 100 == 0 || f + 1 == frames {
            let (present, asleep) = sim.dynamic_counts();
            tracing::info!(
                frame = f + 1,
                frames,
                bodies = present,
                asleep,
                step_ms = 1e3 * sim.counters().step_seconds / sim.counters().frames as f64,
                "simulating"
            );
        }
    }
    Ok(Trajectory {
        scene_hash: file.source_hash(),
        timestep: file.spec().physics.timestep,
        scene: Some(recorded),
        prototypes: file.spec().prototypes.iter().map(|p| p.name.clone()).collect(),
        bodies: sim.bodies().to_vec(),
        frames: records,
    })
}
