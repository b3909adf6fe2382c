//! Benchmark scenes from real assets: a static environment glTF with a heap of instanced
//! objects on its floor. The heap is laid out procedurally (a stepped pyramid of non-touching
//! objects with random yaw), not simulated: it gives the accelerators the same load a settled
//! pile does without needing physics.

use std::path::Path;

use glam::{Affine3A, Quat, Vec3};

use std::sync::Arc;

use super::description::{Body, Camera, Material, Prototype, SceneDescription, Sky, StaticMesh, Sun};
use super::gltf::{load_gltf, GltfAsset, GltfError};
use super::texture::Texture;
use crate::rng::SplitMix64;

/// A heap of `count` copies of the `object` glTF in the middle of the `env` glTF's floor.
/// Both keep their glTF materials and textures (grey and ochre when a file has none); the
/// environment's punctual lights are kept too.
pub fn asset_pile(env: &Path, object: &Path, count: usize, seed: u64) -> Result<SceneDescription, GltfError> {
    let mut env_asset = load_gltf(env)?;
    let mut object_asset = load_gltf(object)?;
    let mut textures = Vec::new();
    let (materials, object_material) = pile_materials(&mut env_asset, &mut object_asset, &mut textures);
    let env_mesh = env_asset.mesh;
    let object_mesh = object_asset.mesh;
    let env_bounds = env_mesh.bounds();
    let obj_bounds = object_mesh.bounds();
    let size = obj_bounds.extent().max_element().max(1e-6);
    // Scale objects to about 1/60 of the environment's width, like ducks in a monastery.
    let scale = (env_bounds.extent().x.max(env_bounds.extent().z) / 60.0) / size;
    let spacing = size * scale * 1.05;
    let floor = env_bounds.min.y;
    let centre = env_bounds.center();

    let base = pyramid_base(count);
    let bottom = Vec3::new(centre.x, floor, centre.z);
    // Re-centre the object on its bounds, then scale, turn and place it.
    let recentre = Affine3A::from_translation(-obj_bounds.center());
    let place =
        |(at, turn)| Affine3A::from_scale_rotation_translation(Vec3::splat(scale), turn, at) * recentre;
    let bodies = pyramid(count, base, spacing, bottom, seed)
        .map(|p| Body { prototype: 0, transform: place(p) })
        .collect();

    let extent = env_bounds.extent();
    let name = |p: &Path| p.file_stem().map_or_else(|| "asset".into(), |s| s.to_string_lossy().into_owned());
    Ok(SceneDescription {
        name: format!("{} + {count} {}", name(env), name(object)),
        materials,
        textures,
        statics: vec![StaticMesh { mesh: env_mesh, material: 0 }],
        prototypes: vec![Prototype { name: name(object), mesh: object_mesh, material: object_material }],
        bodies,
        camera: Camera::pinhole(
            centre + Vec3::new(0.35 * extent.x, 0.6 * extent.y.max(0.2 * extent.x), 0.35 * extent.z),
            Vec3::new(centre.x, floor + base as f32 * spacing * 0.3, centre.z),
            Vec3::Y,
            50.0,
        ),
        sun: Sun {
            direction: Vec3::new(-0.4, 0.85, 0.3).normalize(),
            irradiance: Vec3::new(3.0, 2.8, 2.5),
            angular_radius_deg: 1.5,
        },
        sky: Sky::DAYLIGHT,
        lights: env_asset.lights,
    })
}

/// Smallest base side whose pyramid of square layers holds `count` objects.
fn pyramid_base(count: usize) -> usize {
    let mut base = 1usize;
    while (1..=base).map(|n| n * n).sum::<usize>() < count {
        base += 1;
    }
    base
}

/// `count` places in a pyramid of square layers, `spacing` apart, on a base of `base` x `base`
/// centred on `bottom`, bottom layer first, each with a random turn about the vertical.
fn pyramid(
    count: usize,
    base: usize,
    spacing: f32,
    bottom: Vec3,
    seed: u64,
) -> impl Iterator<Item = (Vec3, Quat)> {
    let mut rng = SplitMix64::new(seed);
    (0..base)
        .flat_map(move |layer| {
            let side = base - layer;
            let half = (side as f32 - 1.0) * 0.5;
            (0..side * side).map(move |k| {
                let (i, j) = (k / side, k % side);
                let offset = Vec3::new(i as f32 - half, layer as f32 + 0.5, j as f32 - half);
                bottom + offset * spacing
            })
        })
        .take(count)
        .map(move |at| (at, Quat::from_rotation_y(rng.unit() * std::f32::consts::TAU)))
}

/// The environment's materials (grey when it has none), then the object's (ochre when it has
/// none), their textures moved to `textures`; and the index of the object's first material.
fn pile_materials(
    env: &mut GltfAsset,
    object: &mut GltfAsset,
    textures: &mut Vec<Arc<Texture>>,
) -> (Vec<Material>, u32) {
    let mut materials = env.take_materials(textures);
    if materials.is_empty() {
        materials.push(Material::diffuse(Vec3::splat(0.6)));
    }
    let object_material = materials.len() as u32;
    let object_materials = object.take_materials(textures);
    if object_materials.is_empty() {
        materials.push(Material::diffuse(Vec3::new(0.8, 0.65, 0.2)));
    } else {
        materials.extend(object_materials);
    }
    (materials, object_material)
}
