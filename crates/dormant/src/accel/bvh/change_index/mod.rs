//! [`ChangeIndex`]: where and when a sequence's scene changes, indexed in space and time for
//! the horizons of exact temporal reuse. Each [`ChangeBox`] bounds something whose look
//! differs from one rendered frame to the next (a body that moved, appeared or left, with
//! motion blur over both shutters) and carries the ordinal of the first rendered frame that
//! shows the difference. The boxes sit in a binned-SAH BVH, traversed as its 8-wide copy (the
//! SIMD path's box kernel, as rays traverse the BVH backend) whose children also carry the
//! range of their boxes' ordinals, so a query ("the earliest change after ordinal `n` that
//! this ray segment meets") skips subtrees that lie wholly in the past or no earlier than the
//! best change found so far.
//!
//! A box may also name the geometry it bounds ([`ChangeShape`]: a small mesh at the poses of
//! the body before and after the change). A segment that crosses such a box then counts only
//! if it comes near that geometry at either pose: a ray passing a moved body without touching
//! it sees nothing change. The test is conservative (f64, with a margin), so it never misses a
//! hit either tracer could find.
//!
//! Exact reuse (`render/reuse/`) is its one user: `changes.rs` there makes the boxes from the
//! trajectory and builds the index window by window, `horizon.rs` queries it ray by ray.

mod shape;

use glam::Vec3;
use rayon::prelude::*;

pub(crate) use shape::{ChangeShape, EXACT_MESH_TRIANGLES};
use shape::{ExactMesh, ShapeTest};

use super::flat::{build, interval_is_valid, BoxRay, FlatBvh, Node, Start, Visitor, Wide, WideChild};
use super::flat::{ANY_HIT, WIDTH};
use super::simd::dispatch;
use super::BuildParams;
use crate::geometry::{Aabb, Ray};

/// A world box whose content looks different from rendered frame `visible_at` on (an
/// ordinal: 0 for the first rendered frame) than at the frame before it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ChangeBox {
    pub bounds: Aabb,
    pub visible_at: u32,
    /// The body that changed, when a body did.
    pub body: Option<u32>,
    /// What changed inside the box, when it can be tested exactly; `None`: anything in it.
    pub shape: Option<ChangeShape>,
}

/// The least and most `visible_at` below each child of a wide node (unused slots: none).
#[derive(Clone, Copy, Debug)]
struct SlotTimes {
    earliest: [u32; WIDTH],
    latest: [u32; WIDTH],
}

impl SlotTimes {
    const NONE: SlotTimes = SlotTimes { earliest: [u32::MAX; WIDTH], latest: [0; WIDTH] };

    /// The least and most of all slots.
    fn span(&self) -> (u32, u32) {
        let earliest = self.earliest.iter().copied().min().unwrap_or(u32::MAX);
        (earliest, self.latest.iter().copied().max().unwrap_or(0))
    }
}

/// What a query reads of a box in a leaf of several: its bounds and frame, 32 bytes (a
/// [`ChangeBox`] with its shape's two poses is 224, and queries walk many leaves).
#[derive(Clone, Copy, Debug)]
struct LeafBox {
    min: Vec3,
    visible_at: u32,
    max: Vec3,
}

/// The change boxes of a sequence in a BVH (see the module docs). Immutable once built; queries
/// run from many threads at once.
#[derive(Clone, Debug, Default)]
pub(crate) struct ChangeIndex {
    bvh: FlatBvh,
    wide: Wide,
    /// Per wide node, its children's frame ranges.
    times: Vec<SlotTimes>,
    /// The least and most `visible_at` of all boxes.
    span: (u32, u32),
    /// The boxes in leaf order.
    boxes: Vec<LeafBox>,
    /// Per box (leaf order), the object-space views of its shape's poses.
    shapes: Vec<Option<ShapeTest>>,
    /// The meshes shapes refer to, ready for exact tests.
    meshes: Vec<ExactMesh>,
    /// Per body, the `visible_at` of its changes in ascending order (`body_changes[b]` are
    /// `changes[body_changes[b]..body_changes[b + 1]]`), and each change's box (leaf order).
    body_changes: Vec<u32>,
    changes: Vec<u32>,
    change_boxes: Vec<u32>,
}

/// Builds change indexes with a cheap build: the index is built once per sequence and its
/// queries are short.
const INDEX_PARAMS: BuildParams = BuildParams::TOP_LEVEL;

impl ChangeIndex {
    /// The index over `boxes`; each box is padded by a small margin (a relative 1e-4 of its
    /// size plus 1e-5 of its distance from the origin) so that rounding in the tracers' hit
    /// points and instance transforms never puts a change outside its box. Empty and
    /// non-finite boxes are dropped.
    pub(crate) fn build(mut boxes: Vec<ChangeBox>, meshes: Vec<Vec<[Vec3; 3]>>) -> Self {
        // Built before a window's first frame, which waits for it: its passes go over rayon
        // (what each costs: docs/lab/reuse.md, 2026-12-06).
        boxes.retain(|b| !b.bounds.is_empty() && b.bounds.min.is_finite() && b.bounds.max.is_finite());
        boxes.par_iter_mut().for_each(|b| b.bounds = padded(b.bounds));
        let bounds: Vec<Aabb> = boxes.par_iter().map(|b| b.bounds).collect();
        let (bvh, order) = build(&bounds, INDEX_PARAMS);
        let mut boxes: Vec<ChangeBox> = order.par_iter().map(|&i| boxes[i as usize]).collect();
        sort_leaves(&bvh.nodes, &mut boxes);
        let wide = Wide::new(&bvh, |_, n| (n.first, n.count));
        let times = slot_times(&wide, &boxes);
        let span =
            boxes.iter().fold((u32::MAX, 0), |(lo, hi), b| (lo.min(b.visible_at), hi.max(b.visible_at)));
        let meshes: Vec<ExactMesh> = meshes.iter().map(|m| ExactMesh::new(m)).collect();
        let shapes = boxes.par_iter().map(|b| b.shape.and_then(|s| ShapeTest::new(&s, &meshes))).collect();
        let (body_changes, changes, change_boxes) = changes_by_body(&boxes);
        let boxes = boxes
            .par_iter()
            .map(|b| LeafBox { min: b.bounds.min, visible_at: b.visible_at, max: b.bounds.max })
            .collect();
        Self { bvh, wide, times, span, boxes, shapes, meshes, body_changes, changes, change_boxes }
    }

    /// The earliest `visible_at` greater than `after` of body `body`'s changes, if it has one.
    /// A segment that ends on the body at ordinal `after` changes there at the latest, so its
    /// horizon is no later: a query for it needs to look only before that.
    pub(crate) fn next_change_of(&self, body: u32, after: u32) -> Option<u32> {
        self.changes_after(body, after)?.next().map(|i| self.changes[i])
    }

    /// For an occlusion ray that body `body` blocks at ordinal `after`: the earliest
    /// `visible_at` greater than `after` and less than `before` of the body's changes after
    /// which it may no longer block the ray (its shape is not surely crossed at both poses, or
    /// is not known), or `before`. While the body blocks the ray nothing else along it
    /// matters, so no other change is looked at.
    pub(crate) fn blocked_until(&self, body: u32, ray: &Ray, after: u32, before: u32) -> u32 {
        let Some(range) = self.changes_after(body, after) else { return before };
        for i in range {
            let visible_at = self.changes[i];
            if visible_at >= before {
                break;
            }
            let blocks = self.shapes[self.change_boxes[i] as usize]
                .is_some_and(|s| s.blocks_at_both(&self.meshes, ray));
            if !blocks {
                return visible_at;
            }
        }
        before
    }

    /// The positions in `changes` of body `body`'s changes later than `after`, if the index
    /// knows the body.
    fn changes_after(&self, body: u32, after: u32) -> Option<std::ops::Range<usize>> {
        let b = body as usize;
        let (start, end) = (*self.body_changes.get(b)? as usize, *self.body_changes.get(b + 1)? as usize);
        Some(start + self.changes[start..end].partition_point(|&f| f <= after)..end)
    }

    /// The earliest `visible_at` greater than `after` and less than `before` of a box that the
    /// segment of `ray` over `[t_min, t_max]` meets, or `before` when there is none. A segment
    /// traced at ordinal `after` stays valid until the returned ordinal.
    ///
    /// With `occlusion` the segment is an occlusion ray's, whose result is only whether
    /// anything blocks it: a shape it meets at both poses blocks it before and after the
    /// change, so only a shape met at one pose counts.
    pub(crate) fn first_change(&self, ray: &Ray, after: u32, before: u32, occlusion: bool) -> u32 {
        let (earliest, latest) = self.span;
        if self.bvh.is_empty()
            || after.saturating_add(1) >= before
            || latest <= after
            || earliest >= before
            || !interval_is_valid(ray)
        {
            return before;
        }
        let r = BoxRay::new(ray);
        let mut search = ChangeSearch { index: self, ray, r: &r, after, best: before, occlusion };
        let mut t_max = ray.t_max;
        dispatch!(|k| self.wide.visit::<_, _, ANY_HIT>(
            k,
            &self.bvh,
            Start::Test(0),
            &r,
            &mut t_max,
            &mut search
        ));
        search.best
    }
}

/// One [`ChangeIndex::first_change`] query as it walks the index: the earliest change found
/// so far that the segment meets (`best`), and the frames it seeks, which turn away every
/// subtree whose changes all lie at or before `after` or at or after `best`.
struct ChangeSearch<'a> {
    index: &'a ChangeIndex,
    ray: &'a Ray,
    r: &'a BoxRay,
    after: u32,
    best: u32,
    occlusion: bool,
}

impl Visitor for ChangeSearch<'_> {
    /// The leaf's boxes in order of `visible_at` until one the segment meets (the earliest of
    /// the leaf) or one no earlier than the best; stops the walk once nothing can come sooner.
    #[inline(always)]
    fn leaf(&mut self, first: u32, count: u32, _t_max: &mut f32) -> bool {
        let index = self.index;
        for k in first as usize..(first + count) as usize {
            let b = &index.boxes[k];
            if b.visible_at >= self.best {
                break;
            }
            // A leaf of one box was entered through the box itself, just tested.
            let enters = count == 1 || self.r.hit_bounds(b.min, b.max, self.ray.t_max) != f32::INFINITY;
            if b.visible_at > self.after
                && enters
                && index.shapes[k].is_none_or(|s| s.changes_for(&index.meshes, self.ray, self.occlusion))
            {
                self.best = b.visible_at;
                break;
            }
        }
        // Nothing can come before the frame right after `after`.
        self.best == self.after + 1
    }

    #[inline(always)]
    fn allow(&self, w: u32) -> u32 {
        let t = &self.index.times[w as usize];
        let mut mask = 0;
        for slot in 0..WIDTH {
            let live = t.earliest[slot] < self.best && t.latest[slot] > self.after;
            mask |= u32::from(live) << slot;
        }
        mask
    }
}

/// Sorts each leaf's `boxes` (in leaf order) by `visible_at`, so a query stops in a leaf at
/// the first box no earlier than its best change.
fn sort_leaves(nodes: &[Node], boxes: &mut [ChangeBox]) {
    for n in nodes.iter().filter(|n| n.is_leaf()) {
        boxes[n.first as usize..(n.first + n.count) as usize].sort_by_key(|b| b.visible_at);
    }
}

/// The frame ranges of every wide node's children over `boxes` (leaf order, each leaf
/// sorted). Children come after their parents, so one backwards pass sees every child's
/// range before its parent's.
fn slot_times(wide: &Wide, boxes: &[ChangeBox]) -> Vec<SlotTimes> {
    let mut times = vec![SlotTimes::NONE; wide.node_count()];
    for w in (0..wide.node_count()).rev() {
        let mut t = SlotTimes::NONE;
        for (slot, child) in wide.children(w as u32) {
            (t.earliest[slot], t.latest[slot]) = match child {
                WideChild::Node(c) => times[c as usize].span(),
                WideChild::Leaf(first, count) => {
                    (boxes[first as usize].visible_at, boxes[(first + count - 1) as usize].visible_at)
                }
            };
        }
        times[w] = t;
    }
    times
}

/// Each body's changes among `boxes` (in leaf order): offsets per body into the `visible_at`
/// of its changes, ascending, and each change's box.
fn changes_by_body(boxes: &[ChangeBox]) -> (Vec<u32>, Vec<u32>, Vec<u32>) {
    let mut changed: Vec<(u32, u32, u32)> =
        boxes.iter().enumerate().filter_map(|(k, b)| Some((b.body?, b.visible_at, k as u32))).collect();
    changed.par_sort_unstable();
    let bodies = changed.last().map_or(0, |c| c.0 as usize + 1);
    let mut offsets = vec![0u32; bodies + 1];
    for &(b, _, _) in &changed {
        offsets[b as usize + 1] += 1;
    }
    for b in 0..bodies {
        offsets[b + 1] += offsets[b];
    }
    let (visible_at, boxes) = changed.into_iter().map(|c| (c.1, c.2)).unzip();
    (offsets, visible_at, boxes)
}

/// `b` grown by a margin that absorbs rounding: 1e-4 of its largest side plus 1e-5 of its
/// largest coordinate's magnitude.
fn padded(b: Aabb) -> Aabb {
    let size = (b.max - b.min).max_element();
    let reach = b.min.abs().max(b.max.abs()).max_element();
    let pad = Vec3::splat(1e-4 * size + 1e-5 * reach);
    Aabb { min: b.min - pad, max: b.max + pad }
}

#[cfg(test)]
mod tests {
    use glam::Affine3A;

    use super::*;

    fn unit_box_at(x: f32, visible_at: u32) -> ChangeBox {
        let min = Vec3::new(x, 0.0, 0.0);
        ChangeBox { bounds: Aabb { min, max: min + Vec3::ONE }, visible_at, body: None, shape: None }
    }

    #[test]
    fn the_earliest_change_after_the_frame_on_the_segment_wins() {
        let index = ChangeIndex::build(
            vec![unit_box_at(0.0, 5), unit_box_at(3.0, 2), unit_box_at(6.0, 9)],
            Vec::new(),
        );
        let along_x = Ray::new(Vec3::new(-1.0, 0.5, 0.5), Vec3::X);
        assert_eq!(index.first_change(&along_x, 0, u32::MAX, false), 2);
        // Traced at ordinal 2 or later, the change at 2 is in the past.
        assert_eq!(index.first_change(&along_x, 2, u32::MAX, false), 5);
        assert_eq!(index.first_change(&along_x, 5, u32::MAX, false), 9);
        assert_eq!(index.first_change(&along_x, 9, u32::MAX, false), u32::MAX);
        // A segment that stops before the second box.
        let short = Ray::segment(along_x.origin, along_x.dir, 0.0, 2.5);
        assert_eq!(index.first_change(&short, 0, u32::MAX, false), 5);
        // Nothing beyond `before`; a ray that misses every box.
        assert_eq!(index.first_change(&along_x, 0, 2, false), 2);
        let up = Ray::new(Vec3::new(-1.0, 0.5, 0.5), Vec3::Y);
        assert_eq!(index.first_change(&up, 0, 7, false), 7);
    }

    #[test]
    fn an_empty_index_never_changes() {
        let index = ChangeIndex::build(Vec::new(), Vec::new());
        assert_eq!(index.first_change(&Ray::new(Vec3::ZERO, Vec3::X), 0, 42, false), 42);
    }

    #[test]
    fn a_shaped_box_counts_only_segments_near_its_geometry() {
        // The lower-left half of the unit square at z = 0.5, placed 5 units along x.
        let tri = [Vec3::new(0.0, 0.0, 0.5), Vec3::new(1.0, 0.0, 0.5), Vec3::new(0.0, 1.0, 0.5)];
        let pose = Affine3A::from_translation(Vec3::new(5.0, 0.0, 0.0));
        let bounds = Aabb { min: Vec3::new(5.0, 0.0, 0.0), max: Vec3::new(6.0, 1.0, 1.0) };
        let shape = ChangeShape { mesh: 0, poses: [Some(pose), None] };
        let index = ChangeIndex::build(
            vec![ChangeBox { bounds, visible_at: 3, body: Some(0), shape: Some(shape) }],
            vec![vec![tri]],
        );
        // Through the box and the triangle.
        let through = Ray::new(Vec3::new(5.25, 0.25, -1.0), Vec3::Z);
        assert_eq!(index.first_change(&through, 0, 10, false), 3);
        // Through the box's corner the triangle leaves empty.
        let past = Ray::new(Vec3::new(5.9, 0.9, -1.0), Vec3::Z);
        assert_eq!(index.first_change(&past, 0, 10, false), 10);
        // A segment that stops short of the triangle (at z = -0.5).
        let short = Ray::segment(through.origin, through.dir, 0.0, 0.5);
        assert_eq!(index.first_change(&short, 0, 10, false), 10);
    }

    #[test]
    fn a_body_changes_next_at_its_first_change_after_the_frame() {
        let at =
            |x: f32, visible_at: u32, body: Option<u32>| ChangeBox { body, ..unit_box_at(x, visible_at) };
        let index = ChangeIndex::build(
            vec![at(0.0, 4, Some(2)), at(0.0, 9, Some(2)), at(3.0, 2, Some(0)), at(6.0, 1, None)],
            Vec::new(),
        );
        assert_eq!(index.next_change_of(2, 0), Some(4));
        assert_eq!(index.next_change_of(2, 4), Some(9));
        assert_eq!(index.next_change_of(2, 9), None);
        assert_eq!(index.next_change_of(0, 0), Some(2));
        // A body without changes, and one the index never heard of.
        assert_eq!(index.next_change_of(1, 0), None);
        assert_eq!(index.next_change_of(7, 0), None);
    }

    #[test]
    fn a_blocked_ray_stays_blocked_until_its_blocker_may_leave_it() {
        // A unit cube (body 0) 3 above the origin: it slides along x at ordinal 2 and still
        // covers a ray straight up (off its faces' diagonals, where the strict test gives up);
        // at 5 it slides off the ray; at 7 it comes back.
        let cube = crate::geometry::primitives::cuboid(Vec3::splat(0.5));
        let mesh: Vec<[Vec3; 3]> = (0..cube.triangle_count()).map(|i| cube.triangle(i)).collect();
        let at = |x: f32| Some(Affine3A::from_translation(Vec3::new(x, 3.0, 0.0)));
        let change = |visible_at: u32, from: f32, to: f32| {
            let (lo, hi) = (from.min(to), from.max(to));
            ChangeBox {
                bounds: Aabb { min: Vec3::new(lo - 0.5, 2.5, -0.5), max: Vec3::new(hi + 0.5, 3.5, 0.5) },
                visible_at,
                body: Some(0),
                shape: Some(ChangeShape { mesh: 0, poses: [at(from), at(to)] }),
            }
        };
        let index = ChangeIndex::build(
            vec![change(2, 0.0, 0.2), change(5, 0.2, 3.0), change(7, 3.0, 0.1)],
            vec![mesh],
        );
        let up = Ray::new(Vec3::new(0.1, 0.0, 0.27), Vec3::Y);
        assert_eq!(index.blocked_until(0, &up, 0, 10), 5);
        assert_eq!(index.blocked_until(0, &up, 5, 10), 7);
        // Nothing to look at before `before`; a body without changes blocks for good.
        assert_eq!(index.blocked_until(0, &up, 0, 4), 4);
        assert_eq!(index.blocked_until(3, &up, 0, 10), 10);
        // A box without a shape may be anything: its change counts.
        let shapeless = ChangeBox { shape: None, ..change(2, 0.0, 0.2) };
        let index = ChangeIndex::build(vec![shapeless], Vec::new());
        assert_eq!(index.blocked_until(0, &up, 0, 10), 2);
    }
}
