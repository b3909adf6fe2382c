//! Re-braiding (after Benthin, Woop, Wald and Áfra 2017, "Improved two-level BVHs using
//! partial re-braiding"): the overlay built top-down by binned SAH over *pieces* of the
//! blocks, the blocks larger than every other opened into subtrees, so that the overlay can
//! put an island's block between the parts of the environment around it instead of beside the
//! whole. Every commit of the persistent tree makes its overlay this way
//! ([`super::StaticBvh::apply`], through `StaticBvh::braid`, which falls back to a rebuild when
//! the overlay comes out too deep).
//!
//! Why: a ray walks each block subtree it enters to the end before the next, so a subtree of
//! the environment that encloses an island (the floor and walls around a pile) is walked
//! behind the island by rays aimed at it. Overlays made by inserting blocks one at a time
//! (`insert.rs`, still what [`super::StaticBvh::insert`] does) kept such subtrees whole, and
//! at its most fragmented such a tree traced well behind a fresh build of its triangles.
//!
//! Which pieces: the largest first, while a piece is larger than a quarter of the
//! second-largest block (the largest island, where the largest block is the environment),
//! within a budget of four per block. So the environment opens down to the size of the islands
//! around it and the islands stay whole. Coarser thresholds left rays walking more nodes than
//! in a fresh build; finer ones tested more leaves and made every commit dearer:
//! docs/lab/persistent-tree.md#2026-12-03-the-overlay-re-braided-at-every-commit

use std::cmp::Ordering;
use std::collections::BinaryHeap;
use std::sync::Arc;

use super::{Block, Link, ONode, StaticBvh, MAX_OVERLAY_HEIGHT};
use crate::accel::bvh::flat::{build, FlatBvh};
use crate::accel::bvh::BuildParams;
use crate::geometry::Aabb;

impl StaticBvh {
    /// [`Self::braid`], or a rebuild from the triangles of `blocks` where that fails; returns
    /// whether it rebuilt.
    pub(super) fn braid_or_rebuild(&mut self, blocks: &[Arc<Block>]) -> bool {
        if self.braid(blocks) {
            return false;
        }
        // From `blocks`, not the current tree: after a merge, only `blocks` holds the block
        // the mesh entries name.
        let tris = blocks.iter().flat_map(|b| self.live_tris_of(b)).collect();
        self.rebuild_from(tris);
        true
    }

    /// Makes the overlay a re-braided one ([`super::rebraid`]) over the whole of `blocks`; returns
    /// false, leaving the tree as it was, if that came out deeper than
    /// [`MAX_OVERLAY_HEIGHT`].
    fn braid(&mut self, blocks: &[Arc<Block>]) -> bool {
        let root = match blocks {
            [] => None,
            [one] => Some(Link::Ref(one.clone(), 0)),
            _ => Some(rebraid(blocks)),
        };
        if root.as_ref().is_some_and(|r| r.height() > MAX_OVERLAY_HEIGHT) {
            return false;
        }
        self.state.set_root(root);
        true
    }
}

/// At most this many pieces per block.
const PIECES_PER_BLOCK: usize = 4;
/// ... and at least this many in all, where blocks are few.
const MIN_PIECES: usize = 64;
/// Pieces are opened while their surface area is above this fraction of the second-largest
/// block's (the largest island's, where the largest block is the environment).
const OPEN_ABOVE: f32 = 0.25;

/// A re-braided overlay over the whole of `blocks` (two or more).
pub(crate) fn rebraid(blocks: &[Arc<Block>]) -> Link {
    debug_assert!(blocks.len() > 1);
    let whole: Vec<Piece> = blocks.iter().map(|b| Piece::new(Link::Ref(b.clone(), 0))).collect();
    let (mut largest, mut second) = (0.0f32, 0.0f32);
    for p in &whole {
        (largest, second) = if p.0 > largest { (p.0, largest) } else { (largest, second.max(p.0)) };
    }
    let budget = (PIECES_PER_BLOCK * blocks.len()).max(MIN_PIECES);
    let pieces = pieces(whole, budget, OPEN_ABOVE * second);
    let bounds: Vec<Aabb> = pieces.iter().map(Link::aabb).collect();
    // One piece per leaf: entering a piece starts a block traversal.
    let (bvh, order) = build(&bounds, BuildParams::TOP_LEVEL);
    link_of(&bvh, 0, &order, &pieces)
}

/// A piece waiting to be opened, ordered by surface area (largest first).
struct Piece(f32, Link);

impl Piece {
    fn new(link: Link) -> Self {
        Piece(link.aabb().surface_area(), link)
    }
}

impl PartialEq for Piece {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}

impl Eq for Piece {}

impl PartialOrd for Piece {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Piece {
    fn cmp(&self, other: &Self) -> Ordering {
        self.0.total_cmp(&other.0)
    }
}

/// `whole` (block subtrees) opened largest first while the largest piece's surface area is
/// above `min_area` and there are fewer than `budget` pieces; block leaves stay whole.
fn pieces(whole: Vec<Piece>, budget: usize, min_area: f32) -> Vec<Link> {
    let mut open = BinaryHeap::from(whole);
    let mut done = Vec::new();
    while open.len() + done.len() < budget && open.peek().is_some_and(|p| p.0 > min_area) {
        let Some(Piece(_, l)) = open.pop() else { break };
        match l.children() {
            Some(kids) => open.extend(kids.into_iter().map(Piece::new)),
            None => done.push(l),
        }
    }
    done.extend(open.into_iter().map(|Piece(_, l)| l));
    done
}

/// Node `i` of the build over `pieces` as an overlay link.
fn link_of(bvh: &FlatBvh, i: u32, order: &[u32], pieces: &[Link]) -> Link {
    let n = &bvh.nodes[i as usize];
    if n.is_leaf() {
        debug_assert_eq!(n.count, 1);
        return pieces[order[n.first as usize] as usize].clone();
    }
    let kids = [link_of(bvh, n.first, order, pieces), link_of(bvh, n.first + 1, order, pieces)];
    Link::Node(Arc::new(ONode::new(kids, None)))
}
