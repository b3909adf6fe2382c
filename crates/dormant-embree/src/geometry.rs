//! [`TriangleGeometry`]: a triangle mesh as an Embree geometry, its buffers copied into
//! Embree's or shared with the caller.

use std::sync::Arc;

use embree4_sys as sys;
use glam::Vec3;

use super::device::Device;
use super::error::EmbreeError;
use super::quality::BuildQuality;

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

    /// Lets argument filters see hits on this geometry (rtcSetGeometryEnableFilterFunctionFromArguments):
    /// what [`super::SceneView::skipping`] needs of the meshes inside the instances it skips.
    pub fn with_argument_filter(self) -> Result<Self, EmbreeError> {
        // SAFETY: `raw` is valid; the geometry is recommitted below, before it is attached.
        unsafe { sys::rtcSetGeometryEnableFilterFunctionFromArguments(self.raw, true) };
        self.commit()
    }
}
