//! [`InstanceArrayGeometry`]: many instances of a few prototypes as one Embree geometry
//! (RTC_GEOMETRY_TYPE_INSTANCE_ARRAY), still (one time step) or moving over the shutter (two).
//!
//! `dormant bench instances` measures it against one instance geometry per instance, which is
//! what `EmbreeAccel` keeps: the array's blurred commit costs the same, and it saves little
//! of a still commit:
//! docs/lab/motion-blur.md#2026-12-02-where-the-blurred-commit-goes-barely-turning-instances-as-matrices

use std::sync::Arc;

use embree4_sys as sys;
use glam::{Affine3A, Quat, Vec3};

use super::device::Device;
use super::error::EmbreeError;
use super::frozen::FrozenScene;
use super::motion::{column_major_3x4, quaternion_decomposition, ShutterPoses};

/// One entry of an instance array: the index of its prototype in the array's prototype list
/// and its placement. `None` is a hole Embree skips (index RTC_INVALID_GEOMETRY_ID).
pub type ArrayEntry<T> = (Option<u32>, T);

/// Instances of a fixed list of prototypes in one geometry. Hits report the array's geometry id
/// as the instance id and the entry's index as `inst_prim_id`.
pub struct InstanceArrayGeometry {
    pub(crate) raw: sys::RTCGeometry,
    device: Device,
    /// The instanced scenes, kept alive while Embree holds them.
    _prototypes: Vec<Arc<FrozenScene>>,
    /// Two time steps (quaternion decompositions) rather than one (3x4 matrices).
    moving: bool,
}

// SAFETY: mutation needs `&mut self`; Embree objects are not bound to a thread.
unsafe impl Send for InstanceArrayGeometry {}
// SAFETY: `&InstanceArrayGeometry` exposes no mutation.
unsafe impl Sync for InstanceArrayGeometry {}

impl Drop for InstanceArrayGeometry {
    fn drop(&mut self) {
        // SAFETY: we own one reference to `raw`; the prototypes are dropped after it.
        unsafe { sys::rtcReleaseGeometry(self.raw) };
    }
}

impl InstanceArrayGeometry {
    /// An empty array over `prototypes` with one time step (`moving == false`) or two.
    pub fn new(device: &Device, prototypes: &[Arc<FrozenScene>], moving: bool) -> Result<Self, EmbreeError> {
        // SAFETY: the device is valid; a null result is reported through `check`.
        let raw = unsafe {
            sys::rtcNewGeometry(device.inner.raw, sys::RTCGeometryType::RTC_GEOMETRY_TYPE_INSTANCE_ARRAY)
        };
        device.check()?;
        let array = Self { raw, device: device.clone(), _prototypes: prototypes.to_vec(), moving };
        let mut scenes: Vec<sys::RTCScene> = prototypes.iter().map(|p| p.raw()).collect();
        // SAFETY: `raw` is a valid instance array; Embree copies the scene handles (retaining
        // each) and `prototypes` keeps them alive too. The time step count is set before any
        // transform buffer.
        unsafe {
            sys::rtcSetGeometryInstancedScenes(array.raw, scenes.as_mut_ptr(), scenes.len());
            sys::rtcSetGeometryTimeStepCount(array.raw, if moving { 2 } else { 1 });
        }
        array.device.check()?;
        Ok(array)
    }

    /// Replaces every entry of a still array by matrices, and commits the geometry.
    pub fn set_still(&mut self, entries: &[ArrayEntry<Affine3A>]) -> Result<(), EmbreeError> {
        debug_assert!(!self.moving);
        if entries.iter().any(|(_, t)| !t.is_finite()) {
            return Err(EmbreeError::NonFiniteTransform);
        }
        let matrices: Vec<[f32; 12]> = entries.iter().map(|(_, t)| column_major_3x4(t)).collect();
        self.write(
            entries.iter().map(|e| e.0),
            &[(&matrices, sys::RTCFormat::RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR)],
        )
    }

    /// Replaces every entry of a moving array by its poses over the shutter (at ray times 0 and
    /// 1), and commits the geometry. An array holds one format: every entry's poses are
    /// matrices, or every entry's are rigid ([`EmbreeError::MixedPoses`] otherwise).
    pub fn set_moving(&mut self, entries: &[ArrayEntry<ShutterPoses>]) -> Result<(), EmbreeError> {
        debug_assert!(self.moving);
        if entries.iter().any(|(_, m)| !m.is_finite()) {
            return Err(EmbreeError::NonFiniteTransform);
        }
        let prototypes = || entries.iter().map(|e| e.0);
        if let Some(matrices) = entries.iter().map(|(_, m)| as_matrices(m)).collect::<Option<Vec<_>>>() {
            let open: Vec<_> = matrices.iter().map(|m| column_major_3x4(&m[0])).collect();
            let close: Vec<_> = matrices.iter().map(|m| column_major_3x4(&m[1])).collect();
            let format = sys::RTCFormat::RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR;
            return self.write(prototypes(), &[(&open, format), (&close, format)]);
        }
        let rigid = entries.iter().map(|(_, m)| as_rigid(m)).collect::<Option<Vec<_>>>();
        let rigid = rigid.ok_or(EmbreeError::MixedPoses)?;
        let open: Vec<_> = rigid.iter().map(|p| quaternion_decomposition(p[0])).collect();
        let close: Vec<_> = rigid.iter().map(|p| quaternion_decomposition(p[1])).collect();
        let format = sys::RTCFormat::RTC_FORMAT_QUATERNION_DECOMPOSITION;
        self.write(prototypes(), &[(&open, format), (&close, format)])
    }

    /// New Embree-owned buffers: the scene index of each entry and one transform buffer per
    /// time step (`T` one transform in `format`).
    fn write<T: Copy>(
        &mut self,
        prototypes: impl ExactSizeIterator<Item = Option<u32>>,
        steps: &[(&Vec<T>, sys::RTCFormat::Type)],
    ) -> Result<(), EmbreeError> {
        let n = prototypes.len();
        // SAFETY: `raw` is a valid instance array with `steps.len()` time steps; each buffer
        // Embree returns holds `n` items of the given stride (null on error, checked), and we
        // write exactly `n` items into it. `&mut self`: no ray traverses a scene holding the
        // geometry meanwhile (the parent's `SceneView` borrows the parent).
        unsafe {
            let ib = sys::rtcSetNewGeometryBuffer(
                self.raw,
                sys::RTCBufferType::RTC_BUFFER_TYPE_INDEX,
                0,
                sys::RTCFormat::RTC_FORMAT_UINT,
                4,
                n,
            ) as *mut u32;
            self.device.check()?;
            if !ib.is_null() {
                for (i, p) in prototypes.enumerate() {
                    ib.add(i).write(p.unwrap_or(sys::RTC_INVALID_GEOMETRY_ID));
                }
            }
            for (slot, (items, format)) in steps.iter().enumerate() {
                debug_assert_eq!(items.len(), n);
                let tb = sys::rtcSetNewGeometryBuffer(
                    self.raw,
                    sys::RTCBufferType::RTC_BUFFER_TYPE_TRANSFORM,
                    slot as u32,
                    *format,
                    std::mem::size_of::<T>(),
                    n,
                ) as *mut T;
                self.device.check()?;
                if !tb.is_null() {
                    std::ptr::copy_nonoverlapping(items.as_ptr(), tb, n);
                }
            }
            sys::rtcCommitGeometry(self.raw);
        }
        self.device.check()
    }
}

fn as_matrices(poses: &ShutterPoses) -> Option<[Affine3A; 2]> {
    match poses {
        ShutterPoses::Matrices(m) => Some(*m),
        ShutterPoses::Rigid(_) => None,
    }
}

fn as_rigid(poses: &ShutterPoses) -> Option<[(Quat, Vec3); 2]> {
    match poses {
        ShutterPoses::Rigid(r) => Some(*r),
        ShutterPoses::Matrices(_) => None,
    }
}
