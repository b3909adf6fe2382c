//! The Embree backend: [`EmbreeAccel`], the [`crate::accel::Accelerator`] over Intel Embree 4
//! through the safe wrapper `dormant_embree` (its scenes are described on the type), the build
//! quality of each kind of scene it makes ([`EmbreeBuildParams`]), and when a moving instance's
//! poses go to Embree as matrices (`shutter_poses.rs`).

mod awake_bounds;
mod query;
mod shutter_poses;

pub use shutter_poses::{lerps_as_matrices, shutter_poses};

use std::sync::Arc;
use std::time::Instant;

use glam::{Affine3A, Mat3};
use rayon::prelude::*;

use crate::accel::{
    AccelError, Accelerator, Backend, CommitReport, InstanceId, PrototypeId, RestingCounts, RestingSchedule,
    SceneQuery, StaticId,
};
use crate::geometry::{Aabb, InstanceMotion, TriangleMesh};
use dormant_embree::{
    BuildQuality, Device, FrozenScene, GeometrySet, InstanceGeometry, Scene, SceneFlags, TriangleGeometry,
};

use awake_bounds::AwakeBounds;

/// Geometry id of the static scene's instance (in the top level, or in the resting scene
/// while that holds instances); instance `i` is `i + 1` in whichever of the two holds it.
const STATIC_SLOT: u32 = 0;

struct InstanceSlot {
    prototype: u32,
    transform: Affine3A,
    /// Object-to-world normal transform: Embree reports instanced normals in object space.
    normal_matrix: Mat3,
    /// Declared at rest ([`Accelerator::set_instance_resting`]).
    resting: bool,
    /// In the resting scene (live, not a ghost) rather than the top level.
    in_level: bool,
    /// Motion over the shutter ([`Accelerator::set_instance_motion`]): the instance geometry
    /// has two time steps. Never while resting, so the resting scene keeps one time step.
    motion: Option<InstanceMotion>,
}

/// Elapsed milliseconds since `t`.
fn ms_since(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// Build qualities of the backend's three kinds of scene, with named presets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EmbreeBuildParams {
    /// Prototypes: built once, traced a lot.
    pub prototype: BuildQuality,
    /// The static scene's top structure over its meshes. LOW (with the scene's DYNAMIC flag)
    /// selects Embree's two-level builder, which keeps each mesh's BVH across commits: adding
    /// a baked island then costs a build of that island plus a small top rebuild. MEDIUM or
    /// HIGH build one flat BVH over all static triangles at every commit.
    pub static_scene: BuildQuality,
    /// Each static mesh's own BVH under the two-level builder.
    pub static_mesh: BuildQuality,
    /// The top level over instances: rebuilt at every commit where an instance changed. HIGH
    /// is both the fastest to build and to trace here (against LOW and MEDIUM, on the atrium's
    /// 8,000 instances): docs/lab/accelerators.md#2026-11-22-embrees-instance-top-level-built-at-high
    pub top_level: BuildQuality,
    /// Every scene with `RTC_SCENE_FLAG_ROBUST`: conservative box tests and a watertight
    /// triangle test, the guarantees the pure-Rust BVH always gives. Off by default, as in
    /// Embree; `bench accel` measures Embree both ways.
    pub robust: bool,
}

impl EmbreeBuildParams {
    /// What dormant renders with.
    pub const DEFAULT: EmbreeBuildParams = EmbreeBuildParams {
        prototype: BuildQuality::High,
        static_scene: BuildQuality::Low,
        static_mesh: BuildQuality::Medium,
        top_level: BuildQuality::High,
        robust: false,
    };

    /// Every scene at one quality (for comparing Embree's builders).
    pub const fn uniform(quality: BuildQuality) -> Self {
        Self {
            prototype: quality,
            static_scene: quality,
            static_mesh: quality,
            top_level: quality,
            robust: false,
        }
    }

    /// The scene flags for one of this backend's scenes.
    fn flags(&self, dynamic: bool) -> SceneFlags {
        SceneFlags { dynamic, robust: self.robust, ..SceneFlags::default() }
    }
}

impl Default for EmbreeBuildParams {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The Embree backend: a top-level scene of instances, one of which is the static scene, and
/// a resting scene of instances beside it.
///
/// - Prototypes are frozen one-mesh scenes shared by their instances.
/// - The static scene (environment plus baked islands) is a DYNAMIC scene owned by an identity
///   instance at id 0, so adding a baked mesh commits it incrementally and the per-frame
///   top-level rebuild never touches its triangles.
/// - The top level is rebuilt at HIGH quality at each commit that changed an instance; it
///   holds only instances.
/// - Resting instances (integrated islands kept as instances) live in a second instance
///   scene, rebuilt on the [`RestingSchedule`]: a new resting instance waits in the top level
///   until then, a woken one leaves a ghost there that rays skip (an argument filter reading
///   [`GeometrySet`]) and rejoins the top level as a new instance geometry. While the resting
///   scene holds any, the static scene's instance moves there too, so the top level keeps only
///   the awake (and waiting) bodies: a ray traces the resting scene (environment and resting
///   bodies, like one top level without the awake ones) and then the small top level up to the
///   first hit. With no resting instance every ray traces the top level alone, as before.
pub struct EmbreeAccel {
    device: Device,
    params: EmbreeBuildParams,
    prototypes: Vec<Arc<FrozenScene>>,
    /// Object-space bounds of each prototype.
    prototype_bounds: Vec<Aabb>,
    top: Scene,
    resting: Scene,
    /// Whether the static scene's instance is in the resting scene (it is from the rebuild
    /// that first puts instances there to the one that leaves none).
    static_in_resting: bool,
    /// Live, ghost and waiting resting instances.
    level: RestingCounts,
    /// Geometry ids (instance id + 1) of the ghosts in the resting scene.
    ghosts: GeometrySet,
    schedule: RestingSchedule,
    /// Bounds of the committed top level while the resting scene is in use: rays that miss
    /// them skip the top level.
    awake_bounds: AwakeBounds,
    instances: Vec<Option<InstanceSlot>>,
    free_instances: Vec<u32>,
    static_triangles: Vec<Option<usize>>,
    free_statics: Vec<u32>,
    pending: CommitReport,
    /// Ghosts left or dropped since the last commit: queries wait for it.
    ghosts_staged: bool,
}

impl EmbreeAccel {
    pub(crate) fn new(threads: Option<usize>) -> Result<Self, AccelError> {
        Self::with_device(Device::new(threads)?, EmbreeBuildParams::DEFAULT)
    }

    pub fn with_device(device: Device, params: EmbreeBuildParams) -> Result<Self, AccelError> {
        let static_scene = Scene::new(&device, params.flags(true), params.static_scene)?;
        let mut top = Scene::new(&device, params.flags(true), params.top_level)?;
        top.attach_by_id(InstanceGeometry::owning(&device, static_scene, &Affine3A::IDENTITY)?, STATIC_SLOT)?;
        let mut resting = Scene::new(&device, params.flags(false), params.top_level)?;
        resting.commit()?;
        Ok(Self {
            device,
            params,
            prototypes: Vec::new(),
            prototype_bounds: Vec::new(),
            top,
            resting,
            static_in_resting: false,
            level: RestingCounts::default(),
            ghosts: GeometrySet::default(),
            schedule: RestingSchedule::default(),
            awake_bounds: AwakeBounds::NONE,
            instances: Vec::new(),
            free_instances: Vec::new(),
            static_triangles: Vec::new(),
            free_statics: Vec::new(),
            pending: CommitReport::default(),
            ghosts_staged: false,
        })
    }

    pub fn device(&self) -> &Device {
        &self.device
    }

    /// The scene holding the static scene's instance: the resting scene while it holds
    /// instances, else the top level.
    fn static_holder(&mut self) -> &mut Scene {
        if self.static_in_resting {
            &mut self.resting
        } else {
            &mut self.top
        }
    }

    fn static_scene(&mut self) -> Result<&mut Scene, AccelError> {
        let inst = self.static_holder().instance_mut(STATIC_SLOT)?;
        Ok(inst.child_mut().expect("the static slot owns its scene"))
    }

    /// Moves the static scene's instance into the resting scene (`true`) or back to the top
    /// level.
    fn move_static(&mut self, to_resting: bool) -> Result<(), AccelError> {
        let (from, to) =
            if to_resting { (&mut self.top, &mut self.resting) } else { (&mut self.resting, &mut self.top) };
        let geometry = from.detach(STATIC_SLOT)?;
        to.attach_by_id(geometry, STATIC_SLOT)?;
        self.static_in_resting = to_resting;
        Ok(())
    }

    fn triangle_geometry(
        &self,
        mesh: &TriangleMesh,
        quality: BuildQuality,
    ) -> Result<(TriangleGeometry, usize), AccelError> {
        mesh.validate()?;
        // In parallel: on one thread this count was a share of a large island's insert:
        // docs/lab/accelerators.md#2026-12-01-embrees-static-insert-counts-skipped-triangles-in-parallel
        let skipped = (0..mesh.triangle_count())
            .into_par_iter()
            .with_min_len(1 << 14)
            .filter(|&i| !mesh.triangle_is_valid(i))
            .count();
        Ok((TriangleGeometry::with_quality(&self.device, &mesh.positions, &mesh.indices, quality)?, skipped))
    }

    fn slot(&self, id: InstanceId) -> Result<&InstanceSlot, AccelError> {
        self.instances
            .get(id.0 as usize)
            .and_then(Option::as_ref)
            .ok_or(AccelError::UnknownId { kind: "instance", id: id.0 })
    }
}

fn checked_transform(id: u32, transform: &Affine3A) -> Result<Mat3, AccelError> {
    let m = Mat3::from(transform.matrix3);
    let det = m.determinant();
    if !transform.is_finite() || !det.is_finite() || det == 0.0 {
        return Err(AccelError::InvalidTransform { instance: id });
    }
    Ok(m.inverse().transpose())
}

impl Accelerator for EmbreeAccel {
    fn backend(&self) -> Backend {
        Backend::Embree
    }

    fn add_prototype(&mut self, mesh: &TriangleMesh) -> Result<PrototypeId, AccelError> {
        let (geometry, skipped) = self.triangle_geometry(mesh, self.params.prototype)?;
        let mut scene = Scene::new(&self.device, self.params.flags(false), self.params.prototype)?;
        // Hits inside ghosts of the resting scene are rejected by an argument filter.
        scene.attach(geometry.with_argument_filter()?)?;
        let frozen = scene.freeze()?;
        let (min, max) = frozen.view().bounds();
        self.prototype_bounds.push(Aabb { min, max });
        self.prototypes.push(frozen);
        self.pending.built_triangles += mesh.triangle_count();
        self.pending.skipped_triangles += skipped;
        Ok(PrototypeId(self.prototypes.len() as u32 - 1))
    }

    fn add_static(&mut self, mesh: &TriangleMesh) -> Result<StaticId, AccelError> {
        let (geometry, skipped) = self.triangle_geometry(mesh, self.params.static_mesh)?;
        let id = self.free_statics.pop().unwrap_or(self.static_triangles.len() as u32);
        self.static_scene()?.attach_by_id(geometry, id)?;
        if id as usize == self.static_triangles.len() {
            self.static_triangles.push(None);
        }
        self.static_triangles[id as usize] = Some(mesh.triangle_count());
        self.pending.built_triangles += mesh.triangle_count();
        self.pending.skipped_triangles += skipped;
        Ok(StaticId(id))
    }

    fn remove_static(&mut self, id: StaticId) -> Result<(), AccelError> {
        let known = self.static_triangles.get(id.0 as usize).is_some_and(Option::is_some);
        if !known {
            return Err(AccelError::UnknownId { kind: "static", id: id.0 });
        }
        self.static_scene()?.detach(id.0)?;
        self.static_triangles[id.0 as usize] = None;
        self.free_statics.push(id.0);
        Ok(())
    }

    fn add_instance(
        &mut self,
        prototype: PrototypeId,
        transform: Affine3A,
    ) -> Result<InstanceId, AccelError> {
        // The id is taken only once the instance is attached: a bad transform must not lose
        // a free id.
        let id = self.free_instances.last().copied().unwrap_or(self.instances.len() as u32);
        let normal_matrix = checked_transform(id, &transform)?;
        let geometry = self.instance_geometry(prototype, &transform)?;
        self.top.attach_by_id(geometry, id + 1)?;
        if id as usize == self.instances.len() {
            self.instances.push(None);
        } else {
            self.free_instances.pop();
        }
        self.instances[id as usize] = Some(InstanceSlot {
            prototype: prototype.0,
            transform,
            normal_matrix,
            resting: false,
            in_level: false,
            motion: None,
        });
        Ok(InstanceId(id))
    }

    /// A member of the resting scene that moves leaves a ghost there and moves in the top level.
    fn set_instance_transform(&mut self, id: InstanceId, transform: Affine3A) -> Result<(), AccelError> {
        let normal_matrix = checked_transform(id.0, &transform)?;
        if self.slot(id)?.in_level {
            // Still declared resting: it waits in the top level for the next rebuild.
            self.leave_ghost(id)?;
            self.level.waiting += 1;
        }
        // A moving instance keeps its two time steps; the transform is what it stops at.
        if self.slot(id)?.motion.is_none() {
            self.top.instance_mut(id.0 + 1)?.set_transform(&transform)?;
        }
        if let Some(slot) = self.instances[id.0 as usize].as_mut() {
            slot.normal_matrix = normal_matrix;
            slot.transform = transform;
        }
        Ok(())
    }

    /// The instance geometry in the top level gets two time steps (or one again); the top
    /// level then builds a motion-blur BVH. Resting instances are never blurred, so the
    /// resting scene and the static scene keep one time step and are not rebuilt for it.
    fn set_instance_motion(
        &mut self,
        id: InstanceId,
        motion: Option<InstanceMotion>,
    ) -> Result<(), AccelError> {
        let slot = self.slot(id)?;
        if slot.motion == motion {
            return Ok(());
        }
        crate::accel::check_motion(id, slot.resting, motion.as_ref())?;
        let transform = slot.transform;
        let geometry = self.top.instance_mut(id.0 + 1)?;
        match &motion {
            Some(m) => {
                let poses = shutter_poses(m, geometry.child_radius());
                geometry.set_motion(&poses)?
            }
            None => geometry.set_transform(&transform)?,
        }
        if let Some(slot) = self.instances[id.0 as usize].as_mut() {
            slot.motion = motion;
        }
        Ok(())
    }

    fn remove_instance(&mut self, id: InstanceId) -> Result<(), AccelError> {
        let slot = self.slot(id)?;
        let (resting, in_level) = (slot.resting, slot.in_level);
        if in_level {
            self.ghost(id);
        } else {
            self.top.detach(id.0 + 1)?;
            if resting {
                self.level.waiting -= 1;
            }
        }
        self.instances[id.0 as usize] = None;
        self.free_instances.push(id.0);
        Ok(())
    }

    fn set_instance_resting(&mut self, id: InstanceId, resting: bool) -> Result<(), AccelError> {
        let slot = self.slot(id)?;
        let (was_resting, moving, in_level) = (slot.resting, slot.motion.is_some(), slot.in_level);
        if was_resting == resting {
            return Ok(());
        }
        if resting && moving {
            // Only the top level blurs: a resting instance is still, at its transform.
            self.set_instance_motion(id, None)?;
        }
        if resting {
            self.level.waiting += 1;
        } else if in_level {
            self.leave_ghost(id)?;
        } else {
            self.level.waiting -= 1;
        }
        if let Some(slot) = self.instances[id.0 as usize].as_mut() {
            slot.resting = resting;
        }
        Ok(())
    }

    fn commit(&mut self) -> Result<CommitReport, AccelError> {
        let resting = self.commit_resting(false)?;
        let top_changed = self.top.is_dirty();
        // With moving instances the top level is a motion-blur BVH. Most of its cost is Embree
        // bounding each quaternion (slerped) instance by a root search, so barely turning
        // instances get matrices instead (`InstanceGeometry::set_motion`). Building it at
        // MEDIUM or LOW, or as one instance array, did not make the blurred commit cheaper:
        // docs/lab/motion-blur.md#2026-12-02-where-the-blurred-commit-goes-barely-turning-instances-as-matrices
        let t = Instant::now();
        self.top.commit()?;
        let instances = self.top_instances();
        if top_changed {
            self.schedule.record_top_build(instances, self.level.waiting, ms_since(t));
        }
        self.awake_bounds = if self.static_in_resting && self.top.geometry_count() > 0 {
            let boxes: Vec<Aabb> = self
                .top
                .geometry_ids()
                .filter_map(|g| self.instances.get(g.checked_sub(1)? as usize)?.as_ref())
                .map(|s| {
                    let local = &self.prototype_bounds[s.prototype as usize];
                    s.motion.as_ref().map_or_else(|| local.transformed(&s.transform), |m| m.bounds(local))
                })
                .collect();
            AwakeBounds::around(&boxes)
        } else {
            AwakeBounds::NONE
        };
        let mut report = std::mem::take(&mut self.pending);
        report.instances = instances;
        report.resting_rebuilt |= resting.resting_rebuilt;
        report.resting_instances = self.level.live;
        report.resting_waiting = self.level.waiting;
        self.ghosts_staged = false;
        Ok(report)
    }

    fn commit_static(&mut self) -> Result<CommitReport, AccelError> {
        // Committing the owned child scene now leaves its holder dirty (the instance changed),
        // so nothing is visible before `commit`; the report waits for it too.
        self.commit_static_and_resting(false)
    }

    fn compact_resting(&mut self) -> Result<CommitReport, AccelError> {
        self.commit_static_and_resting(true)
    }

    /// Removal is a detach: the two-level builder keeps every other mesh's BVH and rebuilds
    /// only its small top over the meshes.
    fn static_removal_cost(&self, _id: StaticId) -> usize {
        0
    }

    fn query(&self) -> Result<&dyn SceneQuery, AccelError> {
        // A resting scene rebuilt by `commit_static` is committed in Embree's sense but not
        // published before `commit`; nor are ghosts left since.
        if self.top.is_dirty()
            || self.resting.is_dirty()
            || self.pending.resting_rebuilt
            || self.ghosts_staged
        {
            Err(AccelError::NotCommitted)
        } else {
            Ok(self)
        }
    }
}

impl EmbreeAccel {
    /// A new instance geometry of `prototype` at `transform`.
    fn instance_geometry(
        &self,
        prototype: PrototypeId,
        transform: &Affine3A,
    ) -> Result<InstanceGeometry, AccelError> {
        let proto = self
            .prototypes
            .get(prototype.0 as usize)
            .ok_or(AccelError::UnknownId { kind: "prototype", id: prototype.0 })?;
        Ok(InstanceGeometry::new(&self.device, proto, transform)?)
    }

    /// Instances in the top level: awake ones and resting ones waiting for the resting scene
    /// (the static scene's instance is not counted).
    fn top_instances(&self) -> usize {
        self.top.geometry_count() - usize::from(!self.static_in_resting)
    }

    /// Commits the static scene, then the resting scene (rebuilt when due, or when `force`);
    /// the next `commit` publishes both.
    fn commit_static_and_resting(&mut self, force: bool) -> Result<CommitReport, AccelError> {
        self.static_holder().commit_child_of(STATIC_SLOT)?;
        let report = self.commit_resting(force)?;
        self.pending.resting_rebuilt |= report.resting_rebuilt;
        Ok(report)
    }

    /// Member `id` of the resting scene becomes a ghost there.
    fn ghost(&mut self, id: InstanceId) {
        self.ghosts.insert(id.0 + 1);
        self.ghosts_staged = true;
        self.level.live -= 1;
        self.level.ghosts += 1;
        if let Some(slot) = self.instances[id.0 as usize].as_mut() {
            slot.in_level = false;
        }
    }

    /// Member `id` of the resting scene becomes a ghost there and joins the top level as a new
    /// instance geometry at its current transform.
    fn leave_ghost(&mut self, id: InstanceId) -> Result<(), AccelError> {
        let slot = self.slot(id)?;
        let geometry = self.instance_geometry(PrototypeId(slot.prototype), &slot.transform)?;
        self.ghost(id);
        self.top.attach_by_id(geometry, id.0 + 1)?;
        Ok(())
    }

    /// Rebuilds the resting scene when the schedule (or `force`) says so, or when it must be
    /// committed anyway (the static scene's instance in it changed).
    fn commit_resting(&mut self, force: bool) -> Result<CommitReport, AccelError> {
        let top_instances = self.top_instances();
        debug_assert!(top_instances >= self.level.waiting, "waiting instances are in the top level");
        let awake = top_instances.saturating_sub(self.level.waiting);
        let due = force || self.schedule.rebuild_due(self.level, awake);
        if due {
            self.regroup_resting()?;
        }
        let rebuilt = self.resting.is_dirty();
        if rebuilt {
            let t = Instant::now();
            self.resting.commit()?;
            if due {
                self.schedule.record_rebuild(self.level.live, ms_since(t));
            }
        }
        Ok(CommitReport {
            resting_rebuilt: rebuilt,
            resting_instances: self.level.live,
            resting_waiting: self.level.waiting,
            ..CommitReport::default()
        })
    }

    /// Drops the ghosts from the resting scene and moves every waiting instance into it (the
    /// static scene's instance follows: there while any instance is); the rebuild is the
    /// caller's commit.
    fn regroup_resting(&mut self) -> Result<(), AccelError> {
        for g in self.ghosts.iter() {
            self.resting.detach(g)?;
        }
        self.ghosts.clear();
        self.ghosts_staged = true;
        for (i, slot) in self.instances.iter_mut().enumerate() {
            let Some(slot) = slot.as_mut().filter(|s| s.resting && !s.in_level) else { continue };
            let geometry = self.top.detach(i as u32 + 1)?;
            self.resting.attach_by_id(geometry, i as u32 + 1)?;
            slot.in_level = true;
        }
        self.level = RestingCounts { live: self.level.live + self.level.waiting, ghosts: 0, waiting: 0 };
        if (self.level.live > 0) != self.static_in_resting {
            self.move_static(self.level.live > 0)?;
        }
        Ok(())
    }
}
