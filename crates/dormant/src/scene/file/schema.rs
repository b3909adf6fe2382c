//! The scene file's raw TOML shape as serde structs, private to the parser. Every table
//! rejects unknown keys and gets its defaults here; [`super::validate`] checks the values and
//! builds the public [`super::SceneSpec`] from them. Tables that need no reshaping
//! ([`SceneInfo`], [`PhysicsSettings`], regions and keyframes) are the public types
//! themselves. Serde names each raw type as messages have always shown it (`expected struct
//! PrototypeDef`, `expected struct RenderSettings`), so syntax errors read as before.

use serde::Deserialize;

use super::spec::{
    CameraKeyframeDef, ColliderKind, GeneratorKind, KeyframeDef, PhysicsSettings, RegionDef, SceneInfo,
    SpawnPattern,
};

/// A whole scene file as written.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(rename = "SceneDocument", deny_unknown_fields)]
pub(super) struct SceneToml {
    pub scene: SceneInfo,
    #[serde(default)]
    pub physics: PhysicsSettings,
    pub environment: Option<EnvironmentToml>,
    pub animation: Option<AnimationToml>,
    #[serde(default)]
    pub prototypes: Vec<PrototypeToml>,
    #[serde(default)]
    pub spawners: Vec<SpawnerToml>,
    #[serde(default)]
    pub(crate) kinematics: Vec<KinematicToml>,
    #[serde(default)]
    pub(crate) disturbances: Vec<DisturbanceToml>,
    #[serde(default)]
    pub structures: Vec<StructureToml>,
    #[serde(default)]
    pub projectiles: Vec<ProjectileToml>,
    #[serde(default)]
    pub cameras: Vec<CameraToml>,
    #[serde(default)]
    pub lights: Vec<LightToml>,
    pub sky: Option<SkyToml>,
    #[serde(default)]
    pub render: RenderToml,
}

/// `[sky]`: a constant `color`, or a gradient (`zenith`, `horizon`, `ground`).
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(rename = "SkyDef", deny_unknown_fields)]
pub(super) struct SkyToml {
    pub color: Option<[f32; 3]>,
    pub zenith: Option<[f32; 3]>,
    pub horizon: Option<[f32; 3]>,
    pub ground: Option<[f32; 3]>,
    #[serde(default = "one")]
    pub intensity: f32,
}

/// `[animation]`: an animated glTF file whose static nodes are the environment and whose
/// moving mesh nodes are the bodies.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(rename = "AnimationDef", deny_unknown_fields)]
pub(super) struct AnimationToml {
    pub gltf: String,
    pub fps: Option<f64>,
    pub name: Option<String>,
    pub rest_tolerance: Option<f32>,
    pub min_rest_frames: Option<u32>,
}

/// `[environment]`: exactly one of `gltf` and `generator` (checked later).
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(rename = "EnvironmentDef", deny_unknown_fields)]
pub(super) struct EnvironmentToml {
    pub gltf: Option<String>,
    pub(crate) generator: Option<GeneratorKind>,
    #[serde(default = "one")]
    pub(crate) scale: f32,
    #[serde(default)]
    pub offset: [f32; 3],
    #[serde(default = "default_friction")]
    pub(crate) friction: f32,
    #[serde(default = "one_u32")]
    pub collider_cells: u32,
}

/// `[[prototypes]]`: the shape's sizes are all optional here; the shape says which it needs.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(rename = "PrototypeDef", deny_unknown_fields)]
pub(super) struct PrototypeToml {
    pub name: String,
    pub shape: ShapeKind,
    pub half_extents: Option<[f32; 3]>,
    pub radius: Option<f32>,
    pub(crate) half_height: Option<f32>,
    pub gltf: Option<String>,
    #[serde(default = "one")]
    pub(crate) scale: f32,
    #[serde(default)]
    pub collider: ColliderKind,
    #[serde(default = "one")]
    pub(crate) density: f32,
    #[serde(default = "default_friction")]
    pub(crate) friction: f32,
    #[serde(default)]
    pub(crate) restitution: f32,
    pub color: Option<[f32; 3]>,
}

/// `shape = "..."`; its `Debug` name appears in messages (`shape Box needs ...`).
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub(super) enum ShapeKind {
    Box,
    Sphere,
    Capsule,
    Cylinder,
    Gltf,
}

/// `[[spawners]]`: prototypes by name.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(rename = "SpawnerDef", deny_unknown_fields)]
pub(super) struct SpawnerToml {
    pub prototypes: Vec<String>,
    pub count: u32,
    pub region: RegionDef,
    #[serde(default)]
    pub pattern: SpawnPattern,
    #[serde(default)]
    pub(crate) position_jitter: f32,
    #[serde(default = "one_u32")]
    pub waves: u32,
    #[serde(default)]
    pub(crate) wave_interval: f32,
    #[serde(default)]
    pub(crate) start_time: f32,
    pub seed: Option<u64>,
    #[serde(default)]
    pub(crate) initial_velocity: [f32; 3],
    #[serde(default)]
    pub(crate) velocity_jitter: f32,
    #[serde(default = "yes")]
    pub(crate) random_rotation: bool,
}

/// `[[kinematics]]`: the prototype by name.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(rename = "KinematicDef", deny_unknown_fields)]
pub(super) struct KinematicToml {
    pub name: String,
    pub prototype: String,
    pub(crate) keyframes: Vec<KeyframeDef>,
    #[serde(default)]
    pub(crate) looped: bool,
}

/// `[[disturbances]]`: `impulse` or `strength` by `kind`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(rename = "DisturbanceDef", deny_unknown_fields)]
pub(super) struct DisturbanceToml {
    pub frame: u32,
    pub kind: DisturbanceTag,
    pub center: [f32; 3],
    pub radius: f32,
    pub(crate) impulse: Option<[f32; 3]>,
    pub(crate) strength: Option<f32>,
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename = "DisturbanceKind", rename_all = "snake_case")]
pub(super) enum DisturbanceTag {
    Impulse,
    Explosion,
}

/// `[[structures]]`: the prototype by name; the layout keys `kind` needs are optional here.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(rename = "StructureDef", deny_unknown_fields)]
pub(super) struct StructureToml {
    pub name: String,
    pub kind: StructureKind,
    pub prototype: String,
    #[serde(default)]
    pub origin: [f32; 3],
    #[serde(default)]
    pub(crate) yaw_degrees: f32,
    #[serde(default)]
    pub gap: f32,
    pub layers: Option<u32>,
    pub per_layer: Option<u32>,
    pub count: Option<u32>,
    pub spacing: Option<f32>,
    pub counts: Option<[u32; 3]>,
    pub array: Option<ArrayToml>,
}

/// `kind = "..."`; its `Debug` name appears in messages (`a Tower needs ...`).
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename = "StructureKind", rename_all = "snake_case")]
pub(super) enum StructureKind {
    Tower,
    Wall,
    Dominoes,
    Grid,
}

/// A structure's `array = { counts, spacing }`.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(rename = "StructureArray", deny_unknown_fields)]
pub(super) struct ArrayToml {
    pub counts: [u32; 2],
    #[serde(default)]
    pub spacing: [f32; 2],
}

/// `[[projectiles]]`: prototype and structure by name; `count`, `step` and `every` depend on
/// whether a structure is aimed at.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(rename = "ProjectileDef", deny_unknown_fields)]
pub(super) struct ProjectileToml {
    pub prototype: String,
    pub frame: u32,
    #[serde(default)]
    pub(crate) interval_frames: u32,
    pub position: [f32; 3],
    #[serde(default)]
    pub(crate) velocity: [f32; 3],
    pub structure: Option<String>,
    pub count: Option<u32>,
    pub step: Option<[f32; 3]>,
    pub every: Option<u32>,
}

/// `[[cameras]]`: `position` and `look_at`, or `keyframes`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(rename = "CameraDef", deny_unknown_fields)]
pub(super) struct CameraToml {
    pub name: String,
    pub position: Option<[f32; 3]>,
    pub(crate) look_at: Option<[f32; 3]>,
    #[serde(default)]
    pub(crate) keyframes: Vec<CameraKeyframeDef>,
    #[serde(default = "default_fov")]
    pub(crate) fov_degrees: f32,
    #[serde(default)]
    pub aperture_radius: f32,
    pub focus_distance: Option<f32>,
}

/// `[[lights]]`: the fields `kind` needs are optional here.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(rename = "LightDef", deny_unknown_fields)]
pub(super) struct LightToml {
    pub kind: LightTag,
    pub direction: Option<[f32; 3]>,
    pub position: Option<[f32; 3]>,
    #[serde(default = "white")]
    pub color: [f32; 3],
    #[serde(default = "one")]
    pub intensity: f32,
    pub(crate) inner_cone_degrees: Option<f32>,
    pub(crate) outer_cone_degrees: Option<f32>,
}

/// `kind = "..."`; its `Debug` name appears in messages (`a Point light needs ...`).
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename = "LightKind", rename_all = "snake_case")]
pub(super) enum LightTag {
    Directional,
    Point,
    Spot,
}

/// `[render]`: the camera by name, the image, the frame step and the shutter (motion blur).
/// A key the file does not give is `None`: the run's flags, preset or built-in default
/// decide it (`dormant render`'s settings rule).
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(rename = "RenderSettings", deny_unknown_fields, default)]
pub(super) struct RenderToml {
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub(crate) samples_per_pixel: Option<u32>,
    pub camera: Option<String>,
    pub frame_step: Option<u32>,
    pub noise_threshold: Option<f32>,
    pub min_spp: Option<u32>,
    pub shutter: Option<f32>,
}

fn one() -> f32 {
    1.0
}
fn one_u32() -> u32 {
    1
}
fn yes() -> bool {
    true
}
fn default_friction() -> f32 {
    0.6
}
fn default_fov() -> f32 {
    50.0
}
fn white() -> [f32; 3] {
    [1.0; 3]
}
