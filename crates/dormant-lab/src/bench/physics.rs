//! The physics benchmark: milliseconds per Rapier step with every body awake versus with
//! most bodies asleep, on the same settled scene.

use std::time::Instant;

use dormant::physics::{PhysicsError, SimulateOptions, Simulation};
use dormant::scene::file::SceneFile;

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PhysicsBenchOptions {
    pub simulate: SimulateOptions,
    /// Frames measured in each phase.
    pub measure_frames: u32,
}

impl Default for PhysicsBenchOptions {
    fn default() -> Self {
        Self { simulate: SimulateOptions::default(), measure_frames: 60 }
    }
}

#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PhysicsBenchReport {
    pub scene: String,
    pub dynamic_bodies: usize,
    /// Frames simulated before measuring (the scene's frame count).
    pub settle_frames: u32,
    pub settle_seconds: f64,
    pub measure_frames: u32,
    pub substeps: u32,
    /// Fraction of dynamic bodies asleep during the "mostly asleep" phase (mean).
    pub asleep_fraction: f64,
    pub ms_per_step_mostly_asleep: f64,
    pub ms_per_step_all_awake: f64,
    /// Island tracking cost per frame in the mostly-asleep phase.
    pub ms_per_frame_island_tracking: f64,
    pub speedup: f64,
}

/// Simulates the scene to its last frame, then measures `measure_frames` frames as they
/// are (mostly asleep) and `measure_frames` frames with every body woken before each frame.
pub fn bench_physics(
    file: &SceneFile,
    options: &PhysicsBenchOptions,
) -> Result<PhysicsBenchReport, PhysicsError> {
    if options.measure_frames == 0 {
        return Err(PhysicsError::Option { option: "measure_frames", message: "must be at least 1".into() });
    }
    let file = options.simulate.effective_scene(file)?;
    let mut sim = Simulation::new(&file)?;
    let settle_frames = file.spec().scene.frames;
    let t0 = Instant::now();
    for _ in 0..settle_frames {
        sim.step();
    }
    let settle_seconds = t0.elapsed().as_secs_f64();

    let before = *sim.counters();
    let mut asleep_sum = 0.0;
    for _ in 0..options.measure_frames {
        sim.step();
        let (present, asleep) = sim.dynamic_counts();
        asleep_sum += asleep as f64 / present.max(1) as f64;
    }
    let mid = *sim.counters();
    for _ in 0..options.measure_frames {
        sim.wake_all();
        sim.step();
    }
    let after = *sim.counters();
    let steps = |a: f64, b: f64, n: u64| 1e3 * (b - a) / n.max(1) as f64;
    let asleep_ms = steps(before.step_seconds, mid.step_seconds, mid.rapier_steps - before.rapier_steps);
    let awake_ms = steps(mid.step_seconds, after.step_seconds, after.rapier_steps - mid.rapier_steps);
    Ok(PhysicsBenchReport {
        scene: file.spec().scene.name.clone(),
        dynamic_bodies: sim.dynamic_counts().0,
        settle_frames,
        settle_seconds,
        measure_frames: options.measure_frames,
        substeps: file.spec().physics.substeps,
        asleep_fraction: asleep_sum / options.measure_frames as f64,
        ms_per_step_mostly_asleep: asleep_ms,
        ms_per_step_all_awake: awake_ms,
        ms_per_frame_island_tracking: 1e3 * (mid.islands_seconds - before.islands_seconds)
            / options.measure_frames as f64,
        speedup: if asleep_ms > 0.0 { awake_ms / asleep_ms } else { 0.0 },
    })
}
