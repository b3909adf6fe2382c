//! The flattened binary BVH: 32-byte nodes in one array, built once by binned SAH and never
//! modified. Every structure of this backend is made of these: prototype meshes, the top level
//! over instances, and the immutable blocks of the persistent static tree.
//!
//! A node is a leaf when `count > 0` (positions `first..first + count` of the owner's leaf
//! order: the primitive order the build returns) and interior otherwise, with its children at
//! `first` and `first + 1` so both sit in one cache line pair. Rays traverse the [`Wide`] copy
//! (8 children per node, tested together by the SIMD path's kernel); the binary tree stays the
//! structure of record.

mod build;
mod mesh_bvh;
mod packet;
mod sah;
mod stack;
mod traverse;
mod wide;

pub(crate) use build::{build, build_with};
pub(crate) use mesh_bvh::{MeshBvh, PrimHit};
pub(crate) use packet::{each_bit, Lanes, PacketLanes, RayPacket, PACKET};
pub(crate) use sah::subtree_cost;
#[cfg(test)]
pub(crate) use traverse::traverse;
pub(crate) use traverse::{interval_is_valid, BoxRay, STACK_SIZE};
pub(crate) use wide::{Start, Visitor, Wide, WideChild, ANY_HIT, CLOSEST_HIT, WIDTH};

use glam::Vec3;

use crate::geometry::Aabb;

pub(crate) use super::params::PAR_CHUNK;

/// One BVH node: bounds plus either a child index (interior) or a primitive range (leaf).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(32))]
pub(crate) struct Node {
    pub min: Vec3,
    /// Interior: index of the first child (the second follows it). Leaf: first primitive.
    pub first: u32,
    pub max: Vec3,
    /// Primitives in the leaf; 0 for interior nodes.
    pub count: u32,
}

const _: () = assert!(std::mem::size_of::<Node>() == 32);

impl Node {
    pub(crate) fn leaf(b: Aabb, first: u32, count: u32) -> Self {
        debug_assert!(count > 0);
        Self { min: b.min, first, max: b.max, count }
    }

    pub(crate) fn interior(b: Aabb, first_child: u32) -> Self {
        Self { min: b.min, first: first_child, max: b.max, count: 0 }
    }

    #[inline(always)]
    pub(crate) fn is_leaf(&self) -> bool {
        self.count > 0
    }

    pub(crate) fn aabb(&self) -> Aabb {
        Aabb { min: self.min, max: self.max }
    }
}

/// A built tree. Leaves refer to a primitive array its owner keeps in build order.
#[derive(Clone, Debug, Default)]
pub(crate) struct FlatBvh {
    pub(crate) nodes: Vec<Node>,
}

impl FlatBvh {
    pub(crate) fn bounds(&self) -> Aabb {
        self.nodes.first().map_or(Aabb::EMPTY, Node::aabb)
    }

    pub(crate) fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    pub(crate) fn memory_bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<Node>()
    }
}
