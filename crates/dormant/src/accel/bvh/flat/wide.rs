//! An 8-wide copy of a flat BVH for traversal: every wide node tests its (up to) eight children
//! in one go with the SIMD path's box kernel ([`crate::accel::bvh::simd::Kernel`]: AVX2 or
//! AVX-512 intrinsics, or glam's `Vec4` in two halves on the portable path), boxes in
//! structure-of-arrays layout, children visited nearest first (closest hits) or in slot order
//! (any-hit queries: [`Wide::traverse`]). Built by collapsing the binary tree, which
//! stays the structure of record (insertion, SAH, references into blocks); a binary node that
//! was folded into its parent's wide node is entered through its children.
//!
//! Leaves keep the owner's meaning with the range remapped at collapse: triangle meshes point
//! leaves at their 4-triangle packets ([`crate::accel::bvh::triangle::Tri4`]), instance levels
//! at their items.
//!
//! Width 8 measured against the former 4-wide nodes:
//! docs/lab/accelerators.md#2026-12-02-simd-paths-8-wide-nodes-four-triangle-leaves-avx2-avx-512-portable

use super::stack::TraversalStack;
use super::{BoxRay, FlatBvh, Node, STACK_SIZE};
use crate::accel::bvh::simd::{BoxRay8, Boxes8, Kernel};

/// Children per wide node.
pub(crate) const WIDTH: usize = 8;

/// Up to seven entries are pushed per wide level, and a wide tree is no deeper than its binary
/// tree (shallower than [`STACK_SIZE`]).
pub(super) const WIDE_STACK: usize = (WIDTH - 1) * STACK_SIZE;

/// [`Wide::traverse`]'s order for closest-hit queries: each node's hit children nearer first.
pub(crate) const CLOSEST_HIT: bool = true;
/// [`Wide::traverse`]'s order for any-hit queries: each node's hit children in slot order.
pub(crate) const ANY_HIT: bool = false;

/// Slot code of an unused child.
const EMPTY: u32 = u32::MAX;
/// `map` entry of a binary interior node that has no wide node of its own.
const NONE: u32 = u32::MAX;
/// Stack code of a leaf child: `LEAF | node << 3 | slot`.
pub(super) const LEAF: u32 = 1 << 31;
/// Stack code of a binary leaf entered on its own (folded into its parent's wide node, reached
/// by entering a folded subtree): `FOLDED | binary node`.
const FOLDED: u32 = LEAF | 1 << 30;

/// What a traversal does at the leaves it reaches ([`Wide::visit`]), and which children it
/// enters of those its box tests let through.
pub(crate) trait Visitor {
    /// Visits leaf items `first..first + count`; may lower `t_max`; returns `true` to stop.
    fn leaf(&mut self, first: u32, count: u32, t_max: &mut f32) -> bool;

    /// Of wide node `w`'s children, those that may be entered: bit `i` for slot `i` (the
    /// change index turns away subtrees whose changes all lie outside the frames it seeks).
    #[inline(always)]
    fn allow(&self, _w: u32) -> u32 {
        u32::MAX
    }
}

/// A leaf closure of [`Wide::traverse`]: every child is entered.
struct EveryChild<'a, F>(&'a mut F);

impl<F: FnMut(u32, u32, &mut f32) -> bool> Visitor for EveryChild<'_, F> {
    #[inline(always)]
    fn leaf(&mut self, first: u32, count: u32, t_max: &mut f32) -> bool {
        (self.0)(first, count, t_max)
    }
}

/// Where a traversal starts: a binary node of the tree, and whether its box is still to be
/// tested.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Start {
    /// The ray enters the node only if it enters its box (a tree's root).
    Test(u32),
    /// The caller has entered the node's box already, or one around it: the static tree's
    /// overlay leaf that names a block subtree has that subtree's box, so testing it again
    /// would only repeat a box test per block entered. An instance's prototype is entered once
    /// its level has tested the instance's world box: its object-space box is tighter, but
    /// testing it too turned away too few rays to pay.
    Entered(u32),
}

impl Start {
    /// The binary node the traversal starts at.
    #[inline(always)]
    pub(crate) fn node(self) -> u32 {
        match self {
            Start::Test(n) | Start::Entered(n) => n,
        }
    }
}

/// Eight children's boxes in structure-of-arrays layout, plus what each child is.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(crate) struct Node8 {
    pub(super) boxes: Boxes8,
    /// Interior child: wide node index. Leaf child: first leaf item. Unused: [`EMPTY`].
    pub(super) child: [u32; WIDTH],
    /// Leaf child: item count; 0 for interior children.
    pub(super) count: [u16; WIDTH],
    /// Bit `i` set when slot `i` is used (unused slots have inverted boxes, which an
    /// axis-parallel ray may not reject).
    pub(super) used: u32,
}

const _: () = assert!(std::mem::size_of::<Node8>() == 256);

/// The wide tree plus, for each binary node, where traversal enters it.
#[derive(Clone, Debug, Default)]
pub(crate) struct Wide {
    pub(super) nodes: Vec<Node8>,
    /// Per binary node: `(w, 0)` for the wide node `w` rooted there, `(first, count)` for a
    /// leaf (remapped), `(NONE, 0)` for an interior node folded into its parent's wide node.
    pub(super) map: Vec<(u32, u32)>,
}

impl Wide {
    /// Collapses `bvh` (children of every node are gathered by repeatedly opening the largest
    /// interior child until there are eight). `leaf` maps a binary leaf to the item range the
    /// traversal hands out for it.
    pub(crate) fn new(bvh: &FlatBvh, leaf: impl Fn(u32, &Node) -> (u32, u32)) -> Self {
        let mut w = Wide {
            nodes: Vec::with_capacity(bvh.nodes.len() / 6 + 1),
            map: bvh
                .nodes
                .iter()
                .enumerate()
                .map(|(i, n)| if n.is_leaf() { leaf(i as u32, n) } else { (NONE, 0) })
                .collect(),
        };
        debug_assert!(w.map.iter().all(|&(x, c)| c < u32::from(u16::MAX) && (c > 0 || x == NONE)));
        if bvh.nodes.first().is_some_and(|n| !n.is_leaf()) {
            w.collapse(bvh, 0);
        }
        w
    }

    pub(crate) fn memory_bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<Node8>() + self.map.len() * 8
    }

    fn collapse(&mut self, bvh: &FlatBvh, n2: u32) -> u32 {
        let nodes = &bvh.nodes;
        let root = &nodes[n2 as usize];
        // Fixed arrays, not a `Vec`: one allocation per wide node showed in build profiles. Each
        // child's area is computed once, when it joins (`None`: a leaf, never opened).
        let area = |k: u32| {
            let n = &nodes[k as usize];
            (!n.is_leaf()).then(|| n.aabb().surface_area())
        };
        let mut kids = [0u32; WIDTH];
        let mut areas = [None; WIDTH];
        (kids[0], kids[1]) = (root.first, root.first + 1);
        (areas[0], areas[1]) = (area(kids[0]), area(kids[1]));
        let mut len = 2;
        while len < WIDTH {
            // The interior child of largest area (the last of equals).
            let mut open: Option<(usize, f32)> = None;
            for (i, a) in areas[..len].iter().enumerate() {
                if let Some(a) = *a {
                    if open.is_none_or(|(_, b)| a.total_cmp(&b).is_ge()) {
                        open = Some((i, a));
                    }
                }
            }
            let Some((i, _)) = open else { break };
            // `swap_remove` then push both children, as the `Vec` did (same slot order).
            let k = kids[i];
            (kids[i], areas[i]) = (kids[len - 1], areas[len - 1]);
            (kids[len - 1], kids[len]) = (nodes[k as usize].first, nodes[k as usize].first + 1);
            (areas[len - 1], areas[len]) = (area(kids[len - 1]), area(kids[len]));
            len += 1;
        }
        let kids = &kids[..len];
        let at = self.nodes.len();
        // Stack codes hold `at << 3` below the `LEAF` and `FOLDED` bits.
        debug_assert!(at < 1 << 27, "wide tree too large for its stack codes");
        self.nodes.push(Node8 {
            boxes: Boxes8 { min: [[f32::INFINITY; WIDTH]; 3], max: [[f32::NEG_INFINITY; WIDTH]; 3] },
            child: [EMPTY; WIDTH],
            count: [0; WIDTH],
            used: 0,
        });
        self.map[n2 as usize] = (at as u32, 0);
        for (slot, &k) in kids.iter().enumerate() {
            let n = &nodes[k as usize];
            let (child, count) = if n.is_leaf() { self.map[k as usize] } else { (self.collapse(bvh, k), 0) };
            let w = &mut self.nodes[at];
            for axis in 0..3 {
                w.boxes.min[axis][slot] = n.min[axis];
                w.boxes.max[axis][slot] = n.max[axis];
            }
            w.child[slot] = child;
            w.count[slot] = count as u16;
            w.used |= 1 << slot;
        }
        at as u32
    }

    /// Visits the leaves of the subtree `root` of `bvh` (the tree this was collapsed from)
    /// that the ray may hit. `leaf` gets each leaf's item range and the current `t_max`, which
    /// it lowers on hits; it returns `true` to stop (any-hit). Returns whether `leaf` stopped
    /// the traversal.
    ///
    /// `NEAREST_FIRST` ([`CLOSEST_HIT`]): each node's hit children are visited nearer first.
    /// Otherwise ([`ANY_HIT`], for queries whose `leaf` stops at the first hit) they are
    /// visited in slot order, unsorted, as Embree's `occluded` does: a query that stops at
    /// any hit gains nothing from the order, and skipping the sort saves instructions and
    /// mispredictions (measured:
    /// docs/lab/accelerators.md#2026-12-03-box-rows-folded-into-the-subtraction-any-hit-unsorted-instances-entered-once-cachegrind).
    ///
    /// `leaf` is called from one place only: a closure called once is inlined into the query's
    /// `#[target_feature]` entry (`simd::dispatch!`), and with it the kernel of nested
    /// traversals (instances, blocks); called from two places it stays out of line and every
    /// intrinsic in it becomes a call.
    #[inline(always)]
    pub(crate) fn traverse<K: Kernel, F, const NEAREST_FIRST: bool>(
        &self,
        k: K,
        bvh: &FlatBvh,
        root: Start,
        ray: &BoxRay,
        t_max: &mut f32,
        leaf: &mut F,
    ) -> bool
    where
        F: FnMut(u32, u32, &mut f32) -> bool,
    {
        self.visit::<K, _, NEAREST_FIRST>(k, bvh, root, ray, t_max, &mut EveryChild(leaf))
    }

    /// [`Self::traverse`] with a [`Visitor`], which may also turn away children their boxes
    /// let through.
    #[inline(always)]
    pub(crate) fn visit<K: Kernel, V: Visitor, const NEAREST_FIRST: bool>(
        &self,
        k: K,
        bvh: &FlatBvh,
        root: Start,
        ray: &BoxRay,
        t_max: &mut f32,
        leaf: &mut V,
    ) -> bool {
        let mut stack = TraversalStack::<(u32, f32), WIDE_STACK>::new();
        // The last entry found is visited first, straight from here: a root with a wide node
        // of its own (most traversals) never goes through the stack.
        let mut first = None;
        self.enter(
            bvh,
            root,
            ray.t_min,
            |n| {
                let t = ray.hit(n, *t_max);
                (t < f32::INFINITY).then_some(t)
            },
            |code, t| {
                if let Some(earlier) = first.replace((code, t)) {
                    stack.push(earlier);
                }
            },
        );
        // Entered within `t_max` (the test's far bound), which nothing lowered since.
        let Some((first, _)) = first else {
            return false;
        };
        self.traverse8::<K, V, NEAREST_FIRST>(k, &mut stack, first, ray, t_max, leaf)
    }

    /// Where a traversal of the subtree `root` starts. Binary nodes folded into a wide node
    /// are entered through their children: at most `WIDTH` of them are pending at once (the
    /// folded part of one wide node). Each wide node or leaf found there that `test` enters
    /// goes to `push` with its stack code and what `test` returned; a root the caller has
    /// [`Start::Entered`] is not tested and goes with `entered`.
    #[inline(always)]
    pub(super) fn enter<T: Copy>(
        &self,
        bvh: &FlatBvh,
        root: Start,
        entered: T,
        mut test: impl FnMut(&Node) -> Option<T>,
        mut push: impl FnMut(u32, T),
    ) {
        let node = root.node();
        // The common case first (a tree's root, an instance's prototype, a block subtree):
        // `root` has a wide node of its own, and the pending list is neither zeroed nor walked
        // (zeroing it at every traversal was a measurable share of the trace's instructions).
        let Some(&(x, count)) = self.map.get(node as usize) else {
            return;
        };
        let n = &bvh.nodes[node as usize];
        let root_t = match root {
            Start::Test(_) => test(n),
            Start::Entered(_) => Some(entered),
        };
        let Some(root_t) = root_t else {
            return;
        };
        if count > 0 {
            push(FOLDED | node, root_t);
            return;
        }
        if x != NONE {
            push(x, root_t);
            return;
        }
        // An interior node folded into its parent's wide node: its descendants are tested.
        let mut pending = [0u32; 2 * WIDTH];
        (pending[0], pending[1]) = (n.first + 1, n.first);
        let mut np = 2;
        while np > 0 {
            np -= 1;
            let r = pending[np];
            let Some(&(x, count)) = self.map.get(r as usize) else {
                continue;
            };
            let n = &bvh.nodes[r as usize];
            let Some(t) = test(n) else {
                continue;
            };
            if count > 0 {
                push(FOLDED | r, t);
            } else if x != NONE {
                push(x, t);
            } else {
                debug_assert!(np + 2 <= pending.len());
                pending[np] = n.first + 1;
                pending[np + 1] = n.first;
                np += 2;
            }
        }
    }

    /// The node loop of [`Self::traverse`], from its first entry `first`: each node's
    /// hit children sorted farthest first, all but the nearest pushed, the nearest taken next
    /// (`NEAREST_FIRST`), or the first in slot order taken and the others pushed.
    ///
    /// The sort and the pushes are most of a node's instructions, yet every way tried to cut
    /// them (fast paths for one or two hit children, children inserted into place on the
    /// stack or pushed in one copy, prefetching pushed children, octant child order) counted
    /// or timed no better. Octant order counted fewer instructions and timed slower on primary
    /// rays, so time a retry as well as counting it. Each variant and its measurements:
    /// docs/lab/accelerators.md#2026-12-04-where-the-accelerator-targets-end-target-by-target
    #[inline(always)]
    fn traverse8<K: Kernel, V: Visitor, const NEAREST_FIRST: bool>(
        &self,
        k: K,
        // By reference: moving the 7 KiB stack would copy it.
        stack: &mut TraversalStack<(u32, f32), WIDE_STACK>,
        first: u32,
        ray: &BoxRay,
        t_max: &mut f32,
        leaf: &mut V,
    ) -> bool {
        let kr = k.prepare(&BoxRay8 { org: ray.org.into(), inv: ray.inv.into(), t_min: ray.t_min });
        let mut cur = first;
        // The hit children of the current node, sorted; only `hits[..m]` of this node is read.
        // Made once per traversal: zeroing it per node cost instructions at every node:
        // docs/lab/accelerators.md#2026-12-03-redundant-box-tests-and-stack-round-trips-removed-cachegrind
        let mut hits = [(0u32, 0f32); WIDTH];
        loop {
            if cur & LEAF == 0 {
                let n = &self.nodes[cur as usize];
                let (mask, near) = k.box8(&kr, &n.boxes, *t_max);
                let mut mask = mask & n.used & leaf.allow(cur);
                if mask != 0 {
                    if !NEAREST_FIRST {
                        // Any-hit: the first hit child next, the others pushed as found.
                        let slot = mask.trailing_zeros() as usize;
                        mask &= mask - 1;
                        let next = n.code(cur, slot);
                        while mask != 0 {
                            let slot = mask.trailing_zeros() as usize;
                            mask &= mask - 1;
                            stack.push((n.code(cur, slot), near[slot]));
                        }
                        cur = next;
                        continue;
                    }
                    // Hit children sorted farthest first: all but the last are pushed, the
                    // last (nearest) is taken next (the variants tried: above).
                    let mut m = 0;
                    while mask != 0 {
                        let slot = mask.trailing_zeros() as usize;
                        mask &= mask - 1;
                        let code = n.code(cur, slot);
                        // Insertion sort, descending by entry distance. At most eight children
                        // are hit, so `j < WIDTH`; `% WIDTH` says so to the compiler, which
                        // otherwise checks both indices in the inner loop.
                        let mut j = m;
                        while j > 0 && hits[(j - 1) % WIDTH].1 < near[slot] {
                            hits[j % WIDTH] = hits[(j - 1) % WIDTH];
                            j -= 1;
                        }
                        hits[j % WIDTH] = (code, near[slot]);
                        m += 1;
                    }
                    for &(code, t) in &hits[..m - 1] {
                        stack.push((code, t));
                    }
                    cur = hits[m - 1].0;
                    continue;
                }
            } else {
                let (first, count) = self.leaf_range(cur);
                // The only call of `leaf` (see `traverse`).
                if leaf.leaf(first, count, t_max) {
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

/// A child of a wide node: another wide node, or a leaf's item range (first, count).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum WideChild {
    Node(u32),
    Leaf(u32, u32),
}

impl Wide {
    /// Wide nodes, each after its parent.
    pub(crate) fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// The used children of wide node `w`, by slot.
    pub(crate) fn children(&self, w: u32) -> impl Iterator<Item = (usize, WideChild)> + '_ {
        let n = &self.nodes[w as usize];
        (0..WIDTH).filter(move |&slot| n.used & (1 << slot) != 0).map(move |slot| {
            let child = match n.count[slot] {
                0 => WideChild::Node(n.child[slot]),
                count => WideChild::Leaf(n.child[slot], u32::from(count)),
            };
            (slot, child)
        })
    }

    /// The item range of the leaf with stack code `code` (`LEAF` or `FOLDED`).
    #[inline(always)]
    pub(super) fn leaf_range(&self, code: u32) -> (u32, u32) {
        if code & FOLDED == FOLDED {
            self.map[(code & !FOLDED) as usize]
        } else {
            let (node, slot) = ((code & !LEAF) >> 3, (code & 7) as usize);
            let n = &self.nodes[node as usize];
            (n.child[slot], u32::from(n.count[slot]))
        }
    }
}

impl Node8 {
    /// The stack code of child `slot` of this node, wide node `at`: its wide node, or `LEAF`
    /// with the node and slot.
    #[inline(always)]
    pub(super) fn code(&self, at: u32, slot: usize) -> u32 {
        // A select, not a branch: whether a child is a leaf follows no pattern a predictor
        // learns (a branch here was a good share of a render's mispredictions):
        // docs/lab/accelerators.md#2026-12-02-counted-instead-of-timed-cachegrind-instance-records-child-codes
        std::hint::select_unpredictable(
            self.count[slot] > 0,
            LEAF | (at << 3) | slot as u32,
            self.child[slot],
        )
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::super::{traverse, MeshBvh};
    use super::Start;
    use crate::accel::bvh::simd::{dispatch, SimdPath};
    use crate::accel::bvh::triangle::{RayTri, Tri};
    use crate::accel::bvh::BuildParams;
    use crate::geometry::Ray;

    fn closest_binary(m: &MeshBvh, root: u32, ray: &Ray) -> Option<f32> {
        let (b, rt) = (super::BoxRay::new(ray), RayTri::new(ray));
        let mut t_max = ray.t_max;
        let mut best = None;
        traverse(&m.bvh.nodes, root, &b, &mut t_max, |first, count, t_max| {
            for tri in m.leaf_tris(first, count) {
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
    fn wide_matches_binary_from_every_node_on_every_path() {
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
        for params in [BuildParams::BALANCED, BuildParams::FAST] {
            let m = MeshBvh::build(tris.clone(), params);
            for path in SimdPath::supported() {
                SimdPath::with_override(path, || {
                    for root in (0..m.bvh.nodes.len() as u32).step_by(97).chain([0, 1, 2, 3, 4, 5]) {
                        for ray in &rays {
                            let mut best = None;
                            let mut t_max = ray.t_max;
                            let (b, rt) = (super::BoxRay::new(ray), RayTri::new(ray));
                            dispatch!(|k| m.intersect_from(
                                k,
                                Start::Test(root),
                                &b,
                                &rt,
                                &mut t_max,
                                &mut best
                            ));
                            assert_eq!(
                                best.map(|h| h.t),
                                closest_binary(&m, root, ray),
                                "root {root} {path:?}"
                            );
                            let occluded =
                                dispatch!(|k| m.occluded_from(k, Start::Test(root), &b, &rt, ray.t_max));
                            assert_eq!(occluded, best.is_some());
                        }
                    }
                });
            }
        }
    }
}
