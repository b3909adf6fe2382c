//! Ray-scene intersection: one interface, [`Accelerator`], implemented by every backend.
//!
//! The scene an accelerator holds has two levels:
//! - **prototypes**: one bottom-level structure per mesh, shared by every instance of it;
//! - **static geometry**: world-space triangle meshes (the environment and baked islands);
//! - **instances**: a prototype plus an affine transform, one per body kept instanced: awake
//!   in the per-frame top level, or at rest in a resting level rebuilt on a schedule
//!   ([`Accelerator::set_instance_resting`], `resting.rs`).
//!
//! Changes are staged and become visible to rays at [`Accelerator::commit`]. Queries go through
//! [`Accelerator::query`], which fails while changes are uncommitted, so no ray ever sees a
//! half-updated scene. The renderer and the integration engine see only these traits; the
//! backends' modules are public for their own types (build parameters for the benchmarks,
//! the Embree wrapper and its version for `dormant info`, the BVH's persistent static tree).

mod backend;
pub mod bvh;
#[cfg(feature = "embree")]
pub mod embree;
mod hit;
mod load;
mod object_map;
mod resting;
mod snapshot;
#[cfg(test)]
mod tests;

pub use backend::Backend;
pub use hit::{Hit, HitObject, Occluder};
pub use load::{load_scene, LoadedScene};
pub(crate) use object_map::mesh_triangle;
pub(crate) use object_map::normal_matrix;
pub(crate) use object_map::ResolvedHit;
pub use object_map::{HitTriangle, LoadedObjectMap, MeshRef, ObjectMap};
pub use snapshot::StaticSceneSnapshot;

use glam::Affine3A;

use crate::geometry::{InstanceMotion, MeshError, Ray, TriangleMesh};

/// Creates an empty accelerator of the given backend. `threads` bounds the backend's own
/// worker pool (Embree's TBB); `None` lets it use every core.
pub fn create(backend: Backend, threads: Option<usize>) -> Result<Box<dyn Accelerator>, AccelError> {
    match backend {
        #[cfg(feature = "embree")]
        Backend::Embree => Ok(Box::new(embree::EmbreeAccel::new(threads)?)),
        #[cfg(not(feature = "embree"))]
        Backend::Embree => {
            let _ = threads;
            Err(AccelError::BackendUnavailable("embree"))
        }
        Backend::Bvh => Ok(Box::new(bvh::BvhAccel::new(threads))),
    }
}
pub(crate) use resting::{RestingCounts, RestingSchedule};

/// Identifies a prototype mesh registered with [`Accelerator::add_prototype`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct PrototypeId(pub u32);

/// Identifies an instance in the top level.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct InstanceId(pub u32);

/// Identifies a world-space mesh in the static scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct StaticId(pub u32);

#[derive(Debug, thiserror::Error)]
pub enum AccelError {
    #[error("the scene has uncommitted changes; call commit() before tracing rays")]
    NotCommitted,
    #[error("unknown {kind} id {id}")]
    UnknownId { kind: &'static str, id: u32 },
    #[error("invalid mesh: {0}")]
    Mesh(#[from] MeshError),
    #[error("transform of instance {instance} is not finite or not invertible")]
    InvalidTransform { instance: u32 },
    #[error("instance {instance} is resting: resting instances cannot be motion-blurred")]
    RestingMotion { instance: u32 },
    #[error("backend '{0}' is not compiled into this build")]
    BackendUnavailable(&'static str),
    #[error("the {backend} backend cannot restore a static scene snapshot taken by the {from} backend")]
    ForeignSnapshot { backend: Backend, from: Backend },
    #[error("the {0} backend does not take static scene snapshots")]
    SnapshotsUnsupported(Backend),
    #[error("the {0} backend has no resting scene")]
    RestingUnsupported(Backend),
    #[cfg(feature = "embree")]
    #[error(transparent)]
    Embree(#[from] dormant_embree::EmbreeError),
}

/// Whether instance `id` (declared resting or not) may take `motion`
/// ([`Accelerator::set_instance_motion`]): a resting instance cannot move, and the motion
/// must be finite.
pub(crate) fn check_motion(
    id: InstanceId,
    resting: bool,
    motion: Option<&InstanceMotion>,
) -> Result<(), AccelError> {
    match motion {
        Some(_) if resting => Err(AccelError::RestingMotion { instance: id.0 }),
        Some(m) if !m.is_finite() => Err(AccelError::InvalidTransform { instance: id.0 }),
        _ => Ok(()),
    }
}

/// What a commit did, for the per-stage counters.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CommitReport {
    /// Triangles the commit (re)built into acceleration structures.
    pub(crate) built_triangles: usize,
    /// Instances in the top level after the commit.
    pub instances: usize,
    /// Triangles skipped because they were degenerate or not finite.
    pub skipped_triangles: usize,
    /// Whether the resting level was rebuilt.
    pub(crate) resting_rebuilt: bool,
    /// Resting instances in the resting level after the commit.
    pub resting_instances: usize,
    /// Resting instances still in the top level after the commit, waiting for the next
    /// rebuild of the resting level.
    pub(crate) resting_waiting: usize,
}

/// Closest-hit and any-hit queries on a committed scene. Safe to call from many threads.
pub trait SceneQuery: Sync {
    /// Closest hit along `ray` within `[t_min, t_max]`.
    fn intersect(&self, ray: &Ray) -> Option<Hit>;
    /// Whether anything blocks `ray` within `[t_min, t_max]` (shadow and occlusion rays).
    fn intersect_p(&self, ray: &Ray) -> bool;

    /// What blocks `ray` within `[t_min, t_max]`: `None` exactly when [`Self::intersect_p`] is
    /// `false`, else one blocker (any). The default only says whether.
    fn occluder(&self, ray: &Ray) -> Option<Occluder> {
        self.intersect_p(ray).then_some(Occluder::Unknown)
    }

    /// Closest hits of a group of rays, `hits[i]` for `rays[i]`, equal to [`Self::intersect`]
    /// per ray (up to ties between surfaces at one distance). For coherent groups
    /// (neighbouring pixels): Embree traces up to 16 at a time as one packet, the BVH up to 8;
    /// the default loops over the rays.
    ///
    /// # Panics
    /// If `rays` and `hits` differ in length.
    fn intersect_packet(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        assert_eq!(rays.len(), hits.len(), "one hit slot per ray");
        for (ray, hit) in rays.iter().zip(hits) {
            *hit = self.intersect(ray);
        }
    }

    /// Occlusion of a group of rays, `occluded[i]` for `rays[i]`, equal to
    /// [`Self::intersect_p`] per ray; packets as in [`Self::intersect_packet`].
    ///
    /// # Panics
    /// If `rays` and `occluded` differ in length.
    fn intersect_p_packet(&self, rays: &[Ray], occluded: &mut [bool]) {
        assert_eq!(rays.len(), occluded.len(), "one result slot per ray");
        for (ray, o) in rays.iter().zip(occluded) {
            *o = self.intersect_p(ray);
        }
    }
}

/// A two-level ray tracing scene: prototypes, static geometry and instances.
pub trait Accelerator: Send + Sync {
    fn backend(&self) -> Backend;

    /// Registers a mesh (object space) that instances can refer to.
    fn add_prototype(&mut self, mesh: &TriangleMesh) -> Result<PrototypeId, AccelError>;

    /// Adds a world-space mesh to the static scene.
    fn add_static(&mut self, mesh: &TriangleMesh) -> Result<StaticId, AccelError>;

    /// Removes a mesh from the static scene.
    fn remove_static(&mut self, id: StaticId) -> Result<(), AccelError>;

    /// Adds an instance of `prototype` placed by `transform` (object to world).
    fn add_instance(&mut self, prototype: PrototypeId, transform: Affine3A)
        -> Result<InstanceId, AccelError>;

    fn set_instance_transform(&mut self, id: InstanceId, transform: Affine3A) -> Result<(), AccelError>;

    fn remove_instance(&mut self, id: InstanceId) -> Result<(), AccelError>;

    /// Blurs instance `id` over the camera shutter (motion blur): a ray at time `s` sees it
    /// at `motion.at(s)` instead of at its transform; `None` makes it still again, at its
    /// transform. Only the per-frame top level holds moving instances: declaring an instance
    /// resting ([`Accelerator::set_instance_resting`]) stills it, and a resting one cannot
    /// move (rejected with [`AccelError::RestingMotion`]). A new transform keeps the motion.
    fn set_instance_motion(
        &mut self,
        id: InstanceId,
        motion: Option<InstanceMotion>,
    ) -> Result<(), AccelError>;

    /// Declares that static mesh `id` will never be removed (an offline render's lookahead
    /// knows its island never wakes). A backend may then merge it with other such meshes into
    /// one structure when it reorganises its static scene; removing it anyway stays correct but
    /// may cost a rebuild. The default ignores the hint.
    fn set_static_permanent(&mut self, id: StaticId) {
        let _ = id;
    }

    /// Declares instance `id` at rest (`resting`: it will not move until woken) or awake.
    /// Resting instances leave the per-frame top level for a resting level that the backend
    /// rebuilds on a schedule shared by all backends (`RestingSchedule`): a new resting
    /// instance waits in the top level until the next rebuild; a woken one leaves a ghost in
    /// the level that rays skip. Rebuilds happen at [`Accelerator::commit_static`] (which
    /// reports them; visible after [`Accelerator::commit`]) or [`Accelerator::compact_resting`].
    /// Hits on resting instances are [`HitObject::Instance`] with the same results as awake
    /// ones, wherever the instance is.
    fn set_instance_resting(&mut self, id: InstanceId, resting: bool) -> Result<(), AccelError> {
        let _ = (id, resting);
        Err(AccelError::RestingUnsupported(self.backend()))
    }

    /// Rebuilds the resting level now, whatever the schedule says: every resting instance in
    /// it, no ghosts. Visible after the next [`Accelerator::commit`], which reports it.
    fn compact_resting(&mut self) -> Result<CommitReport, AccelError> {
        Err(AccelError::RestingUnsupported(self.backend()))
    }

    /// Makes all staged changes visible to rays.
    fn commit(&mut self) -> Result<CommitReport, AccelError>;

    /// Builds the staged static changes now, so callers can time them apart from the top
    /// level; they become visible at the next [`Accelerator::commit`], which reports them.
    fn commit_static(&mut self) -> Result<CommitReport, AccelError>;

    /// Saves the static scene as of the last static build, if this backend can do so without
    /// copying or rebuilding it (the persistent BVH: O(1)). `None` otherwise (Embree: see
    /// docs/design.md, "Geometry cache").
    fn snapshot_static_scene(&self) -> Option<StaticSceneSnapshot> {
        None
    }

    /// Makes a snapshot taken from this accelerator the static scene. Static ids added after it
    /// was taken are unknown again; staged static changes apply on top at the next commit.
    fn restore_static_scene(&mut self, snapshot: &StaticSceneSnapshot) -> Result<(), AccelError> {
        Err(AccelError::ForeignSnapshot { backend: self.backend(), from: snapshot.backend() })
    }

    /// Triangles the next static build must rebuild if `id` is removed: 0 when removal is a
    /// detach or an unlink, the whole static scene when `id` shares a structure with others.
    fn static_removal_cost(&self, id: StaticId) -> usize;

    /// The committed scene; [`AccelError::NotCommitted`] while changes are staged.
    fn query(&self) -> Result<&dyn SceneQuery, AccelError>;

    /// SAH cost of the committed static tree, for backends that expose their tree (the BVH);
    /// compares insertion quality with a rebuild.
    fn static_sah_cost(&self) -> Option<f32> {
        None
    }
}
