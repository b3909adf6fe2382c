//! Ray queries on a static snapshot: the wide traversal over the snapshot's overlay view, whose
//! leaves hand each block subtree to the wide traversal of that block.

use std::sync::Arc;

use super::{Block, Link, StaticSnapshot};
use crate::accel::bvh::flat::{
    interval_is_valid, BoxRay, FlatBvh, Lanes, Node, PacketLanes, PrimHit, RayPacket, Start, Wide, ANY_HIT,
    CLOSEST_HIT, PACKET,
};
use crate::accel::bvh::simd::{dispatch, Kernel};
use crate::accel::bvh::triangle::RayTri;
use crate::accel::{Hit, HitObject, Occluder, SceneQuery, StaticId};
use crate::geometry::{Aabb, Ray};

impl StaticSnapshot {
    /// Closest hit with `t <= *t_max`; lowers `*t_max` and overwrites `best` on a hit.
    #[inline(always)]
    pub(crate) fn intersect_with<K: Kernel>(
        &self,
        k: K,
        bray: &BoxRay,
        tray: &RayTri,
        t_max: &mut f32,
        best: &mut Option<PrimHit>,
    ) {
        self.walk::<K, _, CLOSEST_HIT>(k, bray, t_max, |b, i, t_max| {
            b.mesh.intersect_from(k, Start::Entered(i), bray, tray, t_max, best);
            false
        });
    }

    /// Whether anything is hit within `[t_min, t_max]`.
    #[inline(always)]
    pub(crate) fn occluded_with<K: Kernel>(&self, k: K, bray: &BoxRay, tray: &RayTri, t_max: f32) -> bool {
        let mut t_max = t_max;
        self.walk::<K, _, ANY_HIT>(k, bray, &mut t_max, |b, i, t_max| {
            b.mesh.occluded_from(k, Start::Entered(i), bray, tray, *t_max)
        })
    }

    /// Visits the block subtrees the ray may hit, in the order `NEAREST_FIRST` picks
    /// ([`Wide::traverse`]); `f` returns `true` to stop.
    ///
    /// Each subtree is walked to its end before the next is taken. One stack shared by the
    /// overlay and the blocks would not change that: a depth-first walk visits the same nodes
    /// in the same order either way. What made rays walk an environment subtree behind the
    /// island they hit was the overlay's shape, which re-braiding fixes (`rebraid.rs`).
    #[inline(always)]
    fn walk<K: Kernel, F, const NEAREST_FIRST: bool>(
        &self,
        k: K,
        bray: &BoxRay,
        t_max: &mut f32,
        mut f: F,
    ) -> bool
    where
        F: FnMut(&Block, u32, &mut f32) -> bool,
    {
        let v = &*self.view;
        if v.bvh.is_empty() {
            return false;
        }
        // `f` is called from one place only, so that it is inlined (see `flat::Wide::traverse`);
        // without an overlay the view is one leaf, and this tests its box first.
        v.wide.traverse::<K, _, NEAREST_FIRST>(
            k,
            &v.bvh,
            Start::Test(0),
            bray,
            t_max,
            &mut |first, count, t_max| {
                v.refs[first as usize..(first + count) as usize].iter().any(|(b, i)| f(b, *i, t_max))
            },
        )
    }
}

/// Packet queries: [`Wide::traverse_packet`] over the overlay, then each block subtree.
impl StaticSnapshot {
    /// [`Self::intersect_with`] for the `lanes` of a packet.
    #[inline(always)]
    pub(crate) fn intersect_packet_with<K: Kernel>(
        &self,
        k: K,
        packet: &RayPacket,
        lanes: Lanes,
        t_max: &mut [f32; PACKET],
        best: &mut [Option<PrimHit>; PACKET],
    ) {
        self.walk_packet(k, packet, lanes, t_max, |b, i, lanes, t_max| {
            b.mesh.intersect_packet_from(k, Start::Entered(i), packet, lanes, t_max, best);
            0
        });
    }

    /// [`Self::occluded_with`] for the `lanes` of a packet: the lanes blocked.
    #[inline(always)]
    pub(crate) fn occluded_packet_with<K: Kernel>(
        &self,
        k: K,
        packet: &RayPacket,
        lanes: Lanes,
        t_max: &[f32; PACKET],
    ) -> Lanes {
        let mut t_max = *t_max;
        self.walk_packet(k, packet, lanes, &mut t_max, |b, i, lanes, t_max| {
            b.mesh.occluded_packet_from(k, Start::Entered(i), packet, lanes, t_max)
        })
    }

    /// [`Self::walk`] for a packet: `f` gets the lanes that entered a block subtree and
    /// returns those it finished.
    #[inline(always)]
    fn walk_packet<K: Kernel, F>(
        &self,
        k: K,
        packet: &RayPacket,
        lanes: Lanes,
        t_max: &mut [f32; PACKET],
        mut f: F,
    ) -> Lanes
    where
        F: FnMut(&Block, u32, Lanes, &mut [f32; PACKET]) -> Lanes,
    {
        let v = &*self.view;
        if v.bvh.is_empty() {
            return 0;
        }
        v.wide.traverse_packet(
            k,
            &v.bvh,
            Start::Test(0),
            PacketLanes { packet, lanes },
            t_max,
            &mut |first, count, lanes, t_max| {
                let mut left = lanes;
                for (b, i) in &v.refs[first as usize..(first + count) as usize] {
                    if left == 0 {
                        break;
                    }
                    left &= !f(b, *i, left, t_max);
                }
                lanes & !left
            },
        )
    }
}

/// The overlay of one version as a flat tree: interior nodes are overlay nodes, each leaf
/// names one block subtree (`refs[first]`). Rays traverse its 8-wide copy, as they do the
/// blocks: an overlay can be thousands of nodes and twenty levels deep, too deep to walk one
/// binary node at a time.
///
/// Small blocks copied into the view node for node, so that rays start no traversal per
/// block, traced no better and made every change dearer:
/// docs/lab/persistent-tree.md#2026-12-03-the-tree-at-its-most-fragmented
#[derive(Debug, Default)]
pub(crate) struct View {
    pub bvh: FlatBvh,
    pub(crate) wide: Wide,
    pub(crate) refs: Vec<(Arc<Block>, u32)>,
}

impl View {
    pub(crate) fn new(root: Option<&Link>) -> Self {
        let mut v = View::default();
        if let Some(root) = root {
            v.bvh.nodes.push(Node::interior(Aabb::EMPTY, 0));
            v.add(root, 0);
        }
        v.wide = Wide::new(&v.bvh, |_, n| (n.first, n.count));
        v
    }

    fn add(&mut self, link: &Link, at: usize) {
        let nodes = &mut self.bvh.nodes;
        match link {
            Link::Ref(b, i) => {
                nodes[at] = Node::leaf(link.aabb(), self.refs.len() as u32, 1);
                self.refs.push((b.clone(), *i));
            }
            Link::Node(n) => {
                let first = nodes.len();
                nodes.push(Node::interior(Aabb::EMPTY, 0));
                nodes.push(Node::interior(Aabb::EMPTY, 0));
                nodes[at] = Node::interior(n.aabb, first as u32);
                self.add(&n.kids[0], first);
                self.add(&n.kids[1], first + 1);
            }
        }
    }

    pub(crate) fn memory_bytes(&self) -> usize {
        self.bvh.memory_bytes()
            + self.wide.memory_bytes()
            + self.refs.len() * std::mem::size_of::<(Arc<Block>, u32)>()
    }
}

/// A static snapshot can be traced on its own (tests, tools, the geometry cache).
impl SceneQuery for StaticSnapshot {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        if !interval_is_valid(ray) {
            return None;
        }
        let mut t_max = ray.t_max;
        let mut best = None;
        let (bray, tray) = (BoxRay::new(ray), RayTri::new(ray));
        dispatch!(|k| self.intersect_with(k, &bray, &tray, &mut t_max, &mut best));
        best.map(|h| Hit {
            t: h.t,
            u: h.u,
            v: h.v,
            ng: h.tri.normal().normalize_or_zero(),
            object: HitObject::Static(StaticId(h.tri.geom)),
            prim: h.tri.prim,
        })
    }

    fn intersect_p(&self, ray: &Ray) -> bool {
        let (bray, tray) = (BoxRay::new(ray), RayTri::new(ray));
        interval_is_valid(ray) && dispatch!(|k| self.occluded_with(k, &bray, &tray, ray.t_max))
    }

    fn occluder(&self, ray: &Ray) -> Option<Occluder> {
        self.intersect_p(ray).then_some(Occluder::Static)
    }
}
