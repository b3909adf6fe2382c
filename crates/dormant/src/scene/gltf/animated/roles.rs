//! Which mesh nodes are environment and which are bodies, over the frames a scene samples:
//! a node whose world transform is the same matrix, bit for bit, at every sampled time is
//! environment (unless the file marks it as a body); any other mesh node is a body. A body's
//! prototype is its mesh at its scale (the first one it is seen at, quantized so that float
//! noise in a decomposed scale does not split one mesh into many prototypes).

use glam::{Mat4, Vec3};

use super::super::GltfError;
use super::extras::body_of;
use super::AnimatedGltf;

/// A body: its node, and its prototype (an index into [`Roles::prototypes`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct BodyNode {
    pub(crate) node: usize,
    pub(crate) prototype: u32,
    /// How far from its origin the body's mesh reaches (from its accessors' bounds, scaled).
    pub(crate) radius: f32,
}

/// A prototype: a mesh of the file scaled by `scale` (in the mesh's own axes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PrototypeKey {
    pub(crate) mesh: usize,
    pub(crate) scale: Vec3,
}

/// The default scene's mesh and camera nodes by role.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Roles {
    /// Static mesh nodes with their world transform (nodes scaled to nothing left out).
    pub(crate) environment: Vec<(usize, Mat4)>,
    /// By body id: the file's own (`dormant` extras) when it gives them, else scene order.
    pub(crate) bodies: Vec<BodyNode>,
    /// Ordered by mesh, then scale.
    pub(crate) prototypes: Vec<PrototypeKey>,
    /// The first node with a camera.
    pub(crate) camera: Option<usize>,
}

impl AnimatedGltf {
    /// The roles of the default scene's nodes over the sampled `times`.
    pub(crate) fn roles(&self, times: &[f32]) -> Result<Roles, GltfError> {
        let mut roles = Roles::default();
        let mut bodies: Vec<(Option<u32>, usize, PrototypeKey)> = Vec::new();
        let nodes: Vec<gltf::Node> = self.document.nodes().collect();
        for &n in &self.scene_nodes {
            let node = &nodes[n];
            self.refuse_animated_light(node)?;
            if node.camera().is_some() && roles.camera.is_none() {
                roles.camera = Some(n);
            }
            let Some(mesh) = node.mesh() else { continue };
            let id = body_of(&self.path, node)?;
            if id.is_none() && !self.changes(n, times) {
                let world = self.world_at(n, times.first().copied().unwrap_or(0.0));
                if world.determinant() != 0.0 {
                    roles.environment.push((n, world));
                }
                continue;
            }
            bodies.push((id, n, PrototypeKey { mesh: mesh.index(), scale: self.first_scale(n, times) }));
        }
        self.order_bodies(&mut bodies)?;
        roles.prototypes = bodies.iter().map(|b| b.2).collect();
        roles.prototypes.sort_by(|a, b| {
            (a.mesh, a.scale.to_array()).partial_cmp(&(b.mesh, b.scale.to_array())).expect("finite")
        });
        roles.prototypes.dedup();
        roles.bodies = bodies
            .iter()
            .map(|&(_, node, key)| BodyNode {
                node,
                prototype: roles.prototypes.iter().position(|p| *p == key).expect("listed") as u32,
                radius: reach(&nodes[node]) * key.scale.abs().max_element(),
            })
            .collect();
        Ok(roles)
    }

    /// Whether node `n`'s world transform differs at some sampled time from the first.
    fn changes(&self, n: usize, times: &[f32]) -> bool {
        if !self.moves(n) {
            return false;
        }
        let Some((&first, rest)) = times.split_first() else { return false };
        let at_first = self.world_at(n, first).to_cols_array().map(f32::to_bits);
        rest.iter().any(|&t| self.world_at(n, t).to_cols_array().map(f32::to_bits) != at_first)
    }

    /// Node `n`'s world scale at the first sampled time it is not scaled to nothing
    /// (quantized), or 1 if it never appears.
    fn first_scale(&self, n: usize, times: &[f32]) -> Vec3 {
        times
            .iter()
            .map(|&t| self.trs_at(n, t).2)
            .find(|s| s.is_finite() && s.x != 0.0 && s.y != 0.0 && s.z != 0.0)
            .map_or(Vec3::ONE, |s| Vec3::from_array(s.to_array().map(quantize)))
    }

    /// Puts bodies in body-id order when the file gives ids (all of them, each once, from 0),
    /// else leaves scene order.
    fn order_bodies(&self, bodies: &mut [(Option<u32>, usize, PrototypeKey)]) -> Result<(), GltfError> {
        if bodies.iter().all(|b| b.0.is_none()) {
            return Ok(());
        }
        bodies.sort_by_key(|b| b.0.unwrap_or(u32::MAX));
        for (i, &(id, node, _)) in bodies.iter().enumerate() {
            if id != Some(i as u32) {
                let message = match id {
                    None => "moves but has no dormant body id, while other nodes have one".to_string(),
                    Some(id) => format!("dormant body id {id} is repeated or leaves a gap (expected {i})"),
                };
                return Err(GltfError::new(&self.path, format!("nodes[{node}]"), message));
            }
        }
        Ok(())
    }

    /// Refuses a light whose node moves (animated lights are not supported).
    fn refuse_animated_light(&self, node: &gltf::Node) -> Result<(), GltfError> {
        if node.light().is_some() && self.moves(node.index()) {
            let element = format!("nodes[{}]", node.index());
            return Err(GltfError::new(&self.path, element, "is an animated light (not supported)"));
        }
        Ok(())
    }
}

/// How far from its node's origin a mesh node's primitives reach (their POSITION bounds).
fn reach(node: &gltf::Node) -> f32 {
    let far = |b: gltf::mesh::Bounds<[f32; 3]>| Vec3::from(b.min).abs().max(Vec3::from(b.max).abs()).length();
    node.mesh().map_or(0.0, |m| m.primitives().map(|p| far(p.bounding_box())).fold(0.0, f32::max))
}

/// `x` rounded to 16 significant bits (about 5 decimal digits).
fn quantize(x: f32) -> f32 {
    f32::from_bits((x.to_bits() + 0x40) & !0x7f)
}
