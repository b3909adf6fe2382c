//! A scene file's render assets: [`SceneAssets`] loads its meshes, materials, textures,
//! camera and lights once, and describes the scene at any time without its bodies (which
//! come from a simulation: `sequence` places them).

use std::sync::Arc;

use glam::Vec3;

use super::animated::AnimatedScene;
use super::file::{
    environment_asset, prototype_asset, CameraDef, CameraPlacement, EnvironmentSource, LightDef, LightKind,
    SceneError, SceneFile, Shape, SkyDef,
};
use super::{Camera, Light, Material, Prototype, SceneDescription, Sky, StaticMesh, Sun, Texture};
use crate::geometry::TriangleMesh;

/// A scene file's meshes, loaded once: the environment and one mesh per prototype.
pub struct SceneAssets {
    pub name: String,
    pub environment: TriangleMesh,
    pub prototypes: Vec<(String, TriangleMesh)>,
    /// The glTF materials of the environment (first) and of every prototype; empty where the
    /// mesh has none, which then gets a grey (environment), or the file's or a palette colour
    /// (prototypes).
    pub(super) materials: Vec<Vec<Material>>,
    /// Each prototype's colour from the scene file, if it gives one.
    pub(super) colors: Vec<Option<[f32; 3]>>,
    pub(super) textures: Vec<Arc<Texture>>,
    /// Point, spot and extra directional lights: the scene file's and the environment glTF's.
    pub(super) lights: Vec<Light>,
    /// The scene's chosen camera (`render.camera`, else the first); `None`: frame the
    /// environment.
    pub(super) camera: Option<CameraDef>,
    pub(super) sun: Sun,
    pub(super) sky: Sky,
    /// Where the environment's mesh came from (first), then every prototype's.
    pub(crate) sources: Vec<MeshSource>,
}

/// Where a scene mesh came from and how it was placed: another renderer can load the same
/// file and get the same geometry (`dormant export`).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct MeshSource {
    /// The glTF file (resolved against the scene's asset directory), or `None` for a built-in
    /// shape or generator.
    pub gltf: Option<std::path::PathBuf>,
    /// The built-in shape or generator (e.g. `box`, `atrium`) when there is no glTF.
    pub(crate) builtin: Option<String>,
    /// Uniform scale applied to the file's coordinates (its default scene, node transforms
    /// baked in), then `offset` added.
    pub(crate) scale: f32,
    pub offset: [f32; 3],
}

impl MeshSource {
    /// The animated glTF file of an `[animation]` scene (its environment and every prototype
    /// come from it).
    pub(super) fn animation(gltf: std::path::PathBuf) -> Self {
        Self { gltf: Some(gltf), builtin: None, scale: 1.0, offset: [0.0; 3] }
    }

    fn environment(file: &SceneFile) -> Self {
        let env = &file.spec().environment;
        let (gltf, builtin) = match &env.source {
            EnvironmentSource::Gltf(path) => (Some(file.resolve(path)), None),
            EnvironmentSource::Generator(kind) => (None, Some(format!("{kind:?}").to_lowercase())),
            EnvironmentSource::Animation => (None, None),
        };
        Self { gltf, builtin, scale: env.scale, offset: env.offset }
    }

    fn prototype(file: &SceneFile, index: usize) -> Self {
        let shape = &file.spec().prototypes[index].shape;
        let (gltf, builtin, scale) = match shape {
            Shape::Gltf { path, scale, .. } => (Some(file.resolve(path)), None, *scale),
            Shape::Box { .. } => (None, Some("box".into()), 1.0),
            Shape::Sphere { .. } => (None, Some("sphere".into()), 1.0),
            Shape::Capsule { .. } => (None, Some("capsule".into()), 1.0),
            Shape::Cylinder { .. } => (None, Some("cylinder".into()), 1.0),
        };
        Self { gltf, builtin, scale, offset: [0.0; 3] }
    }
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
        if let Some(animated) = AnimatedScene::load(file)? {
            return Self::load_animated(file, &animated);
        }
        let doc = file.spec();
        let mut textures = Vec::new();
        let mut environment = environment_asset(file)?;
        let mut materials = vec![environment.take_materials(&mut textures)];
        let mut prototypes = Vec::with_capacity(doc.prototypes.len());
        for i in 0..doc.prototypes.len() {
            let mut asset = prototype_asset(file, i)?;
            materials.push(asset.take_materials(&mut textures));
            prototypes.push((doc.prototypes[i].name.clone(), asset.mesh));
        }
        let mut lights = file_lights(file);
        lights.append(&mut environment.lights);
        // The scene file's camera; without any, the environment glTF's first camera.
        let camera = doc.render_camera().cloned().or_else(|| {
            environment.cameras.first().map(|c| CameraDef {
                name: c.name.clone(),
                placement: CameraPlacement::Fixed {
                    position: c.position.to_array(),
                    look_at: (c.position + c.forward).to_array(),
                },
                fov_degrees: c.yfov_degrees,
                aperture_radius: 0.0,
                focus_distance: None,
            })
        });
        Ok(Self {
            name: doc.scene.name.clone(),
            camera,
            sun: sun(file),
            sky: sky(file),
            environment: environment.mesh,
            prototypes,
            materials,
            colors: doc.prototypes.iter().map(|p| p.color).collect(),
            textures,
            lights,
            sources: std::iter::once(MeshSource::environment(file))
                .chain((0..doc.prototypes.len()).map(|i| MeshSource::prototype(file, i)))
                .collect(),
        })
    }
}

/// The scene's camera at time `t` seconds (keyframes interpolated linearly), or a view of the
/// environment's bounds when the file has no camera.
fn camera_at(cam: Option<&CameraDef>, environment: &TriangleMesh, t: f32) -> Camera {
    let Some(cam) = cam else {
        let b = environment.bounds();
        let e = b.extent();
        return Camera::pinhole(
            b.center() + Vec3::new(0.6 * e.x, 0.5 * e.y.max(0.3 * e.x), 0.6 * e.z),
            b.center(),
            Vec3::Y,
            45.0,
        );
    };
    let (eye, target) = match &cam.placement {
        CameraPlacement::Keyframed(keyframes) => {
            let next = keyframes.iter().position(|k| k.time > t).unwrap_or(keyframes.len());
            if next == 0 {
                (keyframes[0].position, keyframes[0].look_at)
            } else if next == keyframes.len() {
                let last = keyframes[next - 1];
                (last.position, last.look_at)
            } else {
                let (a, b) = (keyframes[next - 1], keyframes[next]);
                let s = ((t - a.time) / (b.time - a.time).max(1e-6)).clamp(0.0, 1.0);
                let lerp = |p: [f32; 3], q: [f32; 3]| Vec3::from(p).lerp(Vec3::from(q), s).to_array();
                (lerp(a.position, b.position), lerp(a.look_at, b.look_at))
            }
        }
        CameraPlacement::Fixed { position, look_at } => (*position, *look_at),
    };
    Camera {
        aperture_radius: cam.aperture_radius,
        focus_distance: cam.focus_distance,
        ..Camera::pinhole(eye.into(), target.into(), Vec3::Y, cam.fov_degrees)
    }
}

/// The scene file's `[sky]`, or the daylight gradient.
pub(super) fn sky(file: &SceneFile) -> Sky {
    match file.spec().sky {
        None => Sky::DAYLIGHT,
        Some(SkyDef::Constant { color, intensity }) => Sky::constant(Vec3::from(color) * intensity),
        Some(SkyDef::Gradient { zenith, horizon, ground, intensity }) => {
            let rgb = |v: Option<[f32; 3]>, default: Vec3| v.map_or(default, Vec3::from) * intensity;
            Sky {
                zenith: rgb(zenith, Sky::DAYLIGHT.zenith),
                horizon: rgb(horizon, Sky::DAYLIGHT.horizon),
                ground: rgb(ground, Sky::DAYLIGHT.ground),
            }
        }
    }
}

/// The angular radius of a sun that gives none, in degrees.
pub(super) const DEFAULT_SUN_RADIUS_DEG: f32 = 1.0;

/// The first directional light as the sun (its `direction` is where light travels).
pub(super) fn sun(file: &SceneFile) -> Sun {
    let sun = file.spec().lights.iter().find_map(|l| match l.kind {
        LightKind::Directional { direction } => Some((l, direction)),
        _ => None,
    });
    match sun {
        Some((l, d)) => Sun {
            direction: (-Vec3::from(d)).normalize_or(Vec3::Y),
            irradiance: Vec3::from(l.color) * l.intensity,
            angular_radius_deg: DEFAULT_SUN_RADIUS_DEG,
        },
        None => Sun {
            direction: Vec3::new(-0.4, 0.85, 0.3).normalize(),
            irradiance: Vec3::splat(2.4),
            angular_radius_deg: DEFAULT_SUN_RADIUS_DEG,
        },
    }
}

/// The scene file's point and spot lights, and its directional lights after the first (which
/// is the sun).
pub(super) fn file_lights(file: &SceneFile) -> Vec<Light> {
    let color = |l: &LightDef| Vec3::from(l.color) * l.intensity;
    let direction = |d: [f32; 3]| Vec3::from(d).normalize_or(Vec3::NEG_Y);
    let mut suns = 0;
    let mut lights = Vec::new();
    for l in &file.spec().lights {
        match l.kind {
            LightKind::Directional { direction: d } => {
                suns += 1;
                if suns > 1 {
                    lights.push(Light::Directional { direction: direction(d), irradiance: color(l) });
                }
            }
            LightKind::Point { position } => {
                lights.push(Light::Point { position: position.into(), intensity: color(l) })
            }
            LightKind::Spot { position, direction: d, inner_cone_degrees, outer_cone_degrees } => {
                let outer = outer_cone_degrees.clamp(0.0, 90.0);
                let inner = inner_cone_degrees.clamp(0.0, outer);
                lights.push(Light::Spot {
                    position: position.into(),
                    direction: direction(d),
                    intensity: color(l),
                    cos_inner: inner.to_radians().cos(),
                    cos_outer: outer.to_radians().cos(),
                });
            }
        }
    }
    lights
}

/// Appends `own` (a mesh's glTF materials) to `materials`, or `fallback` when it has none;
/// returns the index of the first.
fn push_materials(materials: &mut Vec<Material>, own: &[Material], fallback: Material) -> u32 {
    let first = materials.len() as u32;
    if own.is_empty() {
        materials.push(fallback);
    } else {
        materials.extend_from_slice(own);
    }
    first
}

impl SceneAssets {
    /// The scene at `time` seconds without its bodies: environment, prototypes, materials,
    /// textures, camera and lights (the scene manager's template).
    pub fn describe(&self, time: f32) -> SceneDescription {
        let mut materials = Vec::new();
        let env_material = push_materials(&mut materials, &self.materials[0], self.fallback_material(0));
        let prototypes = self
            .prototypes
            .iter()
            .enumerate()
            .map(|(i, (name, mesh))| Prototype {
                name: name.clone(),
                mesh: mesh.clone(),
                material: push_materials(
                    &mut materials,
                    &self.materials[i + 1],
                    self.fallback_material(i + 1),
                ),
            })
            .collect();
        SceneDescription {
            name: self.name.clone(),
            materials,
            textures: self.textures.clone(),
            statics: vec![StaticMesh { mesh: self.environment.clone(), material: env_material }],
            prototypes,
            bodies: Vec::new(),
            camera: self.camera_at(time),
            sun: self.sun,
            sky: self.sky,
            lights: self.lights.clone(),
        }
    }

    /// The material of mesh `slot` (0 the environment, `i + 1` prototype `i`) when its file
    /// has none: grey for the environment, the file's or a palette colour for a prototype.
    fn fallback_material(&self, slot: usize) -> Material {
        match slot.checked_sub(1) {
            None => Material::diffuse(Vec3::splat(0.6)),
            Some(i) => Material::diffuse(self.colors[i].map_or(PALETTE[i % PALETTE.len()], Vec3::from)),
        }
    }

    /// The material every triangle of mesh `slot` (as [`Self::fallback_material`]) gets
    /// because its file has no materials; `None` when it has its own.
    pub(crate) fn material_without_file_materials(&self, slot: usize) -> Option<Material> {
        self.materials.get(slot).filter(|m| m.is_empty()).map(|_| self.fallback_material(slot))
    }

    /// The camera at `time` seconds.
    pub(crate) fn camera_at(&self, time: f32) -> Camera {
        camera_at(self.camera.as_ref(), &self.environment, time)
    }
}
