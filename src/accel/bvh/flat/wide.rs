//! A 4-wide copy of a flat BVH for traversal: every 4-wide node tests its (up to) four children
//! in one go with glam's `Vec4` (SSE2 on x86-64, NEON on aarch64, scalar elsewhere; there is no
//! hand-written SIMD). Built by collapsing the binary tree, which stays the structure of record
//! (insertion, SAH, references into blocks); a binary node that was folded into its parent's
//! wide node is entered through its children.

use glam::Vec4;

use super::stack::TraversalStack;
use super::traverse::FAR_SCALE;
use super::{BoxRay, FlatBvh, STACK_SIZE};

/// Up to three entries are pushed per wide level, and a wide tree is no deeper than its binary
/// tree (shallower than [`STACK_SIZE`]).
const WIDE_STACK: usize = 3 * STACK_SIZE;

/// Slot code of an unused child.
const EMPTY: u32 = u32::MAX;
/// `map` entry of a binary node that has no wide node of its own.
const NONE: u32 = u32::MAX;

/// Four children's boxes in structure-of-arrays layout, plus what each child is.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(crate) struct Node4 {
    min: [[f32; 4]; 3],
    max: [[f32; 4]; 3],
    /// Interior child: wide node index. Leaf child: first primitive. Unused: [`EMPTY`].
    child: [u32; 4],
    /// Leaf child: primitive count; 0 for interior children.
    count: [u32; 4],
}

const _: () = assert!(std::mem::size_of::<Node4>() == 128);

/// The wide tree plus, for each binary node, the wide node rooted there (if any).
#[derive(Clone, Debug, Default)]
pub(crate) struct Wide {
    nodes: Vec<Node4>,
    map: Vec<u32>,
}

impl Wide {
    /// Collapses `bvh` (children of every node are gathered by repeatedly opening the largest
    /// interior child until there are four).
    pub fn new(bvh: &FlatBvh) -> Self {
        let mut w =
            Wide { nodes: Vec::with_capacity(bvh.nodes.len() / 3 + 1), map: vec![NONE; bvh.nodes.len()] };
        if !bvh.nodes.is_empty() {
            w.collapse(bvh, 0);
        }
        w
    }

    pub fn memory_bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<Node4>() + self.map.len() * 4
    }

    fn collapse(&mut self, bvh: &FlatBvh, n2: u32) -> u32 {
        let nodes = &bvh.nodes;
        let root = &nodes[n2 as usize];
        let mut kids: Vec<u32> = if root.is_leaf() { vec![n2] } else { vec![root.first, root.first + 1] };
        while kids.len() < 4 {
            let open = kids
                .iter()
                .enumerate()
                .filter(|(_, &k)| !nodes[k as usize].is_leaf())
                .max_by(|(_, &a), (_, &b)| {
                    let (a, b) =
                        (nodes[a as usize].aabb().surface_area(), nodes[b as usize].aabb().surface_area());
                    a.total_cmp(&b)
                })
                .map(|(i, _)| i);
            let Some(i) = open else { break };
            let k = kids.swap_remove(i);
            kids.extend([nodes[k as usize].first, nodes[k as usize].first + 1]);
        }
        let at = self.nodes.len();
        self.nodes.push(Node4 {
            min: [[f32::INFINITY; 4]; 3],
            max: [[f32::NEG_INFINITY; 4]; 3],
            child: [EMPTY; 4],
            count: [0; 4],
        });
        self.map[n2 as usize] = at as u32;
        for (slot, &k) in kids.iter().enumerate() {
            let n = &nodes[k as usize];
            let (child, count) = if n.is_leaf() { (n.first, n.count) } else { (self.collapse(bvh, k), 0) };
            let w = &mut self.nodes[at];
            for axis in 0..3 {
                w.min[axis][slot] = n.min[axis];
                w.max[axis][slot] = n.max[axis];
            }
            w.child[slot] = child;
            w.count[slot] = count;
        }
        at as u32
    }

    /// Like [`super::traverse`], for the subtree of binary node `root` of `bvh` (the tree this
    /// was collapsed from). Leaves are visited roughly nearer first.
    #[inline]
    pub fn traverse<F>(&self, bvh: &FlatBvh, root: u32, ray: &BoxRay, t_max: &mut f32, leaf: &mut F) -> bool
    where
        F: FnMut(u32, u32, &mut f32) -> bool,
    {
        let Some(&w) = self.map.get(root as usize) else {
            return false;
        };
        if w != NONE {
            return self.traverse4(w, ray, t_max, leaf);
        }
        // A binary node folded into its parent's wide node: enter through its children.
        let n = &bvh.nodes[root as usize];
        if ray.hit(n, *t_max) == f32::INFINITY {
            return false;
        }
        if n.is_leaf() {
            return leaf(n.first, n.count, t_max);
        }
        self.traverse(bvh, n.first, ray, t_max, leaf) || self.traverse(bvh, n.first + 1, ray, t_max, leaf)
    }

    #[inline]
    fn traverse4<F>(&self, root: u32, ray: &BoxRay, t_max: &mut f32, leaf: &mut F) -> bool
    where
        F: FnMut(u32, u32, &mut f32) -> bool,
    {
        let (ox, oy, oz) = (Vec4::splat(ray.org.x), Vec4::splat(ray.org.y), Vec4::splat(ray.org.z));
        let (ix, iy, iz) = (Vec4::splat(ray.inv.x), Vec4::splat(ray.inv.y), Vec4::splat(ray.inv.z));
        let t_min = Vec4::splat(ray.t_min);
        // Entries: wide node index, or `LEAF | (node << 2 | slot)` for a leaf child.
        const LEAF: u32 = 1 << 31;
        let mut stack = TraversalStack::<WIDE_STACK>::new();
        let mut cur = root;
        loop {
            if cur & LEAF == 0 {
                let n = &self.nodes[cur as usize];
                let tx0 = (Vec4::from_array(n.min[0]) - ox) * ix;
                let tx1 = (Vec4::from_array(n.max[0]) - ox) * ix;
                let ty0 = (Vec4::from_array(n.min[1]) - oy) * iy;
                let ty1 = (Vec4::from_array(n.max[1]) - oy) * iy;
                let tz0 = (Vec4::from_array(n.min[2]) - oz) * iz;
                let tz1 = (Vec4::from_array(n.max[2]) - oz) * iz;
                let near = tx0.min(tx1).max(ty0.min(ty1)).max(tz0.min(tz1)).max(t_min);
                let far =
                    (tx0.max(tx1).min(ty0.max(ty1)).min(tz0.max(tz1)) * FAR_SCALE).min(Vec4::splat(*t_max));
                let mut mask = near.cmple(far).bitmask();
                // Unused slots have inverted boxes, which an axis-parallel ray may not reject.
                for (slot, &c) in n.child.iter().enumerate() {
                    if c == EMPTY {
                        mask &= !(1 << slot);
                    }
                }
                // Push hit children farthest first so the nearest is taken next.
                let near = near.to_array();
                let mut hits = [(0u32, 0f32); 4];
                let mut k = 0;
                while mask != 0 {
                    let slot = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    let code =
                        if n.count[slot] > 0 { LEAF | (cur << 2) | slot as u32 } else { n.child[slot] };
                    // Insertion sort, descending by entry distance.
                    let mut j = k;
                    while j > 0 && hits[j - 1].1 < near[slot] {
                        hits[j] = hits[j - 1];
                        j -= 1;
                    }
                    hits[j] = (code, near[slot]);
                    k += 1;
                }
                if k > 0 {
                    for &(code, t) in &hits[..k - 1] {
                        stack.push(code, t);
                    }
                    cur = hits[k - 1].0;
                    continue;
                }
            } else {
                let (node, slot) = ((cur & !LEAF) >> 2, (cur & 3) as usize);
                let n = &self.nodes[node as usize];
                if leaf(n.child[slot], n.count[slot], t_max) {
                    return true;
                }
            }
            // The next entry still in front of the closest hit.
            match stack.pop_within(*t_max) {
                Some(c) => cur = c,
                None => return false,
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::super::{traverse, MeshBvh};
    use crate::accel::bvh::triangle::{RayTri, Tri};
    use crate::accel::bvh::BuildParams;
    use crate::geometry::Ray;

    fn closest_binary(m: &MeshBvh, root: u32, ray: &Ray) -> Option<f32> {
        let (b, rt) = (super::BoxRay::new(ray), RayTri::new(ray));
        let mut t_max = ray.t_max;
        let mut best = None;
        traverse(&m.bvh.nodes, root, &b, &mut t_max, |first, count, t_max| {
            for tri in &m.tris[first as usize..(first + count) as usize] {
                if let Some(h) = rt.intersect(&tri.p, *t_max) {
                    *t_max = h.t;
                    best = Some(h.t);
                }
            }
            false
        });
        best
    }

    #[test]
    fn wide_matches_binary_from_every_node() {
        let mut s = 7u32;
        let mut r = || {
            s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (s >> 8) as f32 / (1u32 << 24) as f32 * 2.0 - 1.0
        };
        let tris: Vec<Tri> = (0..2000)
            .map(|i| {
                let c = Vec3::new(r(), r(), r()) * 10.0;
                Tri { p: [c, c + Vec3::new(r(), r(), r()), c + Vec3::new(r(), r(), r())], geom: 0, prim: i }
            })
            .collect();
        let m = MeshBvh::build(tris, BuildParams::BALANCED);
        let rays: Vec<Ray> = (0..200)
            .map(|i| {
                let o = Vec3::new(r(), r(), r()) * 15.0;
                let mut d = Vec3::new(r(), r(), r()) * 10.0 - o * 0.5;
                if i % 7 == 0 {
                    d.y = 0.0;
                }
                Ray::new(o, d)
            })
            .collect();
        for root in (0..m.bvh.nodes.len() as u32).step_by(97).chain([0]) {
            for ray in &rays {
                let mut best = None;
                let mut t_max = ray.t_max;
                let (b, rt) = (super::BoxRay::new(ray), RayTri::new(ray));
                m.intersect_from(root, &b, &rt, &mut t_max, &mut best);
                assert_eq!(best.map(|h| h.t), closest_binary(&m, root, ray), "root {root}");
                assert_eq!(m.occluded_from(root, &b, &rt, ray.t_max), best.is_some());
            }
        }
    }
}
