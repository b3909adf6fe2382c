//! The atrium scene, scaled down with a count override so it runs in seconds.

use crate::common;

use common::scenes;
use dormant::physics::{simulate, BodyKind, IslandEvent, SimulateOptions};

#[test]
fn a_scaled_down_atrium_settles_into_sleeping_islands() {
    let file = scenes::load("atrium");
    let options = SimulateOptions { count: Some(160), frames: Some(700) };
    let t = simulate(&file, &options).unwrap();
    assert_eq!(t.bodies.iter().filter(|b| b.kind == BodyKind::Dynamic).count(), 160);
    assert_eq!(t.bodies.iter().filter(|b| b.kind == BodyKind::Kinematic).count(), 1, "the sweeper");
    let stats = t.island_stats();
    assert!(stats.asleep_fraction_at_end > 0.5, "{stats:?}");
    assert!(stats.islands_asleep_at_end >= 8, "one or more islands per bay: {stats:?}");
    let slept =
        t.frames.iter().flat_map(|f| &f.events).filter(|e| matches!(e, IslandEvent::Slept { .. })).count();
    assert_eq!(slept as u64, stats.islands_formed);
}
