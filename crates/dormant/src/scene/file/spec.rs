//! The checked content of a scene file: what physics and rendering read. Only the parser
//! builds these (validated values, references resolved to indices, each kind of table with
//! exactly the fields it uses), so a consumer never checks them again. Plain data; the raw
//! TOML shape they are parsed from is private to the parser ([`super::schema`]).

use serde::Deserialize;

/// A checked scene file: every table of docs/scene-format.md.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct SceneSpec {
    pub scene: SceneInfo,
    pub physics: PhysicsSettings,
    pub environment: EnvironmentDef,
    /// `[animation]`: the bodies (and the environment) come from an animated glTF file
    /// instead of a simulation.
    pub animation: Option<AnimationDef>,
    pub prototypes: Vec<PrototypeDef>,
    pub spawners: Vec<SpawnerDef>,
    pub(crate) kinematics: Vec<KinematicDef>,
    pub(crate) disturbances: Vec<DisturbanceDef>,
    pub structures: Vec<StructureDef>,
    pub projectiles: Vec<ProjectileDef>,
    pub cameras: Vec<CameraDef>,
    pub lights: Vec<LightDef>,
    /// `[sky]`: absent means the built-in daylight gradient.
    pub sky: Option<SkyDef>,
    pub render: RenderDef,
}

impl SceneSpec {
    /// The camera to render through: `render.camera`, else the first; `None` when the file
    /// has no camera.
    pub fn render_camera(&self) -> Option<&CameraDef> {
        self.render.camera.map_or(self.cameras.first(), |i| self.cameras.get(i))
    }
}

/// `[scene]`: name, master seed and how many frames to simulate.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
#[non_exhaustive]
pub struct SceneInfo {
    /// Not empty.
    pub name: String,
    #[serde(default)]
    pub seed: u64,
    /// Number of recorded frames (at least 1); each frame advances the world by
    /// `physics.timestep`. In an `[animation]` scene it may be left out (0): the animation's
    /// own length.
    #[serde(default)]
    pub frames: u32,
    /// Directory that relative asset paths (glTF files) are resolved against, itself
    /// relative to the scene file; the scene file's directory when absent. A command line
    /// can override it.
    pub assets: Option<String>,
}

/// `[physics]`: integration and sleep parameters (checked: finite, sizes positive, rates and
/// times not negative, counts at least 1).
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
#[non_exhaustive]
pub struct PhysicsSettings {
    /// Seconds per recorded frame.
    pub timestep: f32,
    /// Rapier steps per frame (each of `timestep / substeps` seconds).
    pub substeps: u32,
    pub(crate) gravity: [f32; 3],
    /// Sleep when the farthest-point speed stays below this (units per second) ...
    pub(crate) sleep_linear_threshold: f32,
    /// ... (collider-less bodies only: radians per second) ...
    pub(crate) sleep_angular_threshold: f32,
    /// ... for this many seconds.
    pub(crate) sleep_time: f32,
    /// Bodies whose centre falls below this height leave the world.
    pub(crate) kill_plane_y: f32,
    /// Rapier solver iterations per step.
    pub(crate) solver_iterations: u32,
    /// Velocity damping of dynamic bodies (per second); angular damping lets balls stop
    /// rolling so their islands can fall asleep.
    pub(crate) linear_damping: f32,
    pub(crate) angular_damping: f32,
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

/// `[environment]`: the static set.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct EnvironmentDef {
    pub source: EnvironmentSource,
    /// Uniform scale applied to the environment (greater than 0).
    pub(crate) scale: f32,
    /// Translation applied after scaling.
    pub offset: [f32; 3],
    /// Friction of the static set (not negative).
    pub(crate) friction: f32,
    /// The static set collides as this many by this many colliders over its XZ bounds (at
    /// least 1, at most [`EnvironmentDef::MAX_COLLIDER_CELLS`]); 1 is one triangle mesh.
    pub collider_cells: u32,
}

impl EnvironmentDef {
    pub(crate) const MAX_COLLIDER_CELLS: u32 = 256;
}

/// `[animation]`: an animated glTF file (rigid-body bake) sampled at a frame rate.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct AnimationDef {
    /// The file as written (it existed when the scene was parsed).
    pub gltf: String,
    /// Frames per second to sample at (positive); `None`: the file's `dormant` extras give it.
    pub fps: Option<f64>,
    /// Play only the animation of this name (else all together).
    pub name: Option<String>,
    /// How far (scene units) any corner of a body's bounds may drift from where its rest
    /// began while it still counts as resting; `None`: the file's extras, else
    /// [`AnimationDef::DEFAULT_REST_TOLERANCE`].
    pub rest_tolerance: Option<f32>,
    /// A rest lasts at least this many frames (at least 2); `None`: the file's extras, else
    /// [`AnimationDef::DEFAULT_MIN_REST_FRAMES`].
    pub min_rest_frames: Option<u32>,
}

impl AnimationDef {
    /// 1 mm for a scene in metres: settled bodies in Blender's rigid-body bakes still drift
    /// by 1e-6 to 1e-5 a frame, which adds up over a rest of a hundred frames; a resting body
    /// is shown at most this far from where it is.
    pub(crate) const DEFAULT_REST_TOLERANCE: f32 = 1e-3;
    /// A third of a second at 24 frames per second: shorter pauses (a body at the top of a
    /// bounce, a pile still shifting) are not worth taking out of the per-frame build.
    pub(crate) const DEFAULT_MIN_REST_FRAMES: u32 = 8;
}

/// Where the environment's triangles come from.
#[derive(Clone, Debug, PartialEq)]
pub enum EnvironmentSource {
    /// A glTF file (as written; resolve it with [`super::SceneFile::resolve`]). It existed when
    /// the scene was parsed.
    Gltf(String),
    /// A built-in procedural set.
    Generator(GeneratorKind),
    /// The static mesh nodes of the `[animation]` file.
    Animation,
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
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct PrototypeDef {
    /// Not empty, unique among the prototypes.
    pub name: String,
    pub shape: Shape,
    /// Greater than 0.
    pub(crate) density: f32,
    /// Not negative.
    pub(crate) friction: f32,
    /// Within [0, 1].
    pub(crate) restitution: f32,
    /// Linear base colour (within [0, 1]) of a primitive shape; `None`: a palette colour.
    pub color: Option<[f32; 3]>,
}

/// A prototype's shape with exactly the sizes it takes, all greater than 0.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    Box {
        half_extents: [f32; 3],
    },
    Sphere {
        radius: f32,
    },
    /// Along Y: a cylinder of `half_height` capped by hemispheres of `radius`.
    Capsule {
        half_height: f32,
        radius: f32,
    },
    /// Along Y.
    Cylinder {
        half_height: f32,
        radius: f32,
    },
    /// A glTF mesh (the path as written; it existed when the scene was parsed), scaled
    /// uniformly, and how it becomes a collider.
    Gltf {
        path: String,
        scale: f32,
        collider: ColliderKind,
    },
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
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct SpawnerDef {
    /// Indices into [`SceneSpec::prototypes`] (at least one); each spawned object picks one
    /// uniformly at random.
    pub prototypes: Vec<usize>,
    /// Total objects over all waves (at least 1).
    pub count: u32,
    /// Not empty: `min` is nowhere above `max`.
    pub region: RegionDef,
    pub pattern: SpawnPattern,
    /// `grid`: random offset per axis in `[-jitter, jitter]` units (cells grow to fit it).
    pub(crate) position_jitter: f32,
    /// At least 1 and at most `count`, so no wave is empty.
    pub waves: u32,
    /// Seconds between waves (not negative).
    pub(crate) wave_interval: f32,
    /// Seconds before the first wave (not negative).
    pub(crate) start_time: f32,
    /// Mixed with the scene seed: the file's, else the spawner's index.
    pub seed: u64,
    pub(crate) initial_velocity: [f32; 3],
    /// Uniform random velocity added per axis, in `[-jitter, jitter]`.
    pub(crate) velocity_jitter: f32,
    /// Random initial orientation.
    pub(crate) random_rotation: bool,
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
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub(crate) struct KinematicDef {
    /// Unique among the kinematic bodies.
    pub name: String,
    /// Shape, as an index into [`SceneSpec::prototypes`] (its density is ignored).
    pub prototype: usize,
    /// At least one key (two when `looped`), times not negative and increasing.
    pub(crate) keyframes: Vec<KeyframeDef>,
    /// Repeat the path after its last key (the last key should equal the first).
    pub(crate) looped: bool,
}

/// A pose at a time; poses between keys are interpolated linearly (rotation about Y).
#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub(crate) struct KeyframeDef {
    /// Seconds.
    pub time: f32,
    pub position: [f32; 3],
    /// Heading about +Y in degrees.
    #[serde(default)]
    pub(crate) yaw_degrees: f32,
}

/// `[[disturbances]]`: a scripted impulse or explosion at a frame.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub(crate) struct DisturbanceDef {
    /// Before the file's last frame (a `--frames` override may end the run before it).
    pub frame: u32,
    pub center: [f32; 3],
    /// Greater than 0.
    pub radius: f32,
    pub kind: DisturbanceKind,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum DisturbanceKind {
    /// The linear impulse given to every dynamic body within `radius`.
    Impulse { impulse: [f32; 3] },
    /// Peak outward velocity change at the centre (greater than 0), falling linearly to 0 at
    /// `radius`.
    Explosion { strength: f32 },
}

/// `[[structures]]`: box bodies laid out as a tower, a wall, a domino run or a grid, repeated
/// on an array of copies set apart from each other. Every body is spawned asleep before the
/// first frame, and each copy sleeps as one island until something wakes it.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct StructureDef {
    /// Unique among the structures.
    pub name: String,
    /// Index into [`SceneSpec::prototypes`]: a box.
    pub prototype: usize,
    /// The prototype's half extents, copied from it (the layout is built from them).
    pub half_extents: [f32; 3],
    pub layout: StructureLayout,
    /// The first copy's anchor: the centre of its base (dominoes: of the first domino's base).
    pub origin: [f32; 3],
    /// Heading of every copy, and of the array's axes, about +Y.
    pub(crate) yaw_degrees: f32,
    /// Space left between neighbouring blocks (not negative).
    pub gap: f32,
    pub array: StructureArray,
}

/// How one copy's blocks are laid out, in the copy's frame (X right, Y up, Z forward), with
/// counts at least 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StructureLayout {
    /// Layers of `per_layer` blocks side by side, each layer turned 90 degrees from the one
    /// below (a Jenga tower: the block's X is its length).
    Tower { layers: u32, per_layer: u32 },
    /// Courses (`layers`) of `per_layer` blocks end to end along X, every other course shifted
    /// by half a block (running bond).
    Wall { layers: u32, per_layer: u32 },
    /// `count` blocks standing as authored, one every `spacing` units along +Z (greater than a
    /// block's depth plus the gap).
    Dominoes { count: u32, spacing: f32 },
    /// A box of `counts` blocks (X, Y, Z), touching but for the gap.
    Grid { counts: [u32; 3] },
}

/// Copies of a structure on a grid in its own frame: `counts` along X and Z (at least 1),
/// `spacing` apart (greater than a copy's footprint, so copies never touch).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StructureArray {
    pub counts: [u32; 2],
    pub spacing: [f32; 2],
}

/// `[[projectiles]]`: dynamic bodies launched at a frame with a velocity, one after another.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct ProjectileDef {
    /// Index into [`SceneSpec::prototypes`].
    pub prototype: usize,
    /// Frame of the first launch (before the file's last frame).
    pub frame: u32,
    /// Frames between launches.
    pub(crate) interval_frames: u32,
    /// Where the body starts and how fast it moves: in world space, or in each aimed-at copy's
    /// frame.
    pub position: [f32; 3],
    pub(crate) velocity: [f32; 3],
    pub aim: ProjectileAim,
}

/// What a projectile table launches at.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ProjectileAim {
    /// `count` launches (at least 1) in world space, each `step` further than the last.
    World { count: u32, step: [f32; 3] },
    /// One launch at every `every`-th copy (at least 1) of [`SceneSpec::structures`]`[structure]`,
    /// in array order, at most `count` of them (all when `None`).
    Structure { structure: usize, every: u32, count: Option<u32> },
}

/// `[[cameras]]`.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct CameraDef {
    /// Unique among the cameras.
    pub name: String,
    pub placement: CameraPlacement,
    /// Within (0, 180).
    pub(crate) fov_degrees: f32,
    /// Lens radius in scene units for depth of field; 0 is a pinhole.
    pub aperture_radius: f32,
    /// Distance in focus (greater than 0); the `look_at` point's distance when absent.
    pub focus_distance: Option<f32>,
}

/// Where a camera is: fixed, or key-framed.
#[derive(Clone, Debug, PartialEq)]
pub enum CameraPlacement {
    Fixed {
        position: [f32; 3],
        look_at: [f32; 3],
    },
    /// At least one key, times increasing.
    Keyframed(Vec<CameraKeyframeDef>),
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CameraKeyframeDef {
    pub time: f32,
    pub position: [f32; 3],
    pub(crate) look_at: [f32; 3],
}

/// `[[lights]]`.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct LightDef {
    pub kind: LightKind,
    /// Not negative.
    pub color: [f32; 3],
    /// `directional`: irradiance; `point`, `spot`: intensity (per steradian). Not negative.
    pub intensity: f32,
}

/// A light's kind with exactly the fields it takes; directions are not zero.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    /// `direction` is where the light travels.
    Directional {
        direction: [f32; 3],
    },
    Point {
        position: [f32; 3],
    },
    /// Full intensity within `inner_cone_degrees` of `direction`, none beyond
    /// `outer_cone_degrees`: 0 <= inner < outer <= 90.
    Spot {
        position: [f32; 3],
        direction: [f32; 3],
        inner_cone_degrees: f32,
        outer_cone_degrees: f32,
    },
}

/// `[sky]`: linear RGB radiance (not negative) times `intensity`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SkyDef {
    /// `color`: the same radiance in every direction.
    Constant { color: [f32; 3], intensity: f32 },
    /// A gradient from `ground` through `horizon` to `zenith`; each absent one is the
    /// daylight sky's.
    Gradient { zenith: Option<[f32; 3]>, horizon: Option<[f32; 3]>, ground: Option<[f32; 3]>, intensity: f32 },
}

/// `[render]`: output settings for the renderer (sizes and counts at least 1). Each is `None`
/// where the file gives none: a run's flag or preset, else the built-in default, decides it.
#[derive(Clone, Debug, Default, PartialEq)]
#[non_exhaustive]
pub struct RenderDef {
    /// `width` and `height` (the file gives both or neither).
    pub size: Option<(u32, u32)>,
    pub samples_per_pixel: Option<u32>,
    /// An index into [`SceneSpec::cameras`]; the first camera when absent (see
    /// [`SceneSpec::render_camera`]).
    pub camera: Option<usize>,
    /// Render every n-th simulated frame.
    pub frame_step: Option<u32>,
    /// Adaptive sampling's noise threshold (0: off); at least 0.
    pub noise_threshold: Option<f32>,
    /// Adaptive sampling's minimum samples per pixel; at least 1 (checked against the run's
    /// samples per pixel when rendering).
    pub min_spp: Option<u32>,
    /// Motion blur: the shutter as a fraction of the frame interval, centred on the frame
    /// (0: off).
    pub shutter: Option<f32>,
}
