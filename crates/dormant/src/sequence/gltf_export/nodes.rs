//! Nodes: one per body (`body N`), the environment, the camera (`camera`, a perspective
//! camera looking down its -Z with +Y up) and the punctual lights (KHR_lights_punctual, the
//! sun a directional light). The importer takes cameras and lights from the recorded scene
//! TOML; these are for other tools (Blender).

use glam::{Mat3, Quat, Vec3};
use serde::Serialize;
use serde_json::{json, Value};

use super::animation::Pose;
use crate::scene::gltf::LUMENS_PER_WATT;
use crate::scene::{Camera, Light, Sun};

/// A node of the document: a body's (typed: a large export has tens of thousands) or
/// another as JSON.
#[derive(Debug, Serialize)]
#[serde(untagged)]
pub(super) enum Node {
    Body(BodyNode),
    Other(Value),
}

/// `{"name": "body N", "mesh": M, "extras": {"dormant": {"body": N}}}`.
#[derive(Debug, Serialize)]
pub(super) struct BodyNode {
    name: String,
    mesh: u32,
    extras: BodyExtras,
}

#[derive(Debug, Serialize)]
struct BodyExtras {
    dormant: BodyId,
}

#[derive(Debug, Serialize)]
struct BodyId {
    body: usize,
}

/// A body's node: its prototype's mesh, its id in the extras.
pub(super) fn body_node(body: usize, mesh: u32) -> Node {
    Node::Body(BodyNode {
        name: format!("body {body}"),
        mesh,
        extras: BodyExtras { dormant: BodyId { body } },
    })
}

/// The environment's node (identity transform).
pub(super) fn environment_node(mesh: usize) -> Value {
    json!({ "name": "environment", "mesh": mesh })
}

/// The camera node at `pose` (glTF camera 0).
pub(super) fn camera_node(pose: &Pose) -> Value {
    json!({ "name": "camera", "camera": 0, "translation": &pose[..3], "rotation": &pose[3..] })
}

/// glTF camera 0: `camera`'s vertical field of view, the render size's aspect ratio.
pub(super) fn perspective(camera: &Camera, (width, height): (u32, u32)) -> Value {
    let mut perspective = json!({ "yfov": camera.vfov_deg.to_radians(), "znear": 0.01f32 });
    if width > 0 && height > 0 {
        perspective["aspectRatio"] = json!(width as f32 / height as f32);
    }
    json!({ "name": "camera", "type": "perspective", "perspective": perspective })
}

/// The camera node's pose: at the eye, its -Z towards the target, +Y up (dormant's camera
/// basis, `render/camera.rs`).
pub(super) fn camera_pose(camera: &Camera) -> Pose {
    let forward = (camera.target - camera.eye).normalize_or(Vec3::NEG_Z);
    let right = forward.cross(camera.up).normalize_or(Vec3::X);
    let up = right.cross(forward);
    let q = Quat::from_mat3(&Mat3::from_cols(right, up, -forward)).normalize();
    let t = camera.eye;
    [t.x, t.y, t.z, q.x, q.y, q.z, q.w]
}

/// The rotation taking a light's -Z to `direction` (where its light travels).
fn towards(direction: Vec3) -> Quat {
    Quat::from_rotation_arc(Vec3::NEG_Z, direction.normalize_or(Vec3::NEG_Z))
}

/// glTF's `color` (peak 1) and `intensity` for an RGB power.
fn color_intensity(rgb: Vec3) -> (Vec3, f32) {
    let peak = rgb.max_element();
    if peak > 0.0 && peak.is_finite() {
        (rgb / peak, peak)
    } else {
        (Vec3::ONE, 0.0)
    }
}

/// The punctual lights (the sun first) as KHR_lights_punctual lights and their nodes.
pub(super) fn lights(sun: &Sun, lights: &[Light]) -> (Vec<Value>, Vec<Value>) {
    let sun_light = Light::Directional { direction: -sun.direction, irradiance: sun.irradiance };
    let (mut defs, mut nodes) = (Vec::new(), Vec::new());
    for (i, light) in std::iter::once(&sun_light).chain(lights).enumerate() {
        let name = if i == 0 { "sun".to_string() } else { format!("light {}", i - 1) };
        let (rgb, position, direction) = light_json(light);
        let (color, intensity) = color_intensity(rgb);
        // Photometric, as KHR_lights_punctual and Blender read it; the exact value in extras.
        let mut light_def = json!({
            "name": name,
            "color": color.to_array(),
            "intensity": intensity * LUMENS_PER_WATT,
            "extras": { "dormant": { "radiometric": rgb.to_array() } },
        });
        let mut node = json!({
            "name": name,
            "rotation": towards(direction).to_array(),
            "extensions": { "KHR_lights_punctual": { "light": i } },
        });
        match *light {
            Light::Point { .. } => light_def["type"] = json!("point"),
            Light::Directional { .. } => light_def["type"] = json!("directional"),
            Light::Spot { cos_inner, cos_outer, .. } => {
                let outer = cos_outer.clamp(-1.0, 1.0).acos().min(std::f32::consts::FRAC_PI_2);
                let inner = cos_inner.clamp(-1.0, 1.0).acos().min(outer);
                light_def["type"] = json!("spot");
                light_def["spot"] = json!({ "innerConeAngle": inner, "outerConeAngle": outer });
            }
        }
        if let Some(p) = position {
            node["translation"] = json!(p.to_array());
        }
        defs.push(light_def);
        nodes.push(node);
    }
    (defs, nodes)
}

/// A light's radiometric RGB, position (none for directional) and direction.
fn light_json(light: &Light) -> (Vec3, Option<Vec3>, Vec3) {
    match *light {
        Light::Point { position, intensity } => (intensity, Some(position), Vec3::NEG_Z),
        Light::Spot { position, direction, intensity, .. } => (intensity, Some(position), direction),
        Light::Directional { direction, irradiance } => (irradiance, None, direction),
    }
}

#[cfg(test)]
mod tests {
    use glam::{Quat, Vec3};

    use super::camera_pose;
    use crate::scene::Camera;

    #[test]
    fn the_camera_node_looks_down_its_minus_z_at_the_target() {
        let camera = Camera::pinhole(Vec3::new(0.0, 6.0, 12.0), Vec3::new(0.0, 0.5, 0.0), Vec3::Y, 40.0);
        let p = camera_pose(&camera);
        let q = Quat::from_xyzw(p[3], p[4], p[5], p[6]);
        let forward = (camera.target - camera.eye).normalize();
        assert!((q * Vec3::NEG_Z - forward).length() < 1e-5);
        assert!((q * Vec3::Y).dot(Vec3::Y) > 0.0);
        assert!((q * Vec3::X).y.abs() < 1e-5, "no roll");
    }
}
