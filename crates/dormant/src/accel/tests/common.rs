//! Shared helpers of the accelerator tests: random geometry, an f64 brute-force
//! reference, and a hit comparison that tolerates ties and rays grazing an edge.

pub(super) use crate::accel::bvh::testing::{
    build_tree, check_built_tree, watertight_hit, watertight_hit_leaf, BuiltTree,
};
use crate::accel::{Hit, HitObject};
use crate::geometry::{Ray, TriangleMesh};
use glam::Vec3;
use proptest::prelude::*;

/// A triangle of the reference scene, in world space.
#[derive(Clone, Copy, Debug)]
pub(super) struct RefTri {
    pub object: HitObject,
    pub prim: u32,
    pub p: [Vec3; 3],
}

pub(super) fn ref_tris(object: HitObject, mesh: &TriangleMesh) -> Vec<RefTri> {
    (0..mesh.triangle_count()).map(|i| RefTri { object, prim: i as u32, p: mesh.triangle(i) }).collect()
}

/// The backend's own f32 watertight test: the reference for static geometry, where the BVH
/// must find exactly what brute force over the same test finds.
pub(super) fn exact_hit(ray: &Ray, p: &[Vec3; 3]) -> Option<(f64, f64, f64)> {
    watertight_hit(ray, p).map(|(t, u, v)| (f64::from(t), f64::from(u), f64::from(v)))
}

/// Möller-Trumbore in f64: `(t, u, v)` within the ray's interval, both sides.
pub(super) fn ref_hit(ray: &Ray, p: &[Vec3; 3]) -> Option<(f64, f64, f64)> {
    let [p0, p1, p2] = p.map(|v| v.as_dvec3());
    if !(p0.is_finite() && p1.is_finite() && p2.is_finite()) {
        return None;
    }
    let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
    let e1 = p1 - p0;
    let e2 = p2 - p0;
    let pv = d.cross(e2);
    let det = e1.dot(pv);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let tv = o - p0;
    let u = tv.dot(pv) * inv;
    let q = tv.cross(e1);
    let v = d.dot(q) * inv;
    let t = e2.dot(q) * inv;
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t >= f64::from(ray.t_min) && t <= f64::from(ray.t_max))
        .then_some((t, u, v))
}

/// Barycentric error an f32 ray-triangle test can make on this triangle: rounding of the
/// ray-relative vertex coordinates (size `L`) against the area the triangle shows the ray.
/// Slivers seen edge-on have large errors, well-shaped triangles about `1e-6`.
fn f32_error(ray: &Ray, p: &[Vec3; 3]) -> f64 {
    let [p0, p1, p2] = p.map(|v| v.as_dvec3());
    let o = ray.origin.as_dvec3();
    let d = ray.dir.as_dvec3().normalize_or_zero();
    let l = (p0 - o).length().max((p1 - o).length()).max((p2 - o).length());
    let shown = (p1 - p0).cross(p2 - p0).dot(d).abs();
    16.0 * f64::from(f32::EPSILON) * l * l / shown
}

/// How close a ray passes to the triangle's boundary, in barycentric units, less the f32
/// error on this triangle: rays this close may legitimately hit or miss depending on rounding.
fn edge_distance(ray: &Ray, p: &[Vec3; 3]) -> f64 {
    let [p0, p1, p2] = p.map(|v| v.as_dvec3());
    let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
    let e1 = p1 - p0;
    let e2 = p2 - p0;
    let pv = d.cross(e2);
    let det = e1.dot(pv);
    if det.abs() < 1e-12 * e1.length() * e2.length() * d.length() {
        return 0.0;
    }
    let tv = o - p0;
    let u = tv.dot(pv) / det;
    let v = d.dot(tv.cross(e1)) / det;
    u.abs().min(v.abs()).min((1.0 - u - v).abs()) - f32_error(ray, p)
}

/// Checks `got` against the brute-force closest hit over `tris`, with the backend's own f32
/// triangle test when `rel` is below 1e-4 (then `t` must agree to `rel`), else with the f64
/// reference (transformed instances: f32 rounding differs, so `rel` is looser). Ties (several triangles at the same `t`) accept any of them; hits and misses of
/// rays grazing an edge (closer than `1e-4` barycentric) are accepted either way.
pub(super) fn check_hit(ray: &Ray, got: Option<Hit>, tris: &[RefTri], rel: f64) -> Result<(), String> {
    const EDGE: f64 = 1e-4;
    let tol = |t: f64| rel * t.abs().max(1.0);
    let reference = if rel < 1e-4 { exact_hit } else { ref_hit };
    let hits: Vec<(f64, &RefTri)> =
        tris.iter().filter_map(|r| reference(ray, &r.p).map(|h| (h.0, r))).collect();
    // Closest reference hit that is not grazing an edge or an interval end.
    let solid_min = hits
        .iter()
        .filter(|(t, r)| {
            edge_distance(ray, &r.p) > EDGE
                && (t - f64::from(ray.t_min)).abs() > tol(*t)
                && (t - f64::from(ray.t_max)).abs() > tol(*t)
        })
        .map(|(t, _)| *t)
        .fold(f64::INFINITY, f64::min);
    match got {
        None => {
            if solid_min < f64::INFINITY {
                return Err(format!("missed a hit at t = {solid_min} for {ray:?}"));
            }
        }
        Some(h) => {
            let t = f64::from(h.t);
            if t > solid_min + tol(solid_min) {
                return Err(format!("hit at t = {t} but the closest is at {solid_min} for {ray:?}"));
            }
            let same = tris.iter().find(|r| r.object == h.object && r.prim == h.prim);
            let Some(same) = same else {
                return Err(format!("hit an unknown triangle {:?}/{}", h.object, h.prim));
            };
            match reference(ray, &same.p) {
                Some((tr, _, _)) => {
                    // Ill-conditioned triangles get the f32 error on t as well.
                    if (tr - t).abs() > tol(tr) + tr.abs() * f32_error(ray, &same.p) {
                        return Err(format!("t = {t}, reference {tr} for {ray:?}"));
                    }
                    let n = (same.p[1] - same.p[0]).cross(same.p[2] - same.p[0]).as_dvec3().normalize();
                    let ng = h.ng.as_dvec3();
                    if (ng.length() - 1.0).abs() > 1e-3 || (n.dot(ng) - 1.0).abs() > 1e-3 {
                        return Err(format!("normal {ng} vs reference {n}"));
                    }
                    let p = ray.origin.as_dvec3() + t * ray.dir.as_dvec3();
                    let [p0, p1, p2] = same.p.map(|v| v.as_dvec3());
                    let (u, v) = (f64::from(h.u), f64::from(h.v));
                    let pb = (1.0 - u - v) * p0 + u * p1 + v * p2;
                    let scale = p0.abs().max(p1.abs()).max(p2.abs()).max_element().max(1.0);
                    // Grazing rays make barycentrics ill-conditioned in f32.
                    let edge = (p1 - p0).length().max((p2 - p0).length()).max((p2 - p1).length());
                    if (pb - p).length() > 1e-3 * scale + 2.0 * f32_error(ray, &same.p) * edge {
                        return Err(format!("barycentrics give {pb}, ray point {p}"));
                    }
                }
                None => {
                    if edge_distance(ray, &same.p) > EDGE {
                        return Err(format!("hit {:?}/{} the reference misses", h.object, h.prim));
                    }
                }
            }
        }
    }
    Ok(())
}

pub(super) fn check_any(ray: &Ray, got: bool, tris: &[RefTri]) -> Result<(), String> {
    let solid = tris.iter().any(|r| ref_hit(ray, &r.p).is_some() && edge_distance(ray, &r.p) > 1e-4);
    let any = tris.iter().any(|r| ref_hit(ray, &r.p).is_some());
    if solid && !got {
        return Err(format!("any-hit missed {ray:?}"));
    }
    if got && !any && tris.iter().all(|r| edge_distance(ray, &r.p) > 1e-4) {
        return Err(format!("any-hit reported a miss as a hit {ray:?}"));
    }
    Ok(())
}

pub(super) fn vec3(range: f32) -> impl Strategy<Value = Vec3> {
    (-range..range, -range..range, -range..range).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

/// A soup of `n` triangles of size up to `size` around `center`, as one indexed mesh.
pub(super) fn soup(
    center: Vec3,
    spread: f32,
    size: f32,
    n: std::ops::Range<usize>,
) -> impl Strategy<Value = TriangleMesh> {
    prop::collection::vec((vec3(spread), vec3(size), vec3(size)), n).prop_map(move |ts| {
        let mut positions = Vec::new();
        let mut indices = Vec::new();
        for (c, a, b) in ts {
            let base = positions.len() as u32;
            positions.extend([center + c, center + c + a, center + c + b]);
            indices.push([base, base + 1, base + 2]);
        }
        TriangleMesh::new(positions, indices)
    })
}

/// A xorshift generator of numbers in `[0, 1)`, deterministic from `seed`.
pub(super) fn unit_rng(seed: u64) -> impl FnMut() -> f32 {
    let mut s = seed | 1;
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// Rays aimed at triangle centroids (so most hit) plus fully random ones.
pub(super) fn rays_for(meshes: &[&TriangleMesh], seed: u64, count: usize, range: f32) -> Vec<Ray> {
    let mut next = unit_rng(seed);
    let targets: Vec<Vec3> = meshes
        .iter()
        .flat_map(|m| (0..m.triangle_count()).map(|i| m.triangle(i)))
        .filter(|t| t.iter().all(|p| p.is_finite()))
        .map(|[a, b, c]| (a + b + c) / 3.0)
        .collect();
    (0..count)
        .map(|i| {
            let mut r = || Vec3::new(next() * 2.0 - 1.0, next() * 2.0 - 1.0, next() * 2.0 - 1.0);
            let origin = r() * range;
            let dir = if i % 3 != 0 && !targets.is_empty() {
                let k = ((next() * targets.len() as f32) as usize).min(targets.len() - 1);
                (targets[k] - origin) * (0.5 + next())
            } else {
                r()
            };
            let mut ray = Ray::new(origin, dir);
            if i % 5 == 0 {
                ray.t_max = next() * 2.0;
            }
            ray
        })
        .collect()
}

/// A deterministic cluster of `n` triangles around `c`.
pub(super) fn cluster(c: Vec3, n: usize, seed: u64) -> TriangleMesh {
    let mut s = seed | 1;
    let mut next = || {
        s = s.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        (s >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
    };
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    for i in 0..n as u32 {
        let o = c + Vec3::new(next(), next(), next()) * 1.5;
        positions.extend([o, o + Vec3::new(next(), next(), next()), o + Vec3::new(next(), next(), next())]);
        indices.push([3 * i, 3 * i + 1, 3 * i + 2]);
    }
    TriangleMesh::new(positions, indices)
}
