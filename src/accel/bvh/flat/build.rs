//! Binned SAH construction (Wald 2007), top-down, with the two halves of large ranges built in
//! parallel by rayon. Builds an intermediate pointer tree, then flattens it so siblings are
//! adjacent.

use glam::Vec3A;

use super::{FlatBvh, Node};
use crate::accel::bvh::BuildParams;
use crate::geometry::Aabb;

/// Below this depth splits are chosen by SAH; deeper ranges are split at the object median,
/// which keeps every tree shallower than [`super::traverse::STACK_SIZE`].
const MAX_SAH_DEPTH: u32 = 48;

enum BuildNode {
    Leaf { b: Aabb, start: u32, count: u32 },
    Inner { b: Aabb, kids: Box<[BuildNode; 2]> },
}

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

struct Ctx {
    prims: Vec<Box3>,
    p: BuildParams,
}

/// Builds a BVH over primitives with the given bounds (all finite and non-empty). Returns the
/// tree and the primitive order its leaves refer to: leaf range `i` covers primitives
/// `order[first..first + count]`.
pub(crate) fn build(bounds: &[Aabb], params: BuildParams) -> (FlatBvh, Vec<u32>) {
    debug_assert!(bounds.iter().all(|b| !b.is_empty() && b.min.is_finite() && b.max.is_finite()));
    let mut order: Vec<u32> = (0..bounds.len() as u32).collect();
    if bounds.is_empty() {
        return (FlatBvh::default(), order);
    }
    let ctx = Ctx {
        prims: bounds.iter().map(|b| Box3 { min: b.min.into(), max: b.max.into() }).collect(),
        p: params.sanitized(),
    };
    let root = build_range(&ctx, &mut order, 0, 0);
    let mut nodes = Vec::with_capacity(2 * bounds.len().div_ceil(2));
    nodes.push(Node::interior(Aabb::EMPTY, 0));
    flatten(&root, 0, &mut nodes);
    (FlatBvh { nodes }, order)
}

fn flatten(n: &BuildNode, at: usize, nodes: &mut Vec<Node>) {
    match n {
        BuildNode::Leaf { b, start, count } => nodes[at] = Node::leaf(*b, *start, *count),
        BuildNode::Inner { b, kids } => {
            let first = nodes.len();
            nodes.push(Node::interior(Aabb::EMPTY, 0));
            nodes.push(Node::interior(Aabb::EMPTY, 0));
            nodes[at] = Node::interior(*b, first as u32);
            flatten(&kids[0], first, nodes);
            flatten(&kids[1], first + 1, nodes);
        }
    }
}

/// Binning of one range: centroid bounds (doubled centroids, `min + max`) and the bin mapping.
struct Binning {
    cmin: Vec3A,
    scale: Vec3A,
    bins: usize,
}

impl Binning {
    #[inline(always)]
    fn bins_of(&self, b: &Box3) -> [usize; 3] {
        let k = (b.center2() - self.cmin) * self.scale;
        let last = self.bins - 1;
        [(k.x as usize).min(last), (k.y as usize).min(last), (k.z as usize).min(last)]
    }
}

fn build_range(ctx: &Ctx, idx: &mut [u32], start: u32, depth: u32) -> BuildNode {
    let mut b = Box3::EMPTY;
    let mut cb = Box3::EMPTY;
    for &i in idx.iter() {
        let pb = ctx.prims[i as usize];
        b = b.union(pb);
        let c = pb.center2();
        cb = Box3 { min: cb.min.min(c), max: cb.max.max(c) };
    }
    let n = idx.len();
    let leaf = || BuildNode::Leaf { b: b.aabb(), start, count: n as u32 };
    if n <= 1 {
        return leaf();
    }
    let p = &ctx.p;
    let mid = if depth >= MAX_SAH_DEPTH {
        median_split(ctx, idx, &cb)
    } else {
        match best_split(ctx, idx, &b, &cb) {
            Some((cost, axis, bin, binning)) => {
                let leaf_cost = p.intersection_cost * n as f32;
                if n <= p.max_leaf_size && leaf_cost <= cost {
                    return leaf();
                }
                partition(idx, |i| binning.bins_of(&ctx.prims[i as usize])[axis] < bin)
            }
            None if n <= p.max_leaf_size => return leaf(),
            None => n / 2,
        }
    };
    debug_assert!(mid > 0 && mid < n);
    let (l, r) = idx.split_at_mut(mid);
    let rstart = start + mid as u32;
    let (a, c) = if n >= p.parallel_threshold {
        rayon::join(|| build_range(ctx, l, start, depth + 1), || build_range(ctx, r, rstart, depth + 1))
    } else {
        (build_range(ctx, l, start, depth + 1), build_range(ctx, r, rstart, depth + 1))
    };
    BuildNode::Inner { b: b.aabb(), kids: Box::new([a, c]) }
}

/// Best (cost, axis, first bin of the right side, binning) over all axes, or `None` when
/// every centroid coincides. All three axes are binned in one pass over the range.
fn best_split(ctx: &Ctx, idx: &[u32], b: &Box3, cb: &Box3) -> Option<(f32, usize, usize, Binning)> {
    // Small ranges need few bins: clearing and sweeping them would cost more than binning.
    let nb = ctx.p.bins.min(2 * idx.len()).max(4);
    match nb {
        0..=8 => best_split_n::<8>(ctx, idx, b, cb, nb),
        9..=16 => best_split_n::<16>(ctx, idx, b, cb, nb),
        17..=32 => best_split_n::<32>(ctx, idx, b, cb, nb),
        _ => best_split_n::<64>(ctx, idx, b, cb, nb),
    }
}

/// [`best_split`] with `nb <= N` bins in arrays of `N`.
fn best_split_n<const N: usize>(
    ctx: &Ctx,
    idx: &[u32],
    b: &Box3,
    cb: &Box3,
    nb: usize,
) -> Option<(f32, usize, usize, Binning)> {
    debug_assert!(nb <= N);
    let p = &ctx.p;
    let ext = cb.max - cb.min;
    let scale = Vec3A::select(
        ext.cmpgt(Vec3A::ZERO) & ext.is_finite_mask(),
        Vec3A::splat(nb as f32 * (1.0 - 1e-6)) / ext,
        Vec3A::ZERO,
    );
    let binning = Binning { cmin: cb.min, scale, bins: nb };
    let area = b.area().max(f32::MIN_POSITIVE);
    let mut boxes = [[Box3::EMPTY; N]; 3];
    let mut counts = [[0u32; N]; 3];
    for &i in idx {
        let pb = &ctx.prims[i as usize];
        let k = binning.bins_of(pb);
        for axis in 0..3 {
            boxes[axis][k[axis]] = boxes[axis][k[axis]].union(*pb);
            counts[axis][k[axis]] += 1;
        }
    }
    let mut best: Option<(f32, usize, usize)> = None;
    for axis in 0..3 {
        if scale[axis] == 0.0 {
            continue;
        }
        let (boxes, counts) = (&boxes[axis], &counts[axis]);
        // Sweep from the right, then from the left evaluating each plane.
        let mut right_cost = [0.0f32; N];
        let (mut acc, mut acc_n) = (Box3::EMPTY, 0u32);
        for k in (1..nb).rev() {
            acc = acc.union(boxes[k]);
            acc_n += counts[k];
            right_cost[k] = acc.area() * acc_n as f32;
        }
        let (mut left, mut left_n) = (Box3::EMPTY, 0u32);
        for k in 1..nb {
            left = left.union(boxes[k - 1]);
            left_n += counts[k - 1];
            if left_n == 0 || left_n as usize == idx.len() {
                continue;
            }
            let cost =
                p.traversal_cost + p.intersection_cost * (left.area() * left_n as f32 + right_cost[k]) / area;
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, k));
            }
        }
    }
    best.map(|(c, a, k)| (c, a, k, binning))
}

/// Splits at the object median along the longest centroid axis.
fn median_split(ctx: &Ctx, idx: &mut [u32], cb: &Box3) -> usize {
    let axis = (cb.max - cb.min).max_position();
    let mid = idx.len() / 2;
    idx.select_nth_unstable_by(mid, |&a, &b| {
        ctx.prims[a as usize].center2()[axis].total_cmp(&ctx.prims[b as usize].center2()[axis])
    });
    mid
}

/// In-place partition; returns how many elements satisfy `left`.
fn partition(idx: &mut [u32], left: impl Fn(u32) -> bool) -> usize {
    let mut i = 0;
    let mut j = idx.len();
    while i < j {
        if left(idx[i]) {
            i += 1;
        } else {
            j -= 1;
            idx.swap(i, j);
        }
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;
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

    fn check(bvh: &FlatBvh, order: &[u32], bounds: &[Aabb]) {
        let mut seen = vec![false; bounds.len()];
        for n in &bvh.nodes {
            if n.is_leaf() {
                for &o in &order[n.first as usize..(n.first + n.count) as usize] {
                    assert!(!seen[o as usize]);
                    seen[o as usize] = true;
                    let b = bounds[o as usize];
                    assert!(n.min.cmple(b.min).all() && n.max.cmpge(b.max).all());
                }
            } else {
                let b = bvh.nodes[n.first as usize].aabb().union(bvh.nodes[n.first as usize + 1].aabb());
                assert_eq!(b, n.aabb());
            }
        }
        assert!(seen.iter().all(|&s| s));
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
            check(&bvh, &order, &bounds);
            assert!(depth(&bvh, 0) < super::super::traverse::STACK_SIZE as u32);
        }
    }
}
