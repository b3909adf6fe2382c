//! Measurements of the persistent tree: SAH cost and per-snapshot memory.

use std::collections::{HashMap, HashSet};
use std::sync::Arc;

use super::{Block, Link, StaticBvh, StaticSnapshot};
use crate::accel::bvh::flat::subtree_cost;
use crate::accel::bvh::BuildParams;

/// Visits every distinct block referenced from `root` once.
pub(crate) fn for_each_block(root: &Link, f: &mut impl FnMut(&Arc<Block>)) {
    let mut seen = HashSet::new();
    let mut stack = vec![root];
    while let Some(l) = stack.pop() {
        match l {
            Link::Ref(b, _) => {
                if seen.insert(b.id) {
                    f(b);
                }
            }
            Link::Node(n) => stack.extend(n.kids.iter()),
        }
    }
}

/// Memory of one snapshot.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct SnapshotMemory {
    /// Bytes of overlay nodes and blocks reachable from the snapshot.
    pub(crate) total_bytes: usize,
    /// Bytes reachable only through this snapshot: what dropping it would free.
    pub(crate) unique_bytes: usize,
}

fn sah_sum(root: &Link, p: &BuildParams) -> f64 {
    let mut sum = 0.0;
    let mut stack = vec![root];
    while let Some(l) = stack.pop() {
        match l {
            Link::Ref(b, i) => sum += subtree_cost(&b.mesh.bvh.nodes, *i, p),
            Link::Node(n) => {
                sum += f64::from(n.aabb.surface_area()) * f64::from(p.traversal_cost);
                stack.extend(n.kids.iter());
            }
        }
    }
    sum
}

impl StaticSnapshot {
    /// SAH cost of this version's tree (overlay nodes and block subtrees alike), normalised
    /// by the root's area; comparable with [`crate::accel::bvh::flat::sah_cost`].
    pub(crate) fn sah_cost(&self, params: &BuildParams) -> f32 {
        let Some(root) = &self.root else {
            return 0.0;
        };
        let area = f64::from(root.aabb().surface_area()).max(f64::from(f32::MIN_POSITIVE));
        (sah_sum(root, params) / area) as f32
    }

    /// Memory reachable from this snapshot, and the part no other live snapshot or tree shares.
    /// An overlay node is unique when only its (unique) parent holds it; a block is unique when
    /// every reference to it (tree links and traversal view entries) is held in this
    /// snapshot's unique part. A snapshot of the current version shares everything with the
    /// live tree, so its unique part is 0 until the tree changes.
    pub(crate) fn memory(&self) -> SnapshotMemory {
        let mut m = SnapshotMemory::default();
        let Some(root) = &self.root else {
            return m;
        };
        let node_bytes = std::mem::size_of::<super::ONode>() + 16;
        // Block id -> (block, references held in the unique part).
        let mut blocks: HashMap<u32, (&Arc<Block>, usize)> = HashMap::new();
        let view_unique = Arc::strong_count(&self.view) == 1;
        let view = self.view.memory_bytes();
        m.total_bytes += view;
        if view_unique {
            m.unique_bytes += view;
        }
        for (b, _) in &self.view.refs {
            blocks.entry(b.id).or_insert((b, 0)).1 += usize::from(view_unique);
        }
        // The root link itself is held by this snapshot alone (a clone of a snapshot clones it).
        let mut stack = vec![(root, true)];
        while let Some((l, held_uniquely)) = stack.pop() {
            match l {
                Link::Ref(b, _) => blocks.entry(b.id).or_insert((b, 0)).1 += usize::from(held_uniquely),
                Link::Node(n) => {
                    let unique = held_uniquely && Arc::strong_count(n) == 1;
                    m.total_bytes += node_bytes;
                    if unique {
                        m.unique_bytes += node_bytes;
                    }
                    stack.extend(n.kids.iter().map(|k| (k, unique)));
                }
            }
        }
        for (b, refs) in blocks.values() {
            let bytes = b.mesh.memory_bytes() + std::mem::size_of::<Block>();
            m.total_bytes += bytes;
            if Arc::strong_count(b) == *refs {
                m.unique_bytes += bytes;
            }
        }
        m
    }
}

impl StaticBvh {
    /// SAH cost of the current tree with this tree's build parameters.
    pub(crate) fn sah_cost(&self) -> f32 {
        self.state.sah_cost(&self.params)
    }
}
