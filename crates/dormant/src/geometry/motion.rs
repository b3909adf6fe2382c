//! Rigid motion over a camera shutter (motion blur): a [`RigidTransform`] at shutter open and
//! one at close, interpolated at a ray's time as Embree interpolates quaternion motion
//! transforms (rtcSetGeometryTransformQuaternion(3)): translation linearly, rotation by slerp
//! along the shorter arc. Both backends and the per-frame shutter poses use this one
//! interpolation, so they agree.

use glam::{Affine3A, Quat, Vec3};

use super::Aabb;

/// A rotation followed by a translation (a body's pose).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigidTransform {
    pub rotation: Quat,
    pub translation: Vec3,
}

impl RigidTransform {
    pub fn to_affine(&self) -> Affine3A {
        Affine3A::from_rotation_translation(self.rotation, self.translation)
    }

    /// `a` at `s = 0`, `b` at `s = 1`: translation lerped, rotation slerped (shorter arc).
    pub(crate) fn interpolate(a: &Self, b: &Self, s: f32) -> Self {
        Self {
            rotation: a.rotation.slerp(b.rotation, s).normalize(),
            translation: a.translation.lerp(b.translation, s),
        }
    }

    pub(crate) fn is_finite(&self) -> bool {
        self.rotation.is_finite() && self.translation.is_finite()
    }
}

/// An instance's motion over the shutter: ray time 0 sees it at `open`, time 1 at `close`,
/// times between at the interpolation of the two ([`RigidTransform::interpolate`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InstanceMotion {
    pub open: RigidTransform,
    pub close: RigidTransform,
}

/// Pieces the shutter interval is cut into when bounding a rotating instance
/// ([`InstanceMotion::bounds`]).
const BOUND_STEPS: u32 = 8;

impl InstanceMotion {
    /// The transform at ray time `time` (clamped to `[0, 1]`).
    pub fn at(&self, time: f32) -> RigidTransform {
        RigidTransform::interpolate(&self.open, &self.close, time.clamp(0.0, 1.0))
    }

    /// The rotation's normal matrix at `time` (a rotation is its own inverse transpose); Embree's
    /// hits need it, the Rust BVH's carry their normal.
    #[cfg(feature = "embree")]
    pub(crate) fn normal_matrix_at(&self, time: f32) -> glam::Mat3 {
        glam::Mat3::from_quat(self.at(time).rotation)
    }

    pub(crate) fn is_finite(&self) -> bool {
        self.open.is_finite() && self.close.is_finite()
    }

    /// The angle (radians) the rotation turns through from open to close: 0 for a pure
    /// translation. From the sine of the half angle, which stays precise for tiny angles
    /// (the cosine, the quaternions' dot product, rounds to 1 below about 7e-4).
    pub(crate) fn rotation_angle(&self) -> f32 {
        if self.open.rotation == self.close.rotation {
            return 0.0;
        }
        let turn = self.close.rotation * self.open.rotation.inverse();
        2.0 * turn.xyz().length().min(1.0).asin()
    }

    /// A box holding `local` (object space) at every time of the shutter. A pure translation
    /// moves the box linearly, so the union of its two end boxes is exact. With a rotation,
    /// the union of the boxes at `BOUND_STEPS + 1` evenly spaced times, grown by the farthest
    /// any point of the object can travel between two of them: at most a step's share of the
    /// translation plus the arc (angle times radius) the farthest corner sweeps.
    pub(crate) fn bounds(&self, local: &Aabb) -> Aabb {
        if local.is_empty() {
            return *local;
        }
        let (a, b) = (self.open.to_affine(), self.close.to_affine());
        let ends = local.transformed(&a).union(local.transformed(&b));
        let angle = self.rotation_angle();
        if angle == 0.0 {
            return ends;
        }
        let radius = local.min.abs().max(local.max.abs()).length();
        let travel = (self.close.translation - self.open.translation).length() + angle * radius;
        let pad = travel / BOUND_STEPS as f32;
        let sampled = (1..BOUND_STEPS)
            .map(|i| local.transformed(&self.at(i as f32 / BOUND_STEPS as f32).to_affine()))
            .fold(ends, Aabb::union);
        Aabb { min: sampled.min - Vec3::splat(pad), max: sampled.max + Vec3::splat(pad) }
    }
}
