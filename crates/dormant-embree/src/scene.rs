//! Embree scenes: [`Scene`] (geometries plus the BVH its commit builds) and
//! [`InstanceGeometry`] (a scene placed in another by a transform). Scenes and instances nest
//! (a scene holds instances, an instance may own a scene and commits it), so they share this
//! file; what a scene holds otherwise (triangle meshes, instance arrays, frozen prototypes)
//! does not depend on it, and queries go through [`SceneView`] (`view.rs`).

use std::collections::{BTreeMap, BTreeSet};
use std::sync::Arc;

use embree4_sys as sys;
use glam::Affine3A;

use super::device::Device;
use super::error::EmbreeError;
use super::frozen::FrozenScene;
use super::geometry::TriangleGeometry;
use super::instance_array::InstanceArrayGeometry;
use super::motion::{column_major_3x4, quaternion_decomposition, ShutterPoses};
use super::quality::BuildQuality;
use super::view::SceneView;

/// Embree's scene flags (rtcSetSceneFlags(3)).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SceneFlags {
    /// Optimise for frequent incremental changes (attach/detach and recommit).
    pub dynamic: bool,
    /// Use less memory at some cost in speed.
    pub compact: bool,
    /// Avoid optimisations that trade robustness for speed.
    pub robust: bool,
}

impl SceneFlags {
    fn raw(self) -> sys::RTCSceneFlags::Type {
        use sys::RTCSceneFlags::*;
        let mut f = RTC_SCENE_FLAG_NONE;
        if self.dynamic {
            f |= RTC_SCENE_FLAG_DYNAMIC;
        }
        if self.compact {
            f |= RTC_SCENE_FLAG_COMPACT;
        }
        if self.robust {
            f |= RTC_SCENE_FLAG_ROBUST;
        }
        f
    }
}

/// A geometry attached to a scene.
pub enum Geometry {
    Triangles(TriangleGeometry),
    Instance(InstanceGeometry),
    InstanceArray(InstanceArrayGeometry),
}

impl Geometry {
    fn raw(&self) -> sys::RTCGeometry {
        match self {
            Geometry::Triangles(g) => g.raw,
            Geometry::Instance(g) => g.raw,
            Geometry::InstanceArray(g) => g.raw,
        }
    }
}

impl From<TriangleGeometry> for Geometry {
    fn from(g: TriangleGeometry) -> Self {
        Geometry::Triangles(g)
    }
}

impl From<InstanceArrayGeometry> for Geometry {
    fn from(g: InstanceArrayGeometry) -> Self {
        Geometry::InstanceArray(g)
    }
}

impl From<InstanceGeometry> for Geometry {
    fn from(g: InstanceGeometry) -> Self {
        Geometry::Instance(g)
    }
}

/// An Embree scene: geometries plus the acceleration structure built at [`Scene::commit`].
///
/// Mutation needs `&mut self` and marks the scene dirty; rays need a [`SceneView`], which
/// only a clean scene hands out. This is Embree's rule (rtcCommitScene(3)): modification,
/// commit and tracing happen sequentially, never at the same time, and rays after a change
/// need a commit first.
pub struct Scene {
    pub(crate) raw: sys::RTCScene,
    device: Device,
    geometries: BTreeMap<u32, Geometry>,
    /// Instances whose child scene is owned (and so may change); committed before `self`.
    owning_instances: BTreeSet<u32>,
    dirty: bool,
}

// SAFETY: all mutation goes through `&mut self`; `&Scene` only reads Rust-side state and hands
// out `SceneView`s, and Embree allows rtcIntersect/rtcOccluded on a committed scene from many
// threads at once (rtcIntersect1(3)). Embree objects are not bound to a thread.
unsafe impl Send for Scene {}
// SAFETY: see `Send`.
unsafe impl Sync for Scene {}

impl Drop for Scene {
    fn drop(&mut self) {
        // SAFETY: we own one reference to `raw`; attached geometries keep their own references
        // and are released when `geometries` drops after this.
        unsafe { sys::rtcReleaseScene(self.raw) };
    }
}

impl Scene {
    pub fn new(device: &Device, flags: SceneFlags, quality: BuildQuality) -> Result<Self, EmbreeError> {
        // SAFETY: the device is valid; a null result is reported through `check`.
        let raw = unsafe { sys::rtcNewScene(device.inner.raw) };
        device.check()?;
        let mut scene = Self {
            raw,
            device: device.clone(),
            geometries: BTreeMap::new(),
            owning_instances: BTreeSet::new(),
            dirty: true,
        };
        scene.set_flags(flags)?;
        scene.set_build_quality(quality)?;
        Ok(scene)
    }

    pub fn set_flags(&mut self, flags: SceneFlags) -> Result<(), EmbreeError> {
        // SAFETY: `raw` is valid and `&mut self` excludes concurrent tracing.
        unsafe { sys::rtcSetSceneFlags(self.raw, flags.raw()) };
        self.dirty = true;
        self.device.check()
    }

    pub fn set_build_quality(&mut self, quality: BuildQuality) -> Result<(), EmbreeError> {
        // SAFETY: as in `set_flags`.
        unsafe { sys::rtcSetSceneBuildQuality(self.raw, quality.raw()) };
        self.dirty = true;
        self.device.check()
    }

    /// Attaches a geometry and returns the id Embree assigned.
    pub fn attach(&mut self, geometry: impl Into<Geometry>) -> Result<u32, EmbreeError> {
        let geometry = geometry.into();
        // SAFETY: both handles are valid; the scene keeps the Rust wrapper (and so any shared
        // buffers) alive in `geometries` while Embree holds the geometry.
        let id = unsafe { sys::rtcAttachGeometry(self.raw, geometry.raw()) };
        self.device.check()?;
        self.insert(id, geometry);
        Ok(id)
    }

    /// Attaches a geometry under a chosen id (rtcAttachGeometryByID(3)).
    pub fn attach_by_id(&mut self, geometry: impl Into<Geometry>, id: u32) -> Result<(), EmbreeError> {
        let geometry = geometry.into();
        // SAFETY: as in `attach`.
        unsafe { sys::rtcAttachGeometryByID(self.raw, geometry.raw(), id) };
        self.device.check()?;
        self.insert(id, geometry);
        Ok(())
    }

    fn insert(&mut self, id: u32, geometry: Geometry) {
        if let Geometry::Instance(inst) = &geometry {
            if inst.child_is_owned() {
                self.owning_instances.insert(id);
            }
        }
        let previous = self.geometries.insert(id, geometry);
        debug_assert!(previous.is_none(), "Embree reused geometry id {id}");
        self.dirty = true;
    }

    /// Detaches geometry `id` and gives it back. Embree validates the id: an unknown one is an
    /// [`EmbreeError::Api`].
    pub fn detach(&mut self, id: u32) -> Result<Geometry, EmbreeError> {
        // SAFETY: `raw` is valid; `&mut self` excludes concurrent tracing. Embree reports an
        // invalid id through the error callback.
        unsafe { sys::rtcDetachGeometry(self.raw, id) };
        self.device.check()?;
        self.dirty = true;
        self.owning_instances.remove(&id);
        self.geometries.remove(&id).ok_or(EmbreeError::NotAttached(id))
    }

    /// The attached instance `id`, for changing its transform or its owned child. Marks the
    /// scene for recommit.
    pub fn instance_mut(&mut self, id: u32) -> Result<&mut InstanceGeometry, EmbreeError> {
        match self.geometries.get_mut(&id) {
            Some(Geometry::Instance(inst)) => {
                self.dirty = true;
                Ok(inst)
            }
            Some(_) => Err(EmbreeError::NotAnInstance { id }),
            None => Err(EmbreeError::NotAttached(id)),
        }
    }

    /// The attached instance array `id`, for new entries. Marks the scene for recommit.
    pub fn instance_array_mut(&mut self, id: u32) -> Result<&mut InstanceArrayGeometry, EmbreeError> {
        match self.geometries.get_mut(&id) {
            Some(Geometry::InstanceArray(array)) => {
                self.dirty = true;
                Ok(array)
            }
            Some(_) => Err(EmbreeError::NotAnInstance { id }),
            None => Err(EmbreeError::NotAttached(id)),
        }
    }

    /// Commits the owned child scene of instance `id` if it has staged changes; only then is
    /// this scene marked for recommit (an unchanged child leaves it as it is).
    pub fn commit_child_of(&mut self, id: u32) -> Result<bool, EmbreeError> {
        match self.geometries.get_mut(&id) {
            Some(Geometry::Instance(inst)) => {
                let changed = inst.commit_child()?;
                self.dirty |= changed;
                Ok(changed)
            }
            Some(_) => Err(EmbreeError::NotAnInstance { id }),
            None => Err(EmbreeError::NotAttached(id)),
        }
    }

    pub fn geometry(&self, id: u32) -> Option<&Geometry> {
        self.geometries.get(&id)
    }

    /// Ids of the attached geometries, ascending.
    pub fn geometry_ids(&self) -> impl Iterator<Item = u32> + '_ {
        self.geometries.keys().copied()
    }

    pub fn geometry_count(&self) -> usize {
        self.geometries.len()
    }

    pub fn is_dirty(&self) -> bool {
        self.dirty
    }

    /// Builds the acceleration structure. Owned child scenes with changes are committed first,
    /// as Embree requires for instancing.
    pub fn commit(&mut self) -> Result<(), EmbreeError> {
        for id in &self.owning_instances {
            if let Some(Geometry::Instance(inst)) = self.geometries.get_mut(id) {
                inst.commit_child()?;
            }
        }
        // SAFETY: `raw` is valid; `&mut self` guarantees no `SceneView` of this scene (or of a
        // parent holding it) is alive, so no ray traverses it during the build.
        unsafe { sys::rtcCommitScene(self.raw) };
        self.device.check()?;
        self.dirty = false;
        Ok(())
    }

    /// The scene for ray queries, or `None` while changes are uncommitted.
    pub fn view(&self) -> Option<SceneView<'_>> {
        (!self.dirty).then(|| SceneView::new(self.raw))
    }

    /// Commits and makes the scene immutable, for sharing as an instancing prototype.
    pub fn freeze(mut self) -> Result<Arc<FrozenScene>, EmbreeError> {
        self.commit()?;
        let bounds = self.view().map(|v| v.bounds());
        // The farthest corner of the bounds (an empty scene's are infinite: no radius).
        let radius = bounds.map_or(f32::INFINITY, |(min, max)| min.abs().max(max.abs()).length());
        Ok(Arc::new(FrozenScene::new(self.raw, radius, Box::new(self))))
    }
}

/// What an instance points to: a frozen prototype shared by many instances, or a mutable scene
/// the instance owns (the static scene in the top level), changed only through the parent.
enum InstanceChild {
    Shared(Arc<FrozenScene>),
    Owned(Box<Scene>),
}

/// An instance of a scene placed by an affine transform (object to world).
pub struct InstanceGeometry {
    raw: sys::RTCGeometry,
    device: Device,
    child: InstanceChild,
    /// Two time steps (motion blur) rather than one.
    moving: bool,
}

// SAFETY: mutation (`set_transform`, `child_mut`) needs `&mut self`; Embree objects are not
// bound to the thread that made them.
unsafe impl Send for InstanceGeometry {}
// SAFETY: `&InstanceGeometry` exposes no mutation.
unsafe impl Sync for InstanceGeometry {}

impl Drop for InstanceGeometry {
    fn drop(&mut self) {
        // SAFETY: we own one reference to `raw`; the child scene is dropped after it.
        unsafe { sys::rtcReleaseGeometry(self.raw) };
    }
}

impl InstanceGeometry {
    /// An instance of a frozen (committed, immutable) scene.
    pub fn new(
        device: &Device,
        prototype: &Arc<FrozenScene>,
        transform: &Affine3A,
    ) -> Result<Self, EmbreeError> {
        Self::with_child(device, InstanceChild::Shared(prototype.clone()), transform)
    }

    /// An instance that owns a mutable scene. Changes to it go through
    /// [`Scene::instance_mut`] and [`InstanceGeometry::child_mut`], so the parent knows to
    /// recommit; the parent commits the child first.
    pub fn owning(device: &Device, scene: Scene, transform: &Affine3A) -> Result<Self, EmbreeError> {
        Self::with_child(device, InstanceChild::Owned(Box::new(scene)), transform)
    }

    fn with_child(device: &Device, child: InstanceChild, transform: &Affine3A) -> Result<Self, EmbreeError> {
        // SAFETY: the device is valid; a null result is reported through `check`.
        let raw = unsafe {
            sys::rtcNewGeometry(device.inner.raw, sys::RTCGeometryType::RTC_GEOMETRY_TYPE_INSTANCE)
        };
        device.check()?;
        let child_raw = match &child {
            InstanceChild::Shared(frozen) => frozen.raw(),
            InstanceChild::Owned(scene) => scene.raw,
        };
        let mut instance = Self { raw, device: device.clone(), child, moving: false };
        // SAFETY: both handles are valid; `instance.child` keeps the child scene alive as long
        // as the instance geometry.
        unsafe { sys::rtcSetGeometryInstancedScene(instance.raw, child_raw) };
        instance.device.check()?;
        instance.set_transform(transform)?;
        Ok(instance)
    }

    /// Replaces the transform (one time step: a moving instance stops). Through a parent
    /// scene, use [`Scene::instance_mut`] so the parent is marked for recommit.
    pub fn set_transform(&mut self, transform: &Affine3A) -> Result<(), EmbreeError> {
        if !transform.is_finite() {
            return Err(EmbreeError::NonFiniteTransform);
        }
        let m = column_major_3x4(transform);
        // SAFETY: `m` holds the 12 floats FLOAT3X4_COLUMN_MAJOR reads; Embree copies them.
        // `&mut self` guarantees no ray traverses a scene holding this geometry meanwhile
        // (the parent's `SceneView` borrows the parent).
        unsafe {
            if self.moving {
                sys::rtcSetGeometryTimeStepCount(self.raw, 1);
            }
            sys::rtcSetGeometryTransform(
                self.raw,
                0,
                sys::RTCFormat::RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR,
                m.as_ptr().cast(),
            );
            sys::rtcCommitGeometry(self.raw);
        }
        self.moving = false;
        self.device.check()
    }

    /// Makes the instance move over the shutter: two time steps, `poses[0]` at ray time 0 and
    /// `poses[1]` at time 1, which Embree interpolates. A scene holding a geometry with several
    /// time steps builds a motion-blur BVH over it. Through a parent scene, use
    /// [`Scene::instance_mut`].
    pub fn set_motion(&mut self, poses: &ShutterPoses) -> Result<(), EmbreeError> {
        if !poses.is_finite() {
            return Err(EmbreeError::NonFiniteTransform);
        }
        // SAFETY: `raw` is a valid instance geometry; time steps 0 and 1 exist once the count
        // is 2; each transform is a valid `RTCQuaternionDecomposition` or the 12 floats
        // FLOAT3X4_COLUMN_MAJOR reads, which Embree copies. `&mut self`: no ray traverses it
        // meanwhile (see `set_transform`).
        unsafe {
            sys::rtcSetGeometryTimeStepCount(self.raw, 2);
            match poses {
                ShutterPoses::Matrices(matrices) => {
                    for (step, t) in matrices.iter().enumerate() {
                        let m = column_major_3x4(t);
                        let format = sys::RTCFormat::RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR;
                        sys::rtcSetGeometryTransform(self.raw, step as u32, format, m.as_ptr().cast());
                    }
                }
                ShutterPoses::Rigid(rigid) => {
                    for (step, &pose) in rigid.iter().enumerate() {
                        let q = quaternion_decomposition(pose);
                        sys::rtcSetGeometryTransformQuaternion(self.raw, step as u32, &q);
                    }
                }
            }
            sys::rtcCommitGeometry(self.raw);
        }
        self.moving = true;
        self.device.check()
    }

    fn child_is_owned(&self) -> bool {
        matches!(self.child, InstanceChild::Owned(_))
    }

    /// How far the child's points lie from its origin at most ([`FrozenScene`]); infinite for
    /// an owned scene, which may change: how far a turn of the instance moves them.
    pub fn child_radius(&self) -> f32 {
        match &self.child {
            InstanceChild::Shared(frozen) => frozen.radius(),
            InstanceChild::Owned(_) => f32::INFINITY,
        }
    }

    /// The owned child scene, for changes; `None` for a shared prototype.
    pub fn child_mut(&mut self) -> Option<&mut Scene> {
        match &mut self.child {
            InstanceChild::Owned(scene) => Some(scene),
            InstanceChild::Shared(_) => None,
        }
    }

    /// Commits an owned child scene that has staged changes and tells Embree the instance
    /// changed. Called by the parent's commit.
    pub(crate) fn commit_child(&mut self) -> Result<bool, EmbreeError> {
        let InstanceChild::Owned(scene) = &mut self.child else {
            return Ok(false);
        };
        if !scene.is_dirty() {
            return Ok(false);
        }
        scene.commit()?;
        // SAFETY: `raw` is valid; the parent is being committed under `&mut`.
        unsafe { sys::rtcCommitGeometry(self.raw) };
        self.device.check()?;
        Ok(true)
    }
}
