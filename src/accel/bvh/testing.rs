//! BVH internals the property tests (`tests/bvh_props.rs`, `tests/bvh_common/`) reach into:
//! not part of dormant's API, hidden from its documentation (`#[doc(hidden)]` on the module
//! rather than a cargo feature, so that `cargo test` builds the library as `cargo build`
//! does and the two never rebuild it in turn).
#![doc(hidden)]

use glam::Vec3;

use super::triangle::{RayTri, Tri, Tri4};
use super::{BvhAccel, StaticBvh};
use crate::geometry::Ray;

/// `(t, u, v)` of `ray` hitting triangle `p` by the backend's own watertight test, within the
/// ray's interval: the exact reference for static geometry.
pub fn watertight_hit(ray: &Ray, p: &[Vec3; 3]) -> Option<(f32, f32, f32)> {
    RayTri::new(ray).intersect(p, ray.t_max).map(|h| (h.t, h.u, h.v))
}

/// The 4-triangle packet test on `tris` (1 to 4 triangles, packed as the BVH packs a leaf):
/// the closest lane hit within the ray's interval, as `(lane, t, u, v)`.
pub fn watertight_hit4(ray: &Ray, tris: &[[Vec3; 3]]) -> Option<(usize, f32, f32, f32)> {
    assert!(!tris.is_empty() && tris.len() <= 4);
    let tris: Vec<Tri> =
        tris.iter().enumerate().map(|(i, p)| Tri { p: *p, geom: 0, prim: i as u32 }).collect();
    let q = Tri4::pack(&tris, 0);
    RayTri::new(ray).intersect4(&q, ray.t_max).map(|(lane, h)| (q.idx[lane] as usize, h.t, h.u, h.v))
}

/// Checks the persistent tree's invariants (O(n)): overlay bounds, masks and heights match
/// their children, every live mesh's triangles are reachable exactly once, nothing else is,
/// and the traversal view matches the tree.
pub fn check_static_tree(tree: &StaticBvh) -> Result<(), String> {
    tree.check_invariants()
}

/// [`check_static_tree`] on the committed static tree of `accel`.
pub fn check_static_tree_of(accel: &BvhAccel) -> Result<(), String> {
    accel.static_tree().check_invariants()
}
