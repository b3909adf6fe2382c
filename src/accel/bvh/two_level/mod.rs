//! The two-level scene and [`BvhAccel`], the pure-Rust [`Accelerator`]: one shared bottom-level
//! BVH per prototype, a top-level BVH over instances (rebuilt at commit when instances changed,
//! it is small), and the persistent static BVH beside it. Changes are staged and published at
//! commit as a new [`BvhScene`], which owns everything rays need (Arcs and a snapshot).

mod query;

pub(crate) use query::BvhScene;

use std::sync::Arc;

use glam::Affine3A;

use super::flat::MeshBvh;
use super::persistent::{StaticBvh, StaticSnapshot};
use super::triangle::{extract, Tri};
use super::BuildParams;
use crate::accel::snapshot::SnapshotPayload;
use crate::accel::{
    AccelError, Accelerator, Backend, CommitReport, InstanceId, PrototypeId, SceneQuery, StaticId,
    StaticSceneSnapshot,
};
use crate::geometry::TriangleMesh;

#[derive(Clone, Copy, Debug)]
struct Instance {
    proto: u32,
    xf: Affine3A,
    inv: Affine3A,
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
    statics: StaticBvh,
    next_static: u32,
    staged_adds: Vec<(StaticId, Vec<Tri>)>,
    staged_removes: Vec<StaticId>,
    instances_changed: bool,
    dirty: bool,
    pending_built: usize,
    pending_skipped: usize,
    scene: BvhScene,
}

impl BvhAccel {
    /// An empty scene; `threads` bounds the rayon pool used for builds (`None`: the global pool).
    pub fn new(threads: Option<usize>) -> Self {
        Self::with_params(BuildParams::QUALITY, BuildParams::TOP_LEVEL, threads)
    }

    /// Like [`Self::new`] with explicit parameters for meshes (prototypes and static blocks)
    /// and for the top level.
    pub fn with_params(mesh: BuildParams, top: BuildParams, threads: Option<usize>) -> Self {
        let pool = threads.and_then(|n| rayon::ThreadPoolBuilder::new().num_threads(n).build().ok());
        Self {
            mesh_params: mesh,
            top_params: top,
            pool,
            prototypes: Vec::new(),
            instances: Vec::new(),
            statics: StaticBvh::new(mesh),
            next_static: 0,
            staged_adds: Vec::new(),
            staged_removes: Vec::new(),
            instances_changed: false,
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

    /// The committed static tree, for the invariant check of [`crate::accel::bvh::testing`].
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

    fn build_top(&mut self) {
        let instances: Vec<(u32, Instance)> = self
            .instances
            .iter()
            .enumerate()
            .filter_map(|(i, x)| x.map(|x| (i as u32, x)))
            .filter(|(_, x)| !self.prototypes[x.proto as usize].bvh.is_empty())
            .collect();
        let (protos, params) = (&self.prototypes, self.top_params);
        let top = self.run(|| {
            query::build_top(
                &instances
                    .iter()
                    .map(|(id, x)| (*id, protos[x.proto as usize].clone(), x.xf, x.inv))
                    .collect::<Vec<_>>(),
                params,
            )
        });
        self.scene.top = top;
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
        let id = self.instances.len() as u32;
        let proto = &self.prototypes[prototype.0 as usize];
        let inv = checked_inverse(&transform, proto).ok_or(AccelError::InvalidTransform { instance: id })?;
        self.instances.push(Some(Instance { proto: prototype.0, xf: transform, inv }));
        self.instances_changed = true;
        self.dirty = true;
        Ok(InstanceId(id))
    }

    fn set_instance_transform(&mut self, id: InstanceId, transform: Affine3A) -> Result<(), AccelError> {
        let proto = self.instance_mut(id)?.proto;
        let inv = checked_inverse(&transform, &self.prototypes[proto as usize])
            .ok_or(AccelError::InvalidTransform { instance: id.0 })?;
        let inst = self.instance_mut(id)?;
        inst.xf = transform;
        inst.inv = inv;
        self.instances_changed = true;
        self.dirty = true;
        Ok(())
    }

    fn remove_instance(&mut self, id: InstanceId) -> Result<(), AccelError> {
        self.instance_mut(id)?;
        self.instances[id.0 as usize] = None;
        self.instances_changed = true;
        self.dirty = true;
        Ok(())
    }

    fn commit(&mut self) -> Result<CommitReport, AccelError> {
        let mut report = self.commit_static()?;
        report.built_triangles += std::mem::take(&mut self.pending_built);
        report.skipped_triangles += std::mem::take(&mut self.pending_skipped);
        if self.instances_changed {
            self.build_top();
            self.instances_changed = false;
        }
        self.scene.statics = self.statics.snapshot();
        report.instances = self.instances.iter().flatten().count();
        self.dirty = false;
        Ok(report)
    }

    fn commit_static(&mut self) -> Result<CommitReport, AccelError> {
        let mut report = CommitReport::default();
        if !self.staged_adds.is_empty() || !self.staged_removes.is_empty() {
            let adds = std::mem::take(&mut self.staged_adds);
            let removes = std::mem::take(&mut self.staged_removes);
            let statics = &mut self.statics;
            let update = match &self.pool {
                Some(p) => p.install(|| statics.apply_extracted(&removes, adds)),
                None => statics.apply_extracted(&removes, adds),
            };
            report.built_triangles = update.built_triangles;
        }
        Ok(report)
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
