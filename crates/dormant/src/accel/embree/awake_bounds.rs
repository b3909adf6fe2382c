//! [`AwakeBounds`]: a few boxes around the top level's instances while the resting scene is in
//! use, so that rays that cannot meet an awake body skip the top level without a call into
//! Embree.
//!
//! A ray is tested against the box around all of them first, then against grid cells, up to
//! [`MAX_BOXES`], each bounding the instances inside it: one box alone skips little when the
//! awake bodies are spread out (a few collapsing structures far apart span the scene), and
//! more cells, or no box around all first, cost rays as much as they save:
//! docs/lab/accelerators.md#2026-12-01-how-rays-meet-the-resting-level-the-bvhs-order-embrees-skipped-top-level

use glam::{UVec3, Vec3, Vec3A};

use crate::geometry::{Aabb, Ray};

/// Relative widening of the box and of each ray's float error: far more than rounding.
const SLACK: f32 = 1e-5;

/// Most boxes a ray is tested against after the box around all.
const MAX_BOXES: usize = 8;

/// Boxes around the top level's instances.
#[derive(Clone, Debug)]
pub(super) struct AwakeBounds {
    /// Around all of them: rays that miss it need no other test.
    all: AwakeBox,
    boxes: Vec<AwakeBox>,
}

impl AwakeBounds {
    /// Meets nothing.
    pub(crate) const NONE: AwakeBounds = AwakeBounds { all: AwakeBox::NONE, boxes: Vec::new() };

    /// The box around the world bounds `instances`, and inside it: each one if there are at
    /// most [`MAX_BOXES`], else the occupied cells of a 4x4x4 (or, if more than [`MAX_BOXES`]
    /// are occupied, 2x2x2) grid over their union, each cell bounding the instances whose
    /// centre lies in it. A non-finite box gives one box that meets every ray alone: Embree
    /// decides.
    pub(crate) fn around(instances: &[Aabb]) -> Self {
        let union = instances.iter().fold(Aabb::EMPTY, |a, b| a.union(*b));
        if union.is_empty() {
            return Self::NONE;
        }
        if !union.min.is_finite() || !union.max.is_finite() {
            return Self { all: AwakeBox::EVERYWHERE, boxes: Vec::new() };
        }
        let all = AwakeBox::new(union);
        if instances.len() <= MAX_BOXES {
            return Self { all, boxes: instances.iter().map(|b| AwakeBox::new(*b)).collect() };
        }
        for n in [4u32, 2] {
            let cells = grid_cells(instances, union, n);
            if cells.len() <= MAX_BOXES {
                return Self { all, boxes: cells.into_iter().map(AwakeBox::new).collect() };
            }
        }
        unreachable!("a 2x2x2 grid has at most 8 cells")
    }

    /// Whether `ray` may meet an instance within `[ray.t_min, t_max]` (see
    /// [`AwakeBox::may_hit`]): the box around all, then the boxes inside it.
    #[inline]
    pub(crate) fn may_hit(&self, ray: &Ray, t_max: f32) -> bool {
        self.all.may_hit(ray, t_max)
            && (self.boxes.is_empty() || self.boxes.iter().any(|b| b.may_hit(ray, t_max)))
    }
}

/// The bounds of `instances` grouped by the cell of an `n`x`n`x`n` grid over `all` that holds
/// each one's centre; occupied cells only.
fn grid_cells(instances: &[Aabb], all: Aabb, n: u32) -> Vec<Aabb> {
    let size = all.extent().max(Vec3::splat(f32::MIN_POSITIVE));
    let mut cells = vec![Aabb::EMPTY; (n * n * n) as usize];
    for b in instances {
        let rel = (b.center() - all.min) / size * n as f32;
        let c = rel.as_uvec3().min(UVec3::splat(n - 1));
        let i = ((c.z * n + c.y) * n + c.x) as usize;
        cells[i] = cells[i].union(*b);
    }
    cells.retain(|c| !c.is_empty());
    cells
}

/// A box prepared for a fast, conservative "may this ray meet it?" test.
#[derive(Clone, Copy, Debug)]
struct AwakeBox {
    lo: Vec3A,
    hi: Vec3A,
}

impl AwakeBox {
    /// Meets nothing.
    const NONE: AwakeBox = AwakeBox { lo: Vec3A::INFINITY, hi: Vec3A::NEG_INFINITY };
    /// Meets every ray ([`AwakeBox::new`] gives `NONE` for a non-finite box).
    const EVERYWHERE: AwakeBox = AwakeBox { lo: Vec3A::NEG_INFINITY, hi: Vec3A::INFINITY };

    /// `b` widened by [`SLACK`] of its size and distance from the origin; `NONE` for an empty
    /// or non-finite box.
    pub(crate) fn new(b: Aabb) -> Self {
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
    pub(crate) fn may_hit(&self, ray: &Ray, t_max: f32) -> bool {
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
        let b = AwakeBox::new(Aabb { min: Vec3::new(-1.0, 0.0, 2.0), max: Vec3::new(1.0, 0.5, 3.0) });
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
        assert!(!AwakeBox::NONE.may_hit(&r, f32::INFINITY) && !AwakeBox::NONE.may_hit(&r, 10.0));
        assert!(!AwakeBounds::NONE.may_hit(&r, f32::INFINITY));
        assert!(b.may_hit(&Ray::new(Vec3::splat(f32::NAN), Vec3::Z), f32::INFINITY), "Embree decides");
    }
}

#[cfg(test)]
mod grouping_tests {
    use glam::Vec3;

    use super::*;

    fn cube(at: Vec3) -> Aabb {
        Aabb { min: at - 0.5, max: at + 0.5 }
    }

    #[test]
    fn spread_groups_get_their_own_boxes_and_every_instance_is_covered() {
        // Two clusters of 40 bodies at opposite corners of a 100-unit scene.
        let mut bodies: Vec<Aabb> = (0..40).map(|i| cube(Vec3::new(i as f32 * 0.1, 0.0, 0.0))).collect();
        bodies.extend((0..40).map(|i| cube(Vec3::new(100.0, 0.0, 100.0 + i as f32 * 0.1))));
        let b = AwakeBounds::around(&bodies);
        assert!(b.boxes.len() == 2, "{} boxes", b.boxes.len());
        // A ray between the clusters misses both; rays at each body meet a box.
        assert!(!b.may_hit(&Ray::new(Vec3::new(50.0, 10.0, 50.0), Vec3::NEG_Y), f32::INFINITY));
        for body in &bodies {
            let r = Ray::new(body.center() + Vec3::Y * 10.0, Vec3::NEG_Y);
            assert!(b.may_hit(&r, f32::INFINITY), "{body:?}");
        }
    }

    #[test]
    fn scattered_bodies_fall_back_to_a_coarse_grid() {
        let bodies: Vec<Aabb> = (0..512)
            .map(|i| cube(Vec3::new((i % 8) as f32, ((i / 8) % 8) as f32, (i / 64) as f32) * 10.0))
            .collect();
        let b = AwakeBounds::around(&bodies);
        assert_eq!(b.boxes.len(), 8);
        assert!(!AwakeBounds::around(&[]).may_hit(&Ray::new(Vec3::ZERO, Vec3::X), f32::INFINITY));
    }

    #[test]
    fn a_body_with_non_finite_bounds_leaves_every_ray_to_embree() {
        let far = Aabb { min: Vec3::splat(f32::NEG_INFINITY), max: Vec3::splat(1.0) };
        let b = AwakeBounds::around(&[cube(Vec3::ZERO), far]);
        for (o, d) in [(Vec3::splat(50.0), Vec3::Y), (Vec3::new(-3.0, 7.0, 2.0), Vec3::NEG_X)] {
            assert!(b.may_hit(&Ray::new(o, d), f32::INFINITY) && b.may_hit(&Ray::new(o, d), 1.0));
        }
    }
}
