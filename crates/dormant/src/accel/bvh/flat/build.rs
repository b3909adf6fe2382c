//! Binned SAH construction (Wald 2007), top-down, with the two halves of large ranges built in
//! parallel by rayon. Primitive boxes are partitioned in place (so passes read memory in
//! order). Ranges below the parallel threshold build their subtrees into arrays of their own,
//! depth-first with siblings adjacent; the parallel top is then walked once to place them.

use glam::{Vec3A, Vec4};
use rayon::prelude::*;

use super::{FlatBvh, Node, PAR_CHUNK};
use crate::accel::bvh::simd::truncate3;
use crate::accel::bvh::BuildParams;
use crate::geometry::Aabb;

/// Below this depth splits are chosen by SAH; deeper ranges are split at the object median,
/// which keeps every tree shallower than [`super::traverse::STACK_SIZE`].
const MAX_SAH_DEPTH: u32 = 48;

/// Box with SIMD-friendly corners; the builder's working type.
#[derive(Clone, Copy)]
struct Box3 {
    min: Vec3A,
    max: Vec3A,
}

impl Box3 {
    const EMPTY: Box3 = Box3 { min: Vec3A::splat(f32::INFINITY), max: Vec3A::splat(f32::NEG_INFINITY) };

    #[inline(always)]
    fn union(self, o: Box3) -> Box3 {
        Box3 { min: self.min.min(o.min), max: self.max.max(o.max) }
    }

    #[inline(always)]
    fn area(self) -> f32 {
        let e = (self.max - self.min).max(Vec3A::ZERO);
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    #[inline(always)]
    fn center2(self) -> Vec3A {
        self.min + self.max
    }

    fn aabb(self) -> Aabb {
        Aabb { min: self.min.into(), max: self.max.into() }
    }
}

/// A primitive as the builder moves it: its box, with its index in the `w` lane of `min`.
/// Ranges are partitioned in place, so every pass over a range reads memory in order.
#[derive(Clone, Copy)]
#[repr(C)]
struct PrimRef {
    min: Vec4,
    max: Vec4,
}

impl PrimRef {
    fn new(b: &Aabb, index: u32) -> Self {
        Self { min: b.min.extend(f32::from_bits(index)), max: b.max.extend(0.0) }
    }

    #[inline(always)]
    fn bounds(&self) -> Box3 {
        Box3 { min: Vec3A::from_vec4(self.min), max: Vec3A::from_vec4(self.max) }
    }

    fn index(&self) -> u32 {
        self.min.w.to_bits()
    }
}

/// Bounds of a range: of the boxes, and of their (doubled) centroids.
#[derive(Clone, Copy)]
struct RangeBounds {
    b: Box3,
    cb: Box3,
}

impl RangeBounds {
    const EMPTY: RangeBounds = RangeBounds { b: Box3::EMPTY, cb: Box3::EMPTY };

    #[inline(always)]
    fn add(&mut self, pb: Box3) {
        self.b = self.b.union(pb);
        let c = pb.center2();
        self.cb = Box3 { min: self.cb.min.min(c), max: self.cb.max.max(c) };
    }

    fn of(prims: &[PrimRef]) -> Self {
        let mut r = Self::EMPTY;
        for p in prims {
            r.add(p.bounds());
        }
        r
    }

    fn merge(self, o: Self) -> Self {
        RangeBounds { b: self.b.union(o.b), cb: self.cb.union(o.cb) }
    }
}

struct Ctx {
    p: BuildParams,
}

/// Builds a BVH over primitives with the given bounds (all finite and non-empty). Returns the
/// tree and the primitive order its leaves refer to: leaf range `i` covers primitives
/// `order[first..first + count]`.
pub(crate) fn build(bounds: &[Aabb], params: BuildParams) -> (FlatBvh, Vec<u32>) {
    build_with(bounds.len(), |i| bounds[i], params)
}

/// [`build`] over `n` primitives whose bounds `bounds_of` gives (read once each, in
/// parallel), without a vector of them.
pub(crate) fn build_with(
    n: usize,
    bounds_of: impl Fn(usize) -> Aabb + Sync,
    params: BuildParams,
) -> (FlatBvh, Vec<u32>) {
    if n == 0 {
        return (FlatBvh::default(), Vec::new());
    }
    let ctx = Ctx { p: params.sanitized() };
    let mut prims: Vec<PrimRef> = (0..n)
        .into_par_iter()
        .with_min_len(PAR_CHUNK)
        .map(|i| {
            let b = bounds_of(i);
            debug_assert!(!b.is_empty() && b.min.is_finite() && b.max.is_finite());
            PrimRef::new(&b, i as u32)
        })
        .collect();
    // Exact in any grouping (min and max).
    let rb =
        prims.par_chunks(PAR_CHUNK).map(RangeBounds::of).reduce(|| RangeBounds::EMPTY, RangeBounds::merge);
    let top = build_range(&ctx, &mut prims, rb, 0, 0);
    let order = prims.par_iter().with_min_len(PAR_CHUNK).map(PrimRef::index).collect();
    let mut nodes = Vec::with_capacity(top.node_count());
    nodes.push(Node::interior(Aabb::EMPTY, 0));
    top.place(&mut nodes, 0);
    (FlatBvh { nodes }, order)
}

/// A subtree as [`build_range`] leaves it: below the parallel threshold, its nodes in their
/// final order (depth-first, each interior node's children pair allocated when the node is
/// split, left subtree before right) with child indices relative to its root at 0; above it,
/// the split node's box and its two halves, built at once.
///
/// Subtrees build into arrays of their own, placed once at the end, not into one array of
/// `2n - 1` slots sized for the worst case: that array was mostly unused, yet spread so that
/// every page of it was touched (a good share of a scene load's page faults):
/// docs/lab/bvh-build.md#2026-12-02-where-the-builds-time-goes-in-a-fresh-process-node-slots-leaves-of-8
enum Subtree {
    Nodes(Vec<Node>),
    Split(Aabb, Box<(Subtree, Subtree)>),
}

impl Subtree {
    fn node_count(&self) -> usize {
        match self {
            Subtree::Nodes(nodes) => nodes.len(),
            Subtree::Split(_, halves) => 1 + halves.0.node_count() + halves.1.node_count(),
        }
    }

    /// Writes this subtree's root at `nodes[at]` and appends its descendants: the whole tree
    /// comes out depth-first, each node's children pair allocated when the node is visited,
    /// left subtree before right.
    fn place(&self, nodes: &mut Vec<Node>, at: usize) {
        match self {
            Subtree::Nodes(own) => {
                // `own[k]` goes to `nodes.len() + k - 1` for k >= 1, and every child index
                // is >= 1.
                let offset = (nodes.len() - 1) as u32;
                nodes[at] = shifted(own[0], offset);
                nodes.extend(own[1..].iter().map(|&n| shifted(n, offset)));
            }
            Subtree::Split(b, halves) => {
                let first = nodes.len();
                nodes[at] = Node::interior(*b, first as u32);
                nodes.extend([Node::interior(Aabb::EMPTY, 0); 2]);
                halves.0.place(nodes, first);
                halves.1.place(nodes, first + 1);
            }
        }
    }
}

/// Binning of one range: centroid bounds (doubled centroids, `min + max`) and the bin mapping.
struct Binning {
    cmin: Vec3A,
    scale: Vec3A,
    /// The last bin's index, as a float: scaled centroids are clamped to it before truncation.
    last: Vec3A,
    bins: usize,
}

impl Binning {
    /// `nb` bins over the centroid bounds `cb`; axes where the centroids coincide get scale 0.
    fn new(cb: &Box3, nb: usize) -> Self {
        let ext = cb.max - cb.min;
        let scale = Vec3A::select(
            ext.cmpgt(Vec3A::ZERO) & ext.is_finite_mask(),
            Vec3A::splat(nb as f32 * (1.0 - 1e-6)) / ext,
            Vec3A::ZERO,
        );
        Binning { cmin: cb.min, scale, last: Vec3A::splat((nb - 1) as f32), bins: nb }
    }

    /// The centroid of `b` in bin units: bin `k` covers `[k, k + 1)`, and every value is at
    /// least 0 (`cmin` is the least centroid, `scale` at least 0).
    #[inline(always)]
    fn scaled(&self, b: &Box3) -> Vec3A {
        (b.center2() - self.cmin) * self.scale
    }

    /// `bins_of(b)[axis]`, computed for that axis only.
    #[inline(always)]
    fn bin_on(&self, b: &Box3, axis: usize) -> usize {
        (self.scaled(b)[axis] as usize).min(self.bins - 1)
    }

    /// Partitions `prims` by `plane` (of this binning) into those whose bin on its axis is
    /// below its bin (`1..bins`) and the rest ([`partition`]); the sides' boxes are the
    /// plane's, from the bins. The test is `scaled < bin` rather than `bin_on < bin`: the
    /// same, since `trunc(x) < bin` exactly when `x < bin` for `x >= 0`, without the conversion.
    fn partition(&self, prims: &mut [PrimRef], plane: &Plane) -> (usize, RangeBounds, RangeBounds) {
        debug_assert!(plane.bin >= 1 && plane.bin < self.bins);
        let (axis, at) = (plane.axis, plane.bin as f32);
        let (k, left_cb, right_cb) = partition(prims, |b| self.scaled(b)[axis] < at);
        (k, RangeBounds { b: plane.left, cb: left_cb }, RangeBounds { b: plane.right, cb: right_cb })
    }

    /// The bin of `b` on each axis: clamped to the last bin, then truncated.
    #[inline(always)]
    fn bins_of(&self, b: &Box3) -> [usize; 3] {
        truncate3(self.scaled(b).min(self.last))
    }
}

/// Builds the subtree over `prims` (whose bounds are `rb`), which start at `start` in the
/// final order. The children's bounds come from the partition, so every level reads its
/// range twice (binning, partition) rather than three times. Ranges of at least the parallel
/// threshold build their two halves at once; the tree does not depend on the thread count.
fn build_range(ctx: &Ctx, prims: &mut [PrimRef], rb: RangeBounds, start: u32, depth: u32) -> Subtree {
    let n = prims.len();
    if n < ctx.p.parallel_threshold {
        // At most `2n - 1` nodes: the capacity is reserved, its pages touched only as used.
        let mut nodes = Vec::with_capacity(2 * n - 1);
        nodes.push(Node::interior(Aabb::EMPTY, 0));
        build_serial(ctx, prims, rb, start, depth, &mut nodes, 0);
        return Subtree::Nodes(nodes);
    }
    let Some((mid, lb, rbb)) = split(ctx, prims, &rb, depth) else {
        return Subtree::Nodes(vec![Node::leaf(rb.b.aabb(), start, n as u32)]);
    };
    debug_assert!(mid > 0 && mid < n);
    let (l, r) = prims.split_at_mut(mid);
    let rstart = start + mid as u32;
    let halves = rayon::join(
        || build_range(ctx, l, lb, start, depth + 1),
        || build_range(ctx, r, rbb, rstart, depth + 1),
    );
    Subtree::Split(rb.b.aabb(), Box::new(halves))
}

/// `n` with its children `offset` further on (a leaf's range does not move).
fn shifted(mut n: Node, offset: u32) -> Node {
    if !n.is_leaf() {
        n.first += offset;
    }
    n
}

/// [`build_range`] below the parallel threshold, into `nodes`: the subtree's root goes to
/// `nodes[at]`, each interior node's children pair is appended when the node is split, and
/// the left subtree is built before the right.
fn build_serial(
    ctx: &Ctx,
    prims: &mut [PrimRef],
    rb: RangeBounds,
    start: u32,
    depth: u32,
    nodes: &mut Vec<Node>,
    at: usize,
) {
    let Some((mid, lb, rbb)) = split(ctx, prims, &rb, depth) else {
        nodes[at] = Node::leaf(rb.b.aabb(), start, prims.len() as u32);
        return;
    };
    debug_assert!(mid > 0 && mid < prims.len());
    let first = nodes.len();
    nodes[at] = Node::interior(rb.b.aabb(), first as u32);
    nodes.extend([Node::interior(Aabb::EMPTY, 0); 2]);
    let (l, r) = prims.split_at_mut(mid);
    build_serial(ctx, l, lb, start, depth + 1, nodes, first);
    build_serial(ctx, r, rbb, start + mid as u32, depth + 1, nodes, first + 1);
}

/// Where to split `prims` (whose bounds are `rb`): the split point and both sides' bounds,
/// with `prims` partitioned; `None` for a leaf.
fn split(
    ctx: &Ctx,
    prims: &mut [PrimRef],
    rb: &RangeBounds,
    depth: u32,
) -> Option<(usize, RangeBounds, RangeBounds)> {
    let (n, p) = (prims.len(), &ctx.p);
    if n <= 1 {
        return None;
    }
    if depth >= MAX_SAH_DEPTH {
        let mid = median_split(prims, &rb.cb);
        return Some(split_at(prims, mid));
    }
    if n <= p.max_leaf_size && p.leaf_cost(n) <= p.traversal_cost {
        // Every split costs at least `traversal_cost`, and ties go to the leaf: the same
        // answer as binning the range, without the bins. What it saves, counted:
        // docs/lab/bvh-build.md#2026-12-07-the-build-ratios-regression-no-commit-added-work
        return None;
    }
    match best_split(ctx, prims, &rb.b, &rb.cb) {
        Some((plane, _)) if n <= p.max_leaf_size && p.leaf_cost(n) <= plane.cost => None,
        Some((plane, binning)) => Some(binning.partition(prims, &plane)),
        None if n <= p.max_leaf_size => None,
        None => Some(split_at(prims, n / 2)),
    }
}

/// `mid` and the bounds of the two sides of `prims` split there (the rare splits that do not
/// come from [`partition`]).
fn split_at(prims: &[PrimRef], mid: usize) -> (usize, RangeBounds, RangeBounds) {
    (mid, RangeBounds::of(&prims[..mid]), RangeBounds::of(&prims[mid..]))
}

/// A split plane: its SAH cost, its axis, the first bin of its right side, and the boxes of
/// both sides, unions of the bins' boxes (exact: the same as the boxes of the primitives
/// each side gets, so the partition need not compute them).
struct Plane {
    cost: f32,
    axis: usize,
    bin: usize,
    left: Box3,
    right: Box3,
}

/// The best plane over all axes and the binning it refers to, or `None` when every centroid
/// coincides. All three axes are binned in one pass over the range.
fn best_split(ctx: &Ctx, prims: &[PrimRef], b: &Box3, cb: &Box3) -> Option<(Plane, Binning)> {
    // Small ranges need few bins: clearing and sweeping them would cost more than binning.
    // Embree's rule, 4 + n / 20 (up to `bins`), built fastest for the same trace; other
    // divisors and 4 bins everywhere did not pay:
    // docs/lab/bvh-build.md#2026-12-02-embrees-bin-count-one-sse2-conversion-triangles-stored-once
    // nor an exact sweep of small ranges: docs/lab/bvh-build.md#2026-12-02-second-pass-branch-build2
    let nb = ctx.p.bins.min(4 + prims.len() / 20);
    if prims.len() == 2 {
        return best_split_pair(ctx, prims, b, cb);
    }
    match nb {
        0..=4 => best_split_n::<4>(ctx, prims, b, cb, nb),
        5..=8 => best_split_n::<8>(ctx, prims, b, cb, nb),
        9..=16 => best_split_n::<16>(ctx, prims, b, cb, nb),
        17..=32 => best_split_n::<32>(ctx, prims, b, cb, nb),
        _ => best_split_n::<64>(ctx, prims, b, cb, nb),
    }
}

/// [`best_split`] of two primitives (a good share of all calls), without the bins and sweeps it
/// would cost: the same answer (docs/lab/bvh-build.md#2026-12-02-the-binned-sah-builder-reworked-first-pass). However many bins, the two centroids fall in the first and
/// last bin of every axis where they differ, every plane costs the same, and the first axis
/// and plane win.
fn best_split_pair(ctx: &Ctx, prims: &[PrimRef], b: &Box3, cb: &Box3) -> Option<(Plane, Binning)> {
    let binning = Binning::new(cb, 4);
    let axis = (0..3).find(|&a| binning.scale[a] != 0.0)?;
    let (p0, p1) = (prims[0].bounds(), prims[1].bounds());
    let (lo, hi) = if binning.bin_on(&p0, axis) == 0 { (p0, p1) } else { (p1, p0) };
    debug_assert!(binning.bin_on(&lo, axis) == 0 && binning.bin_on(&hi, axis) > 0);
    // The sweep's `area * count` with counts of 1, exactly.
    let x = lo.area() + hi.area();
    let area = b.area().max(f32::MIN_POSITIVE);
    let cost = ctx.p.traversal_cost + ctx.p.intersection_cost * x / area;
    Some((Plane { cost, axis, bin: 1, left: lo, right: hi }, binning))
}

/// [`best_split`] with `nb <= N` bins in arrays of `N`.
fn best_split_n<const N: usize>(
    ctx: &Ctx,
    prims: &[PrimRef],
    b: &Box3,
    cb: &Box3,
    nb: usize,
) -> Option<(Plane, Binning)> {
    debug_assert!(nb <= N);
    let p = &ctx.p;
    let binning = Binning::new(cb, nb);
    let area = b.area().max(f32::MIN_POSITIVE);
    let block = p.leaf_block as u32;
    let mut bins = Bins::<N>::EMPTY;
    bins.add(prims, &binning);
    // Planes are compared by their unnormalised cost (left area * count + right area * count);
    // only the best is normalised, which saves a division per plane. The three axes are swept
    // side by side: three independent chains of box unions instead of one after the other.
    let n = prims.len() as u32;
    let (boxes, counts) = (&bins.boxes, &bins.counts);
    let mut right_cost = [[0.0f32; N]; 3];
    let (mut acc, mut acc_n) = ([Box3::EMPTY; 3], [0u32; 3]);
    for k in (1..nb).rev() {
        for axis in 0..3 {
            acc[axis] = acc[axis].union(boxes[axis][k]);
            acc_n[axis] += counts[axis][k];
            right_cost[axis][k] = acc[axis].area() * acc_n[axis].div_ceil(block) as f32;
        }
    }
    // Per axis the first best plane. A plane just right of an empty bin splits the range as
    // the plane before it does, at the same cost, so it never wins (ties keep the first); planes
    // with an empty side are not splits (every plane of an axis whose centroids coincide).
    let mut best = [(f32::INFINITY, 0usize); 3];
    let (mut left, mut left_n) = ([Box3::EMPTY; 3], [0u32; 3]);
    for k in 1..nb {
        for axis in 0..3 {
            left[axis] = left[axis].union(boxes[axis][k - 1]);
            left_n[axis] += counts[axis][k - 1];
            let cost = left[axis].area() * left_n[axis].div_ceil(block) as f32 + right_cost[axis][k];
            let valid = left_n[axis] > 0 && left_n[axis] < n;
            if valid && (best[axis].1 == 0 || cost < best[axis].0) {
                best[axis] = (cost, k);
            }
        }
    }
    let mut pick: Option<(f32, usize, usize)> = None;
    for (axis, &(c, k)) in best.iter().enumerate() {
        if k > 0 && pick.is_none_or(|(pc, _, _)| c < pc) {
            pick = Some((c, axis, k));
        }
    }
    let (c, axis, bin) = pick?;
    let union = |bins: &[Box3]| bins.iter().fold(Box3::EMPTY, |acc, &b| acc.union(b));
    let (left, right) = (union(&boxes[axis][..bin]), union(&boxes[axis][bin..nb]));
    Some((Plane { cost: p.traversal_cost + p.intersection_cost * c / area, axis, bin, left, right }, binning))
}

/// Ranges at least twice this long are binned in two halves at once (exact: bins merge by
/// min/max and sums, so the result does not depend on the split).
const PAR_BIN_CHUNK: usize = 16 * 1024;

/// Per axis, the box and count of every bin.
struct Bins<const N: usize> {
    boxes: [[Box3; N]; 3],
    counts: [[u32; N]; 3],
}

impl<const N: usize> Bins<N> {
    const EMPTY: Self = Bins { boxes: [[Box3::EMPTY; N]; 3], counts: [[0u32; N]; 3] };

    /// Adds `prims` to the bins. In place: returning the bins by value copied them, a `memcpy`
    /// per node: docs/lab/bvh-build.md#2026-12-02-the-binned-sah-builder-reworked-first-pass
    fn add(&mut self, prims: &[PrimRef], binning: &Binning) {
        if prims.len() >= 2 * PAR_BIN_CHUNK {
            let (l, r) = prims.split_at(prims.len() / 2);
            let mut b = Self::EMPTY;
            rayon::join(|| self.add(l, binning), || b.add(r, binning));
            self.merge(&b);
            return;
        }
        // Two sets of bins filled side by side (even and odd primitives, merged at the end), so
        // that neighbours in the same bins do not wait for each other's stores, built no faster
        // than one: docs/lab/bvh-build.md#2026-12-02-second-pass-branch-build2
        for pr in prims {
            self.add_one(pr, binning);
        }
    }

    #[inline(always)]
    fn add_one(&mut self, pr: &PrimRef, binning: &Binning) {
        let pb = pr.bounds();
        for (axis, k) in binning.bins_of(&pb).into_iter().enumerate() {
            self.boxes[axis][k] = self.boxes[axis][k].union(pb);
            self.counts[axis][k] += 1;
        }
    }

    /// Adds `b`'s contents (exact: boxes merge by min/max, counts by sums).
    fn merge(&mut self, b: &Self) {
        for axis in 0..3 {
            for k in 0..N {
                self.boxes[axis][k] = self.boxes[axis][k].union(b.boxes[axis][k]);
                self.counts[axis][k] += b.counts[axis][k];
            }
        }
    }
}

/// Splits at the object median along the longest centroid axis.
fn median_split(prims: &mut [PrimRef], cb: &Box3) -> usize {
    let axis = (cb.max - cb.min).max_position();
    let mid = prims.len() / 2;
    prims.select_nth_unstable_by(mid, |a, b| {
        a.bounds().center2()[axis].total_cmp(&b.bounds().center2()[axis])
    });
    mid
}

/// In-place partition; returns how many elements satisfy `left` and the bounds of both sides'
/// (doubled) centroids (every element is tested once, and counted on its side then; the
/// sides' boxes come from the bins). Branch-free (Lomuto: each element swaps with the first
/// right one, which moves on when it went left): which side an element goes is close to
/// random, so a branch on it could not be predicted.
/// Both sides' bounds are indexed by the side: kept in registers and updated through selects
/// instead, they doubled the min/max work and built slower:
/// docs/lab/bvh-build.md#2026-12-02-embrees-bin-count-one-sse2-conversion-triangles-stored-once
fn partition(prims: &mut [PrimRef], left: impl Fn(&Box3) -> bool) -> (usize, Box3, Box3) {
    let mut sides = [Box3::EMPTY; 2];
    let mut k = 0;
    for i in 0..prims.len() {
        let p = prims[i];
        let b = p.bounds();
        let l = left(&b);
        let (side, c) = (&mut sides[usize::from(!l)], b.center2());
        *side = Box3 { min: side.min.min(c), max: side.max.max(c) };
        prims[i] = prims[k];
        prims[k] = p;
        k += usize::from(l);
    }
    let [left_cb, right_cb] = sides;
    (k, left_cb, right_cb)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::bvh::testing;
    use glam::Vec3;

    /// Greatest root-to-leaf depth (root = 0), which the traversal stack must exceed.
    fn depth(bvh: &FlatBvh, node: u32) -> u32 {
        let n = &bvh.nodes[node as usize];
        if n.is_leaf() {
            0
        } else {
            1 + depth(bvh, n.first).max(depth(bvh, n.first + 1))
        }
    }

    #[test]
    fn builds_valid_trees() {
        let mut bounds = Vec::new();
        let mut s = 1u32;
        for _ in 0..10_000 {
            s = s.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            let p = Vec3::new((s % 1000) as f32, ((s >> 10) % 1000) as f32, ((s >> 20) % 1000) as f32);
            bounds.push(Aabb::from_points([p, p + Vec3::ONE]));
        }
        // Many coincident boxes as well.
        bounds.extend(std::iter::repeat_n(Aabb::from_points([Vec3::ZERO, Vec3::ONE]), 500));
        for p in [BuildParams::FAST, BuildParams::BALANCED, BuildParams::QUALITY] {
            let (bvh, order) = build(&bounds, p);
            let tree = testing::BuiltTree {
                nodes: bvh.nodes.iter().map(|n| (n.aabb(), n.first, n.count)).collect(),
                order,
            };
            testing::check_built_tree(&tree, &bounds).unwrap();
            assert!(depth(&bvh, 0) < super::super::traverse::STACK_SIZE as u32);
        }
    }
}
