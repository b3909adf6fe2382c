//! The render assets of an `[animation]` scene ([`SceneAssets::load`] comes here when the
//! scene file has `[animation]`): the static nodes merged into the environment, a prototype
//! per mesh and scale, the file's materials and textures loaded once; the scene file's camera,
//! else the glTF file's; its lights and the glTF file's, or, with none in the scene file, the
//! glTF file's first directional light as the sun (unless its `dormant` extras recorded a
//! scene: then the scene file is that one and has them exactly).

use std::path::Path;
use std::sync::Arc;

use glam::{Mat4, Vec3};

use super::animated::{animation_error, AnimatedScene};
use super::assets::{file_lights, sky, sun, MeshSource, SceneAssets, DEFAULT_SUN_RADIUS_DEG};
use super::builtin::builtin_sun;
use super::file::{CameraDef, CameraKeyframeDef, CameraPlacement, SceneError, SceneFile};
use super::{Light, Material, Sun};

impl SceneAssets {
    /// The assets of an `[animation]` scene: the static nodes merged into the environment, a
    /// prototype per mesh and scale, the file's materials once; the scene file's camera and
    /// lights, else the glTF file's (when its extras hold no scene of dormant's).
    pub(super) fn load_animated(file: &SceneFile, scene: &AnimatedScene) -> Result<Self, SceneError> {
        let asset_error = |source| animation_error(file, source);
        let (file_materials, textures) = scene.gltf.materials();
        let pick = |used: &[u32]| used.iter().map(|&i| file_materials[i as usize]).collect::<Vec<Material>>();
        let roles = &scene.roles;
        let parts: Vec<(usize, Mat4)> =
            roles.environment.iter().map(|&(n, xf)| (mesh_of(scene, n), xf)).collect();
        let environment = scene.gltf.gather(&parts).map_err(asset_error)?;
        let mut materials = vec![pick(&environment.materials)];
        let mut prototypes = Vec::with_capacity(roles.prototypes.len());
        for key in &roles.prototypes {
            let gathered =
                scene.gltf.gather(&[(key.mesh, Mat4::from_scale(key.scale))]).map_err(asset_error)?;
            materials.push(pick(&gathered.materials));
            prototypes.push((scene.prototype_name(key.mesh, key.scale), gathered.mesh));
        }
        let gltf_path = file.resolve(&file.spec().animation.as_ref().expect("animated").gltf);
        let (sun, lights) = sun_and_lights(file, scene, &gltf_path);
        let source = MeshSource::animation(gltf_path);
        Ok(Self {
            name: file.spec().scene.name.clone(),
            camera: file.spec().render_camera().cloned().or_else(|| gltf_camera(scene)),
            sun,
            sky: sky(file),
            environment: environment.mesh,
            colors: vec![None; prototypes.len()],
            sources: vec![source; prototypes.len() + 1],
            prototypes,
            materials,
            textures: textures.into_iter().map(Arc::new).collect(),
            lights,
        })
    }
}

/// The sun and the other lights. Where the glTF file's extras recorded dormant's scene, the
/// scene file is that scene and has them exactly; where the scene file has lights, those and
/// the glTF file's. Otherwise the glTF file's (a Blender bake's): its first directional light
/// is the sun (none without one); with no light at all, the built-in scene's sun, said in one
/// line (the sky is the scene file's, by default the built-in scene's daylight).
fn sun_and_lights(file: &SceneFile, scene: &AnimatedScene, gltf_path: &Path) -> (Sun, Vec<Light>) {
    if scene.gltf.extras.scene.is_some() {
        return (sun(file), file_lights(file));
    }
    let mut lights = scene.gltf.static_lights();
    if !file.spec().lights.is_empty() {
        let mut own = file_lights(file);
        own.append(&mut lights);
        return (sun(file), own);
    }
    if lights.is_empty() {
        tracing::warn!(
            "{}: no lights in the file: lit by the built-in scene's sun and the scene's sky (a scene file's [[lights]] replace them)",
            gltf_path.display()
        );
        return (builtin_sun(), lights);
    }
    let first = lights.iter().position(|l| matches!(l, Light::Directional { .. }));
    let sun = match first.map(|i| lights.remove(i)) {
        Some(Light::Directional { direction, irradiance }) => {
            Sun { direction: -direction, irradiance, angular_radius_deg: DEFAULT_SUN_RADIUS_DEG }
        }
        _ => Sun { direction: Vec3::Y, irradiance: Vec3::ZERO, angular_radius_deg: DEFAULT_SUN_RADIUS_DEG },
    };
    (sun, lights)
}

fn mesh_of(scene: &AnimatedScene, node: usize) -> usize {
    scene.gltf.document.nodes().nth(node).and_then(|n| n.mesh()).map_or(0, |m| m.index())
}

/// The file's first camera, fixed or following its node frame by frame.
fn gltf_camera(scene: &AnimatedScene) -> Option<CameraDef> {
    let node = scene.roles.camera?;
    let camera = scene.gltf.camera(node)?;
    let key = |index: u32| {
        let world = scene.gltf.world_at(node, scene.time(index));
        let position = world.transform_point3(Vec3::ZERO);
        let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or(Vec3::NEG_Z);
        CameraKeyframeDef {
            time: index as f32 * scene.timestep(),
            position: position.to_array(),
            look_at: (position + forward).to_array(),
        }
    };
    let placement = if scene.gltf.moves(node) {
        CameraPlacement::Keyframed((0..scene.frames).map(key).collect())
    } else {
        let k = key(0);
        CameraPlacement::Fixed { position: k.position, look_at: k.look_at }
    };
    Some(CameraDef {
        name: camera.name,
        placement,
        fov_degrees: camera.yfov_degrees,
        aperture_radius: 0.0,
        focus_distance: None,
    })
}
