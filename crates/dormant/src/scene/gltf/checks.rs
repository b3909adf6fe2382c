//! What the importer checks before it reads: the GLB length, extensions, and every accessor a
//! triangle primitive reads (type, count, bounds within its buffer view), so that malformed
//! input is an error naming the element instead of a panic in the reader.

use std::path::Path;

use gltf::accessor::{DataType, Dimensions};

use super::{GltfError, SUPPORTED_EXTENSIONS};

/// Refuses a GLB whose header declares a total length shorter than the 12-byte header itself
/// (the gltf crate subtracts the header's size from it unchecked).
pub(super) fn check_glb_length(path: &Path, bytes: &[u8]) -> Result<(), GltfError> {
    const HEADER_LEN: u32 = 12;
    if let Some(length) = bytes.strip_prefix(b"glTF").and_then(|rest| rest.get(4..8)) {
        let length = u32::from_le_bytes(length.try_into().expect("4 bytes"));
        if length < HEADER_LEN {
            let message = format!("GLB header declares {length} bytes, less than its own {HEADER_LEN}");
            return Err(GltfError::new(path, "(header)", message));
        }
        if length as usize > bytes.len() {
            let message = format!(
                "the file is truncated: its GLB header declares {length} bytes, the file has {}",
                bytes.len()
            );
            return Err(GltfError::new(path, "(header)", message));
        }
    }
    Ok(())
}

/// Refuses a primitive whose POSITION names an accessor that does not exist (the gltf crate's
/// validation indexes the accessors with it unchecked).
pub(super) fn check_position_accessors(path: &Path, json: &gltf::json::Root) -> Result<(), GltfError> {
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

/// Refuses an animation whose channels or samplers name a sampler, node or accessor that does
/// not exist (the gltf crate's accessors for them index unchecked).
pub(super) fn check_animation_indices(path: &Path, json: &gltf::json::Root) -> Result<(), GltfError> {
    let (nodes, accessors) = (json.nodes.len(), json.accessors.len());
    let missing = |element: String, what: &str, index: usize, count: usize| {
        GltfError::new(path, element, format!("{what} {index} does not exist ({count} {what}s)"))
    };
    for (a, animation) in json.animations.iter().enumerate() {
        for (c, channel) in animation.channels.iter().enumerate() {
            let element = format!("animations[{a}].channels[{c}]");
            if channel.sampler.value() >= animation.samplers.len() {
                return Err(missing(element, "sampler", channel.sampler.value(), animation.samplers.len()));
            }
            if channel.target.node.value() >= nodes {
                return Err(missing(element, "node", channel.target.node.value(), nodes));
            }
        }
        for (s, sampler) in animation.samplers.iter().enumerate() {
            for index in [sampler.input.value(), sampler.output.value()] {
                if index >= accessors {
                    return Err(missing(
                        format!("animations[{a}].samplers[{s}]"),
                        "accessor",
                        index,
                        accessors,
                    ));
                }
            }
        }
    }
    Ok(())
}

/// What the importer reads from an accessor: the element's dimensions and the component
/// types it accepts.
pub(super) struct AccessorLayout {
    what: &'static str,
    dimensions: Dimensions,
    types: &'static [DataType],
}

impl AccessorLayout {
    pub(super) const fn new(what: &'static str, dimensions: Dimensions, types: &'static [DataType]) -> Self {
        Self { what, dimensions, types }
    }

    /// What the accessor is to the importer (`POSITION`, `input`), as messages name it.
    pub(super) fn what(&self) -> &'static str {
        self.what
    }
}

pub(super) const POSITIONS: AccessorLayout =
    AccessorLayout { what: "POSITION", dimensions: Dimensions::Vec3, types: &[DataType::F32] };

pub(super) const NORMALS: AccessorLayout =
    AccessorLayout { what: "NORMAL", dimensions: Dimensions::Vec3, types: &[DataType::F32] };

pub(super) const TEX_COORDS: AccessorLayout = AccessorLayout {
    what: "TEXCOORD_0",
    dimensions: Dimensions::Vec2,
    types: &[DataType::U8, DataType::U16, DataType::F32],
};

pub(super) const INDICES: AccessorLayout = AccessorLayout {
    what: "indices",
    dimensions: Dimensions::Scalar,
    types: &[DataType::U8, DataType::U16, DataType::U32],
};

/// Checks every accessor of `prim` the importer reads, before the gltf crate's reader does:
/// its reader trusts accessors' types, counts, strides and ranges, and panics, or yields
/// more elements than the file holds, when they are wrong.
pub(super) fn check_attributes(
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
pub(super) fn check_accessor(
    accessor: &gltf::Accessor,
    layout: &AccessorLayout,
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
pub(super) fn check_elements(
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
pub(super) fn unreadable(
    path: &Path,
    element: &str,
    what: &str,
    accessor: Option<gltf::Accessor>,
) -> GltfError {
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
pub(super) fn warn_textures_without_uvs(path: &Path, element: &str, m: &gltf::Material) {
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
pub(super) fn check_extensions(path: &Path, document: &gltf::Document) -> Result<(), GltfError> {
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
