//! The meshes of an animated file as scene data: the mesh nodes of one role gathered into one
//! [`TriangleMesh`] (the environment's at their world transforms, a prototype's in its own
//! space at its scale), with material slots local to it, and the file's materials and
//! textures loaded once for all of them.

use glam::Mat4;

use super::super::materials::material;
use super::super::textures::TextureLoader;
use super::super::triangles::Triangles;
use super::super::{GltfError, Source};
use super::AnimatedGltf;
use crate::geometry::TriangleMesh;
use crate::scene::texture::Texture;
use crate::scene::Material;

/// Triangles of some mesh nodes, and which of the file's materials their slots are.
pub(crate) struct GatheredMesh {
    /// `material_ids` (when the file gives materials) index `materials`.
    pub(crate) mesh: TriangleMesh,
    /// Indices into [`AnimatedGltf::materials`]' list, ascending; empty without materials.
    pub(crate) materials: Vec<u32>,
}

impl AnimatedGltf {
    /// Every material of the file (glTF's default material last) and their textures.
    pub(crate) fn materials(&self) -> (Vec<Material>, Vec<Texture>) {
        let source = Source { name: &self.path, base: self.path.parent() };
        let mut textures = TextureLoader::new(&source, &self.document, &self.buffers);
        let mut materials: Vec<Material> =
            self.document.materials().map(|m| material(&self.path, &m, &mut textures)).collect();
        materials.push(Material::gltf_default());
        (materials, textures.into_textures())
    }

    /// The meshes `parts` (mesh index, transform) gathered into one.
    pub(crate) fn gather(&self, parts: &[(usize, Mat4)]) -> Result<GatheredMesh, GltfError> {
        let mut triangles = Triangles::default();
        for (m, xf) in parts {
            // The gltf crate's `nth` indexes its slice: no walk over every mesh per call.
            let mesh = self.document.meshes().nth(*m).expect("roles name existing meshes");
            triangles.add_mesh(&self.path, &mesh, xf, &self.buffers, true)?;
        }
        let Triangles { mut mesh, normals, uvs, material_ids, any_normals, any_uvs, any_material } =
            triangles;
        mesh.normals = any_normals.then_some(normals);
        mesh.uvs = any_uvs.then_some(uvs);
        let mut used = Vec::new();
        if any_material {
            let default_slot = self.document.materials().len() as u32;
            let global: Vec<u32> =
                material_ids.iter().map(|&id| if id == u32::MAX { default_slot } else { id }).collect();
            used = global.clone();
            used.sort_unstable();
            used.dedup();
            let local = |id: &u32| used.binary_search(id).expect("listed") as u32;
            mesh.material_ids = Some(global.iter().map(local).collect());
        }
        let element = format!("meshes {:?}", parts.iter().map(|p| p.0).collect::<Vec<_>>());
        mesh.validate().map_err(|e| GltfError::new(&self.path, element, e.to_string()))?;
        Ok(GatheredMesh { mesh, materials: used })
    }
}
