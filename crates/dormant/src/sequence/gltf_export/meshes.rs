//! Meshes: each of dormant's triangle meshes as one glTF mesh whose primitives share its
//! vertex accessors (POSITION, and NORMAL and TEXCOORD_0 when it has them, bit-exact f32
//! copies) and take its triangles in order, one primitive per run of consecutive triangles
//! with the same material.

use serde_json::{json, Map, Value};

use super::buffer::{BufferBuilder, Kind};
use super::GltfExportError;
use crate::geometry::TriangleMesh;

/// The materials a mesh's triangles may use: glTF materials `first..first + count`.
#[derive(Clone, Copy, Debug)]
pub(super) struct MaterialRange {
    pub(super) first: u32,
    pub(super) count: u32,
}

/// `mesh` as a glTF mesh named `name`, its triangles' material slots mapped into `materials`.
pub(super) fn mesh_json(
    name: &str,
    mesh: &TriangleMesh,
    materials: MaterialRange,
    buffer: &mut BufferBuilder,
) -> Result<Value, GltfExportError> {
    mesh.validate().map_err(|source| GltfExportError::Mesh { mesh: name.into(), source })?;
    let attributes = vertex_attributes(mesh, buffer);
    let mut primitives = Vec::new();
    for (start, end, slot) in material_runs(mesh) {
        if slot >= materials.count {
            return Err(GltfExportError::MaterialSlot { mesh: name.into(), triangle: start, slot });
        }
        let indices: Vec<u32> = mesh.indices[start..end].iter().flatten().copied().collect();
        primitives.push(json!({
            "attributes": attributes,
            "indices": buffer.indices(&indices),
            "material": materials.first + slot,
            "mode": 4,
        }));
    }
    Ok(json!({ "name": name, "primitives": primitives }))
}

/// The vertex accessors every primitive of `mesh` shares.
fn vertex_attributes(mesh: &TriangleMesh, buffer: &mut BufferBuilder) -> Value {
    let mut attributes = Map::new();
    let flat3 = |v: &[glam::Vec3]| v.iter().flat_map(|p| p.to_array()).collect::<Vec<f32>>();
    attributes.insert("POSITION".into(), json!(buffer.floats(Kind::Vec3, &flat3(&mesh.positions))));
    if let Some(normals) = &mesh.normals {
        attributes.insert("NORMAL".into(), json!(buffer.floats(Kind::Vec3, &flat3(normals))));
    }
    if let Some(uvs) = &mesh.uvs {
        let flat: Vec<f32> = uvs.iter().flat_map(|p| p.to_array()).collect();
        attributes.insert("TEXCOORD_0".into(), json!(buffer.floats(Kind::Vec2, &flat)));
    }
    Value::Object(attributes)
}

/// Maximal runs of consecutive triangles with the same material slot, in order:
/// `(first triangle, end, slot)`.
pub(super) fn material_runs(mesh: &TriangleMesh) -> Vec<(usize, usize, u32)> {
    let mut runs: Vec<(usize, usize, u32)> = Vec::new();
    for t in 0..mesh.indices.len() {
        let slot = mesh.material_slot(t);
        match runs.last_mut() {
            Some(run) if run.2 == slot => run.1 = t + 1,
            _ => runs.push((t, t + 1, slot)),
        }
    }
    runs
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::material_runs;
    use crate::geometry::TriangleMesh;

    #[test]
    fn material_runs_keep_the_triangle_order() {
        let mut mesh = TriangleMesh::new(vec![Vec3::ZERO; 3], vec![[0, 1, 2]; 6]);
        mesh.material_ids = Some(vec![0, 0, 1, 0, 2, 2]);
        assert_eq!(material_runs(&mesh), vec![(0, 2, 0), (2, 3, 1), (3, 4, 0), (4, 6, 2)]);
        mesh.material_ids = None;
        assert_eq!(material_runs(&mesh), vec![(0, 6, 0)]);
    }
}
