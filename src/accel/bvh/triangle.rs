//! Triangles as the BVH leaves store them, and the watertight ray-triangle test (Woop, Benthin
//! and Wald 2013) that keeps rays from leaking through edges shared by two triangles, on one
//! triangle ([`RayTri::intersect`]) and on four at once ([`Tri4`], [`RayTri::intersect4`]: the
//! same operations in the same order on glam's `Vec4` lanes, so each lane's hit is bit for bit
//! the one-triangle test's; `tests/bvh_props.rs` pins that).

use glam::{Vec3, Vec4};
use rayon::prelude::*;

use crate::geometry::{Ray, TriangleMesh};

/// One triangle copied out of its mesh, with the ids a [`crate::accel::Hit`] reports.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Tri {
    pub p: [Vec3; 3],
    /// The mesh it came from (a `StaticId` for static geometry, unused for prototypes).
    pub geom: u32,
    /// Triangle index within that mesh.
    pub prim: u32,
}

impl Tri {
    pub fn bounds(&self) -> crate::geometry::Aabb {
        crate::geometry::Aabb::from_points(self.p)
    }

    /// Unnormalised geometric normal `(p1 - p0) x (p2 - p0)`.
    pub fn normal(&self) -> Vec3 {
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
    let chunk = super::flat::PAR_CHUNK;
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
    kx: usize,
    ky: usize,
    kz: usize,
    /// The origin's coordinates on the axes `kx`, `ky`, `kz`, picked once per ray: glam's
    /// `Vec3` indexed by a variable is a `match`, and the leaves read these on every call
    /// (cachegrind, session 27).
    org_k: [f32; 3],
    sx: f32,
    sy: f32,
    pub t_min: f32,
}

impl RayTri {
    pub fn new(ray: &Ray) -> Self {
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
            kx,
            ky,
            kz,
            org_k: [o[kx], o[ky], o[kz]],
            sx: d[kx] / d[kz],
            sy: d[ky] / d[kz],
            t_min: ray.t_min,
        }
    }

    /// Hit with `t_min <= t <= t_max`, if any. Both sides of the triangle are hit.
    #[inline(always)]
    pub fn intersect(&self, tri: &[Vec3; 3], t_max: f32) -> Option<TriHit> {
        let (kx, ky, kz) = (self.kx, self.ky, self.kz);
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

/// Four triangles in structure-of-arrays layout: `p[vertex][axis]` holds the four lanes.
/// A leaf with fewer than four triangles repeats its last one (a duplicate never wins: ties
/// keep the lowest lane).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub(crate) struct Tri4 {
    p: [[Vec4; 3]; 3],
    /// Unnormalised normals `(p1 - p0) x (p2 - p0)` ([`Tri::normal`], bit for bit).
    n: [Vec4; 3],
    /// Index of each lane's triangle in the owner's triangle array.
    pub idx: [u32; 4],
}

impl Tri4 {
    /// Packs the triangles `tris[idx[..]]` (1 to 4 of them) into one packet.
    pub fn pack(tris: &[Tri], idx: &[u32]) -> Self {
        debug_assert!(!idx.is_empty() && idx.len() <= 4);
        let idx: [u32; 4] = std::array::from_fn(|i| idx[i.min(idx.len() - 1)]);
        let lanes: [&Tri; 4] = idx.map(|i| &tris[i as usize]);
        let p = std::array::from_fn(|v| {
            std::array::from_fn(|a| Vec4::from_array(std::array::from_fn(|i| lanes[i].p[v][a])))
        });
        let normals: [Vec3; 4] = lanes.map(Tri::normal);
        let n = std::array::from_fn(|a| Vec4::from_array(std::array::from_fn(|i| normals[i][a])));
        Self { p, n, idx }
    }

    /// Lane `i`'s vertices.
    fn lane(&self, i: usize) -> [Vec3; 3] {
        std::array::from_fn(|v| Vec3::new(self.p[v][0][i], self.p[v][1][i], self.p[v][2][i]))
    }
}

impl RayTri {
    /// The closest of the four lanes hit with `t_min <= t <= t_max` (the lowest lane on ties),
    /// with its lane; each lane's hit equals [`Self::intersect`] on that triangle.
    ///
    /// The vertices are read by the ray's axes straight from the packet (one load each, the
    /// axis offsets fixed per ray), not shifted on all three axes first and then picked: that
    /// form stored the nine shifted rows to the stack and read them back by index (cachegrind,
    /// session 27, monastery with 8,000 ducks: the leaf closures ran 205M instructions before,
    /// 184M after). A lane exactly on an edge goes to the one-triangle test only if it could be
    /// inside: a strictly negative and a strictly positive edge function keep their signs in
    /// f64 (both products are exact there), so such a lane is out either way.
    ///
    /// The axes index the packet with bounds checks (nine instructions per leaf call). Tried
    /// (session 29, cachegrind, monastery with 8,000 ducks): the axes as a `u8` enum, whose
    /// range the compiler knows: the leaf tests ran 6.2M fewer instructions and the query
    /// entries 8.7M more (program +2.8M); not kept.
    #[inline(always)]
    pub fn intersect4(&self, q: &Tri4, t_max: f32) -> Option<(usize, TriHit)> {
        let (kx, ky, kz) = (self.kx, self.ky, self.kz);
        let [ox, oy, oz] = self.org_k.map(Vec4::splat);
        let (sx, sy) = (Vec4::splat(self.sx), Vec4::splat(self.sy));
        // Vertex `v` relative to the origin, sheared so that the ray runs along +z: the same
        // operations as `intersect`'s `a[kx] - sx * a[kz]`.
        let sheared = |v: usize| {
            let z = q.p[v][kz] - oz;
            ((q.p[v][kx] - ox) - sx * z, (q.p[v][ky] - oy) - sy * z)
        };
        let ((ax, ay), (bx, by), (cx, cy)) = (sheared(0), sheared(1), sheared(2));
        let u = cx * by - cy * bx;
        let v = ax * cy - ay * cx;
        let w = bx * ay - by * ax;
        let zero = Vec4::ZERO;
        let neg = u.cmplt(zero) | v.cmplt(zero) | w.cmplt(zero);
        let pos = u.cmpgt(zero) | v.cmpgt(zero) | w.cmpgt(zero);
        let maybe_inside = !(neg & pos);
        if !maybe_inside.any() {
            // Every lane outside an edge (most packets a ray reaches): no distance, no division.
            return None;
        }
        if (maybe_inside & (u.cmpeq(zero) | v.cmpeq(zero) | w.cmpeq(zero))).any() {
            // A lane exactly on an edge in f32: the one-triangle test decides it in f64.
            return self.intersect4_scalar(q, t_max);
        }
        let det = u + v + w;
        let n = &q.n;
        let a = [
            q.p[0][0] - Vec4::splat(self.org.x),
            q.p[0][1] - Vec4::splat(self.org.y),
            q.p[0][2] - Vec4::splat(self.org.z),
        ];
        let dir = [Vec4::splat(self.dir.x), Vec4::splat(self.dir.y), Vec4::splat(self.dir.z)];
        let t = (n[0] * a[0] + n[1] * a[1] + n[2] * a[2]) / (n[0] * dir[0] + n[1] * dir[1] + n[2] * dir[2]);
        let ok = maybe_inside
            & det.cmpne(zero)
            & det.is_finite_mask()
            & t.cmpge(Vec4::splat(self.t_min))
            & t.cmple(Vec4::splat(t_max));
        let mut mask = ok.bitmask();
        if mask == 0 {
            return None;
        }
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
        let rcp = 1.0 / det[best];
        Some((best, TriHit { t: ts[best], u: v[best] * rcp, v: w[best] * rcp }))
    }

    /// [`Self::intersect4`] one lane at a time with [`Self::intersect`].
    #[cold]
    fn intersect4_scalar(&self, q: &Tri4, t_max: f32) -> Option<(usize, TriHit)> {
        let mut best: Option<(usize, TriHit)> = None;
        for i in 0..4 {
            if let Some(h) = self.intersect(&q.lane(i), t_max) {
                if best.is_none_or(|(_, b)| h.t < b.t) {
                    best = Some((i, h));
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
