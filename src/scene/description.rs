use glam::{Affine3A, Vec3};

use crate::geometry::TriangleMesh;

/// A simple metallic-roughness material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Linear RGB reflectance.
    pub base_color: Vec3,
    pub roughness: f32,
    pub metallic: f32,
}

impl Material {
    pub fn diffuse(base_color: Vec3) -> Self {
        Self { base_color, roughness: 1.0, metallic: 0.0 }
    }
}

/// A world-space mesh that never moves (environment).
#[derive(Clone, Debug, PartialEq)]
pub struct StaticMesh {
    pub mesh: TriangleMesh,
    /// Index into [`SceneDescription::materials`].
    pub material: u32,
}

/// A mesh in object space shared by every body that uses it.
#[derive(Clone, Debug, PartialEq)]
pub struct Prototype {
    pub name: String,
    pub mesh: TriangleMesh,
    pub material: u32,
}

/// A body: a prototype placed in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Body {
    /// Index into [`SceneDescription::prototypes`].
    pub prototype: u32,
    pub transform: Affine3A,
}

/// Pinhole camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub eye: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub vfov_deg: f32,
}

/// A directional light with a finite angular size, for soft shadows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sun {
    /// Unit direction from the scene towards the sun.
    pub direction: Vec3,
    /// Linear RGB irradiance on a surface facing the sun.
    pub irradiance: Vec3,
    /// Angular radius of the sun's disc, in degrees.
    pub angular_radius_deg: f32,
}

/// A sky whose radiance blends from `horizon` to `zenith` with elevation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sky {
    pub zenith: Vec3,
    pub horizon: Vec3,
    pub ground: Vec3,
}

impl Sky {
    /// Radiance arriving from unit direction `dir`.
    pub fn radiance(&self, dir: Vec3) -> Vec3 {
        let y = dir.y;
        if y >= 0.0 {
            self.horizon.lerp(self.zenith, y.sqrt())
        } else {
            self.horizon.lerp(self.ground, (-y).sqrt().min(1.0))
        }
    }
}

/// Everything needed to render one frame of a scene.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneDescription {
    pub name: String,
    pub materials: Vec<Material>,
    pub statics: Vec<StaticMesh>,
    pub prototypes: Vec<Prototype>,
    pub bodies: Vec<Body>,
    pub camera: Camera,
    pub sun: Sun,
    pub sky: Sky,
}
