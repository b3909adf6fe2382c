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

/// Lumens per watt by which KHR_lights_punctual's photometric intensities (lux for
/// directional lights, candela for point and spot lights) become dormant's radiometric ones
/// (irradiance in W/m², radiant intensity in W/sr): the constant Blender's glTF importer and
/// exporter use by default (their "Standard" lighting mode), so that a Blender scene's lights
/// come back at the strength they had in Cycles (a sun of strength 3 is written as 2049 lux).
pub(crate) const LUMENS_PER_WATT: f32 = 683.0;

/// A light's own extras, written by dormant's glTF export: its radiometric RGB exactly
/// (`{"dormant": {"radiometric": [r, g, b]}}`), which dividing the photometric value by
/// [`LUMENS_PER_WATT`] would only approximate.
#[derive(serde::Deserialize)]
struct LightExtras {
    dormant: OwnLight,
}

#[derive(serde::Deserialize)]
struct OwnLight {
    radiometric: [f32; 3],
}

/// A light's radiometric RGB: its extras' exact value where dormant wrote one, else its
/// colour times its photometric intensity over [`LUMENS_PER_WATT`].
fn radiometric(light: &gltf::khr_lights_punctual::Light) -> Vec3 {
    let own = light.extras().as_ref().and_then(|raw| serde_json::from_str::<LightExtras>(raw.get()).ok());
    match own {
        Some(e) if e.dormant.radiometric.iter().all(|c| c.is_finite() && *c >= 0.0) => {
            Vec3::from_array(e.dormant.radiometric)
        }
        _ => Vec3::from_array(light.color()) * (light.intensity().max(0.0) / LUMENS_PER_WATT),
    }
}

pub(super) fn punctual_light(light: &gltf::khr_lights_punctual::Light, world: &Mat4) -> Light {
    use gltf::khr_lights_punctual::Kind;
    let intensity = radiometric(light);
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
