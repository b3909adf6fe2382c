//! The node walk: the default scene's (or every root's) nodes with their world transforms,
//! and what a node carries besides meshes: perspective cameras and KHR_lights_punctual lights.

use std::path::Path;

use glam::{Mat4, Vec3};

use super::{GltfCamera, GltfError};
use crate::scene::Light;

/// Calls `visit` with every node of the default scene (else the first scene, else every node
/// that is no other node's child) and its world transform, depth first; stops at the first
/// error, `visit`'s or a node reached twice (a cycle, or a node with two parents), a hierarchy
/// deeper than 256 or a non-finite transform.
pub(super) fn walk_nodes<'d>(
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
pub(super) fn perspective_camera(path: &Path, camera: &gltf::Camera, world: &Mat4) -> Option<GltfCamera> {
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

pub(super) fn punctual_light(light: &gltf::khr_lights_punctual::Light, world: &Mat4) -> Light {
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
