use std::sync::Arc;

use embree4_sys as sys;
use glam::{Affine3A, Vec3};

use super::device::Device;
use super::error::EmbreeError;
use super::scene::{BuildQuality, FrozenScene, Scene};

/// Caller-owned vertex (padded to 16 bytes) and index buffers.
type SharedBuffers = (Arc<[[f32; 4]]>, Arc<[[u32; 3]]>);

/// A triangle mesh geometry. Immutable once created, so one geometry can be attached to several
/// scenes at once (rtcAttachGeometry(3)); clones share the Embree object.
pub struct TriangleGeometry {
    pub(crate) raw: sys::RTCGeometry,
    device: Device,
    triangles: usize,
    /// Keeps user memory alive for shared buffers (Embree does not copy them).
    _shared: Option<SharedBuffers>,
}

// SAFETY: the geometry is immutable after construction (its buffers are never written again);
// Embree allows any thread to use or release it.
unsafe impl Send for TriangleGeometry {}
// SAFETY: as for `Send`: `&TriangleGeometry` exposes no mutation.
unsafe impl Sync for TriangleGeometry {}

impl Clone for TriangleGeometry {
    fn clone(&self) -> Self {
        // SAFETY: `raw` is a valid geometry; the clone owns the new reference.
        unsafe { sys::rtcRetainGeometry(self.raw) };
        Self {
            raw: self.raw,
            device: self.device.clone(),
            triangles: self.triangles,
            _shared: self._shared.clone(),
        }
    }
}

impl Drop for TriangleGeometry {
    fn drop(&mut self) {
        // SAFETY: we own one reference to `raw`.
        unsafe { sys::rtcReleaseGeometry(self.raw) };
    }
}

fn checked_u32(what: &'static str, count: usize) -> Result<u32, EmbreeError> {
    u32::try_from(count).map_err(|_| EmbreeError::TooLarge { what, count })
}

impl TriangleGeometry {
    /// Copies `positions` and `indices` into buffers Embree allocates and owns. The geometry's
    /// own BVH is built at medium quality (see [`Self::with_quality`]).
    pub fn new(device: &Device, positions: &[Vec3], indices: &[[u32; 3]]) -> Result<Self, EmbreeError> {
        Self::with_quality(device, positions, indices, BuildQuality::Medium)
    }

    /// Like [`Self::new`], with the quality of the geometry's own BVH. That BVH exists when the
    /// geometry sits in a scene built by Embree's two-level builder (a DYNAMIC scene at LOW
    /// quality), which keeps it across commits (rtcSetGeometryBuildQuality(3)).
    pub fn with_quality(
        device: &Device,
        positions: &[Vec3],
        indices: &[[u32; 3]],
        quality: BuildQuality,
    ) -> Result<Self, EmbreeError> {
        let vertex_count = checked_u32("vertex buffer", positions.len())?;
        let triangle_count = checked_u32("index buffer", indices.len())?;
        let geometry = Self::empty(device, indices.len())?;
        // SAFETY: `geometry.raw` is valid and not yet committed.
        unsafe { sys::rtcSetGeometryBuildQuality(geometry.raw, quality.raw()) };
        device.check()?;
        // SAFETY: `geometry.raw` is a valid triangle geometry. Embree returns a buffer of
        // `count * stride` bytes (or null on error, checked below); we write exactly that much.
        unsafe {
            let vb = sys::rtcSetNewGeometryBuffer(
                geometry.raw,
                sys::RTCBufferType::RTC_BUFFER_TYPE_VERTEX,
                0,
                sys::RTCFormat::RTC_FORMAT_FLOAT3,
                12,
                vertex_count as usize,
            ) as *mut [f32; 3];
            device.check()?;
            if !vb.is_null() {
                for (i, p) in positions.iter().enumerate() {
                    vb.add(i).write(p.to_array());
                }
            }
            let ib = sys::rtcSetNewGeometryBuffer(
                geometry.raw,
                sys::RTCBufferType::RTC_BUFFER_TYPE_INDEX,
                0,
                sys::RTCFormat::RTC_FORMAT_UINT3,
                12,
                triangle_count as usize,
            ) as *mut [u32; 3];
            device.check()?;
            if !ib.is_null() {
                std::ptr::copy_nonoverlapping(indices.as_ptr(), ib, indices.len());
            }
        }
        geometry.commit()
    }

    /// Uses the caller's buffers without copying. Vertices are padded to 16 bytes because Embree
    /// reads the last vertex with a 16-byte load (rtcSetSharedGeometryBuffer(3)).
    pub fn new_shared(
        device: &Device,
        vertices: Arc<[[f32; 4]]>,
        indices: Arc<[[u32; 3]]>,
    ) -> Result<Self, EmbreeError> {
        checked_u32("vertex buffer", vertices.len())?;
        checked_u32("index buffer", indices.len())?;
        let mut geometry = Self::empty(device, indices.len())?;
        // SAFETY: both buffers live in `geometry._shared` as long as the geometry; strides and
        // counts match the slices, and the 16-byte vertex stride satisfies the padding rule.
        unsafe {
            sys::rtcSetSharedGeometryBuffer(
                geometry.raw,
                sys::RTCBufferType::RTC_BUFFER_TYPE_VERTEX,
                0,
                sys::RTCFormat::RTC_FORMAT_FLOAT3,
                vertices.as_ptr().cast(),
                0,
                16,
                vertices.len(),
            );
            device.check()?;
            sys::rtcSetSharedGeometryBuffer(
                geometry.raw,
                sys::RTCBufferType::RTC_BUFFER_TYPE_INDEX,
                0,
                sys::RTCFormat::RTC_FORMAT_UINT3,
                indices.as_ptr().cast(),
                0,
                12,
                indices.len(),
            );
            device.check()?;
        }
        geometry._shared = Some((vertices, indices));
        geometry.commit()
    }

    fn empty(device: &Device, triangles: usize) -> Result<Self, EmbreeError> {
        // SAFETY: the device is valid; a null result is reported through `check`.
        let raw = unsafe {
            sys::rtcNewGeometry(device.inner.raw, sys::RTCGeometryType::RTC_GEOMETRY_TYPE_TRIANGLE)
        };
        device.check()?;
        debug_assert!(!raw.is_null());
        Ok(Self { raw, device: device.clone(), triangles, _shared: None })
    }

    fn commit(self) -> Result<Self, EmbreeError> {
        // SAFETY: `raw` is valid and not attached anywhere yet, so nothing traces it.
        unsafe { sys::rtcCommitGeometry(self.raw) };
        self.device.check()?;
        Ok(self)
    }

    pub fn triangle_count(&self) -> usize {
        self.triangles
    }
}

/// What an instance points to: a frozen prototype shared by many instances, or a mutable scene
/// the instance owns (the static scene in the top level), changed only through the parent.
pub enum InstanceChild {
    Shared(Arc<FrozenScene>),
    Owned(Box<Scene>),
}

/// An instance of a scene placed by an affine transform (object to world).
pub struct InstanceGeometry {
    pub(crate) raw: sys::RTCGeometry,
    device: Device,
    child: InstanceChild,
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
fn column_major_3x4(xf: &Affine3A) -> [f32; 12] {
    let m = xf.matrix3;
    let t = xf.translation;
    [
        m.x_axis.x, m.x_axis.y, m.x_axis.z, m.y_axis.x, m.y_axis.y, m.y_axis.z, m.z_axis.x, m.z_axis.y,
        m.z_axis.z, t.x, t.y, t.z,
    ]
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
            InstanceChild::Shared(frozen) => frozen.scene().raw,
            InstanceChild::Owned(scene) => scene.raw,
        };
        let mut instance = Self { raw, device: device.clone(), child };
        // SAFETY: both handles are valid; `instance.child` keeps the child scene alive as long
        // as the instance geometry.
        unsafe { sys::rtcSetGeometryInstancedScene(instance.raw, child_raw) };
        instance.device.check()?;
        instance.set_transform(transform)?;
        Ok(instance)
    }

    /// Replaces the transform. Through a parent scene, use [`Scene::instance_mut`] so the
    /// parent is marked for recommit.
    pub fn set_transform(&mut self, transform: &Affine3A) -> Result<(), EmbreeError> {
        if !transform.is_finite() {
            return Err(EmbreeError::NonFiniteTransform);
        }
        let m = column_major_3x4(transform);
        // SAFETY: `m` holds the 12 floats FLOAT3X4_COLUMN_MAJOR reads; Embree copies them.
        // `&mut self` guarantees no ray traverses a scene holding this geometry meanwhile
        // (the parent's `SceneView` borrows the parent).
        unsafe {
            sys::rtcSetGeometryTransform(
                self.raw,
                0,
                sys::RTCFormat::RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR,
                m.as_ptr().cast(),
            );
            sys::rtcCommitGeometry(self.raw);
        }
        self.device.check()
    }

    /// The owned child scene, for changes; `None` for a shared prototype.
    pub fn child_mut(&mut self) -> Option<&mut Scene> {
        match &mut self.child {
            InstanceChild::Owned(scene) => Some(scene),
            InstanceChild::Shared(_) => None,
        }
    }

    pub fn child(&self) -> &InstanceChild {
        &self.child
    }

    /// Gives back the instanced scene.
    pub fn into_child(self) -> InstanceChild {
        // Move the child out without running `Drop` twice: release our geometry reference first.
        let this = std::mem::ManuallyDrop::new(self);
        // SAFETY: we own one reference to `raw` and `this` is never used again except to move
        // the remaining fields out exactly once.
        unsafe {
            sys::rtcReleaseGeometry(this.raw);
            drop(std::ptr::read(&this.device));
            std::ptr::read(&this.child)
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
