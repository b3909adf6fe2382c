//! A flattened BVH over triangles: the bottom level of a prototype and each immutable block of
//! the static tree. Triangles are kept in the order they came in, with the leaf order beside
//! them, and copied into packets of four ([`Tri4`], a leaf's triangles in one or more packets)
//! that the wide traversal's leaves test at once.

use rayon::prelude::*;

use super::packet::{each_bit, Lanes, PacketLanes, RayPacket, PACKET};
use super::{build_with, BoxRay, FlatBvh, Node, Start, Wide, ANY_HIT, CLOSEST_HIT, PAR_CHUNK};
use crate::accel::bvh::simd::Kernel;
use crate::accel::bvh::triangle::{RayTri, Tri, Tri4, TriHit};
use crate::accel::bvh::BuildParams;
use crate::geometry::Aabb;

/// Closest triangle found so far, in the space it was tested in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PrimHit {
    pub t: f32,
    pub u: f32,
    pub v: f32,
    /// The triangle (copied, so the caller can read its ids and normal).
    pub tri: Tri,
}

/// Triangles plus the tree over them.
#[derive(Clone, Debug, Default)]
pub(crate) struct MeshBvh {
    pub bvh: FlatBvh,
    /// The 8-wide copy rays traverse; its leaves are ranges of `packets`.
    pub(crate) wide: Wide,
    /// The triangles as given to [`Self::build`]; packets name them by index here.
    pub(crate) tris: Vec<Tri>,
    /// Leaf order: binary leaf range `first..first + count` holds triangles
    /// `tris[order[first..first + count]]` ([`Self::leaf_tris`]). Kept instead of a copy of
    /// `tris` in that order: 44 bytes less per triangle, and one pass over them less per build.
    order: Vec<u32>,
    /// Each binary leaf's triangles in packets of four, in leaf order.
    pub packets: Vec<Tri4>,
}

impl MeshBvh {
    /// Builds over `tris`, which must all be valid (see [`crate::accel::bvh::triangle::extract`]).
    pub(crate) fn build(tris: Vec<Tri>, params: BuildParams) -> Self {
        let (bvh, order) = build_with(tris.len(), |i| tris[i].bounds(), params);
        let (packets, wide) = packets_and_wide(&bvh, &tris, &order);
        Self { bvh, wide, tris, order, packets }
    }

    /// The triangles of the binary leaf range `first..first + count`, in leaf order (the
    /// tests' reference traversal and the invariant check; rays use the packets).
    #[cfg(test)]
    pub(crate) fn leaf_tris(&self, first: u32, count: u32) -> impl Iterator<Item = &Tri> + '_ {
        self.order[first as usize..(first + count) as usize].iter().map(|&i| &self.tris[i as usize])
    }

    /// Every triangle, in leaf order.
    pub(crate) fn tris_in_leaf_order(&self) -> impl Iterator<Item = &Tri> + '_ {
        self.order.iter().map(|&i| &self.tris[i as usize])
    }

    pub(crate) fn bounds(&self) -> Aabb {
        self.bvh.bounds()
    }

    pub(crate) fn memory_bytes(&self) -> usize {
        self.bvh.memory_bytes()
            + self.wide.memory_bytes()
            + self.tris.len() * std::mem::size_of::<Tri>()
            + self.order.len() * std::mem::size_of::<u32>()
            + self.packets.len() * std::mem::size_of::<Tri4>()
    }

    /// Closest hit in the subtree at `root` with `t <= *t_max`; lowers `*t_max` and overwrites
    /// `best` when it finds one. Returns whether it found one.
    ///
    /// The leaf closures here and in [`Self::occluded_from`] stay out of line (a mesh is
    /// traversed from two places in one query, the static tree's blocks and the instances),
    /// so their tests run inside [`Kernel::leaf`], which compiles them for the path (without
    /// it they are legacy SSE, the x86-64 baseline). Inlining the leaf tests (as closures,
    /// as visitor types, or the whole traversal inside `Kernel::leaf`) was tried several ways
    /// and never paid; with AVX-512 it pushed the entry out of line and doubled render times:
    /// docs/lab/accelerators.md#2026-12-04-where-the-accelerator-targets-end-target-by-target
    #[inline(always)]
    pub(crate) fn intersect_from<K: Kernel>(
        &self,
        k: K,
        root: Start,
        bray: &BoxRay,
        tray: &RayTri,
        t_max: &mut f32,
        best: &mut Option<PrimHit>,
    ) -> bool {
        let mut found = false;
        self.wide.traverse::<_, _, CLOSEST_HIT>(
            k,
            &self.bvh,
            root,
            bray,
            t_max,
            &mut |first, count, t_max| {
                found |= self.intersect_leaf(k, (first, count), tray, t_max, best);
                false
            },
        );
        found
    }

    /// The leaf test of [`Self::intersect_from`] on packets `first..first + count`: lowers
    /// `*t_max` and overwrites `best` when it finds a hit strictly nearer than `best`'s.
    #[inline(always)]
    fn intersect_leaf<K: Kernel>(
        &self,
        k: K,
        (first, count): (u32, u32),
        tray: &RayTri,
        t_max: &mut f32,
        best: &mut Option<PrimHit>,
    ) -> bool {
        let packets = self.leaf_packets(first, count);
        k.leaf(|| match k.closest_tri(tray, packets, *t_max) {
            Some(hit) => self.record(packets, hit, t_max, best),
            None => false,
        })
    }

    /// The packets of leaf range `first..first + count`.
    #[inline(always)]
    fn leaf_packets(&self, first: u32, count: u32) -> &[Tri4] {
        &self.packets[first as usize..(first + count) as usize]
    }

    /// Keeps `hit` (lane `i` of `packets`) as the closest in `best` if it is strictly nearer
    /// (ties keep the first triangle found) and lowers `*t_max` to it; returns whether it did.
    #[inline(always)]
    fn record(
        &self,
        packets: &[Tri4],
        (i, h): (usize, TriHit),
        t_max: &mut f32,
        best: &mut Option<PrimHit>,
    ) -> bool {
        if best.is_some_and(|b| h.t >= b.t) {
            return false;
        }
        *t_max = h.t;
        let tri = self.tris[packets[i / 4].idx[i % 4] as usize];
        *best = Some(PrimHit { t: h.t, u: h.u, v: h.v, tri });
        true
    }

    /// Whether any triangle of the subtree at `root` is hit within `[t_min, t_max]`.
    #[inline(always)]
    pub(crate) fn occluded_from<K: Kernel>(
        &self,
        k: K,
        root: Start,
        bray: &BoxRay,
        tray: &RayTri,
        t_max: f32,
    ) -> bool {
        let mut t_max = t_max;
        self.wide.traverse::<_, _, ANY_HIT>(
            k,
            &self.bvh,
            root,
            bray,
            &mut t_max,
            &mut |first, count, t_max| self.occluded_leaf(k, (first, count), tray, *t_max),
        )
    }

    /// The leaf test of [`Self::occluded_from`] on packets `first..first + count`.
    #[inline(always)]
    fn occluded_leaf<K: Kernel>(&self, k: K, (first, count): (u32, u32), tray: &RayTri, t_max: f32) -> bool {
        let packets = self.leaf_packets(first, count);
        k.leaf(|| k.occluded_tri(tray, packets, t_max))
    }
}

/// Packet queries ([`super::packet`]): each lane gets what the single-ray query above gives it.
impl MeshBvh {
    /// [`Self::intersect_from`] for the `lanes` of a packet; returns the lanes that found a
    /// hit (and lowered their `t_max` and `best`).
    #[inline(always)]
    pub(crate) fn intersect_packet_from<K: Kernel>(
        &self,
        k: K,
        root: Start,
        packet: &RayPacket,
        lanes: Lanes,
        t_max: &mut [f32; PACKET],
        best: &mut [Option<PrimHit>; PACKET],
    ) -> Lanes {
        let mut found = 0;
        self.wide.traverse_packet(
            k,
            &self.bvh,
            root,
            PacketLanes { packet, lanes },
            t_max,
            &mut |first, count, lanes, t_max| {
                found |= self.intersect_packet_leaf(k, (first, count), packet, lanes, t_max, best);
                0
            },
        );
        found
    }

    /// The leaf test of [`Self::intersect_packet_from`] on packets `first..first + count`:
    /// [`Self::intersect_leaf`] for each of `lanes`; returns the lanes that found a nearer hit.
    #[inline(always)]
    fn intersect_packet_leaf<K: Kernel>(
        &self,
        k: K,
        (first, count): (u32, u32),
        packet: &RayPacket,
        lanes: Lanes,
        t_max: &mut [f32; PACKET],
        best: &mut [Option<PrimHit>; PACKET],
    ) -> Lanes {
        let packets = self.leaf_packets(first, count);
        k.leaf(|| {
            let mut found = 0;
            for i in each_bit(lanes) {
                if let Some(hit) = k.closest_tri(&packet.tray[i], packets, t_max[i]) {
                    if self.record(packets, hit, &mut t_max[i], &mut best[i]) {
                        found |= 1 << i;
                    }
                }
            }
            found
        })
    }

    /// [`Self::occluded_from`] for the `lanes` of a packet: the lanes that hit a triangle
    /// within their `[t_min, t_max]`.
    #[inline(always)]
    pub(crate) fn occluded_packet_from<K: Kernel>(
        &self,
        k: K,
        root: Start,
        packet: &RayPacket,
        lanes: Lanes,
        t_max: &[f32; PACKET],
    ) -> Lanes {
        let mut t_max = *t_max;
        self.wide.traverse_packet(
            k,
            &self.bvh,
            root,
            PacketLanes { packet, lanes },
            &mut t_max,
            &mut |first, count, lanes, t_max| {
                self.occluded_packet_leaf(k, (first, count), packet, lanes, t_max)
            },
        )
    }

    /// The leaf test of [`Self::occluded_packet_from`] on packets `first..first + count`: the
    /// lanes blocked.
    #[inline(always)]
    fn occluded_packet_leaf<K: Kernel>(
        &self,
        k: K,
        (first, count): (u32, u32),
        packet: &RayPacket,
        lanes: Lanes,
        t_max: &[f32; PACKET],
    ) -> Lanes {
        let packets = self.leaf_packets(first, count);
        k.leaf(|| {
            let mut blocked = 0;
            for i in each_bit(lanes) {
                if k.occluded_tri(&packet.tray[i], packets, t_max[i]) {
                    blocked |= 1 << i;
                }
            }
            blocked
        })
    }
}

/// The packets of every binary leaf (in node order) and the wide tree whose leaves name them,
/// made at the same time (both only read the tree); the packets over rayon (each is packed
/// from its own range of the leaf order, straight into its place).
fn packets_and_wide(bvh: &FlatBvh, tris: &[Tri], order: &[u32]) -> (Vec<Tri4>, Wide) {
    let mut first_packet = vec![0u32; bvh.nodes.len()];
    // Per packet: its first position in the leaf order and how many triangles it holds.
    let mut ranges: Vec<(u32, u32)> = Vec::with_capacity(tris.len().div_ceil(2));
    for (i, n) in bvh.nodes.iter().enumerate().filter(|(_, n)| n.is_leaf()) {
        first_packet[i] = ranges.len() as u32;
        for start in (n.first..n.first + n.count).step_by(4) {
            ranges.push((start, (n.first + n.count - start).min(4)));
        }
    }
    let packets = || {
        ranges
            .par_iter()
            .with_min_len(PAR_CHUNK / 4)
            .map(|&(start, len)| Tri4::pack(tris, &order[start as usize..(start + len) as usize]))
            .collect()
    };
    rayon::join(packets, || Wide::new(bvh, |i, n: &Node| (first_packet[i as usize], n.count.div_ceil(4))))
}
