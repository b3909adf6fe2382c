//! The plain data of a scene description: materials, meshes placed as statics or prototype
//! instances, camera, sun, sky and punctual lights.

use std::sync::Arc;

use glam::{Affine3A, Vec3};

use crate::geometry::TriangleMesh;
use crate::scene::texture::Texture;

/// A glTF metallic-roughness material. Texture slots index [`SceneDescription::textures`];
/// a texture multiplies its factor (base colour and emission are sRGB-encoded, metallic and
/// roughness come from the B and G channels of a linear texture, as in glTF).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Linear RGB reflectance.
    pub base_color: Vec3,
    pub roughness: f32,
    pub metallic: f32,
    /// Strength of the dielectric specular layer (KHR_materials_specular's `specularFactor`):
    /// 1 is glTF's default F0 of 0.04, 0 leaves a pure Lambertian surface.
    pub specular: f32,
    /// Linear RGB radiance emitted from the front and back (glTF's `emissiveFactor` times
    /// KHR_materials_emissive_strength).
    pub emissive: Vec3,
    pub base_color_texture: Option<u32>,
    pub metallic_roughness_texture: Option<u32>,
    pub emissive_texture: Option<u32>,
}

impl Material {
    /// A rough dielectric, as glTF's default material with this base colour.
    pub fn diffuse(base_color: Vec3) -> Self {
        Self::lambertian(base_color).with_specular(1.0)
    }

    /// A metal with the given colour and roughness.
    pub(crate) fn metal(base_color: Vec3, roughness: f32) -> Self {
        Self { roughness, metallic: 1.0, ..Self::diffuse(base_color) }
    }

    /// A pure Lambertian reflector (no specular layer): analytic tests and furnaces.
    pub fn lambertian(albedo: Vec3) -> Self {
        Self {
            base_color: albedo,
            roughness: 1.0,
            metallic: 0.0,
            specular: 0.0,
            emissive: Vec3::ZERO,
            base_color_texture: None,
            metallic_roughness_texture: None,
            emissive_texture: None,
        }
    }

    /// glTF's default material (no `material` on a primitive): white, metallic 1, roughness 1.
    pub(crate) fn gltf_default() -> Self {
        Self::metal(Vec3::ONE, 1.0)
    }

    fn with_specular(self, specular: f32) -> Self {
        Self { specular, ..self }
    }

    /// The texture indices this material uses.
    pub(crate) fn textures(&self) -> impl Iterator<Item = u32> {
        [self.base_color_texture, self.metallic_roughness_texture, self.emissive_texture]
            .into_iter()
            .flatten()
    }
}

/// A light with no area (KHR_lights_punctual). Intensities are linear RGB: colour times
/// intensity, with glTF's units taken as radiometric (W/sr for point and spot lights, W/m²
/// for directional ones).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    /// Radiates `intensity` (per steradian) in every direction.
    Point { position: Vec3, intensity: Vec3 },
    /// A point light limited to a cone around unit `direction` (where light travels): full
    /// intensity within `cos_inner`, smoothly falling to zero at `cos_outer`.
    Spot { position: Vec3, direction: Vec3, intensity: Vec3, cos_inner: f32, cos_outer: f32 },
    /// Parallel light travelling along unit `direction`, `irradiance` on a surface facing it.
    Directional { direction: Vec3, irradiance: Vec3 },
}

/// A world-space mesh that never moves (environment).
#[derive(Clone, Debug, PartialEq)]
pub struct StaticMesh {
    pub mesh: TriangleMesh,
    /// Index into [`SceneDescription::materials`]; a triangle with a material slot `k`
    /// ([`TriangleMesh::material_ids`]) uses `material + k`.
    pub material: u32,
}

/// A mesh in object space shared by every body that uses it.
#[derive(Clone, Debug, PartialEq)]
pub struct Prototype {
    pub name: String,
    pub mesh: TriangleMesh,
    /// As [`StaticMesh::material`].
    pub material: u32,
}

/// A body: a prototype placed in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Body {
    /// Index into [`SceneDescription::prototypes`].
    pub prototype: u32,
    pub transform: Affine3A,
}

/// A pinhole camera, or a thin lens when `aperture_radius` is positive (depth of field).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub eye: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub vfov_deg: f32,
    /// Radius of the lens in scene units; 0 is a pinhole (everything sharp).
    pub aperture_radius: f32,
    /// Distance along the view direction that is in focus; `None`: the target's distance.
    pub focus_distance: Option<f32>,
}

impl Camera {
    /// A pinhole camera at `eye` looking at `target`.
    pub fn pinhole(eye: Vec3, target: Vec3, up: Vec3, vfov_deg: f32) -> Self {
        Self { eye, target, up, vfov_deg, aperture_radius: 0.0, focus_distance: None }
    }
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
    /// The same radiance from every direction (furnace tests, studio lighting).
    pub const fn constant(radiance: Vec3) -> Sky {
        Sky { zenith: radiance, horizon: radiance, ground: radiance }
    }

    /// A clear daylight sky.
    pub const DAYLIGHT: Sky = Sky {
        zenith: Vec3::new(0.25, 0.45, 0.85),
        horizon: Vec3::new(0.75, 0.82, 0.90),
        ground: Vec3::new(0.25, 0.23, 0.21),
    };

    /// Radiance arriving from unit direction `dir`.
    pub(crate) fn radiance(&self, dir: Vec3) -> Vec3 {
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
    /// Images that materials reference by index (shared, so frames clone cheaply).
    pub textures: Vec<Arc<Texture>>,
    pub statics: Vec<StaticMesh>,
    pub prototypes: Vec<Prototype>,
    pub bodies: Vec<Body>,
    pub camera: Camera,
    pub sun: Sun,
    pub sky: Sky,
    /// Point, spot and directional lights besides the sun.
    pub lights: Vec<Light>,
}
