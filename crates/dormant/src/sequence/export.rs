//! A sequence's frames as plain JSON for another renderer (`dormant export`): where the
//! environment and prototype meshes come from, the sun, sky and punctual lights, and per
//! selected frame the camera and every present body's pose. Coordinates are dormant's world
//! (glTF's: Y up, right-handed, metres as authored); a body's world transform is its pose
//! (translation, then rotation) applied to its prototype's file coordinates times the
//! prototype's `scale`.

use serde::Serialize;

use super::{FrameSelection, Sequence};
use crate::scene::{Camera, Light, Material, MeshSource, SceneDescription};

/// Version of the export's layout; bump it when a field changes meaning.
pub(crate) const EXPORT_FORMAT: &str = "dormant-export-1";

/// Everything another renderer needs to rebuild the selected frames of a sequence.
#[derive(Clone, Debug, Serialize)]
pub struct SequenceExport {
    pub format: &'static str,
    pub scene: String,
    /// Seconds between frames.
    pub timestep: f32,
    pub environment: MeshSource,
    /// As [`PrototypeExport::material`], for the environment.
    pub(crate) environment_material: Option<MaterialExport>,
    pub prototypes: Vec<PrototypeExport>,
    /// Prototype index of every body, by body id (the index into each frame's `poses`).
    pub body_prototypes: Vec<u32>,
    pub sun: SunExport,
    /// Radiance from directions no geometry blocks: `horizon` blended to `zenith` (above the
    /// horizon) or to `ground` (below) with the square root of |elevation|; all three equal
    /// for a constant sky.
    pub sky: SkyExport,
    pub lights: Vec<LightExport>,
    pub frames: Vec<FrameExport>,
}

#[derive(Clone, Debug, Serialize)]
pub struct PrototypeExport {
    pub name: String,
    #[serde(flatten)]
    pub source: MeshSource,
    /// The material dormant gives the whole mesh when its file has none; `None` when the
    /// file's own materials are used.
    pub material: Option<MaterialExport>,
}

/// A material without textures (dormant's fallback for meshes whose file has none).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct MaterialExport {
    /// Linear RGB.
    pub(crate) base_color: [f32; 3],
    pub(crate) roughness: f32,
    pub(crate) metallic: f32,
    /// 1: glTF's F0 of 0.04; 0: no specular layer.
    pub(crate) specular: f32,
    pub emissive: [f32; 3],
}

impl From<Material> for MaterialExport {
    fn from(m: Material) -> Self {
        Self {
            base_color: m.base_color.into(),
            roughness: m.roughness,
            metallic: m.metallic,
            specular: m.specular,
            emissive: m.emissive.into(),
        }
    }
}

/// The sun: a disc of uniform radiance giving `irradiance` on a surface facing it.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct SunExport {
    /// Unit direction from the scene towards the sun.
    pub direction: [f32; 3],
    pub irradiance: [f32; 3],
    pub angular_radius_deg: f32,
}

#[derive(Clone, Copy, Debug, Serialize)]
pub struct SkyExport {
    pub zenith: [f32; 3],
    pub horizon: [f32; 3],
    pub ground: [f32; 3],
}

/// A punctual light; `intensity` is W/sr for point and spot lights, `irradiance` W/m² for
/// directional ones.
#[derive(Clone, Copy, Debug, Serialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum LightExport {
    Point { position: [f32; 3], intensity: [f32; 3] },
    Spot { position: [f32; 3], direction: [f32; 3], intensity: [f32; 3], cos_inner: f32, cos_outer: f32 },
    Directional { direction: [f32; 3], irradiance: [f32; 3] },
}

#[derive(Clone, Copy, Debug, Serialize)]
pub struct CameraExport {
    pub eye: [f32; 3],
    pub target: [f32; 3],
    pub(crate) up: [f32; 3],
    /// Vertical field of view (the image's horizontal one follows from its aspect ratio).
    pub vfov_deg: f32,
    pub aperture_radius: f32,
    pub focus_distance: Option<f32>,
}

/// One frame: its camera and, by body id, `[tx, ty, tz, qx, qy, qz, qw]` or `null` for a body
/// that is not in the world.
#[derive(Clone, Debug, Serialize)]
pub struct FrameExport {
    pub index: u32,
    pub time: f32,
    pub camera: CameraExport,
    pub poses: Vec<Option<[f32; 7]>>,
}

impl From<&Light> for LightExport {
    fn from(l: &Light) -> Self {
        match *l {
            Light::Point { position, intensity } => {
                LightExport::Point { position: position.into(), intensity: intensity.into() }
            }
            Light::Spot { position, direction, intensity, cos_inner, cos_outer } => LightExport::Spot {
                position: position.into(),
                direction: direction.into(),
                intensity: intensity.into(),
                cos_inner,
                cos_outer,
            },
            Light::Directional { direction, irradiance } => {
                LightExport::Directional { direction: direction.into(), irradiance: irradiance.into() }
            }
        }
    }
}

impl From<&Camera> for CameraExport {
    fn from(c: &Camera) -> Self {
        Self {
            eye: c.eye.into(),
            target: c.target.into(),
            up: c.up.into(),
            vfov_deg: c.vfov_deg,
            aperture_radius: c.aperture_radius,
            focus_distance: c.focus_distance,
        }
    }
}

impl Sequence {
    /// The frames `selection` picks, replayed from the trajectory, as a [`SequenceExport`].
    pub fn export(&self, selection: &FrameSelection) -> SequenceExport {
        let mut frames = Vec::with_capacity(selection.count() as usize);
        let _ = self.replay::<std::convert::Infallible>(selection, &mut [], &mut |frame, _| {
            let time = self.time_of(frame.index);
            let poses = (0..frame.poses.len())
                .map(|b| {
                    frame.is_present(b).then(|| {
                        let p = &frame.poses[b];
                        let (t, q) = (p.translation, p.rotation);
                        [t.x, t.y, t.z, q.x, q.y, q.z, q.w]
                    })
                })
                .collect();
            frames.push(FrameExport {
                index: frame.index,
                time,
                camera: (&self.assets.camera_at(time)).into(),
                poses,
            });
            Ok(())
        });
        let template: &SceneDescription = &self.template;
        let sources = &self.assets.sources;
        SequenceExport {
            format: EXPORT_FORMAT,
            scene: self.assets.name.clone(),
            timestep: self.trajectory.timestep,
            environment: sources[0].clone(),
            environment_material: self.assets.material_without_file_materials(0).map(Into::into),
            prototypes: self
                .assets
                .prototypes
                .iter()
                .zip(&sources[1..])
                .enumerate()
                .map(|(i, ((name, _), source))| PrototypeExport {
                    name: name.clone(),
                    source: source.clone(),
                    material: self.assets.material_without_file_materials(i + 1).map(Into::into),
                })
                .collect(),
            body_prototypes: self.trajectory.bodies.iter().map(|b| b.prototype).collect(),
            sun: SunExport {
                direction: template.sun.direction.into(),
                irradiance: template.sun.irradiance.into(),
                angular_radius_deg: template.sun.angular_radius_deg,
            },
            sky: SkyExport {
                zenith: template.sky.zenith.into(),
                horizon: template.sky.horizon.into(),
                ground: template.sky.ground.into(),
            },
            lights: template.lights.iter().map(LightExport::from).collect(),
            frames,
        }
    }
}
