//! The physics benchmark's report on the tiny scene.

use crate::common;

use common::scenes;
use dormant::physics::SimulateOptions;
use dormant_lab::bench::{bench_physics as bench, PhysicsBenchOptions};

#[test]
fn the_bench_measures_both_phases_and_serializes() {
    let file = scenes::load("tiny");
    let options = PhysicsBenchOptions {
        simulate: SimulateOptions { count: None, frames: Some(420) },
        measure_frames: 10,
    };
    let report = bench(&file, &options).unwrap();
    assert_eq!(report.dynamic_bodies, 20);
    assert_eq!(report.measure_frames, 10);
    assert!(report.asleep_fraction > 0.0 && report.asleep_fraction <= 1.0, "{report:?}");
    assert!(report.ms_per_step_all_awake > 0.0 && report.ms_per_step_mostly_asleep > 0.0, "{report:?}");
    let json = serde_json::to_string(&report).unwrap();
    assert!(json.contains("ms_per_step_all_awake"));
    let zero = PhysicsBenchOptions { measure_frames: 0, ..options };
    assert!(bench(&file, &zero).is_err());
}
