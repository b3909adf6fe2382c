//! A plain glTF mesh loader: every triangle primitive of the default scene (or of all
//! scenes' root nodes when there is no default), with node transforms baked in, merged into
//! one [`TriangleMesh`]. No materials, no textures: those belong to the renderer's loader.

use std::path::{Path, PathBuf};

use glam::{Affine3A, Mat4, Vec2, Vec3};

use crate::geometry::TriangleMesh;

/// A glTF file that could not be turned into a mesh: names the file and the element.
#[derive(Debug, thiserror::Error)]
#[error("{}: {element}: {message}", .file.display())]
pub struct GltfError {
    pub file: PathBuf,
    /// The glTF element at fault, e.g. `meshes[2].primitives[0]` or `(file)`.
    pub element: String,
    pub message: String,
}

impl GltfError {
    fn new(file: &Path, element: impl Into<String>, message: impl Into<String>) -> Self {
        Self { file: file.to_path_buf(), element: element.into(), message: message.into() }
    }
}

/// Loads the triangles of a `.gltf` or `.glb` file in world space.
pub fn load_gltf_mesh(path: &Path) -> Result<TriangleMesh, GltfError> {
    let bytes = std::fs::read(path).map_err(|e| GltfError::new(path, "(file)", e.to_string()))?;
    let gltf::Gltf { document, blob } =
        gltf::Gltf::from_slice(&bytes).map_err(|e| GltfError::new(path, "(document)", e.to_string()))?;
    let buffers = gltf::import_buffers(&document, path.parent(), blob)
        .map_err(|e| GltfError::new(path, "buffers", e.to_string()))?;

    let mut out = TriangleMesh::default();
    let mut normals = Vec::new();
    let mut uvs = Vec::new();
    let mut all_have_normals = true;
    let mut all_have_uvs = true;

    let roots: Vec<gltf::Node> = match document.default_scene().or_else(|| document.scenes().next()) {
        Some(scene) => scene.nodes().collect(),
        // No scene at all: treat every node that is no other node's child as a root.
        None => {
            let children: std::collections::BTreeSet<usize> =
                document.nodes().flat_map(|n| n.children().map(|c| c.index()).collect::<Vec<_>>()).collect();
            document.nodes().filter(|n| !children.contains(&n.index())).collect()
        }
    };
    let mut stack: Vec<(gltf::Node, Mat4, usize)> =
        roots.into_iter().map(|n| (n, Mat4::IDENTITY, 0)).collect();
    while let Some((node, parent, depth)) = stack.pop() {
        if depth > 256 {
            return Err(GltfError::new(
                path,
                format!("nodes[{}]", node.index()),
                "node hierarchy deeper than 256 (a cycle?)",
            ));
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if let Some(mesh) = node.mesh() {
            let xf = Affine3A::from_mat4(world);
            let normal_matrix = glam::Mat3::from(xf.matrix3).inverse().transpose();
            for prim in mesh.primitives() {
                let element = format!("meshes[{}].primitives[{}]", mesh.index(), prim.index());
                if prim.mode() != gltf::mesh::Mode::Triangles {
                    // Points and lines have no surface to collide with or render.
                    continue;
                }
                let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
                let positions: Vec<Vec3> = reader
                    .read_positions()
                    .ok_or_else(|| GltfError::new(path, &element, "has no POSITION attribute"))?
                    .map(Vec3::from_array)
                    .collect();
                let base = out.positions.len();
                let n = positions.len();
                let indices: Vec<u32> = match reader.read_indices() {
                    Some(ix) => ix.into_u32().collect(),
                    None => (0..n as u32).collect(),
                };
                if indices.len() % 3 != 0 {
                    return Err(GltfError::new(
                        path,
                        &element,
                        format!("{} indices is not a whole number of triangles", indices.len()),
                    ));
                }
                if let Some(&bad) = indices.iter().find(|&&i| i as usize >= n) {
                    return Err(GltfError::new(
                        path,
                        &element,
                        format!("index {bad} out of range for {n} vertices"),
                    ));
                }
                if positions.iter().any(|p| !p.is_finite()) {
                    return Err(GltfError::new(path, &element, "POSITION has non-finite values"));
                }
                out.positions.extend(positions.iter().map(|&p| xf.transform_point3(p)));
                out.indices.extend(
                    indices
                        .chunks_exact(3)
                        .map(|t| [t[0] + base as u32, t[1] + base as u32, t[2] + base as u32]),
                );
                match reader.read_normals() {
                    Some(ns) => {
                        normals.extend(ns.map(|v| (normal_matrix * Vec3::from_array(v)).normalize_or_zero()))
                    }
                    None => {
                        all_have_normals = false;
                        normals.resize(out.positions.len(), Vec3::ZERO);
                    }
                }
                match reader.read_tex_coords(0) {
                    Some(tc) => uvs.extend(tc.into_f32().map(Vec2::from_array)),
                    None => {
                        all_have_uvs = false;
                        uvs.resize(out.positions.len(), Vec2::ZERO);
                    }
                }
                if normals.len() != out.positions.len() || uvs.len() != out.positions.len() {
                    return Err(GltfError::new(path, &element, "attribute counts differ from POSITION's"));
                }
            }
        }
        for child in node.children() {
            stack.push((child, world, depth + 1));
        }
    }
    if out.indices.is_empty() {
        return Err(GltfError::new(path, "(document)", "contains no triangles"));
    }
    if all_have_normals {
        out.normals = Some(normals);
    }
    if all_have_uvs {
        out.uvs = Some(uvs);
    }
    out.validate().map_err(|e| GltfError::new(path, "(merged mesh)", e.to_string()))?;
    Ok(out)
}
