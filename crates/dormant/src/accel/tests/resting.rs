//! Resting instances (`Accelerator::set_instance_resting`) hit exactly like awake ones, on
//! every compiled backend: a *subject* scene moves instances to rest and back while a
//! *reference* scene gets the same changes with every instance awake, and after each commit
//! both give the same closest hits and occlusion, ray by ray and in packets. Covered: moving,
//! removing and re-adding resting instances, static meshes added and removed while instances
//! rest, the resting scene becoming empty again and the top level becoming empty, resting
//! instances that wait in the top level for the scheduled rebuild and woken ones that leave
//! ghosts in the resting level (forced by `compact_resting`), the commit reports, and random
//! sequences of all of these (property tests).

use super::common::cluster;
use crate::accel::{
    self, Accelerator, Backend, CommitReport, Hit, HitObject, InstanceId, Occluder, PrototypeId, SceneQuery,
    StaticId,
};
use crate::geometry::{primitives, Ray, TriangleMesh};
use glam::{Affine3A, Quat, Vec3};
use proptest::prelude::*;

/// Where an instance goes: translation, rotation axis and angle, uniform scale.
#[derive(Clone, Copy, Debug)]
struct Pose {
    at: Vec3,
    axis: Vec3,
    angle: f32,
    scale: f32,
}

impl Pose {
    fn affine(&self) -> Affine3A {
        let axis = self.axis.try_normalize().unwrap_or(Vec3::Y);
        Affine3A::from_scale_rotation_translation(
            Vec3::splat(self.scale),
            Quat::from_axis_angle(axis, self.angle),
            self.at,
        )
    }
}

/// One change. Instance and static indices count live ones (modulo how many there are);
/// `Rest` and `Wake` reach only the subject.
#[derive(Clone, Copy, Debug)]
enum Op {
    Add {
        proto: usize,
        pose: Pose,
    },
    Move {
        k: usize,
        pose: Pose,
    },
    Rest(usize),
    Wake(usize),
    Remove(usize),
    AddStatic(u64),
    RemoveStatic(usize),
    /// Commit both scenes (the subject's static and resting builds first when `split`).
    Commit {
        split: bool,
    },
    /// Rebuild the subject's resting level now (every resting instance in it, no ghost), then
    /// commit both.
    Compact,
}

/// Coherent rays from above the scene (a grid, traced as packets too) and incoherent rays
/// between random points, every third with a finite `t_max`.
fn test_rays() -> Vec<Ray> {
    let eye = Vec3::new(0.0, 14.0, 16.0);
    let mut rays = Vec::new();
    for y in 0..24 {
        for x in 0..32 {
            let target = Vec3::new(-10.0 + x as f32 * 0.65, 0.0, -10.0 + y as f32 * 0.85);
            rays.push(Ray::new(eye, target - eye));
        }
    }
    let mut s = 99u64;
    let mut next = || {
        s = s.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        (s >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
    };
    for i in 0..600 {
        let o = Vec3::new(next() * 10.0, next() * 2.0 + 2.0, next() * 10.0);
        let d = Vec3::new(next(), next(), next());
        let t_max = if i % 3 == 0 { 2.0 + next().abs() * 6.0 } else { f32::INFINITY };
        rays.push(Ray::segment(o, d, 0.0, t_max));
    }
    rays
}

/// Equal hits; two different objects or triangles at exactly the same `t` (a tie, such as a
/// ray through an edge two triangles share: Embree may report either when the ghost filter
/// is in the query) may swap.
fn same_hit(reference: Option<Hit>, subject: Option<Hit>) -> bool {
    match (reference, subject) {
        (Some(r), Some(s)) if r.object != s.object || r.prim != s.prim => r.t == s.t,
        (r, s) => r == s,
    }
}

/// Closest hits and occlusion of `rays` in both scenes: single rays, then packets of 8 and 16.
fn compare(reference: &dyn SceneQuery, subject: &dyn SceneQuery, rays: &[Ray]) -> Result<(), String> {
    for (i, ray) in rays.iter().enumerate() {
        let (r, s) = (reference.intersect(ray), subject.intersect(ray));
        if !same_hit(r, s) {
            return Err(format!("ray {i} {ray:?}: closest {r:?} awake, {s:?} resting"));
        }
        if reference.intersect_p(ray) != subject.intersect_p(ray) {
            return Err(format!("ray {i} {ray:?}: occlusion differs"));
        }
    }
    for width in [8, 16] {
        for (c, chunk) in rays.chunks(width).enumerate() {
            let (mut r, mut s) = (vec![None; chunk.len()], vec![None; chunk.len()]);
            reference.intersect_packet(chunk, &mut r);
            subject.intersect_packet(chunk, &mut s);
            if let Some(k) = (0..chunk.len()).find(|&k| !same_hit(r[k], s[k])) {
                return Err(format!("packet {c} of {width}, lane {k}: {:?} awake, {:?} resting", r[k], s[k]));
            }
            let (mut r, mut s) = (vec![false; chunk.len()], vec![false; chunk.len()]);
            reference.intersect_p_packet(chunk, &mut r);
            subject.intersect_p_packet(chunk, &mut s);
            if r != s {
                return Err(format!("occlusion packet {c} of {width}: {r:?} awake, {s:?} resting"));
            }
        }
    }
    Ok(())
}

/// What blocks each of `rays` in `q`: something exactly when the ray is blocked, named (a
/// backend of ours always says what), and an instance only if it is one of `live`.
fn check_occluders(q: &dyn SceneQuery, rays: &[Ray], live: &[(InstanceId, bool)]) -> Result<(), String> {
    for (i, ray) in rays.iter().enumerate() {
        let (blocker, blocked) = (q.occluder(ray), q.intersect_p(ray));
        let named = match blocker {
            Some(Occluder::Instance(id)) => live.iter().any(|(l, _)| *l == id),
            Some(Occluder::Unknown) => false,
            Some(Occluder::Static) | None => true,
        };
        if blocker.is_some() != blocked || !named {
            return Err(format!("ray {i} {ray:?}: occluder {blocker:?}, blocked {blocked}"));
        }
    }
    Ok(())
}

/// The reference (every instance awake) and the subject (some at rest), changed in step.
struct Pair {
    backend: Backend,
    reference: Box<dyn Accelerator>,
    subject: Box<dyn Accelerator>,
    protos: Vec<PrototypeId>,
    /// Live instances and whether each rests in the subject.
    live: Vec<(InstanceId, bool)>,
    statics: Vec<StaticId>,
    rays: Vec<Ray>,
    /// Closest hits on resting instances seen so far (the comparisons are not vacuous).
    resting_hits: usize,
}

impl Pair {
    fn new(backend: Backend) -> Self {
        let mut pair = Self {
            backend,
            reference: accel::create(backend, Some(2)).unwrap(),
            subject: accel::create(backend, Some(2)).unwrap(),
            protos: Vec::new(),
            live: Vec::new(),
            statics: Vec::new(),
            rays: test_rays(),
            resting_hits: 0,
        };
        let meshes = [
            primitives::cuboid(Vec3::new(0.6, 0.3, 0.4)),
            primitives::uv_sphere(0.5, 8, 6),
            cluster(Vec3::ZERO, 24, 5),
        ];
        for m in &meshes {
            let (r, s) = (pair.reference.add_prototype(m).unwrap(), pair.subject.add_prototype(m).unwrap());
            assert_eq!(r, s);
            pair.protos.push(r);
        }
        pair.add_static(&primitives::ground_plane(12.0, 0.0, 4));
        pair
    }

    fn add_static(&mut self, mesh: &TriangleMesh) {
        let (r, s) = (self.reference.add_static(mesh).unwrap(), self.subject.add_static(mesh).unwrap());
        assert_eq!(r, s);
        self.statics.push(r);
    }

    fn apply(&mut self, op: Op) -> Result<(), String> {
        let n = self.live.len();
        match op {
            Op::Add { proto, pose } => {
                let p = self.protos[proto % self.protos.len()];
                let r = self.reference.add_instance(p, pose.affine()).unwrap();
                let s = self.subject.add_instance(p, pose.affine()).unwrap();
                assert_eq!(r, s, "{}: both scenes number instances alike", self.backend);
                self.live.push((r, false));
            }
            Op::Move { k, pose } if n > 0 => {
                let (id, _) = self.live[k % n];
                self.reference.set_instance_transform(id, pose.affine()).unwrap();
                self.subject.set_instance_transform(id, pose.affine()).unwrap();
            }
            Op::Rest(k) | Op::Wake(k) if n > 0 => {
                let to = matches!(op, Op::Rest(_));
                let (id, resting) = &mut self.live[k % n];
                self.subject.set_instance_resting(*id, to).unwrap();
                *resting = to;
            }
            Op::Remove(k) if n > 0 => {
                let (id, _) = self.live.remove(k % n);
                self.reference.remove_instance(id).unwrap();
                self.subject.remove_instance(id).unwrap();
            }
            Op::AddStatic(seed) => {
                let c = Vec3::new((seed % 17) as f32 - 8.0, 1.0, (seed % 13) as f32 - 6.0);
                self.add_static(&cluster(c, 12, seed));
            }
            Op::RemoveStatic(k) if !self.statics.is_empty() => {
                let id = self.statics.remove(k % self.statics.len());
                self.reference.remove_static(id).unwrap();
                self.subject.remove_static(id).unwrap();
            }
            Op::Commit { split } => return self.commit_and_compare(split),
            Op::Compact => {
                let early = self.subject.compact_resting().unwrap();
                if early.resting_waiting != 0 || early.resting_instances != self.resting_count() {
                    return Err(format!("{early:?} after compacting {} resting", self.resting_count()));
                }
                return self.commit_and_compare(false);
            }
            _ => {}
        }
        Ok(())
    }

    fn resting_count(&self) -> usize {
        self.live.iter().filter(|(_, r)| *r).count()
    }

    /// Commits both scenes, checks the subject's report and compares every test ray.
    fn commit_and_compare(&mut self, split: bool) -> Result<(), String> {
        self.reference.commit().unwrap();
        let early = if split { self.subject.commit_static().unwrap() } else { CommitReport::default() };
        if split && early.resting_rebuilt && self.subject.query().is_ok() {
            return Err("the static build published a rebuilt resting level before commit".into());
        }
        let report = self.subject.commit().unwrap();
        let resting = self.resting_count();
        // Resting instances are in the level or wait in the top level for its next rebuild.
        if report.resting_instances + report.resting_waiting != resting
            || report.instances != self.live.len() - report.resting_instances
        {
            return Err(format!("{report:?} for {resting} resting of {} instances", self.live.len()));
        }
        if split && early.resting_rebuilt && !report.resting_rebuilt {
            return Err(format!("static build {early:?} and commit {report:?} disagree on the rebuild"));
        }
        let q = self.subject.query().unwrap();
        let resting: Vec<HitObject> =
            self.live.iter().filter(|(_, r)| *r).map(|(id, _)| HitObject::Instance(*id)).collect();
        self.resting_hits +=
            self.rays.iter().filter_map(|r| q.intersect(r)).filter(|h| resting.contains(&h.object)).count();
        compare(self.reference.query().unwrap(), self.subject.query().unwrap(), &self.rays)
            .and_then(|()| check_occluders(self.reference.query().unwrap(), &self.rays, &self.live))
            .and_then(|()| check_occluders(q, &self.rays, &self.live))
            .map_err(|e| format!("{}: {e}", self.backend))
    }
}

fn pose(i: usize) -> Pose {
    let f = i as f32;
    Pose {
        at: Vec3::new((f * 2.3) % 18.0 - 9.0, 0.4 + (f * 0.7) % 2.0, (f * 3.1) % 18.0 - 9.0),
        axis: Vec3::new(f.sin(), 1.0, f.cos()),
        angle: f * 0.9,
        scale: 0.6 + (f * 0.37) % 1.0,
    }
}

/// Applies `ops` to a new pair; returns the closest hits on resting instances it compared.
fn run(backend: Backend, ops: impl IntoIterator<Item = Op>) -> usize {
    let mut pair = Pair::new(backend);
    for (step, op) in ops.into_iter().enumerate() {
        if let Err(e) = pair.apply(op) {
            panic!("step {step} ({op:?}): {e}");
        }
    }
    pair.resting_hits
}

#[test]
fn resting_instances_hit_like_awake_ones() {
    let commit = Op::Commit { split: false };
    let split = Op::Commit { split: true };
    for backend in Backend::compiled() {
        let mut ops: Vec<Op> = (0..60).map(|i| Op::Add { proto: i, pose: pose(i) }).collect();
        ops.push(commit);
        // Half of them rest.
        ops.extend((0..60).step_by(2).map(Op::Rest));
        ops.push(split);
        // A resting instance moves, another is removed, an awake one moves.
        ops.extend([Op::Move { k: 4, pose: pose(100) }, commit, Op::Remove(6), split]);
        ops.extend([Op::Move { k: 5, pose: pose(101) }, commit]);
        // Static meshes come and go while instances rest.
        ops.extend([Op::AddStatic(3), commit, Op::RemoveStatic(0), split]);
        // Every instance rests (an empty top level), then every one wakes (an empty resting
        // scene again), then some rest once more.
        ops.extend((0..59).map(Op::Rest));
        ops.push(commit);
        ops.extend((0..59).map(Op::Wake));
        ops.push(split);
        ops.extend((0..59).step_by(3).map(Op::Rest));
        ops.extend([commit, Op::Add { proto: 1, pose: pose(7) }, Op::Rest(59), commit]);
        // Into the resting level, then woken, moved and removed members leave ghosts there;
        // some rest again (waiting) before the next rebuild drops the ghosts.
        ops.extend((0..60).map(Op::Rest));
        ops.push(Op::Compact);
        ops.extend((0..30).step_by(2).map(Op::Wake));
        ops.extend([
            Op::Move { k: 1, pose: pose(102) },
            Op::Move { k: 2, pose: pose(103) },
            Op::Remove(5),
            split,
        ]);
        ops.extend((0..10).step_by(2).map(Op::Rest));
        ops.extend([commit, Op::Compact]);
        let resting_hits = run(backend, ops);
        assert!(resting_hits > 1000, "{backend}: only {resting_hits} hits on resting instances");
    }
}

#[test]
fn removing_every_resting_instance_empties_the_resting_scene() {
    for backend in Backend::compiled() {
        let mut ops: Vec<Op> = (0..10).map(|i| Op::Add { proto: i, pose: pose(i) }).collect();
        ops.extend((0..10).map(Op::Rest));
        ops.push(Op::Commit { split: false });
        ops.extend((0..10).map(|_| Op::Remove(0)));
        ops.push(Op::Commit { split: true });
        ops.extend([Op::Add { proto: 2, pose: pose(3) }, Op::Commit { split: false }]);
        run(backend, ops);
    }
}

#[test]
fn unknown_instances_cannot_rest() {
    for backend in Backend::compiled() {
        let mut a = accel::create(backend, Some(1)).unwrap();
        assert!(a.set_instance_resting(InstanceId(3), true).is_err(), "{backend}");
        let p = a.add_prototype(&primitives::cuboid(Vec3::ONE)).unwrap();
        let i = a.add_instance(p, Affine3A::IDENTITY).unwrap();
        a.remove_instance(i).unwrap();
        assert!(a.set_instance_resting(i, true).is_err(), "{backend}");
    }
}

fn arb_pose() -> impl Strategy<Value = Pose> {
    let v = |s: f32| (-s..s, -s..s, -s..s).prop_map(|(x, y, z)| Vec3::new(x, y, z));
    (v(9.0), v(1.0), -3.0f32..3.0, 0.4f32..1.6).prop_map(|(at, axis, angle, scale)| Pose {
        at: Vec3::new(at.x, at.y.abs() * 0.3, at.z),
        axis,
        angle,
        scale,
    })
}

fn arb_op() -> impl Strategy<Value = Op> {
    prop_oneof![
        4 => (0usize..3, arb_pose()).prop_map(|(proto, pose)| Op::Add { proto, pose }),
        2 => (any::<usize>(), arb_pose()).prop_map(|(k, pose)| Op::Move { k, pose }),
        4 => any::<usize>().prop_map(Op::Rest),
        2 => any::<usize>().prop_map(Op::Wake),
        2 => any::<usize>().prop_map(Op::Remove),
        1 => any::<u64>().prop_map(Op::AddStatic),
        1 => any::<usize>().prop_map(Op::RemoveStatic),
        2 => any::<bool>().prop_map(|split| Op::Commit { split }),
        1 => Just(Op::Compact),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    #[test]
    fn random_add_move_rest_wake_remove_sequences_hit_like_all_awake(
        ops in prop::collection::vec(arb_op(), 1..80),
    ) {
        for backend in Backend::compiled() {
            let mut pair = Pair::new(backend);
            for (step, op) in ops.iter().chain([&Op::Commit { split: false }]).enumerate() {
                if let Err(e) = pair.apply(*op) {
                    return Err(TestCaseError::fail(format!("{backend}, step {step} ({op:?}): {e}")));
                }
            }
        }
    }
}
