//! Island tracking against real Rapier simulations: stacks, piles, pokes and merges.

use crate::common;

use common::scenes;
use dormant::physics::{BodyId, BodyKind, BodyState, IslandEvent, IslandId, SimulateOptions, Simulation};
use dormant::scene::file::SceneFile;

/// A ground, unit boxes, and one spawner per `(x, y, count, start_time)`, each a vertical
/// stack from height `y` up (a one-cell grid footprint, no rotation, no jitter).
fn stacks_scene(stacks: &[(f32, f32, u32, f32)], frames: u32) -> SceneFile {
    let mut text = format!(
        "[scene]\nname = \"stacks\"\nframes = {frames}\n\n[environment]\ngenerator = \"ground\"\n\n\
         [[prototypes]]\nname = \"box\"\nshape = \"box\"\nhalf_extents = [0.5, 0.5, 0.5]\n"
    );
    for (x, y, count, start) in stacks {
        text += &format!(
            "\n[[spawners]]\nprototypes = [\"box\"]\ncount = {count}\nrandom_rotation = false\nstart_time = {start}\n\
             region = {{ min = [{x}, {y}, 0.0], max = [{x}, {y}, 0.0] }}\n"
        );
    }
    SceneFile::parse("stacks.toml", text).expect("valid test scene")
}

fn run_until_all_asleep(sim: &mut Simulation, max_frames: u32) -> Vec<IslandEvent> {
    let mut events = Vec::new();
    for _ in 0..max_frames {
        events.extend(sim.step().events);
        let (present, asleep) = sim.dynamic_counts();
        if present > 0 && present == asleep {
            return events;
        }
    }
    panic!("bodies still awake after {max_frames} frames: {:?}", sim.dynamic_counts());
}

/// Live islands ordered by their first body.
fn live_islands(sim: &Simulation) -> Vec<(IslandId, Vec<BodyId>)> {
    let mut islands: Vec<_> = sim.islands().map(|(id, b)| (id, b.to_vec())).collect();
    islands.sort_by_key(|(_, bodies)| bodies[0]);
    islands
}

#[test]
fn a_stack_of_boxes_sleeps_as_one_island_and_a_poke_wakes_it() {
    let file = stacks_scene(&[(0.0, 0.0, 4, 0.0)], 1);
    let mut sim = Simulation::new(&file).unwrap();
    let events = run_until_all_asleep(&mut sim, 600);
    let islands = live_islands(&sim);
    assert_eq!(islands.len(), 1, "{islands:?}");
    assert_eq!(islands[0].1, (0..4).map(BodyId).collect::<Vec<_>>());
    let slept = events.iter().filter(|e| matches!(e, IslandEvent::Slept { .. })).count();
    assert_eq!(slept, 1, "one group fell asleep once: {events:?}");

    assert!(sim.apply_impulse(BodyId(3), glam::Vec3::new(2.0, 0.0, 0.0)));
    let record = sim.step();
    assert_eq!(record.events, vec![IslandEvent::Woke { island: islands[0].0 }]);
    let bodies = (0..sim.bodies().len() as u32).map(BodyId);
    assert!(bodies.map(|b| sim.state(b)).all(|s| s == BodyState::Awake));
}

#[test]
fn two_separate_piles_are_two_islands_and_a_poke_wakes_exactly_one() {
    let file = stacks_scene(&[(-5.0, 0.0, 3, 0.0), (5.0, 0.0, 3, 0.0)], 1);
    let mut sim = Simulation::new(&file).unwrap();
    run_until_all_asleep(&mut sim, 600);
    let islands = live_islands(&sim);
    assert_eq!(islands.len(), 2, "{islands:?}");
    let (left, right) = (&islands[0], &islands[1]);
    assert_eq!(left.1, vec![BodyId(0), BodyId(1), BodyId(2)]);
    assert_eq!(right.1, vec![BodyId(3), BodyId(4), BodyId(5)]);

    sim.apply_impulse(BodyId(1), glam::Vec3::new(0.0, 0.0, 1.0));
    let record = sim.step();
    assert_eq!(record.events, vec![IslandEvent::Woke { island: left.0 }]);
    for b in &right.1 {
        assert_eq!(sim.state(*b), BodyState::Asleep);
        assert_eq!(sim.island_of(*b), Some(right.0), "the other pile keeps its id");
    }
}

#[test]
fn piles_that_touch_merge_into_one_island() {
    // The second pile lands on the first after the first has fallen asleep.
    let file = stacks_scene(&[(0.0, 0.0, 2, 0.0), (0.0, 4.0, 2, 4.0)], 1);
    let mut sim = Simulation::new(&file).unwrap();
    let mut events = Vec::new();
    for _ in 0..230 {
        events.extend(sim.step().events);
    }
    let first = live_islands(&sim);
    assert_eq!(first.len(), 1, "first pile asleep before the second arrives: {first:?}");
    assert_eq!(first[0].1, vec![BodyId(0), BodyId(1)]);
    while sim.frame() <= 240 {
        events.extend(sim.step().events);
    }
    events.extend(run_until_all_asleep(&mut sim, 900));
    let merged = live_islands(&sim);
    assert_eq!(merged.len(), 1, "{merged:?}");
    assert_eq!(merged[0].1, (0..4).map(BodyId).collect::<Vec<_>>());
    assert!(events.contains(&IslandEvent::Woke { island: first[0].0 }), "the first island ended");
}

#[test]
fn event_stream_invariants_hold_on_the_tiny_scene() {
    let file = scenes::load("tiny");
    let trajectory = dormant::physics::simulate(&file, &SimulateOptions::default()).unwrap();
    let mut live: std::collections::BTreeMap<IslandId, Vec<BodyId>> = Default::default();
    let mut owner = vec![None; trajectory.bodies.len()];
    let (mut slept, mut woke) = (0, 0);
    let mut replay = trajectory.replay();
    while let Some(frame) = replay.next_frame() {
        let f = frame.index;
        for e in frame.events {
            match e {
                IslandEvent::Slept { island, bodies, poses } => {
                    slept += 1;
                    assert_eq!(bodies.len(), poses.len());
                    for b in bodies {
                        assert_eq!(owner[b.0 as usize], None, "frame {f}: body {b:?} in two islands");
                        assert_eq!(frame.states[b.0 as usize], BodyState::Asleep);
                        assert_eq!(trajectory.bodies[b.0 as usize].kind, BodyKind::Dynamic);
                        owner[b.0 as usize] = Some(*island);
                    }
                    live.insert(*island, bodies.clone());
                }
                IslandEvent::Woke { island } => {
                    woke += 1;
                    let bodies = live.remove(island).expect("no Woke without an earlier Slept");
                    for b in bodies {
                        owner[b.0 as usize] = None;
                    }
                }
            }
        }
        // Every sleeping body is in exactly one live island, every awake one in none.
        for (i, s) in frame.states.iter().enumerate() {
            assert_eq!(*s == BodyState::Asleep, owner[i].is_some(), "frame {f}, body {i}");
        }
    }
    assert!(
        slept >= 2 && woke >= 1,
        "the sweeper and the explosion wake islands: {slept} slept, {woke} woke"
    );
    let stats = trajectory.island_stats();
    assert!(stats.asleep_fraction_at_end > 0.5, "{stats:?}");
}

#[test]
fn bodies_below_the_kill_plane_leave_the_world() {
    // No environment under the objects: they fall forever until the kill plane.
    let text = "[scene]\nname = \"void\"\nframes = 120\n[physics]\nkill_plane_y = -5.0\n\
                [environment]\ngenerator = \"ground\"\noffset = [0.0, 0.0, 500.0]\n\
                [[prototypes]]\nname = \"box\"\nshape = \"box\"\nhalf_extents = [0.5, 0.5, 0.5]\n\
                [[spawners]]\nprototypes = [\"box\"]\ncount = 3\nregion = { min = [0.0, 1.0, 0.0], max = [3.0, 1.0, 0.0] }\n";
    let file = SceneFile::parse("void.toml", text).unwrap();
    let t = dormant::physics::simulate(&file, &SimulateOptions::default()).unwrap();
    let last = t.states_at_end();
    assert!(last.iter().all(|s| *s == BodyState::Absent), "{last:?}");
    assert!(t.frames.iter().all(|f| f.events.is_empty()));
}
