//! What `dormant export --gltf` records in a file's `extras` for an exact round trip, read
//! back: in the asset's extras `{"dormant": {"format", "fps", "frames", "rest_tolerance",
//! "min_rest_frames", "scene", "simulation"}}` (the scene file's cameras, lights, sky and render settings as TOML), and in a
//! body node's extras `{"dormant": {"body": N}}`. Files from other tools have none of it.

use std::path::Path;

use serde::Deserialize;

use super::super::GltfError;

/// The asset's `dormant` extras (every field optional).
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(default)]
pub(crate) struct DormantExtras {
    pub(crate) format: Option<String>,
    /// Frames per second the file was sampled at.
    pub(crate) fps: Option<f64>,
    /// Frames the sequence has.
    pub(crate) frames: Option<u32>,
    /// The rest tolerance to detect rest with (0 for a dormant simulation: exact).
    pub(crate) rest_tolerance: Option<f32>,
    /// The shortest rest (2 for a dormant simulation: every sleep that holds a pose).
    pub(crate) min_rest_frames: Option<u32>,
    /// The scene file's text without its bodies, environment and physics.
    pub(crate) scene: Option<String>,
    /// The simulation's islands and kinematic bodies.
    pub(crate) simulation: Option<SimulationExtras>,
}

/// A simulation's islands (`[first frame, frame it woke or null, [bodies]]`, in the order
/// they fell asleep) and kinematic bodies, as dormant's export records them.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(default)]
pub(crate) struct SimulationExtras {
    pub(crate) islands: Vec<(u32, Option<u32>, Vec<u32>)>,
    pub(crate) kinematic: Vec<u32>,
}

#[derive(Deserialize)]
struct Wrapper<T> {
    dormant: Option<T>,
}

#[derive(Deserialize)]
struct BodyExtras {
    body: u32,
}

impl DormantExtras {
    /// The asset's extras; other keys and other tools' extras are ignored.
    pub(super) fn of(path: &Path, document: &gltf::Document) -> Result<Self, GltfError> {
        let Some(raw) = &document.as_json().asset.extras else { return Ok(Self::default()) };
        match serde_json::from_str::<Wrapper<Self>>(raw.get()) {
            Ok(w) => Ok(w.dormant.unwrap_or_default()),
            // Other tools' extras (Blender writes custom properties there) are not ours.
            Err(_) if !raw.get().contains("\"dormant\"") => Ok(Self::default()),
            Err(e) => Err(GltfError::new(path, "asset.extras.dormant", e.to_string())),
        }
    }
}

/// The body id a node's `dormant` extras give it, if any.
pub(super) fn body_of(path: &Path, node: &gltf::Node) -> Result<Option<u32>, GltfError> {
    let Some(raw) = node.extras() else { return Ok(None) };
    match serde_json::from_str::<Wrapper<BodyExtras>>(raw.get()) {
        Ok(w) => Ok(w.dormant.map(|b| b.body)),
        // Other tools' extras (Blender writes custom properties there) are not ours.
        Err(_) if !raw.get().contains("\"dormant\"") => Ok(None),
        Err(e) => Err(GltfError::new(path, format!("nodes[{}].extras.dormant", node.index()), e.to_string())),
    }
}
