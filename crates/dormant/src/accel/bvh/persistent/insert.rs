//! Insertion of one mesh into the persistent tree by path copying ([`StaticBvh::insert`]): its new
//! block placed into the existing overlay (the O(k log(n + k)) update).
//!
//! For a subtree N of the new block, a branch-and-bound search (Bittner et al. 2013, the same
//! bound as Box2D's dynamic tree) finds the sibling S minimising the SAH increase
//! `area(S u N) + sum over S's ancestors A of (area(A u N) - area(A))`, descending into the
//! overlay and into blocks alike. N is inserted whole unless inserting its two children
//! separately is cheaper (their costs plus the area of N's own node, which would disappear),
//! in which case the decision recurses into them; block leaves are always inserted whole.
//! The chosen sibling's path is copied with enlarged bounds.

use std::cmp::Ordering;
use std::collections::BinaryHeap;
use std::sync::Arc;

use super::{Block, Link, ONode, StaticBvh, MAX_OVERLAY_HEIGHT};
use crate::accel::bvh::triangle::{extract, Tri};
use crate::accel::{AccelError, StaticId};
use crate::geometry::{Aabb, TriangleMesh};

impl StaticBvh {
    /// Inserts a world-space mesh without rebuilding: builds a block for it and inserts the
    /// block's subtrees where they add the least SAH cost. Replaces a mesh with the same id.
    /// Returns the number of skipped (degenerate or non-finite) triangles.
    pub fn insert(&mut self, id: StaticId, mesh: &TriangleMesh) -> Result<usize, AccelError> {
        mesh.validate()?;
        let (tris, skipped) = extract(mesh, id.0);
        self.remove(id);
        self.insert_tris(id, tris);
        Ok(skipped)
    }

    /// Inserts already extracted triangles as mesh `id` (which must not be present). Returns
    /// whether the overlay got deeper than [`MAX_OVERLAY_HEIGHT`] so the tree was rebuilt.
    fn insert_tris(&mut self, id: StaticId, tris: Vec<Tri>) -> bool {
        if let Some(block) = self.add_mesh(id, tris) {
            let root = match self.state.root.take() {
                None => Link::Ref(block, 0),
                Some(root) => insert_block(root, &block),
            };
            self.state.set_root(Some(root));
        }
        if self.state.root.as_ref().is_some_and(|r| r.height() > MAX_OVERLAY_HEIGHT) {
            self.rebuild();
            return true;
        }
        false
    }
}

/// Inserts the whole of `block` into the tree at `root` and returns the new root. `root` is not
/// modified: everything off the copied paths stays shared with it.
pub(crate) fn insert_block(root: Link, block: &Arc<Block>) -> Link {
    let mut root = root;
    let n = Link::Ref(block.clone(), 0);
    let first = search(&root, &n.aabb());
    insert_subtree(&mut root, n, first);
    root
}

fn insert_subtree(root: &mut Link, n: Link, found: Found) {
    if let Some([l, r]) = n.children() {
        let fl = search(root, &l.aabb());
        let fr = search(root, &r.aabb());
        if fl.cost + fr.cost < found.cost + n.aabb().surface_area() {
            insert_subtree(root, l, fl);
            // The tree changed: search again for the right half.
            let fr = search(root, &r.aabb());
            insert_subtree(root, r, fr);
            return;
        }
    }
    *root = splice(&found.path, n);
}

/// The best sibling for a box and the path from the root to it.
struct Found {
    cost: f32,
    /// `(link, slot)`: each link on the path and which child of the previous one it is.
    path: Vec<(Link, u8)>,
}

struct Cand {
    link: Link,
    parent: u32,
    slot: u8,
    inherited: f32,
}

#[derive(PartialEq)]
struct Entry(f32, u32);

impl Eq for Entry {}

impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Entry {
    // Min-heap on the lower bound.
    fn cmp(&self, other: &Self) -> Ordering {
        other.0.total_cmp(&self.0).then(other.1.cmp(&self.1))
    }
}

fn search(root: &Link, n: &Aabb) -> Found {
    let an = n.surface_area();
    let mut cands = vec![Cand { link: root.clone(), parent: u32::MAX, slot: 0, inherited: 0.0 }];
    let mut heap = BinaryHeap::new();
    heap.push(Entry(an, 0));
    let mut best = (f32::INFINITY, 0u32);
    while let Some(Entry(bound, ci)) = heap.pop() {
        if bound >= best.0 {
            break;
        }
        let c = &cands[ci as usize];
        let s = c.link.aabb();
        let u = s.union(*n).surface_area();
        let direct = u + c.inherited;
        if direct < best.0 {
            best = (direct, ci);
        }
        let inherited = c.inherited + u - s.surface_area();
        if an + inherited < best.0 {
            if let Some(kids) = c.link.children() {
                for (slot, k) in kids.into_iter().enumerate() {
                    heap.push(Entry(an + inherited, cands.len() as u32));
                    cands.push(Cand { link: k, parent: ci, slot: slot as u8, inherited });
                }
            }
        }
    }
    let mut path = Vec::new();
    let mut ci = best.1;
    while ci != u32::MAX {
        let c = &mut cands[ci as usize];
        path.push((c.link.clone(), c.slot));
        ci = c.parent;
    }
    path.reverse();
    Found { cost: best.0, path }
}

/// Makes `n` the sibling of the path's last link and copies the path up to a new root.
fn splice(path: &[(Link, u8)], n: Link) -> Link {
    let (sibling, _) = path.last().expect("search returns at least the root");
    let mut cur = Link::Node(Arc::new(ONode::new([sibling.clone(), n], None)));
    for w in path.windows(2).rev() {
        let (parent, _) = &w[0];
        let (_, slot) = w[1];
        let mut kids = parent.children().expect("a path goes through interior nodes");
        kids[slot as usize] = cur;
        cur = Link::Node(Arc::new(ONode::new(kids, parent.origin())));
    }
    cur
}
