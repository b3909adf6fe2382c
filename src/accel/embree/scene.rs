use std::collections::{BTreeMap, BTreeSet};
use std::marker::PhantomData;
use std::sync::Arc;

use embree4_sys as sys;

use super::device::Device;
use super::error::EmbreeError;
use super::geometry::{InstanceGeometry, TriangleGeometry};

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

/// Embree's BVH build quality (rtcSetSceneBuildQuality(3)).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum BuildQuality {
    Low,
    #[default]
    Medium,
    High,
}

impl BuildQuality {
    pub const ALL: [BuildQuality; 3] = [BuildQuality::Low, BuildQuality::Medium, BuildQuality::High];

    pub(crate) fn raw(self) -> sys::RTCBuildQuality::Type {
        use sys::RTCBuildQuality::*;
        match self {
            BuildQuality::Low => RTC_BUILD_QUALITY_LOW,
            BuildQuality::Medium => RTC_BUILD_QUALITY_MEDIUM,
            BuildQuality::High => RTC_BUILD_QUALITY_HIGH,
        }
    }
}

/// A geometry attached to a scene.
pub enum Geometry {
    Triangles(TriangleGeometry),
    Instance(InstanceGeometry),
}

impl Geometry {
    fn raw(&self) -> sys::RTCGeometry {
        match self {
            Geometry::Triangles(g) => g.raw,
            Geometry::Instance(g) => g.raw,
        }
    }
}

impl From<TriangleGeometry> for Geometry {
    fn from(g: TriangleGeometry) -> Self {
        Geometry::Triangles(g)
    }
}

impl From<InstanceGeometry> for Geometry {
    fn from(g: InstanceGeometry) -> Self {
        Geometry::Instance(g)
    }
}

/// A closest hit as Embree reports it. For an instanced hit, `ng` is in the instanced
/// object's space and `inst_id` names the instance geometry in the top scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmbreeHit {
    pub t: f32,
    pub u: f32,
    pub v: f32,
    pub ng: [f32; 3],
    pub prim_id: u32,
    pub geom_id: u32,
    pub inst_id: Option<u32>,
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
            Some(Geometry::Triangles(_)) => Err(EmbreeError::NotAnInstance { id }),
            None => Err(EmbreeError::NotAttached(id)),
        }
    }

    pub fn geometry(&self, id: u32) -> Option<&Geometry> {
        self.geometries.get(&id)
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
        (!self.dirty).then_some(SceneView { raw: self.raw, _scene: PhantomData })
    }

    /// Commits and makes the scene immutable, for sharing as an instancing prototype.
    pub fn freeze(mut self) -> Result<Arc<FrozenScene>, EmbreeError> {
        self.commit()?;
        Ok(Arc::new(FrozenScene { scene: self }))
    }
}

impl InstanceGeometry {
    fn child_is_owned(&self) -> bool {
        matches!(self.child(), super::geometry::InstanceChild::Owned(_))
    }
}

/// A committed scene that can no longer change: a prototype shared by instances.
pub struct FrozenScene {
    scene: Scene,
}

impl FrozenScene {
    pub fn view(&self) -> SceneView<'_> {
        self.scene.view().expect("a frozen scene is committed")
    }

    pub(crate) fn scene(&self) -> &Scene {
        &self.scene
    }
}

/// Ray queries on a committed scene. Borrowing the scene keeps it unchanged while rays run.
#[derive(Clone, Copy)]
pub struct SceneView<'a> {
    pub(super) raw: sys::RTCScene,
    _scene: PhantomData<&'a Scene>,
}

// SAFETY: rtcIntersect1/rtcOccluded1 may run concurrently on one committed scene from many
// threads (rtcIntersect1(3)); the borrow keeps the scene committed and alive.
unsafe impl Send for SceneView<'_> {}
// SAFETY: see `Send`.
unsafe impl Sync for SceneView<'_> {}

fn embree_ray(org: [f32; 3], dir: [f32; 3], tnear: f32, tfar: f32) -> sys::RTCRay {
    sys::RTCRay {
        org_x: org[0],
        org_y: org[1],
        org_z: org[2],
        tnear,
        dir_x: dir[0],
        dir_y: dir[1],
        dir_z: dir[2],
        time: 0.0,
        tfar,
        mask: u32::MAX,
        id: 0,
        flags: 0,
    }
}

impl SceneView<'_> {
    /// Closest hit in `[tnear, tfar]` (rtcIntersect1).
    pub fn intersect1(&self, org: [f32; 3], dir: [f32; 3], tnear: f32, tfar: f32) -> Option<EmbreeHit> {
        let mut rayhit = sys::RTCRayHit {
            ray: embree_ray(org, dir, tnear, tfar),
            hit: sys::RTCHit {
                geomID: sys::RTC_INVALID_GEOMETRY_ID,
                instID: [sys::RTC_INVALID_GEOMETRY_ID; sys::RTC_MAX_INSTANCE_LEVEL_COUNT as usize],
                ..Default::default()
            },
        };
        // SAFETY: `rayhit` is an `RTCRayHit` laid out by bindings generated from the linked
        // library's headers (so the library writes within it); the scene is committed and
        // alive for the borrow; null arguments select the defaults.
        unsafe { sys::rtcIntersect1(self.raw, &mut rayhit, std::ptr::null_mut()) };
        let h = &rayhit.hit;
        (h.geomID != sys::RTC_INVALID_GEOMETRY_ID).then(|| EmbreeHit {
            t: rayhit.ray.tfar,
            u: h.u,
            v: h.v,
            ng: [h.Ng_x, h.Ng_y, h.Ng_z],
            prim_id: h.primID,
            geom_id: h.geomID,
            inst_id: (h.instID[0] != sys::RTC_INVALID_GEOMETRY_ID).then_some(h.instID[0]),
        })
    }

    /// Whether anything lies in `[tnear, tfar]` (rtcOccluded1).
    pub fn occluded1(&self, org: [f32; 3], dir: [f32; 3], tnear: f32, tfar: f32) -> bool {
        let mut ray = embree_ray(org, dir, tnear, tfar);
        // SAFETY: as in `intersect1`; rtcOccluded1 writes only `ray.tfar`.
        unsafe { sys::rtcOccluded1(self.raw, &mut ray, std::ptr::null_mut()) };
        ray.tfar == f32::NEG_INFINITY
    }

    /// World bounds of the committed scene.
    pub fn bounds(&self) -> crate::geometry::Aabb {
        let mut b = sys::RTCBounds::default();
        // SAFETY: the scene is committed; `b` is a valid output struct.
        unsafe { sys::rtcGetSceneBounds(self.raw, &mut b) };
        crate::geometry::Aabb {
            min: glam::Vec3::new(b.lower_x, b.lower_y, b.lower_z),
            max: glam::Vec3::new(b.upper_x, b.upper_y, b.upper_z),
        }
    }
}
