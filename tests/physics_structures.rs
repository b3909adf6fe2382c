//! Structures in real Rapier simulations: built asleep as one island per copy, left alone
//! they stay asleep, and whatever hits one (a projectile, a kinematic body, a domino front)
//! wakes the whole copy, whose debris then settles into new islands.

use crate::common;

use std::collections::BTreeSet;

use common::scenes;
use dormant::physics::{
    BodyId, BodyKind, BodyPose, BodyState, IslandEvent, IslandId, SimulateOptions, Simulation,
};
use dormant::scene::file::SceneFile;

/// Three towers of 30 planks, 6 m apart along X, and `extra` (more tables) after them.
fn towers_scene(frames: u32, extra: &str) -> SceneFile {
    let text = format!(
        r#"[scene]
name = "towers"
frames = {frames}

[physics]
sleep_linear_threshold = 0.1
linear_damping = 0.1
angular_damping = 1.0

[environment]
generator = "ground"

[[prototypes]]
name = "plank"
shape = "box"
half_extents = [0.3, 0.06, 0.1]

[[prototypes]]
name = "ball"
shape = "sphere"
radius = 0.25
density = 5.0

[[structures]]
name = "towers"
kind = "tower"
prototype = "plank"
layers = 10
per_layer = 3
origin = [-6.0, 0.0, 0.0]
array = {{ counts = [3, 1], spacing = [6.0, 0.0] }}
{extra}"#
    );
    SceneFile::parse("towers.toml", text).expect("valid test scene")
}

/// One ball at the first tower, launched at frame 20.
const BALL_AT_FIRST_TOWER: &str = r#"
[[projectiles]]
prototype = "ball"
structure = "towers"
count = 1
frame = 20
position = [0.0, 0.8, -3.0]
velocity = [0.0, 1.0, 10.0]
"#;

/// The three towers' bodies: 30 consecutive ids each.
fn tower_bodies(tower: u32) -> Vec<BodyId> {
    (30 * tower..30 * (tower + 1)).map(BodyId).collect()
}

/// The island and the poses each tower fell asleep in at frame 0.
fn built_islands(events: &[IslandEvent]) -> Vec<(IslandId, Vec<BodyId>, Vec<BodyPose>)> {
    events
        .iter()
        .filter_map(|e| match e {
            IslandEvent::Slept { island, bodies, poses } => Some((*island, bodies.clone(), poses.clone())),
            IslandEvent::Woke { .. } => None,
        })
        .collect()
}

#[test]
fn structures_are_built_asleep_as_one_island_per_copy() {
    let file = towers_scene(1, "");
    let mut sim = Simulation::new(&file).unwrap();
    assert_eq!(sim.bodies().len(), 90);
    assert!(sim.bodies().iter().all(|b| b.kind == BodyKind::Dynamic && b.spawn_frame == 0));
    let record = sim.step();
    assert!((0..90).all(|b| sim.state(BodyId(b)) == BodyState::Asleep));
    let islands = built_islands(&record.events);
    assert_eq!(islands.len(), 3, "{:?}", record.events);
    for (tower, (island, bodies, poses)) in islands.iter().enumerate() {
        assert_eq!(bodies, &tower_bodies(tower as u32));
        assert_eq!(sim.island_of(bodies[0]), Some(*island));
        for (body, pose) in bodies.iter().zip(poses) {
            assert_eq!(sim.pose(*body), Some(*pose), "the recorded pose is Rapier's");
        }
    }
    assert_eq!(sim.intact_structures(), 3);
}

#[test]
fn an_untouched_structure_stays_asleep_for_the_whole_run() {
    let file = towers_scene(600, BALL_AT_FIRST_TOWER);
    let mut sim = Simulation::new(&file).unwrap();
    let built = built_islands(&sim.step().events);
    let untouched: BTreeSet<IslandId> = built[1..].iter().map(|(island, ..)| *island).collect();
    for frame in 1..600 {
        let record = sim.step();
        for event in &record.events {
            assert!(!untouched.contains(&event.island()), "frame {frame}: {event:?}");
        }
    }
    for (island, bodies, poses) in &built[1..] {
        for (body, pose) in bodies.iter().zip(poses) {
            assert_eq!(sim.state(*body), BodyState::Asleep);
            assert_eq!(sim.island_of(*body), Some(*island));
            assert_eq!(sim.pose(*body), Some(*pose), "not a jitter");
        }
    }
    // The first tower did fall: its top plank is well below where it was built.
    let top = built[0].1[29];
    assert!(sim.pose(top).unwrap().translation.y < 0.5, "{:?}", sim.pose(top));
    assert_eq!(sim.intact_structures(), 2);
}

#[test]
fn a_projectile_wakes_the_whole_structure_it_hits() {
    let file = towers_scene(200, BALL_AT_FIRST_TOWER);
    let mut sim = Simulation::new(&file).unwrap();
    let built = built_islands(&sim.step().events);
    let ball = BodyId(90);
    assert_eq!(sim.bodies()[90].spawn_frame, 20);
    for frame in 1..200 {
        let record = sim.step();
        if record.events.contains(&IslandEvent::Woke { island: built[0].0 }) {
            assert!(frame > 20, "woken at frame {frame}, before the ball was launched");
            assert_eq!(sim.state(ball), BodyState::Awake);
            for body in tower_bodies(0) {
                assert_eq!(sim.state(body), BodyState::Awake, "frame {frame}: {body:?}");
            }
            let woke: Vec<_> =
                record.events.iter().filter(|e| matches!(e, IslandEvent::Woke { .. })).collect();
            assert_eq!(woke.len(), 1, "only the hit tower wakes: {:?}", record.events);
            return;
        }
    }
    panic!("the ball never woke the first tower");
}

#[test]
fn a_fallen_structure_settles_into_new_islands() {
    let file = towers_scene(900, BALL_AT_FIRST_TOWER);
    let mut sim = Simulation::new(&file).unwrap();
    let built = built_islands(&sim.step().events);
    for _ in 1..900 {
        sim.step();
    }
    let (present, asleep) = sim.dynamic_counts();
    assert_eq!(present, asleep, "everything has settled");
    let debris: BTreeSet<IslandId> = tower_bodies(0).iter().map(|b| sim.island_of(*b).unwrap()).collect();
    assert!(!debris.contains(&built[0].0), "the debris is in new islands: {debris:?}");
    assert!(sim.island_counters().islands_woke >= 1);
}

#[test]
fn a_wrecking_ball_and_a_domino_front_knock_structures_over() {
    let extra = r#"
[[prototypes]]
name = "domino"
shape = "box"
half_extents = [0.1, 0.25, 0.03]
friction = 0.4

[[prototypes]]
name = "brick"
shape = "box"
half_extents = [0.2, 0.1, 0.1]

[[prototypes]]
name = "ram"
shape = "box"
half_extents = [0.4, 0.4, 0.4]

[[structures]]
name = "run"
kind = "dominoes"
prototype = "domino"
count = 12
spacing = 0.3
origin = [0.0, 0.0, 6.0]

[[structures]]
name = "wall"
kind = "wall"
prototype = "brick"
layers = 6
per_layer = 6
origin = [0.0, 0.0, -6.0]

[[projectiles]]
prototype = "domino"
structure = "run"
frame = 10
position = [0.0, 0.42, -0.4]
velocity = [0.0, 0.0, 2.0]

[[kinematics]]
name = "ram"
prototype = "ram"
keyframes = [
  { time = 0.0, position = [0.0, 0.6, -8.0] },
  { time = 0.5, position = [0.0, 0.6, -8.0] },
  { time = 2.5, position = [0.0, 0.6, -4.0] },
]
"#;
    let file = towers_scene(400, extra);
    let mut sim = Simulation::new(&file).unwrap();
    // Kinematic ram first, then towers (90), the run (12) and the wall (36), then the nudge.
    let run: Vec<BodyId> = (91..103).map(BodyId).collect();
    let wall: Vec<BodyId> = (103..139).map(BodyId).collect();
    let built = built_islands(&sim.step().events);
    assert_eq!(built.len(), 5, "three towers, the run and the wall");
    let mut woke = BTreeSet::new();
    for _ in 1..400 {
        woke.extend(sim.step().events.iter().filter_map(|e| match e {
            IslandEvent::Woke { island } => Some(*island),
            IslandEvent::Slept { .. } => None,
        }));
    }
    assert!(woke.contains(&built[3].0) && woke.contains(&built[4].0), "{woke:?}");
    assert!(built[..3].iter().all(|(tower, ..)| !woke.contains(tower)), "the towers stand");
    // The front ran to the end: the last domino lies down.
    let last = sim.pose(*run.last().unwrap()).unwrap();
    assert!((last.rotation * glam::Vec3::Y).y < 0.7, "the last domino still stands: {last:?}");
    // The ram pushed the wall's bottom course back.
    let moved = wall.iter().filter(|b| sim.pose(**b).unwrap().translation.z > -5.8).count();
    assert!(moved >= 6, "{moved} bricks pushed");
}

#[test]
fn a_ground_split_into_collider_cells_holds_structures_like_one_mesh() {
    let cells = |n: u32| {
        let text = towers_scene(300, BALL_AT_FIRST_TOWER)
            .source()
            .replace("generator = \"ground\"", &format!("generator = \"ground\"\ncollider_cells = {n}"));
        SceneFile::parse("towers.toml", text).unwrap()
    };
    for n in [1, 7] {
        let file = cells(n);
        let mut sim = Simulation::new(&file).unwrap();
        for _ in 0..300 {
            sim.step();
        }
        // The debris lies on the floor, not under it, and the other towers stand.
        for body in tower_bodies(0) {
            let y = sim.pose(body).unwrap().translation.y;
            assert!((0.0..1.3).contains(&y), "cells {n}: {body:?} at {y}");
        }
        assert_eq!(sim.intact_structures(), 2, "cells {n}");
    }
}

#[test]
fn the_demolition_scene_scaled_down_builds_asleep_and_falls_in_turn() {
    let file = scenes::load("demolition");
    let options = SimulateOptions { count: Some(1500), frames: Some(150) };
    let file = options.effective_scene(&file).unwrap();
    let copies: u32 = file.spec().structures.iter().map(|s| s.copies()).sum();
    let mut sim = Simulation::new(&file).unwrap();
    let record = sim.step();
    assert_eq!(built_islands(&record.events).len(), copies as usize, "one island per copy");
    let (present, asleep) = sim.dynamic_counts();
    assert_eq!(present, asleep, "every structure is built asleep");
    let mut most_awake = 0.0f64;
    for _ in 1..150 {
        sim.step();
        let (present, asleep) = sim.dynamic_counts();
        most_awake = most_awake.max((present - asleep) as f64 / present as f64);
    }
    assert!(sim.intact_structures() < copies as usize, "something was knocked over");
    assert!(sim.intact_structures() > copies as usize / 2, "most structures still stand");
    assert!(most_awake < 0.5, "at most half awake at once: {most_awake}");
}
