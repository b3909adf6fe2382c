//! Indexed triangle meshes with optional per-vertex normals and UVs and per-triangle material
//! slots.

use glam::{Affine3A, Vec2, Vec3};

use super::Aabb;

/// Problems with mesh data. Callers add the file and element names.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum MeshError {
    #[error("triangle {triangle} references vertex {index}, but the mesh has {vertices} vertices")]
    IndexOutOfRange { triangle: usize, index: u32, vertices: usize },
    #[error("{attribute} has {found} entries, expected one per vertex ({vertices})")]
    AttributeLength { attribute: &'static str, found: usize, vertices: usize },
    #[error("material_ids has {found} entries, expected one per triangle ({triangles})")]
    MaterialIdsLength { found: usize, triangles: usize },
}

/// An indexed triangle mesh in its own object space. Normals and UVs are optional per-vertex
/// attributes; `material_ids` optionally gives each triangle a material slot, an offset from
/// the material the mesh is placed with (so one mesh can carry a glTF file's materials).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleMesh {
    pub positions: Vec<Vec3>,
    pub indices: Vec<[u32; 3]>,
    pub(crate) normals: Option<Vec<Vec3>>,
    pub(crate) uvs: Option<Vec<Vec2>>,
    /// Per triangle: material slot, added to the owning object's material index.
    pub(crate) material_ids: Option<Vec<u32>>,
}

impl TriangleMesh {
    pub fn new(positions: Vec<Vec3>, indices: Vec<[u32; 3]>) -> Self {
        Self { positions, indices, normals: None, uvs: None, material_ids: None }
    }

    /// Triangle `prim`'s material slot (0 when the mesh has no per-triangle materials).
    pub(crate) fn material_slot(&self, prim: usize) -> u32 {
        self.material_ids.as_ref().and_then(|ids| ids.get(prim).copied()).unwrap_or(0)
    }

    /// The largest material slot any triangle uses.
    pub(crate) fn max_material_slot(&self) -> u32 {
        self.material_ids.as_ref().and_then(|ids| ids.iter().copied().max()).unwrap_or(0)
    }

    /// Checks that indices and attributes are consistent. Does not reject degenerate or
    /// non-finite triangles: accelerators skip those and count them.
    pub(crate) fn validate(&self) -> Result<(), MeshError> {
        let n = self.positions.len();
        for (t, tri) in self.indices.iter().enumerate() {
            if let Some(&index) = tri.iter().find(|&&i| i as usize >= n) {
                return Err(MeshError::IndexOutOfRange { triangle: t, index, vertices: n });
            }
        }
        if let Some(normals) = &self.normals {
            if normals.len() != n {
                return Err(MeshError::AttributeLength {
                    attribute: "normals",
                    found: normals.len(),
                    vertices: n,
                });
            }
        }
        if let Some(uvs) = &self.uvs {
            if uvs.len() != n {
                return Err(MeshError::AttributeLength { attribute: "uvs", found: uvs.len(), vertices: n });
            }
        }
        if let Some(ids) = &self.material_ids {
            if ids.len() != self.indices.len() {
                return Err(MeshError::MaterialIdsLength { found: ids.len(), triangles: self.indices.len() });
            }
        }
        Ok(())
    }

    pub fn triangle_count(&self) -> usize {
        self.indices.len()
    }

    pub fn triangle(&self, i: usize) -> [Vec3; 3] {
        let [a, b, c] = self.indices[i];
        [self.positions[a as usize], self.positions[b as usize], self.positions[c as usize]]
    }

    /// A triangle is usable when its vertices are finite and it has non-zero area.
    pub fn triangle_is_valid(&self, i: usize) -> bool {
        let [a, b, c] = self.triangle(i);
        a.is_finite() && b.is_finite() && c.is_finite() && (b - a).cross(c - a).length_squared() > 0.0
    }

    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(self.positions.iter().copied().filter(|p| p.is_finite()))
    }

    /// A copy with positions and normals moved by `xf` (used to bake instances into world space).
    pub fn transformed(&self, xf: &Affine3A) -> Self {
        let turn = NormalTurn::of(xf);
        Self {
            positions: self.positions.iter().map(|&p| xf.transform_point3(p)).collect(),
            indices: self.indices.clone(),
            normals: self.normals.as_ref().map(|ns| ns.iter().map(|&n| turn.apply(n)).collect()),
            uvs: self.uvs.clone(),
            material_ids: self.material_ids.clone(),
        }
    }
}

/// How a transform turns vertex normals: by its normal matrix (the inverse transpose of its
/// linear part), then to unit length. Turning is idempotent on unit normals: the identity
/// leaves a normal's bits alone, and a normal of unit length already (within rounding) is not
/// normalised again, so a mesh that dormant's export writes and its importer reads back
/// shades to the same bits as the mesh it was.
pub(crate) struct NormalTurn {
    /// `None` for the identity.
    matrix: Option<glam::Mat3>,
}

impl NormalTurn {
    /// Squared lengths this close to 1 count as unit: a normalised f32 vector's squared length
    /// is within a few ulps of 1.
    const UNIT_TOLERANCE: f32 = 8.0 * f32::EPSILON;

    pub(crate) fn of(xf: &Affine3A) -> Self {
        let linear = glam::Mat3::from(xf.matrix3);
        Self { matrix: (linear != glam::Mat3::IDENTITY).then(|| linear.inverse().transpose()) }
    }

    pub(crate) fn apply(&self, n: Vec3) -> Vec3 {
        let turned = self.matrix.map_or(n, |m| m * n);
        if (turned.length_squared() - 1.0).abs() <= Self::UNIT_TOLERANCE {
            turned
        } else {
            turned.normalize_or_zero()
        }
    }
}
