use glam::{Affine3A, Vec3};

use crate::geometry::TriangleMesh;

/// A glTF metallic-roughness material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Linear RGB reflectance.
    pub base_color: Vec3,
    pub roughness: f32,
    pub metallic: f32,
    /// Strength of the dielectric specular layer (KHR_materials_specular's `specularFactor`):
    /// 1 is glTF's default F0 of 0.04, 0 leaves a pure Lambertian surface.
    pub specular: f32,
}

impl Material {
    /// A rough dielectric, as glTF's default material with this base colour.
    pub fn diffuse(base_color: Vec3) -> Self {
        Self { base_color, roughness: 1.0, metallic: 0.0, specular: 1.0 }
    }

    /// A metal with the given colour and roughness.
    pub fn metal(base_color: Vec3, roughness: f32) -> Self {
        Self { base_color, roughness, metallic: 1.0, specular: 1.0 }
    }

    /// A pure Lambertian reflector (no specular layer): analytic tests and furnaces.
    pub fn lambertian(albedo: Vec3) -> Self {
        Self { base_color: albedo, roughness: 1.0, metallic: 0.0, specular: 0.0 }
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
    /// A clear daylight sky.
    pub const DAYLIGHT: Sky = Sky {
        zenith: Vec3::new(0.25, 0.45, 0.85),
        horizon: Vec3::new(0.75, 0.82, 0.90),
        ground: Vec3::new(0.25, 0.23, 0.21),
    };

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
