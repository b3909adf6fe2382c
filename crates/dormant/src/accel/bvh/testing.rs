//! Test-only views of the BVH's internals for the accelerator's property tests
//! (`accel/tests/`): the watertight triangle and leaf tests as references, and the flat builder
//! on bare boxes. Compiled only for tests.

use glam::Vec3;

use super::simd::{dispatch, Kernel, SimdPath};
use super::triangle::{RayTri, Tri, Tri4};
use super::BuildParams;
use crate::geometry::{Aabb, Ray};

/// `(t, u, v)` of `ray` hitting triangle `p` by the backend's own watertight test, within the
/// ray's interval: the exact reference for static geometry.
pub(crate) fn watertight_hit(ray: &Ray, p: &[Vec3; 3]) -> Option<(f32, f32, f32)> {
    RayTri::new(ray).intersect(p, ray.t_max).map(|h| (h.t, h.u, h.v))
}

/// A leaf's test on `tris` (packed into packets of four as the BVH packs a leaf) on the SIMD
/// path `path` (which this CPU must run): the closest triangle hit within the ray's interval,
/// as `(index in tris, t, u, v)`, and whether the any-hit test found one.
pub(crate) fn watertight_hit_leaf(
    ray: &Ray,
    tris: &[[Vec3; 3]],
    path: SimdPath,
) -> (Option<(usize, f32, f32, f32)>, bool) {
    assert!(!tris.is_empty());
    let tris: Vec<Tri> =
        tris.iter().enumerate().map(|(i, p)| Tri { p: *p, geom: 0, prim: i as u32 }).collect();
    let idx: Vec<u32> = (0..tris.len() as u32).collect();
    let packets: Vec<Tri4> = idx.chunks(4).map(|c| Tri4::pack(&tris, c)).collect();
    let rt = RayTri::new(ray);
    SimdPath::with_override(path, || {
        let closest = dispatch!(|k| k.closest_tri(&rt, &packets, ray.t_max));
        let occluded = dispatch!(|k| k.occluded_tri(&rt, &packets, ray.t_max));
        (closest.map(|(i, h)| (packets[i / 4].idx[i % 4] as usize, h.t, h.u, h.v)), occluded)
    })
}

/// A binned-SAH tree over boxes as [`build_tree`] returns it: each node's bounds, its first
/// child (interior) or first primitive (leaf), and its primitive count (0 for interior nodes),
/// plus the primitive order the leaves index.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct BuiltTree {
    pub(crate) nodes: Vec<(Aabb, u32, u32)>,
    pub(crate) order: Vec<u32>,
}

/// The flat BVH builder on `bounds` (each finite and non-empty), in the current rayon pool.
pub(crate) fn build_tree(bounds: &[Aabb], params: BuildParams) -> BuiltTree {
    let (bvh, order) = super::flat::build(bounds, params);
    BuiltTree { nodes: bvh.nodes.iter().map(|n| (n.aabb(), n.first, n.count)).collect(), order }
}

/// Checks a [`BuiltTree`] over `bounds`: interior nodes are the union of their adjacent
/// children, leaves contain their primitives' boxes, and every primitive is in one leaf.
pub(crate) fn check_built_tree(tree: &BuiltTree, bounds: &[Aabb]) -> Result<(), String> {
    let mut seen = vec![false; bounds.len()];
    let mut order_seen = vec![false; bounds.len()];
    for &o in &tree.order {
        match order_seen.get_mut(o as usize) {
            Some(s) if !*s => *s = true,
            _ => return Err(format!("order names primitive {o} twice or out of range")),
        }
    }
    for (i, &(b, first, count)) in tree.nodes.iter().enumerate() {
        if count > 0 {
            for k in first..first + count {
                let o = *tree.order.get(k as usize).ok_or(format!("leaf {i} past the order"))?;
                if std::mem::replace(&mut seen[o as usize], true) {
                    return Err(format!("primitive {o} in two leaves"));
                }
                let pb = bounds[o as usize];
                if !(b.min.cmple(pb.min).all() && b.max.cmpge(pb.max).all()) {
                    return Err(format!("leaf {i} does not contain primitive {o}"));
                }
            }
        } else {
            let kids =
                tree.nodes.get(first as usize..first as usize + 2).ok_or(format!("node {i}: bad child"))?;
            if first as usize <= i || kids[0].0.union(kids[1].0) != b {
                return Err(format!("node {i} is not the union of its children"));
            }
        }
    }
    match seen.iter().position(|s| !s) {
        Some(o) => Err(format!("primitive {o} in no leaf")),
        None => Ok(()),
    }
}
