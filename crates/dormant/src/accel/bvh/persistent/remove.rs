//! Removal of a block's references from the persistent tree, refitting the copied path and
//! collapsing path copies that became identical to their block node again.

use std::sync::Arc;

use super::{Link, ONode};

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
