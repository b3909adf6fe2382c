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

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use glam::{Affine3A, Mat4, Vec2, Vec3};
use gltf::accessor::{DataType, Dimensions};

use crate::geometry::TriangleMesh;
use crate::scene::texture::{Texture, Wrap};
use crate::scene::{Light, Material};

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

/// Extensions whose meaning the importer implements; any other one is ignored with a warning
/// (or refused when required).
pub const SUPPORTED_EXTENSIONS: &[&str] = &["KHR_lights_punctual", "KHR_materials_emissive_strength"];

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
    /// `camera N`, by its index in the file (the gltf crate is built without names).
    pub name: String,
    pub position: Vec3,
    /// Unit direction the camera looks (its node's -Z).
    pub forward: Vec3,
    /// Vertical field of view.
    pub yfov_degrees: f32,
}

impl GltfAsset {
    /// An asset of bare geometry (no materials, textures or lights).
    pub fn from_mesh(mesh: TriangleMesh) -> Self {
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
    pub fn transformed(mut self, xf: &Affine3A) -> Self {
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
            asset.textures = textures.textures;
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

/// Refuses a GLB whose header declares a total length shorter than the 12-byte header itself
/// (the gltf crate subtracts the header's size from it unchecked).
fn check_glb_length(path: &Path, bytes: &[u8]) -> Result<(), GltfError> {
    const HEADER_LEN: u32 = 12;
    if let Some(length) = bytes.strip_prefix(b"glTF").and_then(|rest| rest.get(4..8)) {
        let length = u32::from_le_bytes(length.try_into().expect("4 bytes"));
        if length < HEADER_LEN {
            let message = format!("GLB header declares {length} bytes, less than its own {HEADER_LEN}");
            return Err(GltfError::new(path, "(header)", message));
        }
    }
    Ok(())
}

/// Refuses a primitive whose POSITION names an accessor that does not exist (the gltf crate's
/// validation indexes the accessors with it unchecked).
fn check_position_accessors(path: &Path, json: &gltf::json::Root) -> Result<(), GltfError> {
    use gltf::json::{mesh::Semantic, validation::Checked};
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let Some(accessor) = primitive.attributes.get(&Checked::Valid(Semantic::Positions)) else {
                continue;
            };
            let count = json.accessors.len();
            if accessor.value() >= count {
                return Err(GltfError::new(
                    path,
                    format!("meshes[{m}].primitives[{p}].attributes.POSITION"),
                    format!("accessor {} does not exist ({count} accessors)", accessor.value()),
                ));
            }
        }
    }
    Ok(())
}

/// Calls `visit` with every node of the default scene (else the first scene, else every node
/// that is no other node's child) and its world transform, depth first; stops at the first
/// error, `visit`'s or a node reached twice (a cycle, or a node with two parents), a hierarchy
/// deeper than 256 or a non-finite transform.
fn walk_nodes<'d>(
    path: &Path,
    document: &'d gltf::Document,
    visit: &mut dyn FnMut(&gltf::Node<'d>, &Mat4) -> Result<(), GltfError>,
) -> Result<(), GltfError> {
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
    // A node reached twice would be walked again with all its descendants: a node listed
    // twice as a child, at every level, doubles the walk per level.
    let mut reached = vec![false; document.nodes().len()];
    while let Some((node, parent, depth)) = stack.pop() {
        if std::mem::replace(&mut reached[node.index()], true) {
            return Err(GltfError::new(
                path,
                format!("nodes[{}]", node.index()),
                "reached twice: a node may have one parent and belong to a scene once",
            ));
        }
        if depth > 256 {
            return Err(GltfError::new(
                path,
                format!("nodes[{}]", node.index()),
                "node hierarchy deeper than 256",
            ));
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if !world.is_finite() {
            return Err(GltfError::new(path, format!("nodes[{}]", node.index()), "non-finite transform"));
        }
        visit(&node, &world)?;
        for child in node.children() {
            stack.push((child, world, depth + 1));
        }
    }
    Ok(())
}

/// A perspective camera where `world` puts it; other cameras are ignored with a warning.
fn perspective_camera(path: &Path, camera: &gltf::Camera, world: &Mat4) -> Option<GltfCamera> {
    match camera.projection() {
        gltf::camera::Projection::Perspective(p) if p.yfov().is_finite() && p.yfov() > 0.0 => {
            Some(GltfCamera {
                name: format!("camera {}", camera.index()),
                position: world.transform_point3(Vec3::ZERO),
                forward: world.transform_vector3(Vec3::NEG_Z).normalize_or(Vec3::NEG_Z),
                yfov_degrees: p.yfov().to_degrees(),
            })
        }
        gltf::camera::Projection::Perspective(_) => {
            tracing::warn!(
                "{}: cameras[{}]: perspective camera without a usable yfov, ignored",
                path.display(),
                camera.index()
            );
            None
        }
        gltf::camera::Projection::Orthographic(_) => {
            tracing::warn!(
                "{}: cameras[{}]: orthographic cameras are not supported, ignored",
                path.display(),
                camera.index()
            );
            None
        }
    }
}

/// The triangle primitives of a file gathered so far, in the file's space: per-vertex normals
/// and UVs (zeros where a primitive has none) and a glTF material slot per triangle.
#[derive(Default)]
struct Triangles {
    mesh: TriangleMesh,
    normals: Vec<Vec3>,
    uvs: Vec<Vec2>,
    /// The glTF material index per triangle; `u32::MAX` for glTF's default material.
    material_ids: Vec<u32>,
    any_normals: bool,
    any_uvs: bool,
    any_material: bool,
}

impl Triangles {
    /// Appends every triangle primitive of `mesh`, moved by `world` (points and lines have no
    /// surface to collide with or render).
    fn add_mesh(
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

/// What the importer reads from an accessor: the element's dimensions and the component
/// types it accepts.
struct Layout {
    what: &'static str,
    dimensions: Dimensions,
    types: &'static [DataType],
}

const POSITIONS: Layout = Layout { what: "POSITION", dimensions: Dimensions::Vec3, types: &[DataType::F32] };
const NORMALS: Layout = Layout { what: "NORMAL", dimensions: Dimensions::Vec3, types: &[DataType::F32] };
const TEX_COORDS: Layout = Layout {
    what: "TEXCOORD_0",
    dimensions: Dimensions::Vec2,
    types: &[DataType::U8, DataType::U16, DataType::F32],
};
const INDICES: Layout = Layout {
    what: "indices",
    dimensions: Dimensions::Scalar,
    types: &[DataType::U8, DataType::U16, DataType::U32],
};

/// Checks every accessor of `prim` the importer reads, before the gltf crate's reader does:
/// its reader trusts accessors' types, counts, strides and ranges, and panics, or yields
/// more elements than the file holds, when they are wrong.
fn check_attributes(
    path: &Path,
    element: &str,
    prim: &gltf::Primitive,
    buffers: &[gltf::buffer::Data],
) -> Result<(), GltfError> {
    let attributes = [
        (prim.get(&gltf::Semantic::Positions), &POSITIONS),
        (prim.get(&gltf::Semantic::Normals), &NORMALS),
        (prim.get(&gltf::Semantic::TexCoords(0)), &TEX_COORDS),
        (prim.indices(), &INDICES),
    ];
    for (accessor, layout) in attributes {
        let Some(accessor) = accessor else { continue };
        check_accessor(&accessor, layout, buffers).map_err(|message| {
            GltfError::new(
                path,
                element,
                format!("{} (accessors[{}]) {message}", layout.what, accessor.index()),
            )
        })?;
    }
    Ok(())
}

/// Whether the reader can read `accessor` as `layout`: the right type, at least one element,
/// and every element (and every sparse index and value) inside its buffer view and buffer.
/// Without a buffer view its elements are zeros the reader makes up: no more are allowed
/// than the file's buffers have bytes.
fn check_accessor(
    accessor: &gltf::Accessor,
    layout: &Layout,
    buffers: &[gltf::buffer::Data],
) -> Result<(), String> {
    let (dimensions, data_type) = (accessor.dimensions(), accessor.data_type());
    if dimensions != layout.dimensions || !layout.types.contains(&data_type) {
        let expected = format!("{:?} of {:?}", layout.dimensions, layout.types);
        return Err(format!("is {dimensions:?} of {data_type:?}, expected {expected}"));
    }
    let size = data_type.size() * dimensions.multiplicity();
    let count = accessor.count();
    if count == 0 {
        return Err("has no elements (count 0)".into());
    }
    match accessor.view() {
        Some(view) => check_elements(&view, accessor.offset(), count, size, buffers)?,
        None if accessor.sparse().is_none() => {
            return Err("has neither a bufferView nor sparse values".into())
        }
        None => {
            let held: usize = buffers.iter().map(|b| b.len()).sum();
            if count > held {
                return Err(format!(
                    "declares {count} elements without a bufferView, more than the {held} bytes of the file's buffers"
                ));
            }
        }
    }
    if let Some(sparse) = accessor.sparse() {
        let n = sparse.count();
        if n == 0 || n > count {
            return Err(format!("has {n} sparse values, expected 1 to its count {count}"));
        }
        let (indices, values) = (sparse.indices(), sparse.values());
        check_elements(&indices.view(), indices.offset(), n, indices.index_type().size(), buffers)
            .map_err(|e| format!("sparse indices: {e}"))?;
        check_elements(&values.view(), values.offset(), n, size, buffers)
            .map_err(|e| format!("sparse values: {e}"))?;
    }
    Ok(())
}

/// Whether `count` elements of `size` bytes from `offset` in `view`, at the view's stride (or
/// packed), lie inside the view, and the view inside its buffer.
fn check_elements(
    view: &gltf::buffer::View,
    offset: usize,
    count: usize,
    size: usize,
    buffers: &[gltf::buffer::Data],
) -> Result<(), String> {
    let stride = view.stride().unwrap_or(size);
    if stride < size {
        return Err(format!(
            "bufferViews[{}] has stride {stride}, less than its {size}-byte elements",
            view.index()
        ));
    }
    let end =
        stride.checked_mul(count - 1).and_then(|n| n.checked_add(size)).and_then(|n| n.checked_add(offset));
    let buffer = buffers.get(view.buffer().index()).map_or(0, |b| b.len());
    let view_end = view.offset().checked_add(view.length());
    match (end, view_end) {
        (Some(end), Some(view_end)) if end <= view.length() && view_end <= buffer => Ok(()),
        _ => Err(format!(
            "{count} elements of {size} bytes at offset {offset} (stride {stride}) do not fit in bufferViews[{}] \
             ({} bytes at offset {} of a {buffer}-byte buffer)",
            view.index(),
            view.length(),
            view.offset()
        )),
    }
}

/// The error for an attribute the reader could not give: it answers `None` both for a
/// missing attribute and for an accessor whose data lies outside its buffer view or buffer,
/// so this tells them apart.
fn unreadable(path: &Path, element: &str, what: &str, accessor: Option<gltf::Accessor>) -> GltfError {
    match accessor {
        Some(a) => GltfError::new(
            path,
            element,
            format!(
                "{what} (accessors[{}]) cannot be read: its data lies outside its buffer view or buffer",
                a.index()
            ),
        ),
        None => GltfError::new(path, element, format!("has no {what} attribute")),
    }
}

/// Warns that a primitive without TEXCOORD_0 reads its material's textures at (0, 0).
fn warn_textures_without_uvs(path: &Path, element: &str, m: &gltf::Material) {
    let pbr = m.pbr_metallic_roughness();
    let textured = pbr.base_color_texture().is_some()
        || pbr.metallic_roughness_texture().is_some()
        || m.emissive_texture().is_some();
    if textured {
        tracing::warn!(
            file = %path.display(),
            "{element}: its material has textures but the primitive has no \
             TEXCOORD_0; they are read at (0, 0)"
        );
    }
}

/// Warns about every used extension the importer ignores; refuses a file that requires one.
fn check_extensions(path: &Path, document: &gltf::Document) -> Result<(), GltfError> {
    for (i, ext) in document.extensions_required().enumerate() {
        if !SUPPORTED_EXTENSIONS.contains(&ext) {
            return Err(GltfError::new(
                path,
                format!("extensionsRequired[{i}]"),
                format!("requires extension {ext}, which dormant does not support"),
            ));
        }
    }
    for ext in document.extensions_used() {
        if !SUPPORTED_EXTENSIONS.contains(&ext) {
            tracing::warn!(file = %path.display(), "glTF extension {ext} is not supported: ignored");
        }
    }
    Ok(())
}

fn punctual_light(light: &gltf::khr_lights_punctual::Light, world: &Mat4) -> Light {
    use gltf::khr_lights_punctual::Kind;
    let intensity = Vec3::from_array(light.color()) * light.intensity().max(0.0);
    let position = world.transform_point3(Vec3::ZERO);
    // Lights shine along their node's -Z.
    let direction = world.transform_vector3(Vec3::NEG_Z).normalize_or(Vec3::NEG_Y);
    match light.kind() {
        Kind::Point => Light::Point { position, intensity },
        Kind::Directional => Light::Directional { direction, irradiance: intensity },
        Kind::Spot { inner_cone_angle, outer_cone_angle } => {
            let outer = outer_cone_angle.clamp(0.0, std::f32::consts::FRAC_PI_2);
            let inner = inner_cone_angle.clamp(0.0, outer);
            Light::Spot { position, direction, intensity, cos_inner: inner.cos(), cos_outer: outer.cos() }
        }
    }
}

fn material(path: &Path, m: &gltf::Material, textures: &mut TextureLoader) -> Material {
    let pbr = m.pbr_metallic_roughness();
    let [r, g, b, _alpha] = pbr.base_color_factor();
    let at = |slot: &str| format!("materials[{}].{slot}", m.index().unwrap_or(0));
    let mut texture = |info: Option<gltf::texture::Info>, slot: &str| {
        let info = info?;
        if info.tex_coord() != 0 {
            tracing::warn!(
                file = %path.display(),
                "{}: uses TEXCOORD_{}; only TEXCOORD_0 is supported, using it instead",
                at(slot),
                info.tex_coord()
            );
        }
        Some(textures.get(&info.texture()))
    };
    let strength = m.emissive_strength().unwrap_or(1.0).max(0.0);
    Material {
        base_color: Vec3::new(r, g, b).max(Vec3::ZERO),
        roughness: pbr.roughness_factor().clamp(0.0, 1.0),
        metallic: pbr.metallic_factor().clamp(0.0, 1.0),
        specular: 1.0,
        emissive: Vec3::from_array(m.emissive_factor()).max(Vec3::ZERO) * strength,
        base_color_texture: texture(pbr.base_color_texture(), "baseColorTexture"),
        metallic_roughness_texture: texture(pbr.metallic_roughness_texture(), "metallicRoughnessTexture"),
        emissive_texture: texture(m.emissive_texture(), "emissiveTexture"),
    }
}

/// Decodes the textures materials use, each glTF texture once (and each image once).
struct TextureLoader<'a> {
    source: &'a Source<'a>,
    document: &'a gltf::Document,
    buffers: &'a [gltf::buffer::Data],
    /// glTF texture index -> index in `textures`.
    by_texture: BTreeMap<usize, u32>,
    images: BTreeMap<usize, Texture>,
    textures: Vec<Texture>,
}

impl<'a> TextureLoader<'a> {
    fn new(source: &'a Source<'a>, document: &'a gltf::Document, buffers: &'a [gltf::buffer::Data]) -> Self {
        Self {
            source,
            document,
            buffers,
            by_texture: BTreeMap::new(),
            images: BTreeMap::new(),
            textures: Vec::new(),
        }
    }

    fn get(&mut self, texture: &gltf::Texture) -> u32 {
        if let Some(&i) = self.by_texture.get(&texture.index()) {
            return i;
        }
        let image = texture.source();
        let decoded = self.images.entry(image.index()).or_insert_with(|| {
            let name = format!("{}: images[{}]", self.source.name.display(), image.index());
            decode_image(self.source, self.document, self.buffers, &image).unwrap_or_else(|why| {
                tracing::warn!("{name}: {why}; using a magenta texture");
                Texture::magenta(&name)
            })
        });
        let sampler = texture.sampler();
        let wrap = |w: gltf::texture::WrappingMode| match w {
            gltf::texture::WrappingMode::Repeat => Wrap::Repeat,
            gltf::texture::WrappingMode::ClampToEdge => Wrap::ClampToEdge,
            gltf::texture::WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
        };
        let texture_data =
            Texture { wrap_s: wrap(sampler.wrap_s()), wrap_t: wrap(sampler.wrap_t()), ..decoded.clone() };
        let i = self.textures.len() as u32;
        self.textures.push(texture_data);
        self.by_texture.insert(texture.index(), i);
        i
    }
}

/// The encoded bytes of an image (buffer view, data URI or file next to the glTF), decoded by
/// whatever format the bytes are in (PNG and JPEG are compiled in).
fn decode_image(
    source: &Source,
    document: &gltf::Document,
    buffers: &[gltf::buffer::Data],
    image: &gltf::Image,
) -> Result<Texture, String> {
    let json = &document.as_json().images[image.index()];
    let bytes: Vec<u8> = match (&json.buffer_view, &json.uri) {
        (Some(view), _) => {
            let view = document.views().nth(view.value()).ok_or("buffer view does not exist")?;
            let data = buffers.get(view.buffer().index()).ok_or("buffer does not exist")?;
            let end = view.offset().checked_add(view.length()).ok_or("buffer view is too long")?;
            data.0.get(view.offset()..end).ok_or("buffer view lies outside its buffer")?.to_vec()
        }
        (None, Some(uri)) => {
            gltf::buffer::Data::from_source(gltf::buffer::Source::Uri(uri), source.base)
                .map_err(|e| format!("cannot read '{uri}': {e}"))?
                .0
        }
        (None, None) => return Err("has neither a uri nor a bufferView".into()),
    };
    let decoded = image::load_from_memory(&bytes).map_err(|e| format!("cannot decode: {e}"))?.to_rgba8();
    let (width, height) = decoded.dimensions();
    if width == 0 || height == 0 {
        return Err(format!("image is {width}x{height}"));
    }
    Ok(Texture {
        name: format!("{}: images[{}]", source.name.display(), image.index()),
        width,
        height,
        texels: decoded.pixels().map(|p| p.0).collect(),
        wrap_s: Wrap::Repeat,
        wrap_t: Wrap::Repeat,
    })
}
