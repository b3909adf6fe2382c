//! A sequence as one glTF 2.0 binary file (`dormant export --gltf`, format `dormant-gltf-1`,
//! docs/design.md#export-dormant-export): the prototype meshes and the environment with
//! their materials and textures, a node per body, the camera and the lights, and one
//! animation of every body's pose and presence and the camera over all frames.
//!
//! This file assembles the document and writes the GLB; each part has its file:
//! - `buffer.rs`: the binary chunk, buffer views and accessors;
//! - `meshes.rs`: meshes and their per-material primitives;
//! - `materials.rs`: materials, textures (PNG), samplers;
//! - `nodes.rs`: body, environment, camera and light nodes;
//! - `animation.rs`: the key reduction and the animation's channels;
//! - `extras.rs`: the `asset` object with the recorded scene TOML.

mod animation;
mod buffer;
mod extras;
mod materials;
mod meshes;
mod nodes;

use std::borrow::Cow;
use std::path::Path;

use serde::Serialize;
use serde_json::{json, Map, Value};

use self::animation::{Animation, AnimationBuilder, Track};
use self::buffer::{Accessor, BufferBuilder, View};
use self::meshes::MaterialRange;
use super::Sequence;
use crate::geometry::MeshError;

/// Version of the glTF export's layout (in `asset.extras.dormant.format`); bump it when the
/// contract in docs/design.md changes.
pub(crate) const GLTF_FORMAT: &str = "dormant-gltf-1";

/// What stops a glTF export.
#[derive(Debug, thiserror::Error)]
pub enum GltfExportError {
    #[error("cannot write {}: {source}", .path.display())]
    Write {
        path: std::path::PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("mesh `{mesh}`: {source}")]
    Mesh {
        mesh: String,
        #[source]
        source: MeshError,
    },
    #[error("mesh `{mesh}`: triangle {triangle} uses material slot {slot}, which the mesh does not have")]
    MaterialSlot { mesh: String, triangle: usize, slot: u32 },
    #[error("texture `{name}`: {reason}")]
    Texture { name: String, reason: String },
    #[error("the scene file's TOML: {0}")]
    SceneToml(String),
    #[error("the binary data is {0} bytes, more than a GLB file can hold (4 GiB)")]
    TooLarge(usize),
    #[error("the export is not valid glTF (a bug, or a value glTF cannot hold): {0}")]
    Invalid(String),
}

/// What a written glTF export holds.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct GltfSummary {
    pub bytes: u64,
    pub frames: u32,
    pub bodies: usize,
    pub nodes: usize,
}

impl Sequence {
    /// Frames per second of the export's key times: 1 / the trajectory's timestep.
    fn fps(&self) -> f64 {
        1.0 / self.trajectory.timestep as f64
    }

    /// The whole sequence as a glTF binary (GLB) written atomically to `path`.
    pub fn write_gltf(&self, path: &Path) -> Result<GltfSummary, GltfExportError> {
        let (json, bin, nodes) = self.gltf_parts()?;
        let glb = glb(json, bin)?;
        let write_error = |source| GltfExportError::Write { path: path.to_path_buf(), source };
        crate::atomic_file::write_atomic_with(path, |w| glb.to_writer(w).map_err(std::io::Error::other))
            .map_err(write_error)?;
        Ok(GltfSummary {
            bytes: u64::from(glb.header.length),
            frames: self.frame_count(),
            bodies: self.trajectory.bodies.len(),
            nodes,
        })
    }

    /// The GLB file's JSON chunk (checked: it is valid glTF), binary chunk and node count.
    pub(crate) fn gltf_parts(&self) -> Result<(Vec<u8>, Vec<u8>, usize), GltfExportError> {
        let mut buffer = BufferBuilder::default();
        let mut rest = Map::new();
        rest.insert(
            "asset".into(),
            extras::asset(
                self.fps(),
                self.frame_count(),
                &self.scene_source,
                extras::simulation(&self.trajectory),
            )?,
        );
        self.add_meshes(&mut rest, &mut buffer)?;
        let (nodes, animation) = self.add_nodes(&mut rest, &mut buffer);
        rest.insert("scene".into(), json!(0));
        rest.insert("scenes".into(), json!([{ "nodes": (0..nodes.len()).collect::<Vec<_>>() }]));
        let (bin, buffer_views, accessors) = buffer.finish();
        if !bin.is_empty() {
            rest.insert("buffers".into(), json!([{ "byteLength": bin.len() }]));
        }
        let count = nodes.len();
        let document =
            Document { rest, nodes, animations: animation.into_iter().collect(), accessors, buffer_views };
        let json = serde_json::to_vec(&document).map_err(|e| GltfExportError::Invalid(e.to_string()))?;
        check(&json)?;
        Ok((json, bin, count))
    }

    /// Meshes (prototypes, then the environment), materials and textures.
    fn add_meshes(
        &self,
        root: &mut Map<String, Value>,
        buffer: &mut BufferBuilder,
    ) -> Result<(), GltfExportError> {
        let template = &self.template;
        let materials = materials::materials_json(&template.materials, &template.textures, buffer)?;
        let ranges = self.material_ranges();
        let mut meshes = Vec::with_capacity(self.assets.prototypes.len() + 1);
        for (i, (name, mesh)) in self.assets.prototypes.iter().enumerate() {
            meshes.push(meshes::mesh_json(name, mesh, ranges[i + 1], buffer)?);
        }
        meshes.push(meshes::mesh_json("environment", &self.assets.environment, ranges[0], buffer)?);
        root.insert("meshes".into(), Value::Array(meshes));
        if materials.emissive_strength {
            extension_used(root, "KHR_materials_emissive_strength");
        }
        insert_array(root, "materials", materials.materials);
        insert_array(root, "textures", materials.textures);
        insert_array(root, "images", materials.images);
        insert_array(root, "samplers", materials.samplers);
        Ok(())
    }

    /// Each mesh slot's (environment first, then the prototypes) glTF materials: the
    /// template's materials are the slots' own, one slot after another.
    fn material_ranges(&self) -> Vec<MaterialRange> {
        let template = &self.template;
        let firsts: Vec<u32> = template
            .statics
            .iter()
            .take(1)
            .map(|s| s.material)
            .chain(template.prototypes.iter().map(|p| p.material))
            .collect();
        let ends = firsts.iter().skip(1).copied().chain([template.materials.len() as u32]);
        firsts
            .iter()
            .zip(ends)
            .map(|(&first, end)| MaterialRange { first, count: end.saturating_sub(first) })
            .collect()
    }

    /// Body, environment, camera and light nodes (returned), the camera and lights (into
    /// `root`), and the animation (returned).
    fn add_nodes(
        &self,
        root: &mut Map<String, Value>,
        buffer: &mut BufferBuilder,
    ) -> (Vec<nodes::Node>, Option<Animation>) {
        let environment_mesh = self.assets.prototypes.len();
        let mut nodes: Vec<nodes::Node> = (self.trajectory.bodies.iter().enumerate())
            .map(|(b, body)| nodes::body_node(b, body.prototype))
            .collect();
        nodes.push(nodes::Node::Other(nodes::environment_node(environment_mesh)));
        let (body_tracks, camera_track) = self.tracks();
        let camera_keys = camera_track.pose_keys(self.frame_count());
        let first_camera =
            camera_keys.first().map_or_else(|| nodes::camera_pose(&self.template.camera), |k| k.1);
        nodes.push(nodes::Node::Other(nodes::camera_node(&first_camera)));
        let camera_node = nodes.len() - 1;
        let default = crate::render::RenderSettings::default();
        let size = self.render.size.unwrap_or((default.width, default.height));
        root.insert("cameras".into(), json!([nodes::perspective(&self.template.camera, size)]));
        let (lights, light_nodes) = nodes::lights(&self.template.sun, &self.template.lights);
        nodes.extend(light_nodes.into_iter().map(nodes::Node::Other));
        root.insert("extensions".into(), json!({ "KHR_lights_punctual": { "lights": lights } }));
        extension_used(root, "KHR_lights_punctual");
        let mut animation = AnimationBuilder::new(self.fps());
        for (b, track) in body_tracks.iter().enumerate() {
            animation.pose(b, &track.pose_keys(self.frame_count()), buffer);
            animation.presence(b, &track.presence_keys(), buffer);
        }
        animation.pose(camera_node, &camera_keys, buffer);
        (nodes, animation.finish())
    }

    /// Every body's pose and presence and the camera's pose over all frames, replayed.
    fn tracks(&self) -> (Vec<Track>, Track) {
        let mut bodies = vec![Track::default(); self.trajectory.bodies.len()];
        let mut camera = Track::default();
        let all = super::FrameSelection::stepped(super::FrameRange { start: 0, end: self.frame_count() }, 1);
        let _ = self.replay::<std::convert::Infallible>(&all, &mut [], &mut |frame, _| {
            for (b, track) in bodies.iter_mut().enumerate() {
                let present = frame.is_present(b).then(|| {
                    let p = &frame.poses[b];
                    let (t, q) = (p.translation, p.rotation);
                    [t.x, t.y, t.z, q.x, q.y, q.z, q.w]
                });
                track.push(frame.index, present);
            }
            let camera_now = self.assets.camera_at(self.time_of(frame.index));
            camera.push(frame.index, Some(nodes::camera_pose(&camera_now)));
            Ok(())
        });
        (bodies, camera)
    }
}

/// Inserts `values` as `key` unless empty (glTF arrays have at least one element).
fn insert_array(root: &mut Map<String, Value>, key: &str, values: Vec<Value>) {
    if !values.is_empty() {
        root.insert(key.into(), Value::Array(values));
    }
}

/// Adds `name` to `extensionsUsed`.
fn extension_used(root: &mut Map<String, Value>, name: &str) {
    let used = root.entry("extensionsUsed").or_insert_with(|| json!([]));
    if let Some(list) = used.as_array_mut() {
        list.push(json!(name));
    }
}

/// The glTF document: its large arrays typed (a value per accessor would take gigabytes for
/// the demolition), the rest JSON values.
#[derive(Serialize)]
struct Document {
    #[serde(flatten)]
    rest: Map<String, Value>,
    nodes: Vec<nodes::Node>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    animations: Vec<Animation>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    accessors: Vec<Accessor>,
    #[serde(rename = "bufferViews", skip_serializing_if = "Vec::is_empty")]
    buffer_views: Vec<View>,
}

/// Parses `json` back as a glTF document and validates it.
fn check(json: &[u8]) -> Result<(), GltfExportError> {
    let invalid = |e: String| GltfExportError::Invalid(e);
    let root: ::gltf::json::Root = serde_json::from_slice(json).map_err(|e| invalid(e.to_string()))?;
    ::gltf::Document::from_json(root).map_err(|e| invalid(e.to_string()))?;
    Ok(())
}

/// The GLB container of `json` and `bin`, or an error past GLB's 4 GiB.
fn glb(json: Vec<u8>, bin: Vec<u8>) -> Result<::gltf::binary::Glb<'static>, GltfExportError> {
    let bin_chunk = if bin.is_empty() { 0 } else { 8 + bin.len().next_multiple_of(4) };
    let total = 12 + 8 + json.len().next_multiple_of(4) + bin_chunk;
    let length = u32::try_from(total).map_err(|_| GltfExportError::TooLarge(total))?;
    let header = ::gltf::binary::Header { magic: *b"glTF", version: 2, length };
    let bin = (!bin.is_empty()).then_some(Cow::Owned(bin));
    Ok(::gltf::binary::Glb { header, json: Cow::Owned(json), bin })
}
