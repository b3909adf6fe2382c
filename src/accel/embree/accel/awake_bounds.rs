//! [`AwakeBounds`]: the top level's bounds while the resting scene is in use, so that rays that
//! cannot meet an awake body skip the top level without a call into Embree.

use glam::Vec3A;

use crate::geometry::{Aabb, Ray};

/// Relative widening of the box and of each ray's float error: far more than rounding.
const SLACK: f32 = 1e-5;

/// A box prepared for a fast, conservative "may this ray meet it?" test.
#[derive(Clone, Copy, Debug)]
pub(super) struct AwakeBounds {
    lo: Vec3A,
    hi: Vec3A,
}

impl AwakeBounds {
    /// Meets nothing.
    pub const NONE: AwakeBounds = AwakeBounds { lo: Vec3A::INFINITY, hi: Vec3A::NEG_INFINITY };

    /// `b` widened by [`SLACK`] of its size and distance from the origin; `NONE` for an empty
    /// or non-finite box.
    pub fn new(b: Aabb) -> Self {
        if b.is_empty() || !b.min.is_finite() || !b.max.is_finite() {
            return Self::NONE;
        }
        let pad = SLACK * (b.min.abs().max(b.max.abs()).max_element() + b.extent().max_element());
        Self { lo: Vec3A::from(b.min) - pad, hi: Vec3A::from(b.max) + pad }
    }

    /// Whether `ray` may meet the box within `[ray.t_min, t_max]`. Never false for a ray that
    /// touches the box (some passing just outside come back true); true for a non-finite ray
    /// (Embree decides), false for `NONE`.
    ///
    /// First the box of the ray's segment (when `t_max` is finite: most rays are cut at a hit
    /// in the resting scene), which needs no division, then the slab test.
    #[inline]
    pub fn may_hit(&self, ray: &Ray, t_max: f32) -> bool {
        let (o, d) = (Vec3A::from(ray.origin), Vec3A::from(ray.dir));
        if self.lo.cmpgt(self.hi).any() {
            return false;
        }
        if !(o.is_finite() && d.is_finite()) {
            return true;
        }
        if t_max.is_finite() {
            let (a, b) = (o + d * ray.t_min, o + d * t_max);
            // The endpoints' rounding, with room to spare.
            let err = (o.abs() + (d * t_max).abs()) * SLACK;
            if (a.min(b) - err).cmpgt(self.hi).any() || (a.max(b) + err).cmplt(self.lo).any() {
                return false;
            }
        }
        // A zero direction component becomes the smallest normal float: its slab distances are
        // then huge but never `0 * inf = NaN`.
        let safe = Vec3A::select(d.cmpeq(Vec3A::ZERO), Vec3A::splat(f32::MIN_POSITIVE).copysign(d), d);
        let inv = safe.recip();
        let (t0, t1) = ((self.lo - o) * inv, (self.hi - o) * inv);
        let near = t0.min(t1).max_element().max(ray.t_min);
        let far = t0.max(t1).min_element() * (1.0 + 4.0 * f32::EPSILON);
        near <= far.min(t_max)
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    #[test]
    fn rays_that_touch_the_box_are_never_rejected() {
        let b = AwakeBounds::new(Aabb { min: Vec3::new(-1.0, 0.0, 2.0), max: Vec3::new(1.0, 0.5, 3.0) });
        // Through the middle, along a face, on an edge, at a corner, axis-parallel on a face,
        // from inside.
        let touching = [
            Ray::new(Vec3::new(0.0, 0.25, -5.0), Vec3::Z),
            Ray::new(Vec3::new(-1.0, 0.25, -5.0), Vec3::Z),
            Ray::new(Vec3::new(1.0, 0.5, -5.0), Vec3::Z),
            Ray::new(Vec3::new(-3.0, -2.0, 0.0), Vec3::new(2.0, 2.0, 2.0)),
            Ray::new(Vec3::new(0.0, 0.0, 2.5), Vec3::X),
            Ray::new(Vec3::new(0.0, 0.25, 2.5), Vec3::new(0.3, -0.1, 0.2)),
        ];
        for r in &touching {
            assert!(b.may_hit(r, f32::INFINITY), "{r:?}");
            assert!(b.may_hit(r, 1e3), "{r:?}, finite t_max");
        }
        let missing = [
            Ray::new(Vec3::new(0.0, 0.6, -5.0), Vec3::Z),
            Ray::new(Vec3::new(0.0, 0.25, -5.0), Vec3::NEG_Z),
            Ray::new(Vec3::new(2.0, 0.25, -5.0), Vec3::Z),
        ];
        for r in &missing {
            assert!(!b.may_hit(r, f32::INFINITY) && !b.may_hit(r, 1e3), "{r:?}");
        }
        // The interval counts: the box starts at t = 7.
        let r = Ray::new(Vec3::new(0.0, 0.25, -5.0), Vec3::Z);
        assert!(!b.may_hit(&r, 6.9) && b.may_hit(&r, 7.0));
        assert!(!AwakeBounds::NONE.may_hit(&r, f32::INFINITY) && !AwakeBounds::NONE.may_hit(&r, 10.0));
        assert!(b.may_hit(&Ray::new(Vec3::splat(f32::NAN), Vec3::Z), f32::INFINITY), "Embree decides");
    }
}
