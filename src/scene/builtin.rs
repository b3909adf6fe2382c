//! The built-in default scene: a ground plane, a few boxes and spheres, a camera and a sun.
//! Boxes and spheres are instances of shared prototypes, so the default scene exercises
//! both levels of the accelerator.

use glam::{Affine3A, Quat, Vec3};

use super::description::{Body, Camera, Material, Prototype, SceneDescription, Sky, StaticMesh, Sun};
use crate::geometry::primitives;

pub fn default_scene() -> SceneDescription {
    let materials = vec![
        Material::diffuse(Vec3::new(0.55, 0.55, 0.52)),     // 0 ground
        Material::diffuse(Vec3::new(0.80, 0.25, 0.18)),     // 1 box red
        Material::diffuse(Vec3::new(0.20, 0.45, 0.80)),     // 2 sphere blue
        Material::diffuse(Vec3::new(0.85, 0.70, 0.25)),     // 3 plinth
        Material::metal(Vec3::new(0.95, 0.78, 0.45), 0.25), // 4 gold
    ];
    let statics = vec![
        StaticMesh { mesh: primitives::ground_plane(30.0, 0.0, 8), material: 0 },
        StaticMesh {
            mesh: {
                let m = primitives::cuboid(Vec3::new(1.5, 0.25, 1.5));
                m.transformed(&Affine3A::from_translation(Vec3::new(2.5, 0.25, -1.0)))
            },
            material: 3,
        },
    ];
    let prototypes = vec![
        Prototype { name: "box".into(), mesh: primitives::cuboid(Vec3::splat(0.5)), material: 1 },
        Prototype { name: "sphere".into(), mesh: primitives::uv_sphere(0.5, 48, 24), material: 2 },
        Prototype { name: "gold sphere".into(), mesh: primitives::uv_sphere(0.5, 48, 24), material: 4 },
    ];
    let boxes = [
        (Vec3::new(-2.2, 0.5, 0.0), 0.35, 1.0),
        (Vec3::new(-2.0, 1.5, 0.1), 1.1, 1.0),
        (Vec3::new(-0.6, 0.4, 1.6), 0.7, 0.8),
        (Vec3::new(2.5, 1.0, -1.0), 0.2, 1.0),
    ];
    // (centre, diameter, prototype)
    let spheres = [
        (Vec3::new(0.2, 0.7, -0.3), 1.4, 2),
        (Vec3::new(1.6, 0.45, 1.4), 0.9, 1),
        (Vec3::new(-3.6, 0.4, 1.8), 0.8, 1),
    ];
    let mut bodies: Vec<Body> = boxes
        .iter()
        .map(|&(at, yaw, size)| Body {
            prototype: 0,
            transform: Affine3A::from_scale_rotation_translation(
                Vec3::splat(size),
                Quat::from_rotation_y(yaw),
                at,
            ),
        })
        .collect();
    bodies.extend(spheres.iter().map(|&(at, size, prototype)| Body {
        prototype,
        transform: Affine3A::from_scale_rotation_translation(Vec3::splat(size), Quat::IDENTITY, at),
    }));
    SceneDescription {
        name: "default".into(),
        materials,
        textures: Vec::new(),
        statics,
        prototypes,
        bodies,
        camera: Camera::pinhole(Vec3::new(-1.5, 3.2, 8.5), Vec3::new(0.0, 0.6, 0.0), Vec3::Y, 40.0),
        sun: Sun {
            direction: Vec3::new(-0.5, 0.8, 0.35).normalize(),
            irradiance: Vec3::new(2.4, 2.25, 2.0),
            angular_radius_deg: 2.0,
        },
        sky: Sky::DAYLIGHT,
        lights: Vec::new(),
    }
}
