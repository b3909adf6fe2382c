//! The render assets of an `[animation]` scene ([`SceneAssets::load`] comes here when the
//! scene file has `[animation]`): the static nodes merged into the environment, a prototype
//! per mesh and scale, the file's materials and textures loaded once; the scene file's camera
//! and lights, else the glTF file's (unless its `dormant` extras recorded a scene: then the
//! scene file is that one and has them exactly).

use std::sync::Arc;

use glam::{Mat4, Vec3};

use super::animated::{animation_error, AnimatedScene};
use super::assets::{file_lights, sky, sun, MeshSource, SceneAssets};
use super::file::{CameraDef, CameraKeyframeDef, CameraPlacement, SceneError, SceneFile};
use super::Material;

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
        let mut lights = file_lights(file);
        if scene.gltf.extras.scene.is_none() {
            lights.extend(scene.gltf.static_lights());
        }
        let source =
            MeshSource::animation(file.resolve(&file.spec().animation.as_ref().expect("animated").gltf));
        Ok(Self {
            name: file.spec().scene.name.clone(),
            camera: file.spec().render_camera().cloned().or_else(|| gltf_camera(scene)),
            sun: sun(file),
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
