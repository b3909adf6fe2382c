//! [`EmbreeAccel`], the Embree [`crate::accel::Accelerator`] (its scenes are described on the
//! type), and the build quality of each kind of scene it makes ([`EmbreeBuildParams`]).

mod awake_bounds;
mod query;

use std::sync::Arc;

use glam::{Affine3A, Mat3};
use rayon::prelude::*;

use super::{BuildQuality, Device, FrozenScene, InstanceGeometry, Scene, SceneFlags, TriangleGeometry};
use crate::accel::{
    AccelError, Accelerator, Backend, CommitReport, InstanceId, PrototypeId, SceneQuery, StaticId,
};
use crate::geometry::TriangleMesh;

use awake_bounds::AwakeBounds;

/// Geometry id of the static scene's instance (in the top level, or in the resting scene
/// while that holds instances); instance `i` is `i + 1` in whichever of the two holds it.
const STATIC_SLOT: u32 = 0;

struct InstanceSlot {
    /// Object-to-world normal transform: Embree reports instanced normals in object space.
    normal_matrix: Mat3,
    /// In the resting scene rather than the top level.
    resting: bool,
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
    /// is both the fastest to build and to trace here: on the atrium's 8,000 instances LOW,
    /// MEDIUM and HIGH measured 13.6, 10.8 and 7.9 ms per commit and 40.1, 36.1 and 31.5 ms
    /// for 640x360 primary rays (Embree 4.4, 2 threads).
    pub top_level: BuildQuality,
}

impl EmbreeBuildParams {
    /// What dormant renders with.
    pub const DEFAULT: EmbreeBuildParams = EmbreeBuildParams {
        prototype: BuildQuality::High,
        static_scene: BuildQuality::Low,
        static_mesh: BuildQuality::Medium,
        top_level: BuildQuality::High,
    };

    /// Every scene at one quality (for comparing Embree's builders).
    pub const fn uniform(quality: BuildQuality) -> Self {
        Self { prototype: quality, static_scene: quality, static_mesh: quality, top_level: quality }
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
///   scene, rebuilt only when its set changes. While it holds any, the static scene's
///   instance moves there too, so the top level keeps only the awake bodies: a ray traces the
///   resting scene (environment and resting bodies, like one top level without the awake
///   ones) and then the small top level up to the first hit. With no resting instance every
///   ray traces the top level alone, as before.
pub struct EmbreeAccel {
    device: Device,
    params: EmbreeBuildParams,
    prototypes: Vec<Arc<FrozenScene>>,
    top: Scene,
    resting: Scene,
    resting_count: usize,
    /// Bounds of the committed top level while the resting scene is in use: rays that miss
    /// them skip the top level.
    awake_bounds: AwakeBounds,
    instances: Vec<Option<InstanceSlot>>,
    free_instances: Vec<u32>,
    static_triangles: Vec<Option<usize>>,
    free_statics: Vec<u32>,
    pending: CommitReport,
}

impl EmbreeAccel {
    pub fn new(threads: Option<usize>) -> Result<Self, AccelError> {
        Self::with_device(Device::new(threads)?, EmbreeBuildParams::DEFAULT)
    }

    pub fn with_device(device: Device, params: EmbreeBuildParams) -> Result<Self, AccelError> {
        let static_scene =
            Scene::new(&device, SceneFlags { dynamic: true, ..SceneFlags::default() }, params.static_scene)?;
        let mut top =
            Scene::new(&device, SceneFlags { dynamic: true, ..SceneFlags::default() }, params.top_level)?;
        top.attach_by_id(InstanceGeometry::owning(&device, static_scene, &Affine3A::IDENTITY)?, STATIC_SLOT)?;
        let mut resting = Scene::new(&device, SceneFlags::default(), params.top_level)?;
        resting.commit()?;
        Ok(Self {
            device,
            params,
            prototypes: Vec::new(),
            top,
            resting,
            resting_count: 0,
            awake_bounds: AwakeBounds::NONE,
            instances: Vec::new(),
            free_instances: Vec::new(),
            static_triangles: Vec::new(),
            free_statics: Vec::new(),
            pending: CommitReport::default(),
        })
    }

    pub fn device(&self) -> &Device {
        &self.device
    }

    /// The scene holding the static scene's instance: the resting scene while it holds
    /// instances, else the top level.
    fn static_holder(&mut self) -> &mut Scene {
        if self.resting_count > 0 {
            &mut self.resting
        } else {
            &mut self.top
        }
    }

    fn static_scene(&mut self) -> Result<&mut Scene, AccelError> {
        let inst = self.static_holder().instance_mut(STATIC_SLOT)?;
        Ok(inst.child_mut().expect("the static slot owns its scene"))
    }

    /// The scene holding instance `id`.
    fn holder(&mut self, id: InstanceId) -> Result<&mut Scene, AccelError> {
        Ok(if self.slot(id)?.resting { &mut self.resting } else { &mut self.top })
    }

    /// Moves the static scene's instance into the resting scene (`true`) or back to the top
    /// level.
    fn move_static(&mut self, to_resting: bool) -> Result<(), AccelError> {
        let (from, to) =
            if to_resting { (&mut self.top, &mut self.resting) } else { (&mut self.resting, &mut self.top) };
        let geometry = from.detach(STATIC_SLOT)?;
        to.attach_by_id(geometry, STATIC_SLOT)?;
        Ok(())
    }

    fn triangle_geometry(
        &self,
        mesh: &TriangleMesh,
        quality: BuildQuality,
    ) -> Result<(TriangleGeometry, usize), AccelError> {
        mesh.validate()?;
        // In parallel: on a 337k-triangle island this count took 2-3 ms of a 100 ms insert.
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
        let mut scene = Scene::new(&self.device, SceneFlags::default(), self.params.prototype)?;
        scene.attach(geometry)?;
        self.prototypes.push(scene.freeze()?);
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
        let proto = self
            .prototypes
            .get(prototype.0 as usize)
            .ok_or(AccelError::UnknownId { kind: "prototype", id: prototype.0 })?
            .clone();
        // The id is taken only once the instance is attached: a bad transform must not lose
        // a free id.
        let id = self.free_instances.last().copied().unwrap_or(self.instances.len() as u32);
        let normal_matrix = checked_transform(id, &transform)?;
        let geometry = InstanceGeometry::new(&self.device, &proto, &transform)?;
        self.top.attach_by_id(geometry, id + 1)?;
        if id as usize == self.instances.len() {
            self.instances.push(None);
        } else {
            self.free_instances.pop();
        }
        self.instances[id as usize] = Some(InstanceSlot { normal_matrix, resting: false });
        Ok(InstanceId(id))
    }

    fn set_instance_transform(&mut self, id: InstanceId, transform: Affine3A) -> Result<(), AccelError> {
        let normal_matrix = checked_transform(id.0, &transform)?;
        self.holder(id)?.instance_mut(id.0 + 1)?.set_transform(&transform)?;
        if let Some(slot) = self.instances[id.0 as usize].as_mut() {
            slot.normal_matrix = normal_matrix;
        }
        Ok(())
    }

    fn remove_instance(&mut self, id: InstanceId) -> Result<(), AccelError> {
        if self.slot(id)?.resting {
            self.set_instance_resting(id, false)?;
        }
        self.top.detach(id.0 + 1)?;
        self.instances[id.0 as usize] = None;
        self.free_instances.push(id.0);
        Ok(())
    }

    fn set_instance_resting(&mut self, id: InstanceId, resting: bool) -> Result<(), AccelError> {
        if self.slot(id)?.resting == resting {
            return Ok(());
        }
        if resting && self.resting_count == 0 {
            self.move_static(true)?;
        }
        let (from, to) =
            if resting { (&mut self.top, &mut self.resting) } else { (&mut self.resting, &mut self.top) };
        let geometry = from.detach(id.0 + 1)?;
        to.attach_by_id(geometry, id.0 + 1)?;
        if let Some(slot) = self.instances[id.0 as usize].as_mut() {
            slot.resting = resting;
        }
        if resting {
            self.resting_count += 1;
        } else {
            self.resting_count -= 1;
            if self.resting_count == 0 {
                self.move_static(false)?;
            }
        }
        Ok(())
    }

    fn commit(&mut self) -> Result<CommitReport, AccelError> {
        let resting = self.commit_resting()?;
        self.top.commit()?;
        self.awake_bounds = match self.top.view() {
            Some(top) if self.resting_count > 0 && self.top.geometry_count() > 0 => {
                AwakeBounds::new(top.bounds())
            }
            _ => AwakeBounds::NONE,
        };
        let mut report = std::mem::take(&mut self.pending);
        report.instances = self.instances.iter().flatten().filter(|s| !s.resting).count();
        report.resting_rebuilt |= resting.resting_rebuilt;
        report.resting_instances = self.resting_count;
        Ok(report)
    }

    fn commit_static(&mut self) -> Result<CommitReport, AccelError> {
        // Committing the owned child scene now leaves its holder dirty (the instance changed),
        // so nothing is visible before `commit`; the report waits for it too.
        self.static_holder().instance_mut(STATIC_SLOT)?.commit_child()?;
        let report = self.commit_resting()?;
        self.pending.resting_rebuilt |= report.resting_rebuilt;
        Ok(report)
    }

    /// Removal is a detach: the two-level builder keeps every other mesh's BVH and rebuilds
    /// only its small top over the meshes.
    fn static_removal_cost(&self, _id: StaticId) -> usize {
        0
    }

    fn query(&self) -> Result<&dyn SceneQuery, AccelError> {
        // A resting scene rebuilt by `commit_static` is committed in Embree's sense but not
        // published before `commit`.
        if self.top.is_dirty() || self.resting.is_dirty() || self.pending.resting_rebuilt {
            Err(AccelError::NotCommitted)
        } else {
            Ok(self)
        }
    }
}

impl EmbreeAccel {
    /// Rebuilds the resting scene if its set changed (the static scene's instance in it
    /// committed first).
    fn commit_resting(&mut self) -> Result<CommitReport, AccelError> {
        if !self.resting.is_dirty() {
            return Ok(CommitReport { resting_instances: self.resting_count, ..CommitReport::default() });
        }
        self.resting.commit()?;
        Ok(CommitReport {
            resting_rebuilt: true,
            resting_instances: self.resting_count,
            ..CommitReport::default()
        })
    }
}
