//! [`Triangles`]: the triangle primitives of a file gathered into one mesh in the file's
//! space, with per-vertex normals and UVs and a material slot per triangle.

use std::path::Path;

use glam::{Affine3A, Mat4, Vec2, Vec3};

use super::checks::{check_attributes, unreadable, warn_textures_without_uvs};
use super::GltfError;
use crate::geometry::TriangleMesh;

/// The triangle primitives of a file gathered so far, in the file's space: per-vertex normals
/// and UVs (zeros where a primitive has none) and a glTF material slot per triangle.
#[derive(Default)]
pub(super) struct Triangles {
    pub(super) mesh: TriangleMesh,
    pub(super) normals: Vec<Vec3>,
    pub(super) uvs: Vec<Vec2>,
    /// The glTF material index per triangle; `u32::MAX` for glTF's default material.
    pub(super) material_ids: Vec<u32>,
    pub(super) any_normals: bool,
    pub(super) any_uvs: bool,
    pub(super) any_material: bool,
}

impl Triangles {
    /// Appends every triangle primitive of `mesh`, moved by `world` (points and lines have no
    /// surface to collide with or render).
    pub(super) fn add_mesh(
        &mut self,
        path: &Path,
        mesh: &gltf::Mesh,
        world: &Mat4,
        buffers: &[gltf::buffer::Data],
        with_materials: bool,
    ) -> Result<(), GltfError> {
        let xf = Affine3A::from_mat4(*world);
        let normal_matrix = glam::Mat3::from(xf.matrix3).inverse().transpose();
        for prim in mesh.primitives() {
            let element = format!("meshes[{}].primitives[{}]", mesh.index(), prim.index());
            if prim.mode() != gltf::mesh::Mode::Triangles {
                continue;
            }
            check_attributes(path, &element, &prim, buffers)?;
            let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
            let unreadable = |what: &str, accessor| unreadable(path, &element, what, accessor);
            let positions: Vec<Vec3> = reader
                .read_positions()
                .ok_or_else(|| unreadable("POSITION", prim.get(&gltf::Semantic::Positions)))?
                .map(Vec3::from_array)
                .collect();
            let indices: Vec<u32> = match (reader.read_indices(), prim.indices()) {
                (Some(ix), _) => ix.into_u32().collect(),
                (None, None) => (0..positions.len() as u32).collect(),
                (None, Some(a)) => return Err(unreadable("indices", Some(a))),
            };
            self.add_triangles(path, &element, &positions, &indices, &xf)?;
            // Primitives without an attribute get zeros: a zero normal shades with the
            // geometric normal, and a zero UV only matters to an untextured material.
            let vertices = self.mesh.positions.len();
            match reader.read_normals() {
                Some(ns) => {
                    self.any_normals = true;
                    self.normals.extend(ns.map(|v| (normal_matrix * Vec3::from_array(v)).normalize_or_zero()))
                }
                None if prim.get(&gltf::Semantic::Normals).is_some() => {
                    return Err(unreadable("NORMAL", prim.get(&gltf::Semantic::Normals)))
                }
                None => self.normals.resize(vertices, Vec3::ZERO),
            }
            match reader.read_tex_coords(0) {
                Some(tc) => {
                    self.any_uvs = true;
                    self.uvs.extend(tc.into_f32().map(|uv| {
                        let uv = Vec2::from_array(uv);
                        if uv.is_finite() {
                            uv
                        } else {
                            Vec2::ZERO
                        }
                    }))
                }
                None if prim.get(&gltf::Semantic::TexCoords(0)).is_some() => {
                    return Err(unreadable("TEXCOORD_0", prim.get(&gltf::Semantic::TexCoords(0))))
                }
                None => {
                    if with_materials {
                        warn_textures_without_uvs(path, &element, &prim.material());
                    }
                    self.uvs.resize(vertices, Vec2::ZERO)
                }
            }
            if self.normals.len() != vertices || self.uvs.len() != vertices {
                return Err(GltfError::new(path, &element, "attribute counts differ from POSITION's"));
            }
            let material = prim.material().index();
            self.any_material |= material.is_some();
            let slot = material.map_or(u32::MAX, |m| m as u32);
            self.material_ids.resize(self.mesh.indices.len(), slot);
        }
        Ok(())
    }

    /// Appends a primitive's triangles (`indices` into `positions`), moved by `xf`, after
    /// checking them: whole triangles, indices in range, finite positions.
    fn add_triangles(
        &mut self,
        path: &Path,
        element: &str,
        positions: &[Vec3],
        indices: &[u32],
        xf: &Affine3A,
    ) -> Result<(), GltfError> {
        let n = positions.len();
        if indices.len() % 3 != 0 {
            return Err(GltfError::new(
                path,
                element,
                format!("{} indices is not a whole number of triangles", indices.len()),
            ));
        }
        if let Some(&bad) = indices.iter().find(|&&i| i as usize >= n) {
            return Err(GltfError::new(path, element, format!("index {bad} out of range for {n} vertices")));
        }
        if positions.iter().any(|p| !p.is_finite()) {
            return Err(GltfError::new(path, element, "POSITION has non-finite values"));
        }
        let base = self.mesh.positions.len() as u32;
        self.mesh.positions.extend(positions.iter().map(|&p| xf.transform_point3(p)));
        self.mesh.indices.extend(indices.chunks_exact(3).map(|t| [t[0] + base, t[1] + base, t[2] + base]));
        Ok(())
    }
}
