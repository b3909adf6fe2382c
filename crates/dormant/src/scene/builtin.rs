//! The built-in default scene: a tiled ground plane, a few boxes and spheres, a camera and a
//! sun, with procedurally generated textures (floor tiles, checkered boxes). Boxes and spheres
//! are instances of shared prototypes, so the default scene exercises both levels of the
//! accelerator.

use std::sync::Arc;

use glam::{Affine3A, Quat, Vec3};

use super::description::{Body, Camera, Material, Prototype, SceneDescription, Sky, StaticMesh, Sun};
use super::texture::{Texture, Wrap};
use crate::geometry::primitives;

/// Ground texture repeats across the plane (one repeat holds 2 x 2 tiles of 1 m).
const GROUND_REPEATS: f32 = 30.0;

/// A `size x size` texture whose texel at (x, y) is `texel(x, y)` (sRGB bytes), repeating.
fn procedural(name: &str, size: u32, texel: impl Fn(u32, u32) -> [u8; 3]) -> Arc<Texture> {
    let texels = (0..size)
        .flat_map(|y| (0..size).map(move |x| (x, y)))
        .map(|(x, y)| {
            let [r, g, b] = texel(x, y);
            [r, g, b, 255]
        })
        .collect();
    Arc::new(Texture {
        name: format!("builtin: {name}"),
        width: size,
        height: size,
        texels,
        wrap_s: Wrap::Repeat,
        wrap_t: Wrap::Repeat,
    })
}

/// Floor tiles: 2 x 2 stone tiles of two shades with darker grout lines between them.
fn floor_tiles() -> Arc<Texture> {
    const N: u32 = 128;
    procedural("floor tiles", N, |x, y| {
        let half = N / 2;
        let (tx, ty) = (x % half, y % half);
        let grout = 2;
        if tx < grout || ty < grout {
            return [92, 88, 82];
        }
        // A faint diagonal grain so tiles do not look perfectly flat.
        let grain = ((x * 7 + y * 3) % 11) as u8;
        if (x / half + y / half) % 2 == 0 {
            [196 + grain, 190 + grain, 178 + grain]
        } else {
            [158 + grain, 150 + grain, 138 + grain]
        }
    })
}

/// A checkerboard of `cells x cells` squares in two colours, for box faces.
fn checker(name: &str, cells: u32, a: [u8; 3], b: [u8; 3]) -> Arc<Texture> {
    const N: u32 = 64;
    let cell = N / cells;
    procedural(name, N, move |x, y| if (x / cell + y / cell) % 2 == 0 { a } else { b })
}

pub fn default_scene() -> SceneDescription {
    let textures = vec![
        floor_tiles(),                                             // 0
        checker("box checker", 4, [214, 84, 60], [240, 226, 200]), // 1
    ];
    // Base colours multiply their textures (white: the texture as authored).
    let materials = vec![
        Material { base_color_texture: Some(0), ..Material::diffuse(Vec3::ONE) }, // 0 ground
        Material { base_color_texture: Some(1), ..Material::diffuse(Vec3::ONE) }, // 1 box
        Material::diffuse(Vec3::new(0.20, 0.45, 0.80)),                           // 2 sphere blue
        Material::diffuse(Vec3::new(0.85, 0.70, 0.25)),                           // 3 plinth
        Material::metal(Vec3::new(0.95, 0.78, 0.45), 0.25),                       // 4 gold
    ];
    let statics = vec![
        StaticMesh {
            mesh: {
                let mut m = primitives::ground_plane(30.0, 0.0, 8);
                if let Some(uvs) = m.uvs.as_mut() {
                    uvs.iter_mut().for_each(|uv| *uv *= GROUND_REPEATS);
                }
                m
            },
            material: 0,
        },
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
    SceneDescription {
        name: "default".into(),
        materials,
        textures,
        statics,
        prototypes,
        bodies: default_bodies(),
        camera: Camera::pinhole(Vec3::new(-1.5, 3.2, 8.5), Vec3::new(0.0, 0.6, 0.0), Vec3::Y, 40.0),
        sun: builtin_sun(),
        sky: Sky::DAYLIGHT,
        lights: Vec::new(),
    }
}

/// The default scene's sun, which also lights a glTF file that brings no light of its own.
pub(crate) fn builtin_sun() -> Sun {
    Sun {
        direction: Vec3::new(-0.5, 0.8, 0.35).normalize(),
        irradiance: Vec3::new(2.4, 2.25, 2.0),
        angular_radius_deg: 2.0,
    }
}

/// The default scene's bodies: four checkered boxes (two stacked, one on the plinth), a gold
/// sphere and two blue ones.
fn default_bodies() -> Vec<Body> {
    // (centre, yaw, size)
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
    bodies
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn textures_are_consistent_and_referenced_by_textured_meshes() {
        let scene = default_scene();
        assert!(scene.textures.iter().all(|t| t.is_consistent()));
        for m in &scene.materials {
            assert!(m.textures().all(|t| (t as usize) < scene.textures.len()));
        }
        let textured = |material: u32| scene.materials[material as usize].base_color_texture.is_some();
        for s in scene.statics.iter().filter(|s| textured(s.material)) {
            assert!(s.mesh.uvs.is_some());
        }
        for p in scene.prototypes.iter().filter(|p| textured(p.material)) {
            assert!(p.mesh.uvs.is_some());
        }
        assert!(scene.textures.len() >= 2);
    }
}
