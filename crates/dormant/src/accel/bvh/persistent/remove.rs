//! Removal of one mesh from the persistent tree ([`StaticBvh::remove`]): its block's references
//! unlinked, the copied path refitted and path copies that became identical to their block node
//! collapsed again; a mesh sharing a rebuilt block costs a rebuild instead.

use std::sync::Arc;

use super::{Link, ONode, StaticBvh};
use crate::accel::StaticId;

impl StaticBvh {
    /// Removes a mesh; returns whether it was present. A mesh with its own block is unlinked
    /// and the path refitted; one sharing a rebuilt block triggers a rebuild.
    pub(crate) fn remove(&mut self, id: StaticId) -> bool {
        let Some(entry) = self.forget(id) else {
            return false;
        };
        if entry.triangles == 0 {
            return true;
        }
        if entry.shared {
            self.rebuild();
        } else if let Some(root) = self.state.root.take() {
            self.state.set_root(remove_block(&root, entry.block).resolve(root));
        }
        true
    }
}

pub(crate) enum Removed {
    /// Nothing below referenced the block.
    Keep,
    /// Everything below belonged to the block.
    Gone,
    /// A new subtree without the block.
    New(Link),
}

impl Removed {
    /// The new root given the old one.
    pub(crate) fn resolve(self, old: Link) -> Option<Link> {
        match self {
            Removed::Keep => Some(old),
            Removed::Gone => None,
            Removed::New(l) => Some(l),
        }
    }
}

pub(crate) fn remove_block(link: &Link, block: u32) -> Removed {
    match link {
        Link::Ref(b, _) => {
            if b.id == block {
                Removed::Gone
            } else {
                Removed::Keep
            }
        }
        Link::Node(n) => {
            if n.mask & (1u64 << (block % 64)) == 0 {
                return Removed::Keep;
            }
            let r0 = remove_block(&n.kids[0], block);
            let r1 = remove_block(&n.kids[1], block);
            let kid = |r: Removed, i: usize| match r {
                Removed::Keep => Some(n.kids[i].clone()),
                Removed::Gone => None,
                Removed::New(l) => Some(l),
            };
            if matches!((&r0, &r1), (Removed::Keep, Removed::Keep)) {
                return Removed::Keep;
            }
            match (kid(r0, 0), kid(r1, 1)) {
                (None, None) => Removed::Gone,
                (Some(k), None) | (None, Some(k)) => Removed::New(k),
                (Some(a), Some(b)) => Removed::New(rejoin([a, b], n.origin)),
            }
        }
    }
}

/// A node over `kids`, or the block reference it copies when the children are that block
/// node's own children again.
fn rejoin(kids: [Link; 2], origin: Option<(u32, u32)>) -> Link {
    if let (Some((bid, node)), Link::Ref(b0, i0), Link::Ref(b1, i1)) = (origin, &kids[0], &kids[1]) {
        if b0.id == bid && b1.id == bid {
            let n = &b0.mesh.bvh.nodes[node as usize];
            if !n.is_leaf() && n.first == *i0 && n.first + 1 == *i1 {
                return Link::Ref(b0.clone(), node);
            }
        }
    }
    Link::Node(Arc::new(ONode::new(kids, origin)))
}
