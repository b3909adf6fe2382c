//! The update stage visits only the bodies the replay says changed since the frame prepared
//! before (with those integration or reactivation placed anew, and the blurred ones). Over
//! random trajectories, a manager driven that way must place every body as one that visits
//! them all, which it does when its replay never restarts its changes.

use glam::{Quat, Vec3};
use proptest::prelude::*;

use super::{ManagerOptions, SceneManager};
use crate::accel::{self, Backend};
use crate::geometry::primitives;
use crate::physics::trajectory::{FrameRecorder, Trajectory};
use crate::physics::{BodyId, BodyInfo, BodyKind, BodyPose, BodyState, IslandEvent, IslandId};
use crate::residency::{IntegrationForm, IntegrationPolicy, TraceKind};
use crate::rng::SplitMix64;
use crate::scene::{Camera, Material, Prototype, SceneDescription, Sky, StaticMesh, Sun};

const BODIES: usize = 24;

/// A random world of [`BODIES`] bodies on a grid: they spawn, move or stay bit for bit where
/// they are, fall asleep in islands of two to four, and leave; an island ends by waking (its
/// bodies often not moving in that frame), by regrouping as another island, or with its
/// bodies still asleep. Only awake bodies move.
struct RandomWorld {
    rng: SplitMix64,
    states: [BodyState; BODIES],
    poses: [BodyPose; BODIES],
    islands: Vec<(IslandId, Vec<BodyId>)>,
    next_island: u64,
}

impl RandomWorld {
    fn draw(&mut self, n: u64) -> u64 {
        self.rng.below(n as usize) as u64
    }

    fn move_bodies(&mut self) {
        for b in 0..BODIES {
            let (spawn, leave) = (self.draw(8) == 0, self.draw(30) == 0);
            match self.states[b] {
                BodyState::Absent if spawn => self.states[b] = BodyState::Awake,
                BodyState::Awake if leave => self.states[b] = BodyState::Absent,
                _ => {}
            }
            if self.states[b] == BodyState::Awake && self.draw(2) == 0 {
                let cell = Vec3::new((b % 6) as f32 * 3.0, 1.0, (b / 6) as f32 * 3.0);
                let jitter = Vec3::new(self.draw(100) as f32, self.draw(100) as f32, 0.0) * 0.005;
                self.poses[b] =
                    BodyPose { translation: cell + jitter, rotation: Quat::from_rotation_y(jitter.x) };
            }
        }
    }

    /// `bodies` asleep together as a new island.
    fn sleep(&mut self, bodies: Vec<BodyId>, events: &mut Vec<IslandEvent>) {
        for b in &bodies {
            self.states[b.0 as usize] = BodyState::Asleep;
        }
        let island = IslandId(self.next_island);
        self.next_island += 1;
        let poses = bodies.iter().map(|b| self.poses[b.0 as usize]).collect();
        events.push(IslandEvent::Slept { island, bodies: bodies.clone(), poses });
        self.islands.push((island, bodies));
    }

    fn end_an_island(&mut self, events: &mut Vec<IslandEvent>) {
        let i = self.draw(self.islands.len() as u64) as usize;
        let (island, bodies) = self.islands.remove(i);
        events.push(IslandEvent::Woke { island });
        match self.draw(3) {
            0 => bodies.iter().for_each(|b| self.states[b.0 as usize] = BodyState::Awake),
            1 => self.sleep(bodies, events),
            _ => {}
        }
    }

    /// One frame's changes and island events.
    fn step(&mut self) -> Vec<IslandEvent> {
        let mut events = Vec::new();
        self.move_bodies();
        let awake: Vec<BodyId> =
            (0..BODIES).filter(|&b| self.states[b] == BodyState::Awake).map(|b| BodyId(b as u32)).collect();
        if awake.len() >= 4 && self.draw(3) == 0 {
            let (skip, take) = (self.draw(2) as usize, 2 + self.draw(3) as usize);
            self.sleep(awake.into_iter().skip(skip).take(take).collect(), &mut events);
        }
        if !self.islands.is_empty() && self.draw(4) == 0 {
            self.end_an_island(&mut events);
        }
        // Bodies left asleep by an island that ended wake in time.
        for b in 0..BODIES {
            let in_island = self.islands.iter().any(|(_, i)| i.contains(&BodyId(b as u32)));
            if self.states[b] == BodyState::Asleep && !in_island && self.draw(6) == 0 {
                self.states[b] = BodyState::Awake;
            }
        }
        events
    }
}

/// `frames` frames of a [`RandomWorld`] drawn from `seed`, recorded as a trajectory.
fn random_trajectory(seed: u64, frames: u32) -> Trajectory {
    let origin = BodyPose { translation: Vec3::ZERO, rotation: Quat::IDENTITY };
    let mut world = RandomWorld {
        rng: SplitMix64::new(seed),
        states: [BodyState::Absent; BODIES],
        poses: [origin; BODIES],
        islands: Vec::new(),
        next_island: 0,
    };
    let mut recorder = FrameRecorder::new(BODIES);
    let frames = (0..frames)
        .map(|_| {
            let events = world.step();
            for b in 0..BODIES {
                recorder.state(BodyId(b as u32), world.states[b]);
                recorder.pose(BodyId(b as u32), world.poses[b]);
            }
            recorder.finish(events)
        })
        .collect();
    let info = BodyInfo { prototype: 0, kind: BodyKind::Dynamic, spawn_frame: 0 };
    Trajectory {
        scene_hash: 0,
        timestep: 1.0 / 60.0,
        scene: None,
        prototypes: vec!["box".into()],
        bodies: vec![info; BODIES],
        frames,
    }
}

fn template() -> SceneDescription {
    SceneDescription {
        name: "changed-bodies".into(),
        materials: vec![Material::diffuse(Vec3::splat(0.5))],
        textures: Vec::new(),
        statics: vec![StaticMesh { mesh: primitives::ground_plane(30.0, 0.0, 2), material: 0 }],
        prototypes: vec![Prototype {
            name: "box".into(),
            mesh: primitives::cuboid(Vec3::splat(0.4)),
            material: 0,
        }],
        bodies: Vec::new(),
        camera: Camera::pinhole(Vec3::new(8.0, 12.0, -10.0), Vec3::new(8.0, 0.0, 6.0), Vec3::Y, 60.0),
        sun: Sun { direction: Vec3::Y, irradiance: Vec3::ONE, angular_radius_deg: 1.0 },
        sky: Sky::DAYLIGHT,
        lights: Vec::new(),
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn visiting_only_changed_bodies_places_them_as_visiting_all(
        seed in any::<u64>(),
        step in 1u32..4,
        baked in any::<bool>(),
        blurred in any::<bool>(),
    ) {
        let trajectory = random_trajectory(seed, 48);
        let options = ManagerOptions {
            policy: IntegrationPolicy::Always,
            form: if baked { IntegrationForm::Baked } else { IntegrationForm::Resting },
            shutter: if blurred { 0.5 } else { 0.0 },
            ..ManagerOptions::default()
        };
        let manager = || {
            let accel = accel::create(Backend::Bvh, Some(1)).unwrap();
            SceneManager::new(accel, &template(), &trajectory.bodies, options.clone()).unwrap()
        };
        let (mut changed, mut visiting_all) = (manager(), manager());
        // One replay restarts its changes after each prepared frame, as `Sequence::replay`
        // does; the other never, so its frames never say what changed.
        let (mut replay, mut never_restarted) = (trajectory.replay(), trajectory.replay());
        for index in 0..trajectory.frames.len() as u32 {
            let (f, g) = (replay.next_frame().unwrap(), never_restarted.next_frame().unwrap());
            changed.observe(f.events);
            visiting_all.observe(g.events);
            if index % step != 0 {
                continue;
            }
            changed.prepare(&f).unwrap();
            visiting_all.prepare(&g).unwrap();
            changed.record_trace(0.0, 0, TraceKind::Typical);
            visiting_all.record_trace(0.0, 0, TraceKind::Typical);
            for b in 0..BODIES {
                prop_assert_eq!(changed.bodies[b].placement, visiting_all.bodies[b].placement, "frame {} body {}", index, b);
            }
            prop_assert_eq!(&changed.blurred, &visiting_all.blurred, "frame {}", index);
            prop_assert_eq!(changed.instance_owner.awake(), visiting_all.instance_owner.awake());
            replay.restart_changes();
        }
    }
}
