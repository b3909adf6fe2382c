use glam::{Vec3, Vec3A};

use crate::geometry::TriangleMesh;
use crate::physics::{BodyInfo, BodyPose, BodyState};
use crate::scene::file::{environment_mesh, prototype_mesh, CameraDef, LightKind, SceneError, SceneFile};
use crate::scene::{Body, Camera, Material, Prototype, SceneDescription, Sky, StaticMesh, Sun};

/// A scene file's meshes, loaded once: the environment and one mesh per prototype.
pub struct SceneAssets {
    pub name: String,
    pub environment: TriangleMesh,
    pub prototypes: Vec<(String, TriangleMesh)>,
    /// The scene's chosen camera (`render.camera`, else the first); `None`: frame the
    /// environment.
    camera: Option<CameraDef>,
    sun: Sun,
}

/// Distinct, muted colours for prototypes, by index.
const PALETTE: [Vec3; 6] = [
    Vec3::new(0.80, 0.25, 0.18),
    Vec3::new(0.20, 0.45, 0.80),
    Vec3::new(0.85, 0.70, 0.25),
    Vec3::new(0.30, 0.65, 0.35),
    Vec3::new(0.60, 0.35, 0.70),
    Vec3::new(0.85, 0.50, 0.20),
];

impl SceneAssets {
    pub fn load(file: &SceneFile) -> Result<Self, SceneError> {
        let doc = &file.description;
        let prototypes = (0..doc.prototypes.len())
            .map(|i| Ok((doc.prototypes[i].name.clone(), prototype_mesh(file, i)?)))
            .collect::<Result<Vec<_>, SceneError>>()?;
        let camera = doc
            .render
            .camera
            .as_ref()
            .and_then(|name| doc.cameras.iter().find(|c| &c.name == name))
            .or(doc.cameras.first())
            .cloned();
        Ok(Self {
            name: doc.scene.name.clone(),
            camera,
            sun: sun(file),
            environment: environment_mesh(file)?,
            prototypes,
        })
    }
}

/// The scene's camera at time `t` seconds (keyframes interpolated linearly), or a view of the
/// environment's bounds when the file has no camera.
fn camera_at(cam: Option<&CameraDef>, environment: &TriangleMesh, t: f32) -> Camera {
    let Some(cam) = cam else {
        let b = environment.bounds();
        let e = b.extent();
        return Camera {
            eye: b.center() + Vec3::new(0.6 * e.x, 0.5 * e.y.max(0.3 * e.x), 0.6 * e.z),
            target: b.center(),
            up: Vec3::Y,
            vfov_deg: 45.0,
        };
    };
    let (eye, target) = match (cam.position, cam.look_at, cam.keyframes.as_slice()) {
        (_, _, [first, ..]) => {
            let next = cam.keyframes.iter().position(|k| k.time > t).unwrap_or(cam.keyframes.len());
            if next == 0 {
                (first.position, first.look_at)
            } else if next == cam.keyframes.len() {
                let last = cam.keyframes[next - 1];
                (last.position, last.look_at)
            } else {
                let (a, b) = (cam.keyframes[next - 1], cam.keyframes[next]);
                let s = ((t - a.time) / (b.time - a.time).max(1e-6)).clamp(0.0, 1.0);
                let lerp = |p: [f32; 3], q: [f32; 3]| Vec3::from(p).lerp(Vec3::from(q), s).to_array();
                (lerp(a.position, b.position), lerp(a.look_at, b.look_at))
            }
        }
        (Some(p), Some(l), []) => (p, l),
        _ => ([0.0, 5.0, 10.0], [0.0; 3]),
    };
    Camera { eye: eye.into(), target: target.into(), up: Vec3::Y, vfov_deg: cam.fov_degrees }
}

/// The first directional light as the sun (its `direction` is where light travels).
fn sun(file: &SceneFile) -> Sun {
    let light = file.description.lights.iter().find(|l| l.kind == LightKind::Directional);
    match light.and_then(|l| l.direction.map(|d| (l, d))) {
        Some((l, d)) => Sun {
            direction: (-Vec3::from(d)).normalize_or(Vec3::Y),
            irradiance: Vec3::from(l.color) * l.intensity,
            angular_radius_deg: 1.0,
        },
        None => Sun {
            direction: Vec3::new(-0.4, 0.85, 0.3).normalize(),
            irradiance: Vec3::splat(2.4),
            angular_radius_deg: 1.0,
        },
    }
}

impl SceneAssets {
    /// The camera at `time` seconds.
    pub fn camera_at(&self, time: f32) -> Camera {
        camera_at(self.camera.as_ref(), &self.environment, time)
    }
}

/// One frame, at `time` seconds, as a render description: the environment as the only static
/// mesh, every body that is present (awake or asleep) as an instance of its prototype at its
/// pose, and the camera where its keyframes put it.
pub fn describe_frame(
    assets: &SceneAssets,
    time: f32,
    bodies: &[BodyInfo],
    states: &[BodyState],
    poses: &[BodyPose],
) -> SceneDescription {
    debug_assert_eq!(bodies.len(), states.len());
    SceneDescription {
        bodies: bodies
            .iter()
            .zip(states)
            .zip(poses)
            .filter(|((_, state), pose)| {
                **state != BodyState::Absent && Vec3A::from(pose.translation).is_finite()
            })
            .map(|((info, _), pose)| Body { prototype: info.prototype, transform: pose.to_affine() })
            .collect(),
        ..describe_scene(assets, time)
    }
}

/// The scene at `time` seconds without its bodies: environment, prototypes, materials,
/// camera and lights (the scene manager's template).
pub fn describe_scene(assets: &SceneAssets, time: f32) -> SceneDescription {
    let mut materials = vec![Material::diffuse(Vec3::splat(0.6))];
    materials.extend((0..assets.prototypes.len()).map(|i| Material::diffuse(PALETTE[i % PALETTE.len()])));
    SceneDescription {
        name: assets.name.clone(),
        materials,
        statics: vec![StaticMesh { mesh: assets.environment.clone(), material: 0 }],
        prototypes: assets
            .prototypes
            .iter()
            .enumerate()
            .map(|(i, (name, mesh))| Prototype {
                name: name.clone(),
                mesh: mesh.clone(),
                material: i as u32 + 1,
            })
            .collect(),
        bodies: Vec::new(),
        camera: camera_at(assets.camera.as_ref(), &assets.environment, time),
        sun: assets.sun,
        sky: Sky::DAYLIGHT,
    }
}
