//! Procedural meshes for built-in scenes and tests: boxes, spheres and ground planes.

use glam::{Vec2, Vec3};
use std::f32::consts::PI;

use super::TriangleMesh;

/// An axis-aligned box centred at the origin with the given half extents; flat-shaded (24
/// vertices, 12 triangles), outward winding.
pub fn cuboid(half: Vec3) -> TriangleMesh {
    let mut positions = Vec::with_capacity(24);
    let mut normals = Vec::with_capacity(24);
    let mut uvs = Vec::with_capacity(24);
    let mut indices = Vec::with_capacity(12);
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let n = Vec3::from_array(std::array::from_fn(|i| if i == axis { sign } else { 0.0 }));
            // Two tangents spanning the face, ordered so (u x v) points along n.
            let u = Vec3::from_array(std::array::from_fn(|i| if i == (axis + 1) % 3 { 1.0 } else { 0.0 }));
            let v = n.cross(u);
            let base = positions.len() as u32;
            for (su, sv) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                positions.push((n + su * u + sv * v) * half);
                normals.push(n);
                uvs.push(Vec2::new(0.5 * (su + 1.0), 0.5 * (sv + 1.0)));
            }
            indices.push([base, base + 1, base + 2]);
            indices.push([base, base + 2, base + 3]);
        }
    }
    TriangleMesh { positions, indices, normals: Some(normals), uvs: Some(uvs), material_ids: None }
}

/// A UV sphere of the given radius centred at the origin, smooth normals.
pub fn uv_sphere(radius: f32, segments: u32, rings: u32) -> TriangleMesh {
    let segments = segments.max(3);
    let rings = rings.max(2);
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut uvs = Vec::new();
    for r in 0..=rings {
        let theta = PI * r as f32 / rings as f32;
        for s in 0..=segments {
            let phi = 2.0 * PI * s as f32 / segments as f32;
            let n = Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin());
            positions.push(n * radius);
            normals.push(n);
            uvs.push(Vec2::new(s as f32 / segments as f32, r as f32 / rings as f32));
        }
    }
    let row = segments + 1;
    let mut indices = Vec::new();
    for r in 0..rings {
        for s in 0..segments {
            let a = r * row + s;
            let b = a + row;
            // Skip the degenerate triangles at the poles.
            if r != 0 {
                indices.push([a, a + 1, b]);
            }
            if r != rings - 1 {
                indices.push([a + 1, b + 1, b]);
            }
        }
    }
    TriangleMesh { positions, indices, normals: Some(normals), uvs: Some(uvs), material_ids: None }
}

/// A square in the XZ plane at height `y`, facing +Y, split into `n x n` cells.
pub fn ground_plane(half_size: f32, y: f32, n: u32) -> TriangleMesh {
    let n = n.max(1);
    let mut positions = Vec::new();
    let mut uvs = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (fu, fv) = (i as f32 / n as f32, j as f32 / n as f32);
            positions.push(Vec3::new((2.0 * fu - 1.0) * half_size, y, (2.0 * fv - 1.0) * half_size));
            uvs.push(Vec2::new(fu, fv));
        }
    }
    let mut indices = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i;
            let b = a + n + 1;
            indices.push([a, b, a + 1]);
            indices.push([a + 1, b, b + 1]);
        }
    }
    let normals = vec![Vec3::Y; positions.len()];
    TriangleMesh { positions, indices, normals: Some(normals), uvs: Some(uvs), material_ids: None }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn outward(mesh: &TriangleMesh) -> bool {
        (0..mesh.triangle_count()).all(|i| {
            let [a, b, c] = mesh.triangle(i);
            let n = (b - a).cross(c - a);
            n.dot((a + b + c) / 3.0) > 0.0
        })
    }

    #[test]
    fn cuboid_is_closed_and_outward() {
        let m = cuboid(Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(m.triangle_count(), 12);
        assert!(m.validate().is_ok());
        assert!(outward(&m));
    }

    #[test]
    fn sphere_is_outward_without_degenerates() {
        let m = uv_sphere(1.0, 16, 8);
        assert!(m.validate().is_ok());
        assert!((0..m.triangle_count()).all(|i| m.triangle_is_valid(i)));
        assert!(outward(&m));
    }

    #[test]
    fn ground_faces_up() {
        let m = ground_plane(5.0, 0.0, 2);
        assert!((0..m.triangle_count()).all(|i| {
            let [a, b, c] = m.triangle(i);
            (b - a).cross(c - a).y > 0.0
        }));
    }
}
