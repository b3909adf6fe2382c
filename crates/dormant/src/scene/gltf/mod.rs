//! glTF import as plain scene data. Every triangle primitive of the default scene (or of all
//! scenes' root nodes when there is no default), with node transforms baked in, merged into
//! one [`TriangleMesh`] per file; with [`load_gltf`] also the metallic-roughness materials
//! (one material slot per glTF material, per triangle), their textures decoded to RGBA8 with
//! the samplers' wrap modes, and KHR_lights_punctual lights. Builds no render objects.
//!
//! Bad input: a malformed file, accessor or non-finite vertex is an error naming the file
//! and the element; an image that cannot be loaded (missing file, unsupported format, zero
//! size) is a warning and a magenta texture; an unsupported extension is a warning, or an
//! error when the file requires it.
//!
//! Here: the public entry points and the load itself; `nodes` walks the node tree (cameras,
//! lights), `triangles` gathers the primitives, `checks` validates accessors and extensions
//! before anything is read, `materials` and `textures` turn materials and images into scene
//! data.

pub(crate) mod animated;

pub use animated::{inspect_animated_slice, AnimationInventory};
mod checks;
mod materials;
mod nodes;
mod textures;
mod triangles;

use std::path::{Path, PathBuf};

use glam::{Affine3A, Vec3};

use checks::{check_animation_indices, check_extensions, check_glb_length, check_position_accessors};
use materials::material;
pub(crate) use nodes::LUMENS_PER_WATT;
use nodes::{perspective_camera, punctual_light, walk_nodes};
use textures::TextureLoader;
use triangles::Triangles;

use crate::geometry::TriangleMesh;
use crate::scene::texture::Texture;
use crate::scene::{Light, Material};

/// A glTF file that could not be turned into a mesh: names the file and the element.
#[derive(Debug, thiserror::Error)]
#[error("{}: {element}: {message}", .file.display())]
pub struct GltfError {
    pub file: PathBuf,
    /// The glTF element at fault, e.g. `meshes[2].primitives[0]` or `(file)`.
    pub(crate) element: String,
    pub message: String,
}

impl GltfError {
    fn new(file: &Path, element: impl Into<String>, message: impl Into<String>) -> Self {
        Self { file: file.to_path_buf(), element: element.into(), message: message.into() }
    }
}

/// Extensions whose meaning the importer implements; any other one is ignored with a warning
/// (or refused when required).
pub(crate) const SUPPORTED_EXTENSIONS: &[&str] =
    &["KHR_lights_punctual", "KHR_materials_emissive_strength", "KHR_materials_specular"];

/// A glTF file as plain data.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GltfAsset {
    /// All triangles in the file's space. `material_ids` (when the file has materials) are
    /// indices into `materials`.
    pub mesh: TriangleMesh,
    /// Empty when no primitive names a material (the caller picks a colour). Otherwise one
    /// per glTF material, plus glTF's default material last when some primitive has none.
    pub materials: Vec<Material>,
    /// The textures `materials` reference by index.
    pub textures: Vec<Texture>,
    /// Punctual lights placed by the scene's nodes, in the file's space.
    pub lights: Vec<Light>,
    /// Perspective cameras placed by the scene's nodes, in the file's space, in node order.
    pub cameras: Vec<GltfCamera>,
}

/// A glTF perspective camera where its node puts it.
#[derive(Clone, Debug, PartialEq)]
pub struct GltfCamera {
    /// `camera N`, by its index in the file.
    pub name: String,
    pub position: Vec3,
    /// Unit direction the camera looks (its node's -Z).
    pub forward: Vec3,
    /// Vertical field of view.
    pub yfov_degrees: f32,
}

impl GltfAsset {
    /// An asset of bare geometry (no materials, textures or lights).
    pub(crate) fn from_mesh(mesh: TriangleMesh) -> Self {
        Self { mesh, ..Self::default() }
    }

    /// Moves the textures to the end of a scene's shared list and returns the materials
    /// with their texture indices pointing there.
    pub fn take_materials(&mut self, textures: &mut Vec<std::sync::Arc<Texture>>) -> Vec<Material> {
        let offset = textures.len() as u32;
        textures.extend(self.textures.drain(..).map(std::sync::Arc::new));
        let shift = |t: Option<u32>| t.map(|t| t + offset);
        self.materials
            .drain(..)
            .map(|m| Material {
                base_color_texture: shift(m.base_color_texture),
                metallic_roughness_texture: shift(m.metallic_roughness_texture),
                emissive_texture: shift(m.emissive_texture),
                ..m
            })
            .collect()
    }

    /// The asset moved by `xf` (mesh and lights).
    pub(crate) fn transformed(mut self, xf: &Affine3A) -> Self {
        self.mesh = self.mesh.transformed(xf);
        for camera in &mut self.cameras {
            camera.position = xf.transform_point3(camera.position);
            camera.forward = xf.transform_vector3(camera.forward).normalize_or(camera.forward);
        }
        for light in &mut self.lights {
            match light {
                Light::Point { position, .. } => *position = xf.transform_point3(*position),
                Light::Spot { position, direction, .. } => {
                    *position = xf.transform_point3(*position);
                    *direction = xf.transform_vector3(*direction).normalize_or(*direction);
                }
                Light::Directional { direction, .. } => {
                    *direction = xf.transform_vector3(*direction).normalize_or(*direction)
                }
            }
        }
        self
    }
}

/// Loads only the triangles (normals and UVs included) of a `.gltf` or `.glb` file: no
/// materials, no image decoding. For colliders and accelerator benchmarks.
pub fn load_gltf_mesh(path: &Path) -> Result<TriangleMesh, GltfError> {
    let mut asset = load(path, false)?;
    asset.mesh.material_ids = None;
    Ok(asset.mesh)
}

/// Loads triangles, materials, textures and punctual lights of a `.gltf` or `.glb` file.
pub fn load_gltf(path: &Path) -> Result<GltfAsset, GltfError> {
    load(path, true)
}

/// [`load_gltf`] on the bytes of a `.glb` or `.gltf` held in memory; `name` names it in
/// errors. Its buffers and images must be inside it (the GLB binary chunk or `data:` URIs):
/// a reference to another file is an error (a missing image, a warning), and nothing is read
/// from disk.
pub fn load_gltf_slice(bytes: &[u8], name: &Path) -> Result<GltfAsset, GltfError> {
    from_bytes(bytes, &Source { name, base: None }, true)
}

/// Where a glTF's bytes came from: `name` for messages, `base` (the file's directory) for
/// its relative URIs; `None` when it was given in memory and may reference no other file.
struct Source<'a> {
    name: &'a Path,
    base: Option<&'a Path>,
}

fn load(path: &Path, with_materials: bool) -> Result<GltfAsset, GltfError> {
    let bytes = std::fs::read(path).map_err(|e| GltfError::new(path, "(file)", e.to_string()))?;
    from_bytes(&bytes, &Source { name: path, base: path.parent() }, with_materials)
}

fn from_bytes(bytes: &[u8], source: &Source, with_materials: bool) -> Result<GltfAsset, GltfError> {
    let path = source.name;
    let (document, buffers) = read_document(bytes, source)?;
    let mut triangles = Triangles::default();
    let mut lights = Vec::new();
    let mut cameras = Vec::new();
    walk_nodes(path, &document, &mut |node, world| {
        if let (true, Some(light)) = (with_materials, node.light()) {
            lights.push(punctual_light(&light, world));
        }
        if let (true, Some(camera)) = (with_materials, node.camera()) {
            cameras.extend(perspective_camera(path, &camera, world));
        }
        match node.mesh() {
            Some(mesh) => triangles.add_mesh(path, &mesh, world, &buffers, with_materials),
            None => Ok(()),
        }
    })?;
    if triangles.mesh.indices.is_empty() {
        return Err(GltfError::new(path, "(document)", "contains no triangles"));
    }
    let Triangles { mut mesh, normals, uvs, mut material_ids, any_normals, any_uvs, any_material } =
        triangles;
    if any_normals {
        mesh.normals = Some(normals);
    }
    if any_uvs {
        mesh.uvs = Some(uvs);
    }

    let mut asset = GltfAsset { lights, cameras, ..GltfAsset::default() };
    if any_material {
        let default_slot = document.materials().len() as u32;
        if material_ids.contains(&u32::MAX) {
            for id in &mut material_ids {
                if *id == u32::MAX {
                    *id = default_slot;
                }
            }
        }
        mesh.material_ids = Some(material_ids);
        if with_materials {
            let mut textures = TextureLoader::new(source, &document, &buffers);
            asset.materials = document.materials().map(|m| material(path, &m, &mut textures)).collect();
            if mesh.max_material_slot() == default_slot {
                asset.materials.push(Material::gltf_default());
            }
            asset.textures = textures.into_textures();
        }
    }
    mesh.validate().map_err(|e| GltfError::new(path, "(merged mesh)", e.to_string()))?;
    asset.mesh = mesh;
    Ok(asset)
}

/// The document in `bytes`, checked for extensions, and its buffers' data.
fn read_document(
    bytes: &[u8],
    source: &Source,
) -> Result<(gltf::Document, Vec<gltf::buffer::Data>), GltfError> {
    let path = source.name;
    check_glb_length(path, bytes)?;
    let gltf::Gltf { document, blob } = gltf::Gltf::from_slice_without_validation(bytes)
        .map_err(|e| GltfError::new(path, "(document)", e.to_string()))?;
    check_extensions(path, &document)?;
    let json = document.into_json();
    check_position_accessors(path, &json)?;
    check_animation_indices(path, &json)?;
    let document =
        gltf::Document::from_json(json).map_err(|e| GltfError::new(path, "(document)", e.to_string()))?;
    let buffers =
        gltf::import_buffers(&document, source.base, blob).map_err(|e| buffer_error(source, &document, e))?;
    Ok((document, buffers))
}

/// The error for buffers that could not be loaded, naming the first external buffer file
/// that is missing when there is one (the importer's I/O error names no file).
fn buffer_error(source: &Source, document: &gltf::Document, e: gltf::Error) -> GltfError {
    let missing = source.base.and_then(|dir| {
        document.buffers().find_map(|b| match b.source() {
            gltf::buffer::Source::Uri(uri) if !uri.starts_with("data:") && !dir.join(uri).is_file() => {
                Some((b.index(), uri))
            }
            _ => None,
        })
    });
    match missing {
        Some((i, uri)) => {
            GltfError::new(source.name, format!("buffers[{i}]"), format!("cannot read '{uri}': {e}"))
        }
        None => GltfError::new(source.name, "buffers", e.to_string()),
    }
}
