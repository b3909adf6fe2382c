//! Embree scenes: [`Scene`] (geometries plus the BVH its commit builds), [`InstanceGeometry`]
//! (a scene placed in another by a transform), [`FrozenScene`] (a committed scene shared by
//! instances) and [`SceneView`], the single-ray queries of a committed scene. Scenes and
//! instances nest (a scene holds instances, an instance holds a scene and commits it), so they
//! share this file; triangle meshes ([`TriangleGeometry`]) do not depend on them.

use std::collections::{BTreeMap, BTreeSet};
use std::marker::PhantomData;
use std::sync::Arc;

use embree4_sys as sys;
use glam::{Affine3A, Vec3};

use crate::geometry::{InstanceMotion, RigidTransform, FRAME_TIME};

use super::device::Device;
use super::error::EmbreeError;
use super::filter::{self, GeometrySet, SkipContext};
use super::geometry::TriangleGeometry;
use super::instance_array::InstanceArrayGeometry;
use super::quality::BuildQuality;

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
        (!self.dirty).then_some(SceneView { raw: self.raw, skip: None, _scene: PhantomData })
    }

    /// Commits and makes the scene immutable, for sharing as an instancing prototype.
    pub fn freeze(mut self) -> Result<Arc<FrozenScene>, EmbreeError> {
        self.commit()?;
        let bounds = self.view().map(|v| v.bounds());
        // The farthest corner of the bounds (an empty scene's are infinite: no radius).
        let radius = bounds.map_or(f32::INFINITY, |b| b.min.abs().max(b.max.abs()).length());
        Ok(Arc::new(FrozenScene { scene: self, radius }))
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

/// Embree's FLOAT3X4_COLUMN_MAJOR layout of an affine transform.
pub(super) fn column_major_3x4(xf: &Affine3A) -> [f32; 12] {
    let m = xf.matrix3;
    let t = xf.translation;
    [
        m.x_axis.x, m.x_axis.y, m.x_axis.z, m.y_axis.x, m.y_axis.y, m.y_axis.z, m.z_axis.x, m.z_axis.y,
        m.z_axis.z, t.x, t.y, t.z,
    ]
}

/// The largest rotation over the shutter (radians) for which a moving instance is given to
/// Embree as two matrices, which it lerps, rather than two quaternion decompositions, which it
/// slerps like [`InstanceMotion::at`], for an instance no farther from the world origin than
/// its points are from its own origin. Lerping the matrices of a turn by `a` scales the object
/// across the turn's axis by `cos(a/2)` halfway through (the worst time), `1 - a^2/8`, and
/// turns it to within `a^3/24` of the slerp: at 2e-3 the object's points move by 5e-7 of their
/// distance `r` from its origin, eight of f32's unit roundoffs. A pure translation (`a = 0`)
/// lerps exactly.
///
/// An instance farther out may turn further ([`lerps_as_matrices`]): its points may then move
/// by 5e-7 of its translation's magnitude instead, still eight unit roundoffs of it, half of
/// what the crosscheck allows Embree's own f32 transform (16 roundoffs of the ray origin's and
/// the translation's magnitude; docs/crosscheck.md). On the atrium at shutter 0.5 (five frames
/// sampled over the fall, 28k motions) 9% of the moving instances' motions are pure
/// translations, 51% turn by less than 1e-4 rad, 10% by 1e-4 to 1e-3, 4% by 1e-3 to 2e-3, 27%
/// by more (docs/performance.md, "Motion blur").
///
/// Tried (session 24): the instances that turn further as matrices at more time steps (the
/// slerp's poses at `1 + ceil(a / LERP_MAX_ANGLE)` times, up to 16, so that no segment turns
/// by more than this): Embree's multi-segment builder made the atrium's blurred commit 3.2x
/// slower (20.4-21.5 against 6.6-6.7 ms a frame; blur on / off 2.97-3.06 against 1.53-1.57),
/// tracing unchanged. Two time steps, quaternions beyond the angle, stay.
const LERP_MAX_ANGLE: f32 = 2e-3;

/// Whether `motion` of an instance whose points lie within `radius` of its origin goes to
/// Embree as two matrices (lerped) rather than two quaternion decompositions (slerped): it
/// turns by at most [`LERP_MAX_ANGLE`] times `sqrt(max(reach, radius) / radius)`, `reach` a
/// lower bound on its translation's largest coordinate over the shutter. The lerp then moves
/// its points by at most 5e-7 `max(reach, radius)`.
pub(super) fn lerps_as_matrices(motion: &InstanceMotion, radius: f32) -> bool {
    let angle = motion.rotation_angle();
    if angle <= LERP_MAX_ANGLE {
        return true;
    }
    if !radius.is_finite() {
        // Unknown extent (an empty or owned scene): the fixed angle only.
        return false;
    }
    // How far out the instance stays over the shutter, from below: per axis the smallest
    // magnitude of its translation's coordinate on the way (0 where it changes sign), and the
    // largest of those (the translation's largest coordinate is never smaller).
    let (a, b) = (motion.open.translation, motion.close.translation);
    let (lo, hi) = (a.min(b), a.max(b));
    let crosses = lo.cmple(Vec3::ZERO) & hi.cmpge(Vec3::ZERO);
    let reach = Vec3::select(crosses, Vec3::ZERO, lo.abs().min(hi.abs())).max_element();
    // `a^2 r <= LERP_MAX_ANGLE^2 max(reach, r)`, without a division (a point-sized object,
    // `r = 0`, lerps at any angle; a NaN radius never).
    angle * angle * radius <= LERP_MAX_ANGLE * LERP_MAX_ANGLE * reach.max(radius)
}

/// Embree's decomposition of a rigid transform: unit scale, no skew or shift, the rotation as
/// a quaternion (`r` the real part) and the translation.
pub(super) fn quaternion_decomposition(t: &RigidTransform) -> sys::RTCQuaternionDecomposition {
    let (q, p) = (t.rotation, t.translation);
    sys::RTCQuaternionDecomposition {
        scale_x: 1.0,
        scale_y: 1.0,
        scale_z: 1.0,
        quaternion_r: q.w,
        quaternion_i: q.x,
        quaternion_j: q.y,
        quaternion_k: q.z,
        translation_x: p.x,
        translation_y: p.y,
        translation_z: p.z,
        ..Default::default()
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
            InstanceChild::Shared(frozen) => frozen.scene.raw,
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

    /// Makes the instance move over the shutter: two time steps, at `motion.open` (ray time 0)
    /// and `motion.close` (time 1), which Embree interpolates like [`InstanceMotion::at`]. A
    /// scene holding a geometry with several time steps builds a motion-blur BVH over it.
    /// Through a parent scene, use [`Scene::instance_mut`].
    ///
    /// A rotating instance gets quaternion decompositions, which Embree slerps; bounding that
    /// motion costs Embree a root search per box corner and axis at every commit (13 us an
    /// instance for a pure translation, 65 us rotating, under load; `dormant bench
    /// instances`). An instance that barely turns for its size and place
    /// ([`lerps_as_matrices`]) gets two matrices instead, which Embree lerps and bounds in
    /// closed form: on the atrium most moving bodies barely turn within the shutter
    /// (docs/performance.md, "Motion blur").
    pub fn set_motion(&mut self, motion: &InstanceMotion) -> Result<(), EmbreeError> {
        if !motion.is_finite() {
            return Err(EmbreeError::NonFiniteTransform);
        }
        // SAFETY: `raw` is a valid instance geometry; time steps 0 and 1 exist once the count
        // is 2; each transform is a valid `RTCQuaternionDecomposition` or the 12 floats
        // FLOAT3X4_COLUMN_MAJOR reads, which Embree copies. `&mut self`: no ray traverses it
        // meanwhile (see `set_transform`).
        unsafe {
            sys::rtcSetGeometryTimeStepCount(self.raw, 2);
            if lerps_as_matrices(motion, self.child_radius()) {
                for (step, t) in [&motion.open, &motion.close].into_iter().enumerate() {
                    let m = column_major_3x4(&t.to_affine());
                    let format = sys::RTCFormat::RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR;
                    sys::rtcSetGeometryTransform(self.raw, step as u32, format, m.as_ptr().cast());
                }
            } else {
                for (step, t) in [&motion.open, &motion.close].into_iter().enumerate() {
                    sys::rtcSetGeometryTransformQuaternion(
                        self.raw,
                        step as u32,
                        &quaternion_decomposition(t),
                    );
                }
            }
            sys::rtcCommitGeometry(self.raw);
        }
        self.moving = true;
        self.device.check()
    }

    /// Whether the instance has two time steps ([`Self::set_motion`]).
    pub fn is_moving(&self) -> bool {
        self.moving
    }

    fn child_is_owned(&self) -> bool {
        matches!(self.child, InstanceChild::Owned(_))
    }

    /// How far the child's points lie from its origin at most ([`FrozenScene`]); infinite for
    /// an owned scene, which may change.
    fn child_radius(&self) -> f32 {
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

/// A committed scene that can no longer change: a prototype shared by instances.
pub struct FrozenScene {
    scene: Scene,
    /// An upper bound on the distance of the scene's points from its origin (the farthest
    /// corner of its bounds): how far a turn moves them ([`lerps_as_matrices`]).
    radius: f32,
}

impl FrozenScene {
    pub(super) fn radius(&self) -> f32 {
        self.radius
    }

    pub(super) fn raw(&self) -> sys::RTCScene {
        self.scene.raw
    }

    pub fn view(&self) -> SceneView<'_> {
        self.scene.view().expect("a frozen scene is committed")
    }
}

/// Ray queries on a committed scene. Borrowing the scene keeps it unchanged while rays run.
#[derive(Clone, Copy)]
pub struct SceneView<'a> {
    pub(super) raw: sys::RTCScene,
    /// Instances (by geometry id in this scene) whose hits rays reject.
    pub(super) skip: Option<&'a GeometrySet>,
    _scene: PhantomData<&'a Scene>,
}

// SAFETY: rtcIntersect1/rtcOccluded1 may run concurrently on one committed scene from many
// threads (rtcIntersect1(3)); the borrow keeps the scene committed and alive.
unsafe impl Send for SceneView<'_> {}
// SAFETY: see `Send`.
unsafe impl Sync for SceneView<'_> {}

fn embree_ray(org: [f32; 3], dir: [f32; 3], tnear: f32, tfar: f32, time: f32) -> sys::RTCRay {
    sys::RTCRay {
        org_x: org[0],
        org_y: org[1],
        org_z: org[2],
        tnear,
        dir_x: dir[0],
        dir_y: dir[1],
        dir_z: dir[2],
        time,
        tfar,
        mask: u32::MAX,
        id: 0,
        flags: 0,
    }
}

impl<'a> SceneView<'a> {
    /// The same scene, with every hit inside the instances in `skip` (geometry ids in this
    /// scene) rejected; an empty set is no filter at all.
    pub fn skipping(self, skip: &'a GeometrySet) -> SceneView<'a> {
        SceneView { skip: (!skip.is_empty()).then_some(skip), ..self }
    }

    /// The query context that carries the skipped set, if any.
    pub(super) fn skip_context(&self) -> Option<SkipContext<'a>> {
        self.skip.map(SkipContext::new)
    }

    /// Closest hit in `[tnear, tfar]` (rtcIntersect1), at shutter time 0.5.
    pub fn intersect1(&self, org: [f32; 3], dir: [f32; 3], tnear: f32, tfar: f32) -> Option<EmbreeHit> {
        self.intersect1_at(org, dir, tnear, tfar, FRAME_TIME)
    }

    /// Closest hit in `[tnear, tfar]` of a ray at shutter time `time` (motion blur).
    pub fn intersect1_at(
        &self,
        org: [f32; 3],
        dir: [f32; 3],
        tnear: f32,
        tfar: f32,
        time: f32,
    ) -> Option<EmbreeHit> {
        let mut rayhit = sys::RTCRayHit {
            ray: embree_ray(org, dir, tnear, tfar, time),
            hit: sys::RTCHit {
                geomID: sys::RTC_INVALID_GEOMETRY_ID,
                instID: [sys::RTC_INVALID_GEOMETRY_ID; sys::RTC_MAX_INSTANCE_LEVEL_COUNT as usize],
                ..Default::default()
            },
        };
        let mut context = self.skip_context();
        let mut args = filter::intersect_args(sys::RTCRayQueryFlags::RTC_RAY_QUERY_FLAG_INCOHERENT);
        if let Some(c) = context.as_mut() {
            c.intersect_args(&mut args);
        }
        // SAFETY: `rayhit` is an `RTCRayHit` laid out by bindings generated from the linked
        // library's headers (so the library writes within it); the scene is committed and
        // alive for the borrow; `args` is initialised as rtcInitIntersectArguments does and
        // its context, if any, lives until the call returns.
        unsafe { sys::rtcIntersect1(self.raw, &mut rayhit, &mut args) };
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

    /// Whether anything lies in `[tnear, tfar]` (rtcOccluded1), at shutter time 0.5.
    pub fn occluded1(&self, org: [f32; 3], dir: [f32; 3], tnear: f32, tfar: f32) -> bool {
        self.occluded1_at(org, dir, tnear, tfar, FRAME_TIME)
    }

    /// Whether anything lies in `[tnear, tfar]` of a ray at shutter time `time`.
    pub fn occluded1_at(&self, org: [f32; 3], dir: [f32; 3], tnear: f32, tfar: f32, time: f32) -> bool {
        let mut ray = embree_ray(org, dir, tnear, tfar, time);
        let mut context = self.skip_context();
        let mut args = filter::occluded_args(sys::RTCRayQueryFlags::RTC_RAY_QUERY_FLAG_INCOHERENT);
        if let Some(c) = context.as_mut() {
            c.occluded_args(&mut args);
        }
        // SAFETY: as in `intersect1`; rtcOccluded1 writes only `ray.tfar`.
        unsafe { sys::rtcOccluded1(self.raw, &mut ray, &mut args) };
        ray.tfar == f32::NEG_INFINITY
    }

    /// World bounds of the committed scene.
    pub fn bounds(&self) -> crate::geometry::Aabb {
        let mut b = sys::RTCBounds::default();
        // SAFETY: the scene is committed; `b` is a valid output struct.
        unsafe { sys::rtcGetSceneBounds(self.raw, &mut b) };
        crate::geometry::Aabb {
            min: Vec3::new(b.lower_x, b.lower_y, b.lower_z),
            max: Vec3::new(b.upper_x, b.upper_y, b.upper_z),
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::{Quat, Vec3};

    use super::lerps_as_matrices;
    use crate::geometry::{InstanceMotion, RigidTransform};

    /// A turn by `angle` about x, translated to `at` (at both ends).
    fn turn(angle: f32, at: Vec3) -> InstanceMotion {
        let pose = |a: f32| RigidTransform { rotation: Quat::from_rotation_x(a), translation: at };
        InstanceMotion { open: pose(0.0), close: pose(angle) }
    }

    #[test]
    fn the_angle_lerped_grows_with_the_distance_from_the_origin_over_the_radius() {
        let (origin, out) = (Vec3::ZERO, Vec3::new(0.0, -400.0, 2.0));
        // Near the origin, or at most a radius out: 2e-3 rad.
        assert!(lerps_as_matrices(&turn(1.9e-3, origin), 1.0));
        assert!(!lerps_as_matrices(&turn(2.1e-3, origin), 1.0));
        assert!(!lerps_as_matrices(&turn(2.1e-3, Vec3::splat(0.9)), 1.0));
        // 400 radii out: 2e-3 * sqrt(400) = 0.04 rad.
        assert!(lerps_as_matrices(&turn(0.039, out), 1.0));
        assert!(!lerps_as_matrices(&turn(0.041, out), 1.0));
        // The nearer end of the motion counts, and a coordinate that changes sign counts as 0.
        let mut moving = turn(0.039, out);
        moving.close.translation = Vec3::new(0.0, -1.0, 0.0);
        assert!(!lerps_as_matrices(&moving, 1.0));
        moving.close.translation = Vec3::new(0.0, 400.0, 2.0);
        assert!(!lerps_as_matrices(&moving, 1.0));
        moving.close.translation = Vec3::new(0.0, -401.0, 2.0);
        assert!(lerps_as_matrices(&moving, 1.0));
        // Unknown extent: the fixed angle only; a point-sized object: any angle.
        assert!(!lerps_as_matrices(&turn(0.01, out), f32::INFINITY));
        assert!(!lerps_as_matrices(&turn(0.01, out), f32::NAN));
        assert!(lerps_as_matrices(&turn(1.0, out), 0.0));
    }
}
