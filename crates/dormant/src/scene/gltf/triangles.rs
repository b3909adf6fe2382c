//! [`Triangles`]: the triangle primitives of a file gathered into one mesh in the file's
//! space, with per-vertex normals and UVs and a material slot per triangle.

use std::path::Path;

use glam::{Affine3A, Mat4, Vec2, Vec3};

use super::checks::{check_attributes, unreadable, warn_textures_without_uvs};
use super::GltfError;
use crate::geometry::{NormalTurn, TriangleMesh};

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
        for prim in mesh.primitives() {
            if prim.mode() != gltf::mesh::Mode::Triangles {
                continue;
            }
            let element = format!("meshes[{}].primitives[{}]", mesh.index(), prim.index());
            check_attributes(path, &element, &prim, buffers)?;
            let source = Primitive { path, element: &element, prim: &prim, buffers };
            self.add_primitive(&source, &xf, with_materials)?;
        }
        Ok(())
    }

    /// Appends one checked triangle primitive: its triangles, normals, UVs and material slot.
    fn add_primitive(
        &mut self,
        source: &Primitive<'_>,
        xf: &Affine3A,
        with_materials: bool,
    ) -> Result<(), GltfError> {
        let (path, element, prim) = (source.path, source.element, source.prim);
        let reader = source.reader();
        let positions: Vec<Vec3> = reader
            .read_positions()
            .ok_or_else(|| source.unreadable("POSITION", gltf::Semantic::Positions))?
            .map(Vec3::from_array)
            .collect();
        let indices: Vec<u32> = match (reader.read_indices(), prim.indices()) {
            (Some(ix), _) => ix.into_u32().collect(),
            (None, None) => (0..positions.len() as u32).collect(),
            (None, Some(a)) => return Err(unreadable(path, element, "indices", Some(a))),
        };
        self.add_triangles(path, element, &positions, &indices, xf)?;
        // Primitives without an attribute get zeros: a zero normal shades with the geometric
        // normal, and a zero UV only matters to an untextured material.
        self.add_normals(source, xf)?;
        self.add_uvs(source, with_materials)?;
        let vertices = self.mesh.positions.len();
        if self.normals.len() != vertices || self.uvs.len() != vertices {
            return Err(GltfError::new(path, element, "attribute counts differ from POSITION's"));
        }
        let material = prim.material().index();
        self.any_material |= material.is_some();
        let slot = material.map_or(u32::MAX, |m| m as u32);
        self.material_ids.resize(self.mesh.indices.len(), slot);
        Ok(())
    }

    /// The primitive's normals, turned by `xf` ([`NormalTurn`]); zeros when it has none.
    fn add_normals(&mut self, source: &Primitive<'_>, xf: &Affine3A) -> Result<(), GltfError> {
        let turn = NormalTurn::of(xf);
        match source.reader().read_normals() {
            Some(ns) => {
                self.any_normals = true;
                self.normals.extend(ns.map(|v| turn.apply(Vec3::from_array(v))));
                Ok(())
            }
            None if source.prim.get(&gltf::Semantic::Normals).is_some() => {
                Err(source.unreadable("NORMAL", gltf::Semantic::Normals))
            }
            None => {
                self.normals.resize(self.mesh.positions.len(), Vec3::ZERO);
                Ok(())
            }
        }
    }

    /// The primitive's first texture coordinates (non-finite ones as zero); zeros when it has
    /// none, with a warning when its material has textures.
    fn add_uvs(&mut self, source: &Primitive<'_>, with_materials: bool) -> Result<(), GltfError> {
        match source.reader().read_tex_coords(0) {
            Some(tc) => {
                self.any_uvs = true;
                let finite = |uv: Vec2| if uv.is_finite() { uv } else { Vec2::ZERO };
                self.uvs.extend(tc.into_f32().map(|uv| finite(Vec2::from_array(uv))));
                Ok(())
            }
            None if source.prim.get(&gltf::Semantic::TexCoords(0)).is_some() => {
                Err(source.unreadable("TEXCOORD_0", gltf::Semantic::TexCoords(0)))
            }
            None => {
                if with_materials {
                    warn_textures_without_uvs(source.path, source.element, &source.prim.material());
                }
                self.uvs.resize(self.mesh.positions.len(), Vec2::ZERO);
                Ok(())
            }
        }
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

/// A triangle primitive being read, and where it is for messages.
struct Primitive<'a> {
    path: &'a Path,
    /// `meshes[m].primitives[p]`.
    element: &'a str,
    prim: &'a gltf::Primitive<'a>,
    buffers: &'a [gltf::buffer::Data],
}

impl<'a> Primitive<'a> {
    fn reader(&self) -> gltf::mesh::Reader<'a, 'a, impl Fn(gltf::Buffer<'a>) -> Option<&'a [u8]> + Clone> {
        let buffers = self.buffers;
        self.prim.reader(move |b| buffers.get(b.index()).map(|d| &d.0[..]))
    }

    /// The error for an attribute the reader could not read.
    fn unreadable(&self, what: &str, semantic: gltf::Semantic) -> GltfError {
        unreadable(self.path, self.element, what, self.prim.get(&semantic))
    }
}
