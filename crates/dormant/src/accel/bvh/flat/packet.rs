//! Packet traversal of the wide trees: up to [`PACKET`] rays (a renderer's block of camera
//! rays) walk one tree together. Each wide node is loaded once for the packet and tested with
//! the single-ray box kernel for every lane still in it; a child is entered by the lanes that
//! hit its box, nearest (over those lanes) first. Lanes drop out of a subtree when their own
//! closest hit is nearer than its entry, and out of the whole walk when a leaf says they are
//! done (any-hit). Each lane gets the hit a single ray would (up to ties between surfaces at
//! the same distance, which the visiting order decides).
//!
//! Each lane keeps its own box tests rather than one box against eight lanes (Wald's packets):
//! the node step's kernel stays the one every SIMD path already has and is tested on, and a
//! leaf is tested only by the lanes that reach it. One conservative test of the whole packet
//! per node was tried: without each lane's own tests every lane reached every leaf the packet
//! did, and it ran more instructions, not fewer:
//! docs/lab/accelerators.md#2026-12-03-redundant-box-tests-and-stack-round-trips-removed-cachegrind

use glam::Vec4;

use super::stack::TraversalStack;
use super::wide::{LEAF, WIDE_STACK, WIDTH};
use super::{BoxRay, FlatBvh, Node, Start, Wide};
use crate::accel::bvh::simd::{BoxRay8, Kernel};
use crate::accel::bvh::triangle::RayTri;
use crate::geometry::Ray;

/// Rays per packet: the renderer's 4x2 camera blocks.
pub(crate) const PACKET: usize = 8;

/// A set of packet lanes, bit `i` for lane `i`.
pub(crate) type Lanes = u32;

/// Up to [`PACKET`] rays prepared for the box and triangle tests. Lanes beyond the rays given
/// repeat the last ray; traversals only look at the lanes they are asked for.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RayPacket {
    pub(crate) bray: [BoxRay; PACKET],
    pub(crate) tray: [RayTri; PACKET],
}

impl RayPacket {
    /// The packet of `rays` (1 to [`PACKET`] of them) in world or object space.
    pub(crate) fn new(rays: &[Ray]) -> Self {
        debug_assert!(!rays.is_empty() && rays.len() <= PACKET);
        let ray = |i: usize| &rays[i.min(rays.len() - 1)];
        Self {
            bray: std::array::from_fn(|i| BoxRay::new(ray(i))),
            tray: std::array::from_fn(|i| RayTri::new(ray(i))),
        }
    }

    /// Replaces lane `i` by `ray`.
    #[inline(always)]
    pub(crate) fn set(&mut self, i: usize, ray: &Ray) {
        self.bray[i] = BoxRay::new(ray);
        self.tray[i] = RayTri::new(ray);
    }
}

/// The lanes of a packet a traversal serves: the packet's rays and which of them walk.
#[derive(Clone, Copy)]
pub(crate) struct PacketLanes<'a> {
    pub(crate) packet: &'a RayPacket,
    pub(crate) lanes: Lanes,
}

/// The lanes whose `t_max` is at least `t` (those a subtree entered at `t` may still serve).
#[inline(always)]
fn lanes_within(t_max: &[f32; PACKET], t: f32) -> Lanes {
    let t = Vec4::splat(t);
    let lo = Vec4::from_slice(&t_max[..4]).cmpge(t).bitmask();
    let hi = Vec4::from_slice(&t_max[4..]).cmpge(t).bitmask();
    lo | hi << 4
}

/// The set bits of a mask, lowest first: the lanes of a [`Lanes`], or the children of a node.
#[inline(always)]
pub(crate) fn each_bit(mut lanes: Lanes) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        (lanes != 0).then(|| {
            let i = lanes.trailing_zeros() as usize;
            lanes &= lanes - 1;
            i
        })
    })
}

/// The transpose of the 8x8 bit matrix whose row `r` is byte `r` (bit `c` of it column `c`):
/// bit `8r + c` goes to bit `8c + r` (Hacker's Delight, 7-3).
#[inline(always)]
fn transpose8x8(mut x: u64) -> u64 {
    let t = (x ^ (x >> 7)) & 0x00AA_00AA_00AA_00AA;
    x ^= t ^ (t << 7);
    let t = (x ^ (x >> 14)) & 0x0000_CCCC_0000_CCCC;
    x ^= t ^ (t << 14);
    let t = (x ^ (x >> 28)) & 0x0000_0000_F0F0_F0F0;
    x ^ t ^ (t << 28)
}

/// Stack entries of a packet walk: node code, nearest entry over its lanes, its lanes.
type PacketStack = TraversalStack<(u32, f32, Lanes), WIDE_STACK>;

impl Wide {
    /// [`Wide::traverse`] for the `lanes` of a packet: visits the leaves of the subtree `root`
    /// that any of them may hit, nearer first. `leaf` gets each leaf's item
    /// range, the lanes that entered it and every lane's `t_max` (which it lowers on hits),
    /// and returns the lanes it finished (any-hit; closest-hit returns none). Returns the
    /// lanes finished in all.
    ///
    /// `leaf` is called from one place only, for the reason [`Wide::traverse`] gives.
    #[inline(always)]
    pub(crate) fn traverse_packet<K: Kernel, F>(
        &self,
        k: K,
        bvh: &FlatBvh,
        root: Start,
        PacketLanes { packet, lanes }: PacketLanes<'_>,
        t_max: &mut [f32; PACKET],
        leaf: &mut F,
    ) -> Lanes
    where
        F: FnMut(u32, u32, Lanes, &mut [f32; PACKET]) -> Lanes,
    {
        let mut stack = PacketStack::new();
        let enter = |n: &Node| {
            let (mut entered, mut t) = (0, f32::INFINITY);
            for i in each_bit(lanes) {
                let ti = packet.bray[i].hit(n, t_max[i]);
                if ti < f32::INFINITY {
                    entered |= 1 << i;
                    t = t.min(ti);
                }
            }
            (entered != 0).then_some((t, entered))
        };
        // A root entered by the caller is entered by all of `lanes`, at any distance.
        let entered = (f32::NEG_INFINITY, lanes);
        self.enter(bvh, root, entered, enter, |code, (t, entered)| stack.push((code, t, entered)));
        self.traverse8_packet(k, &mut stack, packet, lanes, t_max, leaf)
    }

    #[inline(always)]
    fn traverse8_packet<K: Kernel, F>(
        &self,
        k: K,
        stack: &mut PacketStack,
        packet: &RayPacket,
        mut active: Lanes,
        t_max: &mut [f32; PACKET],
        leaf: &mut F,
    ) -> Lanes
    where
        F: FnMut(u32, u32, Lanes, &mut [f32; PACKET]) -> Lanes,
    {
        let mut finished = 0;
        while let Some((mut cur, t, lanes)) = stack.pop() {
            let mut lanes = lanes & active & lanes_within(t_max, t);
            while lanes != 0 {
                if cur & LEAF != 0 {
                    let (first, count) = self.leaf_range(cur);
                    // The only call of `leaf`.
                    let done = leaf(first, count, lanes, t_max);
                    finished |= done;
                    active &= !done;
                    break;
                }
                match self.enter_children(k, packet, stack, cur, lanes, t_max) {
                    Some(next) => (cur, lanes) = next,
                    None => break,
                }
            }
            if active == 0 {
                break;
            }
        }
        finished
    }

    /// Enters the children of wide node `cur` that some of `lanes` enter: all but the nearest
    /// go on `stack` (stack code, nearest entry over the lanes that enter it, those lanes),
    /// the nearest is returned (code and lanes) to be taken next; `None` if none is entered.
    ///
    /// The node is loaded once and tested with each lane's box test, without branches per
    /// lane and child: each lane's children go into a byte of `rows` (bit = child), turned
    /// into each child's lanes (byte = child, bit = lane); each child's distance is the
    /// nearest over its lanes (misses at infinity).
    ///
    /// Pushing here, not in the caller, and each lane's kernel ray prepared here per node
    /// (broadcasts from the packet) rather than once per traversal into an array: returning
    /// the sorted children to the caller cost part of the packets' gain, and that array was
    /// copied with `memcpy` at every traversal, instance entries included. A loop over each
    /// lane's hit children instead of the transpose made packets slower than single rays:
    /// docs/lab/rendering.md#2026-12-02-bvh-packets
    #[inline(always)]
    fn enter_children<K: Kernel>(
        &self,
        k: K,
        packet: &RayPacket,
        stack: &mut PacketStack,
        cur: u32,
        lanes: Lanes,
        t_max: &[f32; PACKET],
    ) -> Option<(u32, Lanes)> {
        let n = &self.nodes[cur as usize];
        let (mut rows, mut entered) = (0u64, 0u32);
        let (mut lo, mut hi) = (Vec4::INFINITY, Vec4::INFINITY);
        for i in each_bit(lanes) {
            let b = &packet.bray[i];
            let kr = k.prepare(&BoxRay8 { org: b.org.into(), inv: b.inv.into(), t_min: b.t_min });
            let (mask, near) = k.box8_or_inf(&kr, &n.boxes, t_max[i]);
            let mask = mask & n.used;
            rows |= u64::from(mask) << (8 * i);
            entered |= mask;
            lo = lo.min(Vec4::from_slice(&near[..4]));
            hi = hi.min(Vec4::from_slice(&near[4..]));
        }
        let child_lanes = transpose8x8(rows).to_le_bytes();
        let (lo, hi) = (lo.to_array(), hi.to_array());
        let child_t = [lo[0], lo[1], lo[2], lo[3], hi[0], hi[1], hi[2], hi[3]];
        // Insertion sort, descending by entry distance.
        let mut hits = [(0u32, 0f32, 0 as Lanes); WIDTH];
        let mut m = 0;
        for slot in each_bit(entered) {
            let code = n.code(cur, slot);
            let mut j = m;
            while j > 0 && hits[j - 1].1 < child_t[slot] {
                hits[j] = hits[j - 1];
                j -= 1;
            }
            hits[j] = (code, child_t[slot], Lanes::from(child_lanes[slot]));
            m += 1;
        }
        let (&(code, _, lanes), farther) = hits[..m].split_last()?;
        for &entry in farther {
            stack.push(entry);
        }
        Some((code, lanes))
    }
}

#[cfg(test)]
mod tests {
    use super::transpose8x8;

    #[test]
    fn transpose_moves_every_bit_across_the_diagonal() {
        let mut x = 0x9E37_79B9_7F4A_7C15u64;
        for _ in 0..200 {
            x = x.rotate_left(13).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            let t = transpose8x8(x);
            for r in 0..8 {
                for c in 0..8 {
                    assert_eq!(x >> (8 * r + c) & 1, t >> (8 * c + r) & 1, "row {r} column {c} of {x:#x}");
                }
            }
        }
    }
}
