//! The two-level scene and [`BvhAccel`], the pure-Rust [`Accelerator`]: one shared bottom-level
//! BVH per prototype, a top-level BVH over awake instances (rebuilt at commit when one changed,
//! it is small), a resting level over instances at rest (rebuilt on the [`RestingSchedule`];
//! between rebuilds new resting instances wait in the top level and members that wake or move
//! leave ghosts that rays skip), and the persistent static BVH beside them. Changes are staged and
//! published at commit as a new [`BvhScene`], which owns everything rays need (Arcs and a
//! snapshot).

mod query;

pub(crate) use query::{BvhScene, Top, TopInstance};

use std::sync::Arc;
use std::time::Instant;

use glam::Affine3A;

use super::flat::MeshBvh;
use super::persistent::{StaticBvh, StaticSnapshot, StaticUpdate};
use super::triangle::{extract, Tri};
use super::BuildParams;
use crate::accel::snapshot::SnapshotPayload;
use crate::accel::{
    AccelError, Accelerator, Backend, CommitReport, InstanceId, PrototypeId, RestingCounts, RestingSchedule,
    SceneQuery, StaticId, StaticSceneSnapshot,
};
use crate::geometry::{InstanceMotion, TriangleMesh};

#[derive(Clone, Copy, Debug)]
struct Instance {
    proto: u32,
    xf: Affine3A,
    inv: Affine3A,
    /// Declared at rest ([`Accelerator::set_instance_resting`]).
    resting: bool,
    /// In the resting level (live, not a ghost) rather than the top level.
    in_level: bool,
    /// Motion over the shutter ([`Accelerator::set_instance_motion`]); never while resting.
    motion: Option<InstanceMotion>,
}

/// The inverse of `xf` when `xf` and its inverse are finite, it is invertible, and it keeps
/// the prototype's bounds finite.
fn checked_inverse(xf: &Affine3A, proto: &MeshBvh) -> Option<Affine3A> {
    let det = xf.matrix3.determinant();
    if !xf.is_finite() || det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = xf.inverse();
    let world = proto.bounds().transformed(xf);
    (inv.is_finite() && (world.is_empty() || (world.min.is_finite() && world.max.is_finite()))).then_some(inv)
}

/// The pure-Rust BVH backend.
pub struct BvhAccel {
    mesh_params: BuildParams,
    top_params: BuildParams,
    pool: Option<rayon::ThreadPool>,
    prototypes: Vec<Arc<MeshBvh>>,
    instances: Vec<Option<Instance>>,
    /// Ids of removed instances, given out again: a long run adds and removes instances
    /// without end, and the slots (and every scan over them) must not grow with it.
    free_instances: Vec<u32>,
    statics: StaticBvh,
    next_static: u32,
    staged_adds: Vec<(StaticId, Vec<Tri>)>,
    staged_removes: Vec<StaticId>,
    /// The top level (awake instances) must be rebuilt at the next commit.
    awake_changed: bool,
    /// Instances present (the top level holds those not live in the resting level).
    present: usize,
    /// Live, ghost and waiting resting instances.
    level: RestingCounts,
    schedule: RestingSchedule,
    /// A resting rebuild by `commit_static` that the next `commit` reports.
    resting_rebuilt: bool,
    dirty: bool,
    pending_built: usize,
    pending_skipped: usize,
    scene: BvhScene,
}

impl BvhAccel {
    /// [`Self::new`]'s parameters for meshes: prototypes and static blocks.
    pub(crate) const MESH_PARAMS: BuildParams = BuildParams::QUALITY;

    /// An empty scene; `threads` bounds the rayon pool used for builds (`None`: the global pool).
    pub fn new(threads: Option<usize>) -> Self {
        Self::with_params(Self::MESH_PARAMS, BuildParams::TOP_LEVEL, threads)
    }

    /// Like [`Self::new`] with explicit parameters for meshes (prototypes and static blocks)
    /// and for the top level.
    pub(crate) fn with_params(mesh: BuildParams, top: BuildParams, threads: Option<usize>) -> Self {
        let pool = threads.and_then(|n| rayon::ThreadPoolBuilder::new().num_threads(n).build().ok());
        Self {
            mesh_params: mesh,
            top_params: top,
            pool,
            prototypes: Vec::new(),
            instances: Vec::new(),
            free_instances: Vec::new(),
            statics: StaticBvh::new(mesh),
            next_static: 0,
            staged_adds: Vec::new(),
            staged_removes: Vec::new(),
            awake_changed: false,
            present: 0,
            level: RestingCounts::default(),
            schedule: RestingSchedule::default(),
            resting_rebuilt: false,
            dirty: false,
            pending_built: 0,
            pending_skipped: 0,
            scene: BvhScene::default(),
        }
    }

    fn run<R: Send>(&self, f: impl FnOnce() -> R + Send) -> R {
        match &self.pool {
            Some(p) => p.install(f),
            None => f(),
        }
    }

    /// The committed static tree, for the property tests' invariant check.
    #[cfg(test)]
    pub(crate) fn static_tree(&self) -> &StaticBvh {
        &self.statics
    }

    /// The committed scene as a concrete type (the same object [`Accelerator::query`] returns).
    fn scene(&self) -> Result<&BvhScene, AccelError> {
        if self.dirty {
            Err(AccelError::NotCommitted)
        } else {
            Ok(&self.scene)
        }
    }

    fn instance_mut(&mut self, id: InstanceId) -> Result<&mut Instance, AccelError> {
        self.instances
            .get_mut(id.0 as usize)
            .and_then(Option::as_mut)
            .ok_or(AccelError::UnknownId { kind: "instance", id: id.0 })
    }

    /// Instances in the top level: awake ones and resting ones waiting for the resting level.
    fn top_instances(&self) -> usize {
        self.present - self.level.live
    }

    /// Marks the top level for a rebuild.
    fn awake_changed(&mut self) {
        self.awake_changed = true;
        self.dirty = true;
    }

    /// Member `id` of the resting level becomes a ghost there (rays skip it at once, so the
    /// scene counts as changed) and joins the top level.
    fn ghost(&mut self, id: InstanceId) {
        let found = self.scene.resting.ghost(id.0);
        debug_assert!(found, "instance {} is in the resting level", id.0);
        self.level.live -= 1;
        self.level.ghosts += 1;
        if let Some(inst) = self.instances[id.0 as usize].as_mut() {
            inst.in_level = false;
        }
        self.awake_changed();
    }

    /// Rebuilds the resting level over every resting instance (the waiting join, the ghosts
    /// go) when the schedule (or `force`) says so; visible at the next `commit`.
    fn rebuild_resting(&mut self, force: bool) {
        let awake = self.top_instances() - self.level.waiting;
        if !force && !self.schedule.rebuild_due(self.level, awake) {
            return;
        }
        let t = Instant::now();
        self.scene.resting = self.build_level(true);
        for inst in self.instances.iter_mut().flatten() {
            inst.in_level = inst.resting;
        }
        self.level = RestingCounts { live: self.level.live + self.level.waiting, ghosts: 0, waiting: 0 };
        self.schedule.record_rebuild(self.level.live, t.elapsed().as_secs_f64() * 1e3);
        self.resting_rebuilt = true;
        self.awake_changed();
    }

    /// Builds the BVH over the resting (`true`: every resting instance) or the top level's
    /// instances (those not in the resting level).
    fn build_level(&self, resting: bool) -> Top {
        let instances = self.level_instances(resting);
        let params = self.top_params;
        self.run(|| query::build_top(&instances, params))
    }

    /// The instances [`Self::build_level`] builds over.
    fn level_instances(&self, resting: bool) -> Vec<TopInstance> {
        self.instances
            .iter()
            .enumerate()
            .filter_map(|(i, x)| {
                x.filter(|x| if resting { x.resting } else { !x.in_level }).map(|x| (i as u32, x))
            })
            .filter(|(_, x)| !self.prototypes[x.proto as usize].bvh.is_empty())
            .map(|(id, x)| (id, self.prototypes[x.proto as usize].clone(), x.xf, x.inv, x.motion))
            .collect()
    }

    /// Applies the staged static changes (`None`: nothing was staged) while `beside` runs on
    /// the other side of a `rayon::join`, in the builds' pool.
    fn apply_statics_with<R: Send>(
        &mut self,
        beside: impl FnOnce() -> R + Send,
    ) -> (Option<StaticUpdate>, R) {
        let staged = !self.staged_adds.is_empty() || !self.staged_removes.is_empty();
        let adds = std::mem::take(&mut self.staged_adds);
        let removes = std::mem::take(&mut self.staged_removes);
        let statics = &mut self.statics;
        let job = || rayon::join(|| staged.then(|| statics.apply_extracted(&removes, adds)), beside);
        match &self.pool {
            Some(p) => p.install(job),
            None => job(),
        }
    }
}

impl SnapshotPayload for StaticSnapshot {
    fn unique_bytes(&self) -> usize {
        self.memory().unique_bytes
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
}

impl Default for BvhAccel {
    fn default() -> Self {
        Self::new(None)
    }
}

impl Accelerator for BvhAccel {
    fn backend(&self) -> Backend {
        Backend::Bvh
    }

    fn add_prototype(&mut self, mesh: &TriangleMesh) -> Result<PrototypeId, AccelError> {
        mesh.validate()?;
        let (tris, skipped) = extract(mesh, 0);
        let n = tris.len();
        let params = self.mesh_params;
        let bvh = self.run(|| MeshBvh::build(tris, params));
        self.prototypes.push(Arc::new(bvh));
        self.pending_built += n;
        self.pending_skipped += skipped;
        self.dirty = true;
        Ok(PrototypeId(self.prototypes.len() as u32 - 1))
    }

    fn add_static(&mut self, mesh: &TriangleMesh) -> Result<StaticId, AccelError> {
        mesh.validate()?;
        let id = StaticId(self.next_static);
        self.next_static += 1;
        let (tris, skipped) = extract(mesh, id.0);
        self.pending_skipped += skipped;
        self.staged_adds.push((id, tris));
        self.dirty = true;
        Ok(id)
    }

    fn set_static_permanent(&mut self, id: StaticId) {
        self.statics.set_permanent(id);
    }

    fn remove_static(&mut self, id: StaticId) -> Result<(), AccelError> {
        if let Some(i) = self.staged_adds.iter().position(|(s, _)| *s == id) {
            self.staged_adds.swap_remove(i);
        } else if self.statics.contains(id) && !self.staged_removes.contains(&id) {
            self.staged_removes.push(id);
        } else {
            return Err(AccelError::UnknownId { kind: "static", id: id.0 });
        }
        self.dirty = true;
        Ok(())
    }

    fn add_instance(
        &mut self,
        prototype: PrototypeId,
        transform: Affine3A,
    ) -> Result<InstanceId, AccelError> {
        if prototype.0 as usize >= self.prototypes.len() {
            return Err(AccelError::UnknownId { kind: "prototype", id: prototype.0 });
        }
        // The id is taken only once the transform is accepted: a bad one must not lose a free id.
        let id = self.free_instances.last().copied().unwrap_or(self.instances.len() as u32);
        let proto = &self.prototypes[prototype.0 as usize];
        let inv = checked_inverse(&transform, proto).ok_or(AccelError::InvalidTransform { instance: id })?;
        let instance = Instance {
            proto: prototype.0,
            xf: transform,
            inv,
            resting: false,
            in_level: false,
            motion: None,
        };
        if id as usize == self.instances.len() {
            self.instances.push(Some(instance));
        } else {
            self.free_instances.pop();
            self.instances[id as usize] = Some(instance);
        }
        self.present += 1;
        self.awake_changed();
        Ok(InstanceId(id))
    }

    fn set_instance_transform(&mut self, id: InstanceId, transform: Affine3A) -> Result<(), AccelError> {
        let proto = self.instance_mut(id)?.proto;
        let inv = checked_inverse(&transform, &self.prototypes[proto as usize])
            .ok_or(AccelError::InvalidTransform { instance: id.0 })?;
        if self.instance_mut(id)?.in_level {
            // Still declared resting: it waits in the top level for the next rebuild.
            self.ghost(id);
            self.level.waiting += 1;
        }
        let inst = self.instance_mut(id)?;
        inst.xf = transform;
        inst.inv = inv;
        self.awake_changed();
        Ok(())
    }

    fn remove_instance(&mut self, id: InstanceId) -> Result<(), AccelError> {
        let inst = *self.instance_mut(id)?;
        if inst.in_level {
            self.ghost(id);
        } else if inst.resting {
            self.level.waiting -= 1;
        }
        self.instances[id.0 as usize] = None;
        self.free_instances.push(id.0);
        self.present -= 1;
        self.awake_changed();
        Ok(())
    }

    fn set_instance_motion(
        &mut self,
        id: InstanceId,
        motion: Option<InstanceMotion>,
    ) -> Result<(), AccelError> {
        let inst = self.instance_mut(id)?;
        if inst.motion == motion {
            return Ok(());
        }
        crate::accel::check_motion(id, inst.resting, motion.as_ref())?;
        inst.motion = motion;
        self.awake_changed();
        Ok(())
    }

    fn set_instance_resting(&mut self, id: InstanceId, resting: bool) -> Result<(), AccelError> {
        let inst = *self.instance_mut(id)?;
        if inst.resting == resting {
            return Ok(());
        }
        if resting && inst.motion.is_some() {
            // Only the top level blurs: a resting instance is still, at its transform.
            self.instance_mut(id)?.motion = None;
            self.awake_changed();
        }
        if resting {
            self.level.waiting += 1;
        } else if inst.in_level {
            self.ghost(id);
        } else {
            self.level.waiting -= 1;
        }
        self.instance_mut(id)?.resting = resting;
        Ok(())
    }

    fn commit(&mut self) -> Result<CommitReport, AccelError> {
        // The resting level first (it decides which instances the top level holds), then the
        // static changes and the top level at once: they share nothing, and each fills the
        // other's serial stretches. (The top level's time, which the resting schedule weighs,
        // then includes sharing the cores with a static build at the commits that have one.)
        self.rebuild_resting(false);
        let instances = self.top_instances();
        let top = self.awake_changed.then(|| self.level_instances(false));
        let params = self.top_params;
        let (update, top) = self.apply_statics_with(|| {
            top.map(|list| {
                let t = Instant::now();
                (query::build_top(&list, params), t.elapsed().as_secs_f64() * 1e3)
            })
        });
        let mut report = CommitReport {
            built_triangles: update.map_or(0, |u| u.built_triangles)
                + std::mem::take(&mut self.pending_built),
            skipped_triangles: std::mem::take(&mut self.pending_skipped),
            ..CommitReport::default()
        };
        if let Some((top, ms)) = top {
            self.scene.top = top;
            self.awake_changed = false;
            self.schedule.record_top_build(instances, self.level.waiting, ms);
        }
        self.scene.statics = self.statics.snapshot();
        report.instances = instances;
        report.resting_rebuilt = std::mem::take(&mut self.resting_rebuilt);
        report.resting_instances = self.level.live;
        report.resting_waiting = self.level.waiting;
        self.dirty = false;
        Ok(report)
    }

    fn commit_static(&mut self) -> Result<CommitReport, AccelError> {
        let (update, ()) = self.apply_statics_with(|| ());
        let mut report = CommitReport {
            built_triangles: update.map_or(0, |u| u.built_triangles),
            ..CommitReport::default()
        };
        // Not visible before `commit`: queries fail while the scene is dirty, which a
        // rebuild makes it.
        self.rebuild_resting(false);
        report.resting_rebuilt = self.resting_rebuilt;
        report.resting_instances = self.level.live;
        report.resting_waiting = self.level.waiting;
        Ok(report)
    }

    fn compact_resting(&mut self) -> Result<CommitReport, AccelError> {
        self.rebuild_resting(true);
        Ok(CommitReport {
            resting_rebuilt: true,
            resting_instances: self.level.live,
            resting_waiting: self.level.waiting,
            ..CommitReport::default()
        })
    }

    fn snapshot_static_scene(&self) -> Option<StaticSceneSnapshot> {
        Some(StaticSceneSnapshot::new(Backend::Bvh, self.statics.snapshot()))
    }

    fn restore_static_scene(&mut self, snapshot: &StaticSceneSnapshot) -> Result<(), AccelError> {
        let saved = snapshot
            .payload::<StaticSnapshot>()
            .ok_or(AccelError::ForeignSnapshot { backend: Backend::Bvh, from: snapshot.backend() })?;
        // Staged static changes stay staged (they apply on top at the next commit); the scene
        // counts as changed until then.
        self.statics.restore(saved.clone());
        self.dirty = true;
        Ok(())
    }

    fn static_removal_cost(&self, id: StaticId) -> usize {
        if self.statics.removal_rebuilds(id) {
            self.statics.triangles()
        } else {
            0
        }
    }

    fn query(&self) -> Result<&dyn SceneQuery, AccelError> {
        Ok(self.scene()? as &dyn SceneQuery)
    }

    fn static_sah_cost(&self) -> Option<f32> {
        Some(self.statics.sah_cost())
    }
}

/// The BVH's view into the snapshots it takes.
impl StaticSceneSnapshot {
    /// The BVH backend's persistent static tree this snapshot holds (`None` for another
    /// backend's): its shape, for measurements of how it fragments.
    pub fn bvh_tree(&self) -> Option<&StaticSnapshot> {
        self.payload()
    }

    /// The BVH tree's live triangles rebuilt into one block, as a fresh build of the same
    /// scene makes it (`None` for another backend's snapshot).
    pub fn bvh_rebuilt(&self) -> Option<StaticSceneSnapshot> {
        let tree = self.bvh_tree()?.rebuilt(BvhAccel::MESH_PARAMS);
        Some(Self::new(Backend::Bvh, tree))
    }
}
