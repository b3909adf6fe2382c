//! Animated glTF files (rigid-body bakes from Blender, Houdini or `dormant export --gltf`) as
//! plain data: every node's motion under the animations that play, the node tree, and the
//! file's `dormant` extras. [`AnimatedGltf::roles`] sorts the mesh nodes of the default scene
//! into the environment (world transform never changes over the sampled frames) and bodies
//! (it changes, or the file marks the node as a body), and gives each body its prototype
//! (one per mesh and constant scale). Builds no physics or render objects: `physics` turns
//! the bodies' poses into a trajectory, `scene::SceneAssets` loads the meshes.
//!
//! Here: the file and the node tree; `sampler` evaluates keys, `channels` reads them,
//! `roles` classifies nodes, `extras` reads what dormant's own export records.

mod channels;
mod extras;
mod meshes;
mod roles;
mod sampler;

use std::path::{Path, PathBuf};

use glam::{Mat4, Quat, Vec3};

pub(crate) use channels::NodeMotion;
pub(crate) use extras::{DormantExtras, SimulationExtras};
pub(crate) use roles::Roles;

use super::nodes::{perspective_camera, punctual_light, walk_nodes};
use super::{read_document, GltfCamera, GltfError, Source};
use crate::scene::Light;

/// The time of frame `index` at `fps` frames per second, as both the glTF export writes key
/// times and the import samples them (so a key is met at its own time, bit for bit).
pub(crate) fn frame_time(index: u32, fps: f64) -> f32 {
    (index as f64 / fps) as f32
}

/// The scene file text recorded in the `dormant` extras of the glTF file at `path`, if any
/// (reads the document, not its buffers).
pub(crate) fn scene_extras(path: &Path) -> Result<Option<String>, GltfError> {
    let bytes = std::fs::read(path).map_err(|e| GltfError::new(path, "(file)", e.to_string()))?;
    super::checks::check_glb_length(path, &bytes)?;
    let gltf = gltf::Gltf::from_slice_without_validation(&bytes)
        .map_err(|e| GltfError::new(path, "(document)", e.to_string()))?;
    Ok(DormantExtras::of(path, &gltf.document)?.scene)
}

/// What an animated glTF file holds when sampled: see [`inspect_animated_slice`].
#[derive(Clone, Debug, PartialEq)]
pub struct AnimationInventory {
    /// Mesh nodes that move (or that the file marks as bodies).
    pub bodies: usize,
    /// Prototypes: distinct meshes and scales among the bodies.
    pub prototypes: usize,
    /// Mesh nodes that never move.
    pub static_meshes: usize,
    /// The last key time of the animations, in seconds.
    pub duration: f32,
}

/// Reads an animated `.glb` (or `.gltf` with embedded buffers) from memory, as an
/// `[animation]` scene would, and samples every body at `frames` frames of `fps`; `name`
/// names it in errors. Nothing is read from disk.
pub fn inspect_animated_slice(
    bytes: &[u8],
    name: &Path,
    fps: f64,
    frames: u32,
) -> Result<AnimationInventory, GltfError> {
    let file = AnimatedGltf::from_bytes(bytes, &Source { name, base: None }, None)?;
    let times: Vec<f32> = (0..frames).map(|i| frame_time(i, fps)).collect();
    let roles = file.roles(&times)?;
    for body in &roles.bodies {
        for &t in &times {
            std::hint::black_box(file.trs_at(body.node, t));
        }
    }
    Ok(AnimationInventory {
        bodies: roles.bodies.len(),
        prototypes: roles.prototypes.len(),
        static_meshes: roles.environment.len(),
        duration: file.duration(),
    })
}

/// An animated glTF file read and checked; see the module docs.
pub(crate) struct AnimatedGltf {
    pub(crate) path: PathBuf,
    pub(crate) document: gltf::Document,
    pub(crate) buffers: Vec<gltf::buffer::Data>,
    /// Per node (by index).
    motions: Vec<NodeMotion>,
    /// Per node: its parent in the default scene's tree.
    parents: Vec<Option<usize>>,
    /// The default scene's nodes, ascending.
    pub(crate) scene_nodes: Vec<usize>,
    pub(crate) extras: DormantExtras,
}

impl AnimatedGltf {
    /// Reads `path` with the animations that play (all, or the one named `only`).
    pub(crate) fn read(path: &Path, only: Option<&str>) -> Result<Self, GltfError> {
        let bytes = std::fs::read(path).map_err(|e| GltfError::new(path, "(file)", e.to_string()))?;
        Self::from_bytes(&bytes, &Source { name: path, base: path.parent() }, only)
    }

    fn from_bytes(bytes: &[u8], source: &Source, only: Option<&str>) -> Result<Self, GltfError> {
        let path = source.name;
        let (document, buffers) = read_document(bytes, source)?;
        let motions = channels::read_motions(path, &document, &buffers, only)?;
        let mut parents = vec![None; document.nodes().len()];
        for node in document.nodes() {
            for child in node.children() {
                parents[child.index()] = Some(node.index());
            }
        }
        let mut scene_nodes = Vec::new();
        walk_nodes(path, &document, &mut |node, _| {
            refuse_unsupported(path, node)?;
            scene_nodes.push(node.index());
            Ok(())
        })?;
        // The walk pops roots last first; bodies without ids are numbered in node order.
        scene_nodes.sort_unstable();
        let extras = DormantExtras::of(path, &document)?;
        Ok(Self { path: path.to_path_buf(), document, buffers, motions, parents, scene_nodes, extras })
    }

    /// The latest key time of the animations that play (0 without any).
    pub(crate) fn duration(&self) -> f32 {
        self.motions.iter().map(NodeMotion::end).fold(0.0, f32::max)
    }

    /// Whether node `n` or one of its ancestors is animated.
    pub(crate) fn moves(&self, n: usize) -> bool {
        self.chain(n).any(|a| self.motions[a].is_animated())
    }

    /// Node `n` and its ancestors, from `n` up.
    fn chain(&self, n: usize) -> impl Iterator<Item = usize> + '_ {
        std::iter::successors(Some(n), |&a| self.parents[a])
    }

    /// Node `n`'s world transform at time `t`.
    pub(crate) fn world_at(&self, n: usize, t: f32) -> Mat4 {
        let local = self.motions[n].matrix_at(t);
        match self.parents[n] {
            Some(p) => self.world_at(p, t) * local,
            None => local,
        }
    }

    /// Node `n`'s world translation, rotation and scale at time `t`. A root node's are its
    /// own channels' values as stored; a child's are decomposed from its world matrix.
    pub(crate) fn trs_at(&self, n: usize, t: f32) -> (Vec3, Quat, Vec3) {
        if self.parents[n].is_none() {
            return self.motions[n].trs_at(t);
        }
        let (scale, rotation, translation) = self.world_at(n, t).to_scale_rotation_translation();
        (translation, rotation, scale)
    }
}

impl AnimatedGltf {
    /// The punctual lights of the default scene (none of them moves: `roles` refuses that).
    pub(crate) fn static_lights(&self) -> Vec<Light> {
        let nodes: Vec<gltf::Node> = self.document.nodes().collect();
        let lit = self.scene_nodes.iter().filter_map(|&n| Some((n, nodes[n].light()?)));
        lit.map(|(n, light)| punctual_light(&light, &self.world_at(n, 0.0))).collect()
    }

    /// Node `n`'s perspective camera at time 0 (its lens; where it looks comes from
    /// [`Self::world_at`]).
    pub(crate) fn camera(&self, n: usize) -> Option<GltfCamera> {
        let node = self.document.nodes().nth(n)?;
        perspective_camera(&self.path, &node.camera()?, &self.world_at(n, 0.0))
    }
}

/// Refuses what the importer cannot render as it is meant: skinned meshes (animated morph
/// weights are refused with their channel).
fn refuse_unsupported(path: &Path, node: &gltf::Node) -> Result<(), GltfError> {
    if node.skin().is_some() {
        let element = format!("nodes[{}]", node.index());
        return Err(GltfError::new(path, element, "has a skin (skinned meshes are not supported)"));
    }
    Ok(())
}
