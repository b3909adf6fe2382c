//! Triangles as the BVH leaves store them, and the watertight ray-triangle test (Woop, Benthin
//! and Wald 2013) that keeps rays from leaking through edges shared by two triangles, on one
//! triangle ([`RayTri::intersect`]) and on a leaf's packets of four ([`Tri4`],
//! [`RayTri::closest_in`], [`RayTri::occluded_in`]): the same operations in the same order on
//! the lanes of a [`TriLanes`] (four in glam's `Vec4`, or eight in AVX2), so each lane's hit is
//! bit for bit the one-triangle test's; `tests/bvh_props.rs` pins that on every SIMD path.

use std::ops::{Add, BitAnd, BitOr, Div, Index, Mul, Not, Sub};

use glam::{Vec3, Vec4};
use rayon::prelude::*;

use crate::geometry::{Ray, TriangleMesh};

/// One triangle copied out of its mesh, with the ids a [`crate::accel::Hit`] reports.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Tri {
    pub p: [Vec3; 3],
    /// The mesh it came from (a `StaticId` for static geometry, unused for prototypes).
    pub(crate) geom: u32,
    /// Triangle index within that mesh.
    pub prim: u32,
}

impl Tri {
    pub(crate) fn bounds(&self) -> crate::geometry::Aabb {
        crate::geometry::Aabb::from_points(self.p)
    }

    /// Unnormalised geometric normal `(p1 - p0) x (p2 - p0)`.
    pub(crate) fn normal(&self) -> Vec3 {
        (self.p[1] - self.p[0]).cross(self.p[2] - self.p[0])
    }
}

/// Largest coordinate magnitude kept: beyond it, box areas and SAH costs overflow `f32`.
pub(crate) const MAX_COORD: f32 = 1e30;

/// Copies the usable triangles of `mesh` ([`TriangleMesh::triangle_is_valid`]: finite, non-zero
/// area; and every coordinate below [`MAX_COORD`] in magnitude); returns them and how many were
/// skipped. The mesh must have passed [`TriangleMesh::validate`].
///
/// Usable triangles are counted first: when all are (the common case), they are copied
/// straight into place. A filtered parallel collect gathers per-thread pieces and then copies
/// them into one vector on the calling thread.
pub(crate) fn extract(mesh: &TriangleMesh, geom: u32) -> (Vec<Tri>, usize) {
    let n = mesh.triangle_count();
    let usable = |i: usize| {
        mesh.triangle_is_valid(i) && mesh.triangle(i).iter().all(|p| p.abs().max_element() < MAX_COORD)
    };
    let tri = |i: usize| Tri { p: mesh.triangle(i), geom, prim: i as u32 };
    let chunk = super::params::PAR_CHUNK;
    let kept = (0..n).into_par_iter().with_min_len(chunk).filter(|&i| usable(i)).count();
    let tris: Vec<Tri> = if kept == n {
        (0..n).into_par_iter().with_min_len(chunk).map(tri).collect()
    } else {
        (0..n).into_par_iter().with_min_len(chunk).filter(|&i| usable(i)).map(tri).collect()
    };
    (tris, n - kept)
}

/// A triangle hit in the space the triangle was tested in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct TriHit {
    pub t: f32,
    pub u: f32,
    pub v: f32,
}

/// Per-ray constants of the watertight test: the ray is sheared so that it runs along +z.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RayTri {
    org: Vec3,
    dir: Vec3,
    kx: Axis,
    ky: Axis,
    kz: Axis,
    /// The origin's coordinates on the axes `kx`, `ky`, `kz`, picked once per ray: glam's
    /// `Vec3` indexed by a variable is a `match`, and the leaves read these on every call.
    org_k: [f32; 3],
    sx: f32,
    sy: f32,
    pub t_min: f32,
}

impl RayTri {
    /// The watertight test's constants for `ray`. The shear's `kx`, `ky` come from two `% 3`
    /// and a swap: a six-entry table indexed by `2 * kz` and the sign ran more instructions:
    /// docs/lab/accelerators.md#2026-12-03-trace-experiments-none-kept-the-gap-to-embree-by-query-cachegrind-callgrind
    pub(crate) fn new(ray: &Ray) -> Self {
        let (o, d) = (ray.origin.to_array(), ray.dir.to_array());
        let kz = ray.dir.abs().max_position();
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        Self {
            org: ray.origin,
            dir: ray.dir,
            kx: Axis::new(kx),
            ky: Axis::new(ky),
            kz: Axis::new(kz),
            org_k: [o[kx], o[ky], o[kz]],
            sx: d[kx] / d[kz],
            sy: d[ky] / d[kz],
            t_min: ray.t_min,
        }
    }

    /// Hit with `t_min <= t <= t_max`, if any. Both sides of the triangle are hit.
    #[inline(always)]
    pub(crate) fn intersect(&self, tri: &[Vec3; 3], t_max: f32) -> Option<TriHit> {
        let (kx, ky, kz) = (self.kx.0, self.ky.0, self.kz.0);
        let a = tri[0] - self.org;
        let b = tri[1] - self.org;
        let c = tri[2] - self.org;
        let ax = a[kx] - self.sx * a[kz];
        let ay = a[ky] - self.sy * a[kz];
        let bx = b[kx] - self.sx * b[kz];
        let by = b[ky] - self.sy * b[kz];
        let cx = c[kx] - self.sx * c[kz];
        let cy = c[ky] - self.sy * c[kz];
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        if u == 0.0 || v == 0.0 || w == 0.0 {
            // Exactly on an edge in f32: decide in double precision so that the two
            // triangles sharing the edge agree.
            u = (f64::from(cx) * f64::from(by) - f64::from(cy) * f64::from(bx)) as f32;
            v = (f64::from(ax) * f64::from(cy) - f64::from(ay) * f64::from(cx)) as f32;
            w = (f64::from(bx) * f64::from(ay) - f64::from(by) * f64::from(ax)) as f32;
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        // The edge functions above decide *whether* the ray hits (watertight). The distance
        // comes from the plane equation instead of the scaled barycentric sum: for long thin
        // triangles far from the ray origin the sum cancels badly (seen on the monastery:
        // relative t errors of 2e-4 against an exact 1e-7), while the plane equation stays
        // accurate and is what Embree computes.
        let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
        let t = n.dot(a) / n.dot(self.dir);
        if !(t >= self.t_min && t <= t_max) {
            return None;
        }
        let rcp = 1.0 / det;
        Some(TriHit { t, u: v * rcp, v: w * rcp })
    }
}

/// Four triangles in structure-of-arrays layout: `rows[v][axis]` holds coordinate `axis` of
/// vertex `v` of the four lanes, and `rows[NORMAL]` their normals.
/// A leaf with fewer than four triangles repeats its last one (a duplicate never wins: ties
/// keep the lowest lane).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub(crate) struct Tri4 {
    /// Vertices 0 to 2, then the unnormalised normals `(p1 - p0) x (p2 - p0)` ([`Tri::normal`],
    /// bit for bit).
    rows: [[Vec4; 3]; 4],
    /// Index of each lane's triangle in the owner's triangle array.
    pub(crate) idx: [u32; 4],
}

/// [`Tri4::row`]'s index of the normals.
pub(crate) const NORMAL: usize = 3;

/// A coordinate axis, 0 to 2: what [`Tri4::row`] reads a packet by without a bounds check.
///
/// The watertight test reads the packet by the ray's axes, which are known only at run time;
/// checked, that was nine compares and branches per leaf test. The one constructor clamps,
/// and the compiler drops the clamp where it knows the index is below 3, as in
/// [`RayTri::new`]. (A `u8` enum, whose range the compiler knows, saved as much in the leaf
/// tests and cost more where it is made from an index: a `match`.)
#[derive(Clone, Copy, Debug)]
pub(crate) struct Axis(usize);

impl Axis {
    pub(crate) const X: Axis = Axis(0);
    pub(crate) const Y: Axis = Axis(1);
    pub(crate) const Z: Axis = Axis(2);

    #[inline(always)]
    fn new(i: usize) -> Self {
        Axis(i.min(2))
    }
}

impl Tri4 {
    /// Packs the triangles `tris[idx[..]]` (1 to 4 of them) into one packet.
    pub(crate) fn pack(tris: &[Tri], idx: &[u32]) -> Self {
        debug_assert!(!idx.is_empty() && idx.len() <= 4);
        let idx: [u32; 4] = std::array::from_fn(|i| idx[i.min(idx.len() - 1)]);
        let lanes: [&Tri; 4] = idx.map(|i| &tris[i as usize]);
        let normals: [Vec3; 4] = lanes.map(Tri::normal);
        let rows = std::array::from_fn(|v| {
            std::array::from_fn(|a| {
                Vec4::from_array(std::array::from_fn(|i| {
                    if v == NORMAL {
                        normals[i][a]
                    } else {
                        lanes[i].p[v][a]
                    }
                }))
            })
        });
        Self { rows, idx }
    }

    /// Coordinate `axis` of vertex `v` (0 to 2) or of the normal ([`NORMAL`]) of each lane.
    /// `v` is a constant wherever this is inlined, so its bounds check folds away; `axis` is
    /// the ray's, and is read without one.
    #[inline(always)]
    pub(crate) fn row(&self, v: usize, axis: Axis) -> Vec4 {
        let row = &self.rows[v];
        // SAFETY: `axis.0 < 3`, which `Axis`'s only constructor makes sure of, and `row` has
        // three entries.
        unsafe { *row.get_unchecked(axis.0) }
    }

    /// Lane `i`'s vertices.
    fn lane(&self, i: usize) -> [Vec3; 3] {
        std::array::from_fn(|v| Vec3::new(self.rows[v][0][i], self.rows[v][1][i], self.rows[v][2][i]))
    }
}

/// The lane arithmetic of the packet test ([`RayTri::closest_in`]): one packet's four
/// triangles in glam's `Vec4` (every path), or two packets' eight in one AVX register
/// (`simd::x86`). Every operation is the IEEE one on each lane, in the order
/// [`RayTri::intersect`] does it on one triangle, so a lane's hit is bit for bit that test's
/// at either width (`tests/bvh_props.rs` pins it on every path).
pub(crate) trait TriLanes:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Div<Output = Self>
{
    /// One flag per lane.
    type Mask: Copy + BitAnd<Output = Self::Mask> + BitOr<Output = Self::Mask> + Not<Output = Self::Mask>;
    /// The lanes stored.
    type Array: Copy + Index<usize, Output = f32>;
    /// Packets per value (1 or 2): lane `4 * p + i` is lane `i` of packet `p`.
    const PACKETS: usize;
    fn splat(x: f32) -> Self;
    /// Lane-wise minimum and maximum (`minps` / `maxps`).
    fn min(self, o: Self) -> Self;
    fn max(self, o: Self) -> Self;
    /// [`Tri4::row`] of `q[..Self::PACKETS]`.
    fn row(q: &[Tri4], v: usize, axis: Axis) -> Self;
    fn lt(self, o: Self) -> Self::Mask;
    fn gt(self, o: Self) -> Self::Mask;
    fn eq(self, o: Self) -> Self::Mask;
    fn ne(self, o: Self) -> Self::Mask;
    fn ge(self, o: Self) -> Self::Mask;
    fn le(self, o: Self) -> Self::Mask;
    fn finite(self) -> Self::Mask;
    /// Bit `i` set for lane `i`.
    fn bitmask(m: Self::Mask) -> u32;
    fn to_array(self) -> Self::Array;
}

impl TriLanes for Vec4 {
    type Mask = glam::BVec4A;
    type Array = [f32; 4];
    const PACKETS: usize = 1;

    #[inline(always)]
    fn splat(x: f32) -> Self {
        Vec4::splat(x)
    }

    #[inline(always)]
    fn min(self, o: Self) -> Self {
        Vec4::min(self, o)
    }

    #[inline(always)]
    fn max(self, o: Self) -> Self {
        Vec4::max(self, o)
    }

    #[inline(always)]
    fn row(q: &[Tri4], v: usize, axis: Axis) -> Self {
        q[0].row(v, axis)
    }

    #[inline(always)]
    fn lt(self, o: Self) -> Self::Mask {
        self.cmplt(o)
    }

    #[inline(always)]
    fn gt(self, o: Self) -> Self::Mask {
        self.cmpgt(o)
    }

    #[inline(always)]
    fn eq(self, o: Self) -> Self::Mask {
        self.cmpeq(o)
    }

    #[inline(always)]
    fn ne(self, o: Self) -> Self::Mask {
        self.cmpne(o)
    }

    #[inline(always)]
    fn ge(self, o: Self) -> Self::Mask {
        self.cmpge(o)
    }

    #[inline(always)]
    fn le(self, o: Self) -> Self::Mask {
        self.cmple(o)
    }

    #[inline(always)]
    fn finite(self) -> Self::Mask {
        self.is_finite_mask()
    }

    #[inline(always)]
    fn bitmask(m: Self::Mask) -> u32 {
        m.bitmask()
    }

    #[inline(always)]
    fn to_array(self) -> [f32; 4] {
        Vec4::to_array(&self)
    }
}

/// What one packet test found.
enum LaneTest<L: TriLanes> {
    Miss,
    /// A lane that may be inside is exactly on an edge in f32: the one-triangle test decides.
    OnEdge,
    /// `mask`: the lanes hit within the interval, with their distances and edge functions.
    Hit {
        mask: u32,
        t: L,
        v: L,
        w: L,
        det: L,
    },
}

impl RayTri {
    /// The closest triangle of a leaf's `packets` hit with `t_min <= t <= t_max`: its index in
    /// the packets' lanes (`4 * packet + lane`, the lowest on ties) and the hit, which equals
    /// [`Self::intersect`] on that triangle. `L` tests `L::PACKETS` packets at once; a last
    /// packet left over goes 4-wide.
    ///
    /// Eight lanes (the AVX2 and AVX-512 paths) test a leaf's two packets in one go: a leaf
    /// holds up to eight triangles, in 1.66 packets on average on the monastery with 8,000
    /// ducks, and the second packet cost a whole test.
    #[inline(always)]
    pub(crate) fn closest_in<L: TriLanes>(&self, packets: &[Tri4], t_max: f32) -> Option<(usize, TriHit)> {
        // Loops and functions, no closures or iterator adaptors: on the AVX2 path, code left
        // out of line would make every intrinsic a call.
        let mut t_max = t_max;
        let mut best: Option<(usize, TriHit)> = None;
        let full = packets.len() / L::PACKETS * L::PACKETS;
        let mut p = 0;
        while p < packets.len() {
            let hit = if p < full {
                self.closest_lane::<L>(&packets[p..p + L::PACKETS], t_max)
            } else {
                // The last packet, when a leaf has one more than `L` takes.
                self.closest_lane::<Vec4>(&packets[p..p + 1], t_max)
            };
            if let Some((i, h)) = hit {
                // Strictly closer only: ties keep the lowest index.
                if best.is_none_or(|(_, b)| h.t < b.t) {
                    t_max = h.t;
                    best = Some((4 * p + i, h));
                }
            }
            p += if p < full { L::PACKETS } else { 1 };
        }
        best
    }

    /// Whether any triangle of `packets` is hit with `t_min <= t <= t_max` ([`Self::closest_in`]'s
    /// lanes, without picking the closest).
    #[inline(always)]
    pub(crate) fn occluded_in<L: TriLanes>(&self, packets: &[Tri4], t_max: f32) -> bool {
        let full = packets.len() / L::PACKETS * L::PACKETS;
        let mut p = 0;
        while p < full {
            if self.occludes::<L>(&packets[p..p + L::PACKETS], t_max) {
                return true;
            }
            p += L::PACKETS;
        }
        p < packets.len() && self.occludes::<Vec4>(&packets[p..p + 1], t_max)
    }

    /// Whether one packet test finds a lane hit.
    #[inline(always)]
    fn occludes<L: TriLanes>(&self, q: &[Tri4], t_max: f32) -> bool {
        match self.test_lanes::<L>(q, t_max) {
            LaneTest::Miss => false,
            LaneTest::OnEdge => self.closest_scalar(q, t_max).is_some(),
            LaneTest::Hit { .. } => true,
        }
    }

    /// The closest of one packet test's lanes hit with `t_min <= t <= t_max` (the lowest lane
    /// on ties), with its lane.
    ///
    /// The vertices are read by the ray's axes straight from the packet (one load each, the
    /// axis offsets fixed per ray), not shifted on all three axes first and then picked: that
    /// form stored the nine shifted rows to the stack and read them back by index, more
    /// instructions per leaf test:
    /// docs/lab/accelerators.md#2026-12-03-embree-counted-too-half-its-instructions-cachegrind
    #[inline(always)]
    fn closest_lane<L: TriLanes>(&self, q: &[Tri4], t_max: f32) -> Option<(usize, TriHit)> {
        let (mut mask, t, v, w, det) = match self.test_lanes::<L>(q, t_max) {
            LaneTest::Miss => return None,
            LaneTest::OnEdge => return self.closest_scalar(q, t_max),
            LaneTest::Hit { mask, t, v, w, det } => (mask, t, v, w, det),
        };
        let ts = t.to_array();
        let mut best = mask.trailing_zeros() as usize;
        mask &= mask - 1;
        while mask != 0 {
            let i = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            if ts[i] < ts[best] {
                best = i;
            }
        }
        let rcp = 1.0 / det.to_array()[best];
        Some((best, TriHit { t: ts[best], u: v.to_array()[best] * rcp, v: w.to_array()[best] * rcp }))
    }

    /// The watertight test on every lane of `q[..L::PACKETS]`: the same operations in the same
    /// order as [`Self::intersect`]. A lane exactly on an edge goes to the one-triangle test
    /// only if it could be inside: a strictly negative and a strictly positive edge function
    /// keep their signs in f64 (both products are exact there), so such a lane is out either
    /// way.
    ///
    /// The ray's axes index the packet without bounds checks ([`Axis`]).
    #[inline(always)]
    fn test_lanes<L: TriLanes>(&self, q: &[Tri4], t_max: f32) -> LaneTest<L> {
        debug_assert_eq!(q.len(), L::PACKETS);
        let (ax, ay) = self.sheared::<L>(q, 0);
        let (bx, by) = self.sheared::<L>(q, 1);
        let (cx, cy) = self.sheared::<L>(q, 2);
        let u = cx * by - cy * bx;
        let v = ax * cy - ay * cx;
        let w = bx * ay - by * ax;
        let zero = L::splat(0.0);
        // Outside when one edge function is negative and another positive: the smallest below
        // zero and the largest above. A lane with a NaN edge function may come out either way
        // here (min and max pass NaN on from one operand only), but its `det` is NaN and the
        // lane is never hit, on this path or the one-triangle test's. Fewer instructions than
        // three compares per side.
        let neg = u.min(v).min(w).lt(zero);
        let pos = u.max(v).max(w).gt(zero);
        let maybe_inside = !(neg & pos);
        if L::bitmask(maybe_inside) == 0 {
            // Every lane outside an edge (most packets a ray reaches): no distance, no division.
            return LaneTest::Miss;
        }
        if L::bitmask(maybe_inside & (u.eq(zero) | v.eq(zero) | w.eq(zero))) != 0 {
            return LaneTest::OnEdge;
        }
        let det = u + v + w;
        let (o, d) = (self.org, self.dir);
        let a = [
            L::row(q, 0, Axis::X) - L::splat(o.x),
            L::row(q, 0, Axis::Y) - L::splat(o.y),
            L::row(q, 0, Axis::Z) - L::splat(o.z),
        ];
        let n = [L::row(q, NORMAL, Axis::X), L::row(q, NORMAL, Axis::Y), L::row(q, NORMAL, Axis::Z)];
        let dir = [L::splat(d.x), L::splat(d.y), L::splat(d.z)];
        let t = (n[0] * a[0] + n[1] * a[1] + n[2] * a[2]) / (n[0] * dir[0] + n[1] * dir[1] + n[2] * dir[2]);
        let ok =
            maybe_inside & det.ne(zero) & det.finite() & t.ge(L::splat(self.t_min)) & t.le(L::splat(t_max));
        match L::bitmask(ok) {
            0 => LaneTest::Miss,
            mask => LaneTest::Hit { mask, t, v, w, det },
        }
    }

    /// Vertex `v` of each lane relative to the origin, sheared so that the ray runs along +z
    /// (x and y): the same operations as [`Self::intersect`]'s `a[kx] - sx * a[kz]`.
    ///
    /// A function, not a closure: a closure is not `#[inline(always)]`, and the AVX2 lanes'
    /// intrinsics in one left out of line become calls.
    #[inline(always)]
    fn sheared<L: TriLanes>(&self, q: &[Tri4], v: usize) -> (L, L) {
        let z = L::row(q, v, self.kz) - L::splat(self.org_k[2]);
        let x = (L::row(q, v, self.kx) - L::splat(self.org_k[0])) - L::splat(self.sx) * z;
        let y = (L::row(q, v, self.ky) - L::splat(self.org_k[1])) - L::splat(self.sy) * z;
        (x, y)
    }

    /// [`Self::closest_lane`] one lane at a time with [`Self::intersect`].
    #[cold]
    fn closest_scalar(&self, q: &[Tri4], t_max: f32) -> Option<(usize, TriHit)> {
        let mut best: Option<(usize, TriHit)> = None;
        for (p, packet) in q.iter().enumerate() {
            for i in 0..4 {
                if let Some(h) = self.intersect(&packet.lane(i), t_max) {
                    if best.is_none_or(|(_, b)| h.t < b.t) {
                        best = Some((4 * p + i, h));
                    }
                }
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn barycentrics_follow_embree() {
        let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let ray = Ray::new(Vec3::new(0.25, 0.5, 1.0), Vec3::new(0.0, 0.0, -2.0));
        let h = RayTri::new(&ray).intersect(&tri, f32::INFINITY).unwrap();
        assert!((h.t - 0.5).abs() < 1e-6);
        assert!((h.u - 0.25).abs() < 1e-6 && (h.v - 0.5).abs() < 1e-6);
        // Back side is hit too.
        let ray = Ray::new(Vec3::new(0.25, 0.5, -1.0), Vec3::Z);
        assert!(RayTri::new(&ray).intersect(&tri, f32::INFINITY).is_some());
    }

    #[test]
    fn shared_edge_does_not_leak() {
        // Two triangles sharing the diagonal of a unit square; rays through the diagonal hit one.
        let q = [
            [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0)],
            [Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
        ];
        for i in 0..1000 {
            let s = i as f32 / 1000.0;
            for ray in [
                Ray::new(Vec3::new(s, s, 1.0), -Vec3::Z),
                Ray::new(Vec3::new(s + 0.3, s + 0.3, 1.0), Vec3::new(-0.3, -0.3, -1.0)),
                Ray::new(Vec3::new(s - 0.7, s + 0.2, 0.9), Vec3::new(0.7, -0.2, -0.9)),
            ] {
                let rt = RayTri::new(&ray);
                assert!(q.iter().any(|t| rt.intersect(t, f32::INFINITY).is_some()), "leak at {s}");
            }
        }
    }
}
