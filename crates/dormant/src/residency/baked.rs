//! Baked islands: a sleeping island's bodies as one world-space mesh for the static scene,
//! with the table that maps each of its triangles back to its body and prototype triangle.

use std::sync::Arc;

use glam::{Affine3A, Mat3};

use crate::accel::normal_matrix;
use crate::geometry::TriangleMesh;
use crate::physics::{BodyId, BodyPose};

/// One body's triangles within a baked mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct BakedPart {
    /// First triangle of this body in the baked mesh.
    pub(crate) first_prim: u32,
    pub body: BodyId,
    pub prototype: u32,
    pub(crate) normal_matrix: Mat3,
}

/// An island baked into world space.
#[derive(Clone, Debug)]
pub(crate) struct BakedIsland {
    pub mesh: TriangleMesh,
    /// Ascending by `first_prim`.
    pub parts: Vec<BakedPart>,
}

impl BakedIsland {
    /// Transforms each body's prototype mesh by its pose and concatenates them. Only positions
    /// and indices are kept: shading reads normals and UVs from the prototype (see
    /// [`BakedIsland::part_of`]).
    pub(crate) fn bake(bodies: &[(BodyId, u32, BodyPose)], prototypes: &[Arc<TriangleMesh>]) -> BakedIsland {
        let (mut vertices, mut triangles) = (0, 0);
        for (_, proto, _) in bodies {
            vertices += prototypes[*proto as usize].positions.len();
            triangles += prototypes[*proto as usize].indices.len();
        }
        let mut mesh = TriangleMesh {
            positions: Vec::with_capacity(vertices),
            indices: Vec::with_capacity(triangles),
            normals: None,
            uvs: None,
            material_ids: None,
        };
        let mut parts = Vec::with_capacity(bodies.len());
        for &(body, proto, pose) in bodies {
            let src = &prototypes[proto as usize];
            let xf: Affine3A = pose.to_affine();
            let base = mesh.positions.len() as u32;
            parts.push(BakedPart {
                first_prim: mesh.indices.len() as u32,
                body,
                prototype: proto,
                normal_matrix: normal_matrix(&xf),
            });
            mesh.positions.extend(src.positions.iter().map(|p| xf.transform_point3(*p)));
            mesh.indices.extend(src.indices.iter().map(|t| t.map(|i| i + base)));
        }
        BakedIsland { mesh, parts }
    }

    /// The body part holding baked triangle `prim`, and the triangle's index in its prototype.
    pub(crate) fn part_of(&self, prim: u32) -> Option<(&BakedPart, u32)> {
        let i = self.parts.partition_point(|p| p.first_prim <= prim).checked_sub(1)?;
        let part = &self.parts[i];
        Some((part, prim - part.first_prim))
    }

    pub(crate) fn triangle_count(&self) -> usize {
        self.mesh.indices.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::primitives;
    use glam::{Quat, Vec3};

    #[test]
    fn baked_triangles_map_back_to_their_body_and_prototype_triangle() {
        let protos =
            vec![Arc::new(primitives::cuboid(Vec3::ONE)), Arc::new(primitives::uv_sphere(1.0, 6, 4))];
        let pose = |x: f32| BodyPose { translation: Vec3::new(x, 0.0, 0.0), rotation: Quat::IDENTITY };
        let bodies = [(BodyId(7), 1, pose(0.0)), (BodyId(3), 0, pose(5.0))];
        let baked = BakedIsland::bake(&bodies, &protos);
        let n0 = protos[1].indices.len() as u32;
        assert_eq!(baked.triangle_count(), (n0 + 12) as usize);
        let (part, local) = baked.part_of(n0 + 4).unwrap();
        assert_eq!((part.body, part.prototype, local), (BodyId(3), 0, 4));
        let (part, local) = baked.part_of(2).unwrap();
        assert_eq!((part.body, local), (BodyId(7), 2));
        let [a, _, _] = baked.mesh.triangle((n0 + 4) as usize);
        let [b, _, _] = protos[0].triangle(4);
        assert!((a - (b + Vec3::new(5.0, 0.0, 0.0))).length() < 1e-6);
    }
}
