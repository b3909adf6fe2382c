//! Stack-based traversal of a flattened BVH: precomputed inverse direction, slab test with a
//! conservative far bound (Ize 2013) so the box test never rejects a ray the watertight triangle
//! test would accept, and nearer child first by entry distance. The slab test uses glam's
//! `Vec3A` (SSE2 where available, scalar elsewhere); there is no hand-written SIMD.

use glam::{Vec3, Vec3A};

use super::Node;
use crate::accel::bvh::simd::FAR_SCALE;
use crate::geometry::Ray;

/// Traversal stack entries; deeper than any tree the builder makes (its depth is bounded by
/// the object-median fallback).
pub(crate) const STACK_SIZE: usize = 128;

/// Whether the ray's `[t_min, t_max]` is a usable interval (false for NaN bounds).
#[inline]
pub(crate) fn interval_is_valid(ray: &Ray) -> bool {
    ray.t_min <= ray.t_max
}

/// A ray prepared for slab tests.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BoxRay {
    pub org: Vec3A,
    /// `1 / dir`, with zero components replaced by `±1 / f32::MIN_POSITIVE` so that no slab
    /// distance is ever `0 * inf = NaN` (a finite origin on a slab plane gives 0, not NaN).
    pub(crate) inv: Vec3A,
    pub t_min: f32,
}

impl BoxRay {
    pub(crate) fn new(ray: &Ray) -> Self {
        let safe = |d: f32| if d == 0.0 { f32::MIN_POSITIVE.copysign(d) } else { d };
        let dir = Vec3A::new(safe(ray.dir.x), safe(ray.dir.y), safe(ray.dir.z));
        Self { org: ray.origin.into(), inv: dir.recip(), t_min: ray.t_min }
    }

    /// Entry distance into the node's box within `[t_min, t_max]`, or `+inf` on a miss.
    #[inline(always)]
    pub(crate) fn hit(&self, n: &Node, t_max: f32) -> f32 {
        self.hit_bounds(n.min, n.max, t_max)
    }

    /// [`Self::hit`] for a box given by its corners.
    #[inline(always)]
    pub(crate) fn hit_bounds(&self, min: Vec3, max: Vec3, t_max: f32) -> f32 {
        let t0 = (Vec3A::from(min) - self.org) * self.inv;
        let t1 = (Vec3A::from(max) - self.org) * self.inv;
        let near = t0.min(t1).max_element().max(self.t_min);
        let far = (t0.max(t1).min_element() * FAR_SCALE).min(t_max);
        // False for NaN (a non-finite origin): a miss.
        if near <= far {
            near
        } else {
            f32::INFINITY
        }
    }
}

/// Visits the leaves of the subtree at `root` that the ray may hit, nearer first. `leaf` gets
/// each leaf's primitive range and the current `t_max`, which it lowers on hits; it returns
/// `true` to stop (any-hit). Returns whether `leaf` stopped the traversal.
///
/// Rays traverse the [`super::Wide`] copies; this binary walk is the reference the wide
/// traversal is tested against.
#[cfg(test)]
pub(crate) fn traverse<F>(nodes: &[Node], root: u32, ray: &BoxRay, t_max: &mut f32, mut leaf: F) -> bool
where
    F: FnMut(u32, u32, &mut f32) -> bool,
{
    let Some(root_node) = nodes.get(root as usize) else {
        return false;
    };
    if ray.hit(root_node, *t_max) == f32::INFINITY {
        return false;
    }
    let mut stack = super::stack::TraversalStack::<(u32, f32), STACK_SIZE>::new();
    let mut node = root_node;
    loop {
        if node.is_leaf() {
            if leaf(node.first, node.count, t_max) {
                return true;
            }
        } else {
            let a = node.first as usize;
            let (na, nb) = (&nodes[a], &nodes[a + 1]);
            let ta = ray.hit(na, *t_max);
            let tb = ray.hit(nb, *t_max);
            match (ta < f32::INFINITY, tb < f32::INFINITY) {
                (true, true) => {
                    let (near, far, tfar) = if ta <= tb { (na, a + 1, tb) } else { (nb, a, ta) };
                    stack.push((far as u32, tfar));
                    node = near;
                    continue;
                }
                (true, false) => {
                    node = na;
                    continue;
                }
                (false, true) => {
                    node = nb;
                    continue;
                }
                (false, false) => {}
            }
        }
        // The next subtree still in front of the closest hit.
        match stack.pop_within(*t_max) {
            Some(i) => node = &nodes[i as usize],
            None => return false,
        }
    }
}
