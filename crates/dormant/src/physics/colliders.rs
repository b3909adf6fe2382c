//! Collision shapes: the static environment as one triangle mesh; each dynamic prototype as
//! an exact primitive, a convex hull, or (for concave meshes) a convex decomposition, built
//! once per prototype and shared by every body that uses it.

use rapier3d::prelude::SharedShape;

use super::body::to_rapier_vec;
use super::PhysicsError;
use crate::geometry::TriangleMesh;
use crate::scene::file::{prototype_mesh, ColliderKind, SceneFile, Shape};

/// A hull this much smaller in volume than the mesh it wraps marks the mesh as concave.
const CONCAVITY_RATIO: f32 = 0.85;

/// How a prototype's collider was made (reported by the simulation).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum ColliderChoice {
    Primitive,
    ConvexHull,
    ConvexDecomposition { parts: usize },
}

/// A prototype ready to instantiate: shared shape plus material.
#[derive(Clone)]
pub(crate) struct PrototypeShape {
    pub shape: SharedShape,
    pub(crate) choice: ColliderChoice,
    pub(crate) density: f32,
    pub(crate) friction: f32,
    pub(crate) restitution: f32,
    /// Radius of a sphere about the local origin that contains the shape.
    pub(crate) bounding_radius: f32,
}

pub(crate) fn prototype_shape(file: &SceneFile, index: usize) -> Result<PrototypeShape, PhysicsError> {
    let p = &file.spec().prototypes[index];
    let (shape, choice) = match p.shape {
        Shape::Box { half_extents: h } => (SharedShape::cuboid(h[0], h[1], h[2]), ColliderChoice::Primitive),
        Shape::Sphere { radius } => (SharedShape::ball(radius), ColliderChoice::Primitive),
        Shape::Capsule { half_height, radius } => {
            (SharedShape::capsule_y(half_height, radius), ColliderChoice::Primitive)
        }
        Shape::Cylinder { half_height, radius } => {
            (SharedShape::cylinder(half_height, radius), ColliderChoice::Primitive)
        }
        Shape::Gltf { collider, .. } => {
            let mesh = prototype_mesh(file, index)?;
            mesh_shape(&mesh, collider).map_err(|message| PhysicsError::Collider {
                file: file.path().display().to_string(),
                field: format!("prototypes[{index}].gltf"),
                message,
            })?
        }
    };
    let aabb = shape.compute_local_aabb();
    let bounding_radius = aabb.mins.length().max(aabb.maxs.length());
    Ok(PrototypeShape {
        shape,
        choice,
        density: p.density,
        friction: p.friction,
        restitution: p.restitution,
        bounding_radius,
    })
}

/// A convex hull, or a convex decomposition when the mesh is concave (or when asked).
fn mesh_shape(mesh: &TriangleMesh, kind: ColliderKind) -> Result<(SharedShape, ColliderChoice), String> {
    let points: Vec<_> = mesh.positions.iter().filter(|p| p.is_finite()).map(|&p| to_rapier_vec(p)).collect();
    let flat = || format!("the {} points have no volume (flat or degenerate mesh)", points.len());
    let hull = SharedShape::convex_hull(&points).ok_or_else(flat)?;
    let hull_volume = hull.mass_properties(1.0).mass();
    if hull_volume.is_nan() || hull_volume <= 0.0 {
        return Err(flat());
    }
    let decompose = match kind {
        ColliderKind::ConvexHull => false,
        ColliderKind::ConvexDecomposition => true,
        ColliderKind::Auto => {
            let mesh_volume = closed_mesh_volume(mesh);
            // An open or inconsistently wound mesh has no meaningful volume: keep the hull.
            mesh_volume > 0.0 && mesh_volume < CONCAVITY_RATIO * hull_volume
        }
    };
    if !decompose {
        return Ok((hull, ColliderChoice::ConvexHull));
    }
    let indices: Vec<[u32; 3]> =
        (0..mesh.triangle_count()).filter(|&i| mesh.triangle_is_valid(i)).map(|i| mesh.indices[i]).collect();
    let vertices: Vec<_> = mesh.positions.iter().map(|&p| to_rapier_vec(p)).collect();
    let shape = SharedShape::convex_decomposition(&vertices, &indices);
    let parts = shape.as_compound().map_or(1, |c| c.shapes().len());
    Ok((shape, ColliderChoice::ConvexDecomposition { parts }))
}

/// Signed volume by the divergence theorem; positive for a closed outward-wound mesh.
fn closed_mesh_volume(mesh: &TriangleMesh) -> f32 {
    (0..mesh.triangle_count())
        .map(|i| {
            let [a, b, c] = mesh.triangle(i);
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

/// The environment's colliders: one triangle mesh, or with `environment.collider_cells` n > 1
/// one per cell of an n x n grid over the mesh's XZ bounds. Rapier keeps a collider's contact
/// pairs in one list that it walks to find a pair, so a floor that tens of thousands of
/// bodies touch makes every new contact with it that slow; cells keep the lists short.
pub(crate) fn environment_shapes(
    mesh: &TriangleMesh,
    file: &SceneFile,
) -> Result<Vec<SharedShape>, PhysicsError> {
    match file.spec().environment.collider_cells {
        1 => Ok(vec![environment_shape(mesh, file)?]),
        n => match cell_meshes(mesh, n).as_slice() {
            // No valid triangle: the one mesh says why it cannot collide.
            [] => Ok(vec![environment_shape(mesh, file)?]),
            cells => cells.iter().map(|cell| environment_shape(cell, file)).collect(),
        },
    }
}

/// `mesh`'s valid triangles in an `n` x `n` grid over its XZ bounds: each triangle halved
/// along its edges until it is no wider than a cell (at most [`MAX_CELL_SPLITS`] times), then
/// put in the cell of its centroid. Empty cells are left out.
fn cell_meshes(mesh: &TriangleMesh, n: u32) -> Vec<TriangleMesh> {
    let bounds = mesh.bounds();
    let (lo, size) = (bounds.min, bounds.max - bounds.min);
    let cell = (size.x.max(size.z) / n as f32).max(f32::MIN_POSITIVE);
    let index = |v: f32, lo: f32, size: f32| {
        if size > 0.0 {
            ((v - lo) / size * n as f32).clamp(0.0, n as f32 - 1.0) as usize
        } else {
            0
        }
    };
    let mut cells: Vec<Vec<[glam::Vec3; 3]>> = vec![Vec::new(); (n * n) as usize];
    for i in (0..mesh.triangle_count()).filter(|&i| mesh.triangle_is_valid(i)) {
        let mut pending = vec![(mesh.triangle(i), 0)];
        while let Some((t @ [a, b, c], splits)) = pending.pop() {
            let width = [a - b, b - c, c - a].iter().map(|e| e.x.abs().max(e.z.abs())).fold(0.0, f32::max);
            if width > cell && splits < MAX_CELL_SPLITS {
                let (ab, bc, ca) = ((a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5);
                pending
                    .extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]].map(|t| (t, splits + 1)));
            } else {
                let centroid = (a + b + c) / 3.0;
                let (x, z) = (index(centroid.x, lo.x, size.x), index(centroid.z, lo.z, size.z));
                cells[z * n as usize + x].push(t);
            }
        }
    }
    cells
        .into_iter()
        .filter(|triangles| !triangles.is_empty())
        .map(|triangles| {
            let positions: Vec<_> = triangles.iter().flatten().copied().collect();
            let indices = (0..triangles.len() as u32).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
            TriangleMesh::new(positions, indices)
        })
        .collect()
}

/// How often [`cell_meshes`] may halve one triangle (4^8 pieces at most).
const MAX_CELL_SPLITS: u32 = 8;

/// The environment as a Rapier triangle mesh, skipping degenerate triangles.
fn environment_shape(mesh: &TriangleMesh, file: &SceneFile) -> Result<SharedShape, PhysicsError> {
    let vertices: Vec<_> = mesh
        .positions
        .iter()
        .map(|&p| to_rapier_vec(if p.is_finite() { p } else { glam::Vec3::ZERO }))
        .collect();
    let indices: Vec<[u32; 3]> =
        (0..mesh.triangle_count()).filter(|&i| mesh.triangle_is_valid(i)).map(|i| mesh.indices[i]).collect();
    SharedShape::trimesh(vertices, indices).map_err(|e| PhysicsError::Collider {
        file: file.path().display().to_string(),
        field: "environment".into(),
        message: format!("cannot build a triangle-mesh collider: {e:?}"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::primitives;

    #[test]
    fn a_box_mesh_gets_a_hull() {
        let (_, choice) = mesh_shape(&primitives::cuboid(glam::Vec3::ONE), ColliderKind::Auto).unwrap();
        assert_eq!(choice, ColliderChoice::ConvexHull);
    }

    #[test]
    fn an_l_shaped_mesh_is_decomposed() {
        // Two boxes forming an L: the hull is much larger than the solid.
        let a = primitives::cuboid(glam::Vec3::new(1.0, 0.25, 0.25));
        let b = primitives::cuboid(glam::Vec3::new(0.25, 1.0, 0.25))
            .transformed(&glam::Affine3A::from_translation(glam::Vec3::new(-0.75, 1.25, 0.0)));
        let mut l = a.clone();
        let base = l.positions.len() as u32;
        l.positions.extend_from_slice(&b.positions);
        l.indices.extend(b.indices.iter().map(|t| t.map(|i| i + base)));
        l.normals = None;
        l.uvs = None;
        let (_, choice) = mesh_shape(&l, ColliderKind::Auto).unwrap();
        assert!(matches!(choice, ColliderChoice::ConvexDecomposition { .. }), "{choice:?}");
    }

    #[test]
    fn a_flat_mesh_is_an_error() {
        assert!(mesh_shape(&primitives::ground_plane(1.0, 0.0, 1), ColliderKind::Auto).is_err());
    }
}
