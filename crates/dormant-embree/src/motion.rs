//! How instance transforms reach Embree: the FLOAT3X4 column-major matrix layout, the
//! quaternion decomposition of a rigid pose, and a moving instance's two poses over the
//! shutter ([`ShutterPoses`]). Used by single instances ([`super::InstanceGeometry`]) and
//! instance arrays alike.

use embree4_sys as sys;
use glam::{Affine3A, Quat, Vec3};

/// A moving instance's poses at ray times 0 and 1 (shutter open and close), in the form
/// Embree interpolates them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ShutterPoses {
    /// Two matrices, which Embree lerps and bounds in closed form.
    Matrices([Affine3A; 2]),
    /// Two rigid poses (rotation, then translation), which Embree slerps; bounding that motion
    /// costs it a root search per box corner and axis at every commit.
    Rigid([(Quat, Vec3); 2]),
}

impl ShutterPoses {
    /// Whether every number in the poses is finite.
    pub fn is_finite(&self) -> bool {
        match self {
            ShutterPoses::Matrices(m) => m.iter().all(Affine3A::is_finite),
            ShutterPoses::Rigid(p) => p.iter().all(|(q, t)| q.is_finite() && t.is_finite()),
        }
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

/// Embree's decomposition of a rigid pose: unit scale, no skew or shift, the rotation as a
/// quaternion (`r` the real part) and the translation.
pub(super) fn quaternion_decomposition((q, p): (Quat, Vec3)) -> sys::RTCQuaternionDecomposition {
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
