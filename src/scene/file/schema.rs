//! The scene file's TOML schema as plain serde structs. Every table rejects unknown keys;
//! values are checked for meaning (finite, positive, references resolve) by
//! [`super::validate`], never here.

use serde::Deserialize;

/// A parsed scene file: plain data, no physics or render objects.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SceneDocument {
    pub scene: SceneInfo,
    #[serde(default)]
    pub physics: PhysicsSettings,
    pub environment: EnvironmentDef,
    #[serde(default)]
    pub prototypes: Vec<PrototypeDef>,
    #[serde(default)]
    pub spawners: Vec<SpawnerDef>,
    #[serde(default)]
    pub kinematics: Vec<KinematicDef>,
    #[serde(default)]
    pub disturbances: Vec<DisturbanceDef>,
    #[serde(default)]
    pub cameras: Vec<CameraDef>,
    #[serde(default)]
    pub lights: Vec<LightDef>,
    /// `[sky]`: absent means the built-in daylight gradient.
    pub sky: Option<SkyDef>,
    #[serde(default)]
    pub render: RenderSettings,
}

/// `[sky]`: a constant sky (`color`), or a gradient from `ground` through `horizon` to
/// `zenith` (linear RGB radiance; each defaults to the daylight sky's), times `intensity`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SkyDef {
    pub color: Option<[f32; 3]>,
    pub zenith: Option<[f32; 3]>,
    pub horizon: Option<[f32; 3]>,
    pub ground: Option<[f32; 3]>,
    #[serde(default = "one")]
    pub intensity: f32,
}

/// `[scene]`: name, master seed and how many frames to simulate.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SceneInfo {
    pub name: String,
    #[serde(default)]
    pub seed: u64,
    /// Number of recorded frames; each frame advances the world by `physics.timestep`.
    pub frames: u32,
    /// Directory that relative asset paths (glTF files) are resolved against, itself
    /// relative to the scene file; the scene file's directory when absent. A command line
    /// can override it.
    pub assets: Option<String>,
}

/// `[physics]`: integration and sleep parameters.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct PhysicsSettings {
    /// Seconds per recorded frame.
    pub timestep: f32,
    /// Rapier steps per frame (each of `timestep / substeps` seconds).
    pub substeps: u32,
    pub gravity: [f32; 3],
    /// Sleep when the farthest-point speed stays below this (units per second) ...
    pub sleep_linear_threshold: f32,
    /// ... (collider-less bodies only: radians per second) ...
    pub sleep_angular_threshold: f32,
    /// ... for this many seconds.
    pub sleep_time: f32,
    /// Bodies whose centre falls below this height leave the world.
    pub kill_plane_y: f32,
    /// Rapier solver iterations per step.
    pub solver_iterations: u32,
    /// Velocity damping of dynamic bodies (per second); angular damping lets balls stop
    /// rolling so their islands can fall asleep.
    pub linear_damping: f32,
    pub angular_damping: f32,
}

impl Default for PhysicsSettings {
    fn default() -> Self {
        Self {
            timestep: 1.0 / 60.0,
            substeps: 1,
            gravity: [0.0, -9.81, 0.0],
            sleep_linear_threshold: 0.05,
            sleep_angular_threshold: 0.5,
            sleep_time: 0.5,
            kill_plane_y: -50.0,
            solver_iterations: 4,
            linear_damping: 0.0,
            angular_damping: 0.0,
        }
    }
}

/// `[environment]`: the static set, from a glTF file or a built-in generator (exactly one).
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct EnvironmentDef {
    pub gltf: Option<String>,
    pub generator: Option<GeneratorKind>,
    /// Uniform scale applied to the environment.
    #[serde(default = "one")]
    pub scale: f32,
    /// Translation applied after scaling.
    #[serde(default)]
    pub offset: [f32; 3],
    /// Friction of the static set.
    #[serde(default = "default_friction")]
    pub friction: f32,
}

/// Built-in procedural environments.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum GeneratorKind {
    /// A flat square floor.
    Ground,
    /// A Sponza-like atrium: floor, two colonnades, arches and outer walls.
    Atrium,
    /// A floor with scattered pillars and low walls (a set for characters to walk through).
    Courtyard,
}

/// `[[prototypes]]`: a dynamic object's shape and material.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PrototypeDef {
    pub name: String,
    pub shape: ShapeKind,
    /// `box`: half extents.
    pub half_extents: Option<[f32; 3]>,
    /// `sphere`, `capsule`, `cylinder`: radius.
    pub radius: Option<f32>,
    /// `capsule`, `cylinder`: half height of the axis segment (along Y).
    pub half_height: Option<f32>,
    /// `gltf`: path of the mesh, relative to the scene file.
    pub gltf: Option<String>,
    /// `gltf`: uniform scale.
    #[serde(default = "one")]
    pub scale: f32,
    /// `gltf`: how to turn the mesh into a collider.
    #[serde(default)]
    pub collider: ColliderKind,
    #[serde(default = "one")]
    pub density: f32,
    #[serde(default = "default_friction")]
    pub friction: f32,
    #[serde(default)]
    pub restitution: f32,
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum ShapeKind {
    Box,
    Sphere,
    Capsule,
    Cylinder,
    Gltf,
}

/// How a glTF mesh becomes a collider.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum ColliderKind {
    /// Convex hull when the mesh is (nearly) convex, convex decomposition otherwise.
    #[default]
    Auto,
    ConvexHull,
    ConvexDecomposition,
}

/// `[[spawners]]`: objects that appear in waves over time.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SpawnerDef {
    /// Prototype names; each spawned object picks one uniformly at random.
    pub prototypes: Vec<String>,
    /// Total objects over all waves.
    pub count: u32,
    pub region: RegionDef,
    #[serde(default)]
    pub pattern: SpawnPattern,
    /// `grid`: random offset per axis in `[-jitter, jitter]` units (cells grow to fit it).
    #[serde(default)]
    pub position_jitter: f32,
    #[serde(default = "one_u32")]
    pub waves: u32,
    /// Seconds between waves.
    #[serde(default)]
    pub wave_interval: f32,
    /// Seconds before the first wave.
    #[serde(default)]
    pub start_time: f32,
    /// Mixed with the scene seed; defaults to the spawner's index.
    pub seed: Option<u64>,
    #[serde(default)]
    pub initial_velocity: [f32; 3],
    /// Uniform random velocity added per axis, in `[-jitter, jitter]`.
    #[serde(default)]
    pub velocity_jitter: f32,
    /// Random initial orientation.
    #[serde(default = "yes")]
    pub random_rotation: bool,
}

/// An axis-aligned box in world space.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RegionDef {
    pub min: [f32; 3],
    pub max: [f32; 3],
}

#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum SpawnPattern {
    /// Jittered grid cells in the region's XZ footprint, stacked upward as needed: no
    /// object overlaps another of its wave.
    #[default]
    Grid,
    /// Uniform random points in the region (objects may start interpenetrating).
    Random,
}

/// `[[kinematics]]`: a kinematic body following a key-framed path.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct KinematicDef {
    pub name: String,
    /// Shape, by prototype name (its density is ignored).
    pub prototype: String,
    pub keyframes: Vec<KeyframeDef>,
    /// Repeat the path after its last key (the last key should equal the first).
    #[serde(default)]
    pub looped: bool,
}

/// A pose at a time; poses between keys are interpolated linearly (rotation about Y).
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct KeyframeDef {
    /// Seconds.
    pub time: f32,
    pub position: [f32; 3],
    /// Heading about +Y in degrees.
    #[serde(default)]
    pub yaw_degrees: f32,
}

/// `[[disturbances]]`: a scripted impulse or explosion at a frame.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct DisturbanceDef {
    pub frame: u32,
    pub kind: DisturbanceKind,
    pub center: [f32; 3],
    pub radius: f32,
    /// `impulse`: the linear impulse given to every dynamic body within `radius`.
    pub impulse: Option<[f32; 3]>,
    /// `explosion`: peak outward velocity change at the centre, falling linearly to 0 at
    /// `radius`.
    pub strength: Option<f32>,
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum DisturbanceKind {
    Impulse,
    Explosion,
}

/// `[[cameras]]`: fixed (`position`, `look_at`) or key-framed (`keyframes`).
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CameraDef {
    pub name: String,
    pub position: Option<[f32; 3]>,
    pub look_at: Option<[f32; 3]>,
    #[serde(default)]
    pub keyframes: Vec<CameraKeyframeDef>,
    #[serde(default = "default_fov")]
    pub fov_degrees: f32,
    /// Lens radius in scene units for depth of field; 0 is a pinhole.
    #[serde(default)]
    pub aperture_radius: f32,
    /// Distance in focus; the `look_at` point's distance when absent.
    pub focus_distance: Option<f32>,
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CameraKeyframeDef {
    pub time: f32,
    pub position: [f32; 3],
    pub look_at: [f32; 3],
}

/// `[[lights]]`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LightDef {
    pub kind: LightKind,
    /// `directional`, `spot`: direction the light travels.
    pub direction: Option<[f32; 3]>,
    /// `point`, `spot`: position.
    pub position: Option<[f32; 3]>,
    #[serde(default = "white")]
    pub color: [f32; 3],
    /// `directional`: irradiance; `point`, `spot`: intensity (per steradian).
    #[serde(default = "one")]
    pub intensity: f32,
    /// `spot`: half-angle of full intensity, degrees (default 0).
    pub inner_cone_degrees: Option<f32>,
    /// `spot`: half-angle where the light ends, degrees (default 45).
    pub outer_cone_degrees: Option<f32>,
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum LightKind {
    Directional,
    Point,
    Spot,
}

/// `[render]`: output settings for the renderer.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    pub samples_per_pixel: u32,
    /// Camera name; the first camera when absent.
    pub camera: Option<String>,
    /// Render every n-th simulated frame.
    pub frame_step: u32,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self { width: 640, height: 360, samples_per_pixel: 1, camera: None, frame_step: 1 }
    }
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
