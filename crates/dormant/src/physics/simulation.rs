//! The simulation: a Rapier world built from a scene file, stepped frame by frame. Each
//! frame spawns due objects, applies scripted disturbances, moves kinematic bodies along
//! their paths, steps Rapier `substeps` times, removes bodies below the kill plane, and
//! feeds every body's sleep state to the [`IslandTracker`].
//!
//! [`simulate`] runs a scene from its first frame to its last and records a [`Trajectory`].
//!
//! Rapier runs single-threaded (dormant builds it without its `parallel` feature), and
//! nothing here iterates a hash map, so a scene and seed always give the same frames.

use std::time::Instant;

use glam::Vec3;
use rapier3d::prelude::{
    ActiveHooks, ColliderBuilder, IntegrationParameters, PhysicsWorld, RigidBodyBuilder, RigidBodyHandle,
};

use super::body::{
    from_rapier_pose, from_rapier_vec, to_rapier_pose, to_rapier_vec, BodyId, BodyInfo, BodyKind, BodyPose,
    BodyState,
};
use super::colliders::{environment_shapes, prototype_shape, ColliderChoice, PrototypeShape};
use super::island::{IslandCounters, IslandId, IslandTracker, SleepObservation};
use super::kinematic::KinematicPath;
use super::observed::SimulatedFrame;
use super::options::SimulateOptions;
use super::spawn::{spawn_schedule, SpawnOrder};
use super::structures::{RestingContacts, StructureSet};
use super::trajectory::{FrameRecorder, RecordedScene, Trajectory, TrajectoryFrame};
use super::PhysicsError;
use crate::scene::file::{environment_mesh, DisturbanceDef, DisturbanceKind, SceneFile};
use crate::scene::AnimatedScene;

/// Per-stage wall-clock counters, in seconds, and work counts.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct SimulationCounters {
    pub frames: u64,
    pub rapier_steps: u64,
    pub(crate) spawned: u64,
    pub(crate) removed_below_kill_plane: u64,
    pub(crate) disturbances: u64,
    pub(crate) setup_seconds: f64,
    pub(crate) spawn_seconds: f64,
    pub step_seconds: f64,
    pub islands_seconds: f64,
}

/// A scene being simulated.
pub struct Simulation {
    world: PhysicsWorld,
    prototypes: Vec<PrototypeShape>,
    bodies: Vec<BodyInfo>,
    handles: Vec<Option<RigidBodyHandle>>,
    states: Vec<BodyState>,
    spawns: Vec<SpawnOrder>,
    next_spawn: usize,
    first_spawned: u32,
    kinematics: Vec<(BodyId, KinematicPath)>,
    disturbances: Vec<DisturbanceDef>,
    structures: StructureSet,
    tracker: IslandTracker,
    /// The frames' changes against what was recorded before.
    recorder: FrameRecorder,
    frame: u32,
    timestep: f32,
    substeps: u32,
    kill_plane_y: f32,
    sleep: (f32, f32, f32),
    damping: (f32, f32),
    counters: SimulationCounters,
}

impl Simulation {
    /// Builds the world: environment collider, prototype shapes (once each), kinematic
    /// bodies, and the full spawn schedule. No object is spawned before the first frame.
    pub fn new(file: &SceneFile) -> Result<Self, PhysicsError> {
        let t0 = Instant::now();
        let d = file.spec();
        let p = &d.physics;
        let mut world = static_world(file)?;
        let prototypes =
            (0..d.prototypes.len()).map(|i| prototype_shape(file, i)).collect::<Result<Vec<_>, _>>()?;

        let mut bodies = Vec::new();
        let mut handles = Vec::new();
        let mut kinematics = Vec::new();
        for k in &d.kinematics {
            let path = KinematicPath::new(&k.keyframes, k.looped);
            let id = BodyId(bodies.len() as u32);
            let shape = &prototypes[k.prototype];
            let (handle, _) = world.insert(
                RigidBodyBuilder::kinematic_position_based()
                    .pose(to_rapier_pose(path.pose_at(0.0)))
                    .user_data(id.0 as u128),
                ColliderBuilder::new(shape.shape.clone())
                    .friction(shape.friction)
                    .restitution(shape.restitution),
            );
            bodies.push(BodyInfo {
                prototype: k.prototype as u32,
                kind: BodyKind::Kinematic,
                spawn_frame: 0,
            });
            handles.push(Some(handle));
            kinematics.push((id, path));
        }
        let first_spawned = bodies.len() as u32;
        let spawns = spawn_schedule(file, &prototypes);
        for order in &spawns {
            bodies.push(BodyInfo {
                prototype: order.prototype,
                kind: BodyKind::Dynamic,
                spawn_frame: order.frame,
            });
            handles.push(None);
        }
        let structures = StructureSet::new(&spawns, first_spawned, bodies.len());
        let mut disturbances = d.disturbances.clone();
        disturbances.sort_by_key(|d| d.frame);
        let mut states = vec![BodyState::Absent; bodies.len()];
        for (id, _) in &kinematics {
            states[id.0 as usize] = BodyState::Awake;
        }
        let counters =
            SimulationCounters { setup_seconds: t0.elapsed().as_secs_f64(), ..SimulationCounters::default() };
        Ok(Self {
            world,
            prototypes,
            recorder: FrameRecorder::new(bodies.len()),
            bodies,
            handles,
            states,
            spawns,
            next_spawn: 0,
            first_spawned,
            kinematics,
            disturbances,
            structures,
            tracker: IslandTracker::new(),
            frame: 0,
            timestep: p.timestep,
            substeps: p.substeps,
            kill_plane_y: p.kill_plane_y,
            sleep: (p.sleep_linear_threshold, p.sleep_angular_threshold, p.sleep_time),
            damping: (p.linear_damping, p.angular_damping),
            counters,
        })
    }

    /// Every body the simulation will ever have, indexed by [`BodyId`].
    pub fn bodies(&self) -> &[BodyInfo] {
        &self.bodies
    }

    /// How each prototype's collider was built.
    pub fn collider_choices(&self) -> Vec<ColliderChoice> {
        self.prototypes.iter().map(|p| p.choice).collect()
    }

    /// The next frame to simulate (= frames simulated so far).
    pub fn frame(&self) -> u32 {
        self.frame
    }

    /// Seconds of simulated time per frame.
    pub fn timestep(&self) -> f32 {
        self.timestep
    }

    pub fn state(&self, body: BodyId) -> BodyState {
        self.states[body.0 as usize]
    }

    pub fn pose(&self, body: BodyId) -> Option<BodyPose> {
        let handle = self.handles.get(body.0 as usize).copied().flatten()?;
        Some(from_rapier_pose(self.world.bodies[handle].position()))
    }

    /// The sleeping island `body` belongs to, if it sleeps.
    pub fn island_of(&self, body: BodyId) -> Option<IslandId> {
        self.tracker.island_of(body)
    }

    /// The sleeping islands and their bodies.
    pub fn islands(&self) -> impl Iterator<Item = (IslandId, &[BodyId])> {
        self.tracker.islands()
    }

    /// How many islands slept and woke so far.
    pub fn island_counters(&self) -> &IslandCounters {
        self.tracker.counters()
    }

    pub fn counters(&self) -> &SimulationCounters {
        &self.counters
    }

    /// Number of dynamic bodies in the world and how many of them sleep.
    pub fn dynamic_counts(&self) -> (usize, usize) {
        let alive = self.first_spawned as usize..self.bodies.len();
        let present = self.states[alive.clone()].iter().filter(|s| **s != BodyState::Absent).count();
        let asleep = self.states[alive].iter().filter(|s| **s == BodyState::Asleep).count();
        (present, asleep)
    }

    /// Structure copies that have not woken since they were built.
    pub fn intact_structures(&self) -> usize {
        self.structures.intact_count()
    }

    /// Gives `body` a linear impulse (waking its island). False when the body is not in the
    /// world.
    pub fn apply_impulse(&mut self, body: BodyId, impulse: Vec3) -> bool {
        match self.handles.get(body.0 as usize).copied().flatten() {
            Some(h) => {
                self.world.bodies[h].apply_impulse(to_rapier_vec(impulse), true);
                true
            }
            None => false,
        }
    }

    /// Wakes every body (used to measure the cost of a world with nothing asleep).
    pub fn wake_all(&mut self) {
        self.world.wake_up_all(true);
    }

    /// Simulates one frame and returns what changed.
    pub fn step(&mut self) -> TrajectoryFrame {
        let frame = self.frame;
        let t0 = Instant::now();
        self.spawn_due(frame);
        self.disturb(frame);
        let t1 = Instant::now();
        let sub_dt = self.timestep / self.substeps as f32;
        // A structure that anything woke wakes whole, before Rapier steps it and before the
        // tracker observes it.
        self.structures.wake_touched(&mut self.world, &self.handles);
        for s in 0..self.substeps {
            let t_end = frame as f32 * self.timestep + (s + 1) as f32 * sub_dt;
            for (id, path) in &self.kinematics {
                if let Some(h) = self.handles[id.0 as usize] {
                    self.world.bodies[h].set_next_kinematic_position(to_rapier_pose(path.pose_at(t_end)));
                }
            }
            self.world.step_with_events(&RestingContacts, &());
            self.counters.rapier_steps += 1;
            self.structures.wake_touched(&mut self.world, &self.handles);
        }
        let t2 = Instant::now();
        self.remove_fallen();
        let record = self.observe();
        let t3 = Instant::now();
        self.counters.spawn_seconds += (t1 - t0).as_secs_f64();
        self.counters.step_seconds += (t2 - t1).as_secs_f64();
        self.counters.islands_seconds += (t3 - t2).as_secs_f64();
        self.counters.frames += 1;
        self.frame += 1;
        record
    }

    fn spawn_due(&mut self, frame: u32) {
        let (lin, ang, time) = self.sleep;
        while let Some(order) = self.spawns.get(self.next_spawn).filter(|o| o.frame <= frame) {
            let id = BodyId(self.first_spawned + self.next_spawn as u32);
            let shape = &self.prototypes[order.prototype as usize];
            // Structures are built asleep, with the filter that keeps their touching blocks
            // from waking each other (see `structures`).
            let resting = order.structure.is_some();
            let hooks = if resting { ActiveHooks::FILTER_CONTACT_PAIRS } else { ActiveHooks::empty() };
            let (handle, _) = self.world.insert(
                RigidBodyBuilder::dynamic()
                    .pose(to_rapier_pose(order.pose))
                    .linvel(to_rapier_vec(order.velocity))
                    .linear_damping(self.damping.0)
                    .angular_damping(self.damping.1)
                    .sleeping(resting)
                    .user_data(id.0 as u128),
                ColliderBuilder::new(shape.shape.clone())
                    .density(shape.density)
                    .friction(shape.friction)
                    .restitution(shape.restitution)
                    .active_hooks(hooks),
            );
            let activation = self.world.bodies[handle].activation_mut();
            activation.normalized_linear_threshold = lin;
            activation.angular_threshold = ang;
            activation.time_until_sleep = time;
            self.handles[id.0 as usize] = Some(handle);
            self.states[id.0 as usize] = BodyState::Awake;
            self.next_spawn += 1;
            self.counters.spawned += 1;
        }
    }

    fn disturb(&mut self, frame: u32) {
        let start = self.disturbances.partition_point(|d| d.frame < frame);
        let end = self.disturbances.partition_point(|d| d.frame <= frame);
        for i in start..end {
            let d = self.disturbances[i].clone();
            let centre = Vec3::from_array(d.center);
            self.counters.disturbances += 1;
            for id in self.first_spawned as usize..self.bodies.len() {
                let Some(h) = self.handles[id] else { continue };
                let rb = &mut self.world.bodies[h];
                let offset = from_rapier_vec(rb.translation()) - centre;
                let distance = offset.length();
                if distance > d.radius {
                    continue;
                }
                let impulse = match d.kind {
                    DisturbanceKind::Impulse { impulse } => Vec3::from_array(impulse),
                    DisturbanceKind::Explosion { strength } => {
                        let dv = strength * (1.0 - distance / d.radius);
                        offset.try_normalize().unwrap_or(Vec3::Y) * dv * rb.mass()
                    }
                };
                rb.apply_impulse(to_rapier_vec(impulse), true);
            }
        }
    }

    fn remove_fallen(&mut self) {
        for id in self.first_spawned as usize..self.bodies.len() {
            let Some(h) = self.handles[id] else { continue };
            if self.structures.resting(BodyId(id as u32)).is_some() {
                continue; // asleep where it was built
            }
            let y = self.world.bodies[h].translation().y;
            // A NaN height means the body blew up: it leaves the world too.
            if y.is_nan() || y < self.kill_plane_y {
                self.world.remove_body(h);
                self.handles[id] = None;
                self.counters.removed_below_kill_plane += 1;
            }
        }
    }

    /// Whether body `i` (Rapier's `h`) sleeps, its sleep-group key if it does, and its pose.
    fn sleep_state(&self, i: usize, h: RigidBodyHandle) -> (bool, Option<u64>, BodyPose) {
        // An intact structure sleeps as one group where it was built (no need to ask Rapier).
        if let Some((key, pose)) = self.structures.resting(BodyId(i as u32)) {
            return (true, Some(key), pose);
        }
        let rb = &self.world.bodies[h];
        let pose = from_rapier_pose(rb.position());
        let asleep = self.bodies[i].kind == BodyKind::Dynamic && rb.is_sleeping();
        // Rapier sleeps and wakes whole persistent islands, so its island of a sleeping body
        // is exactly the sleeping group. Should it ever not know the body, the body sleeps
        // alone (keys above u32 cannot collide).
        let group = asleep.then(|| {
            self.world
                .islands
                .persistent_island_of(&self.world.bodies, h)
                .map_or(u64::from(u32::MAX) + 1 + i as u64, u64::from)
        });
        (asleep, group, pose)
    }

    /// Observes every body after the frame's steps: its state and pose go to the recorder
    /// (poses of bodies awake at the end or fallen asleep during the frame; a sleeping body
    /// keeps its pose), its sleep group to the island tracker.
    fn observe(&mut self) -> TrajectoryFrame {
        let mut observations = Vec::with_capacity(self.bodies.len());
        for (i, handle) in self.handles.iter().enumerate() {
            let id = BodyId(i as u32);
            let previous = self.states[i];
            let state = match handle {
                None => BodyState::Absent,
                Some(h) => {
                    let (asleep, group, pose) = self.sleep_state(i, *h);
                    observations.push(SleepObservation { body: id, group, pose });
                    let state = if asleep { BodyState::Asleep } else { BodyState::Awake };
                    if state == BodyState::Awake || previous != BodyState::Asleep {
                        self.recorder.pose(id, pose);
                    }
                    state
                }
            };
            self.recorder.state(id, state);
            self.states[i] = state;
        }
        let events = self.tracker.update(&observations);
        self.recorder.finish(events)
    }
}

/// A world with the scene's gravity and step parameters and its environment as the one fixed
/// body (with one collider, or one per collider cell).
fn static_world(file: &SceneFile) -> Result<PhysicsWorld, PhysicsError> {
    let d = file.spec();
    let p = &d.physics;
    let mut world = PhysicsWorld::new();
    world.gravity = to_rapier_vec(Vec3::from_array(p.gravity));
    world.integration_parameters =
        IntegrationParameters { dt: p.timestep / p.substeps as f32, ..IntegrationParameters::default() };
    world.integration_parameters.num_solver_iterations = p.solver_iterations as usize;

    let env = environment_mesh(file)?;
    let friction = d.environment.friction;
    match environment_shapes(&env, file)?.as_slice() {
        [shape] => {
            world.insert(RigidBodyBuilder::fixed(), ColliderBuilder::new(shape.clone()).friction(friction));
        }
        cells => {
            let body = world.insert_body(RigidBodyBuilder::fixed());
            for shape in cells {
                world.insert_collider(ColliderBuilder::new(shape.clone()).friction(friction), Some(body));
            }
        }
    }
    Ok(world)
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
    let recorded = RecordedScene::new(file, options);
    let file = options.effective_scene(file)?;
    if let Some(animated) = AnimatedScene::load(&file)? {
        return super::animated::animated_trajectory(&file, &animated, recorded, on_frame);
    }
    let mut sim = Simulation::new(&file)?;
    let frames = file.spec().scene.frames;
    let mut records = Vec::with_capacity(frames as usize);
    for f in 0..frames {
        let t0 = Instant::now();
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
