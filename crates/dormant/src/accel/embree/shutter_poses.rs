//! When a moving instance's two poses go to Embree as matrices (lerped, bounded in closed
//! form) rather than rigid poses (slerped, bounded by a root search at every commit): dormant's
//! policy over the wrapper's [`ShutterPoses`].

use dormant_embree::ShutterPoses;
use glam::Vec3;

use crate::geometry::InstanceMotion;

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
/// the translation's magnitude; docs/crosscheck.md). On the atrium most of the moving
/// instances' motions over the shutter turn by less than 2e-3 rad.
///
/// Beyond the angle, quaternions at two time steps: the instances that turn further as
/// matrices at more time steps (up to 16, no segment turning by more than this) made Embree's
/// blurred commit slower for the same trace:
/// docs/lab/motion-blur.md#2026-12-02-the-angle-scaled-by-the-instances-distance-from-the-origin
const LERP_MAX_ANGLE: f32 = 2e-3;

/// Whether `motion` of an instance whose points lie within `radius` of its origin goes to
/// Embree as two matrices (lerped) rather than two quaternion decompositions (slerped): it
/// turns by at most [`LERP_MAX_ANGLE`] times `sqrt(max(reach, radius) / radius)`, `reach` a
/// lower bound on its translation's largest coordinate over the shutter. The lerp then moves
/// its points by at most 5e-7 `max(reach, radius)`.
pub fn lerps_as_matrices(motion: &InstanceMotion, radius: f32) -> bool {
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

/// `motion` as Embree takes it for an instance whose points lie within `radius` of its origin:
/// two matrices when it [lerps as matrices](lerps_as_matrices), else two rigid poses.
pub fn shutter_poses(motion: &InstanceMotion, radius: f32) -> ShutterPoses {
    if lerps_as_matrices(motion, radius) {
        ShutterPoses::Matrices([motion.open.to_affine(), motion.close.to_affine()])
    } else {
        ShutterPoses::Rigid([motion.open, motion.close].map(|t| (t.rotation, t.translation)))
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
