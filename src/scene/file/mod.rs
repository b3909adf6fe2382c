//! Scene files: the TOML schema as serde structs, the parser that reports errors by file,
//! line and field, the validation of values, and the resolution of the environment and
//! prototypes into plain triangle meshes. Parsing builds plain data, never physics or render
//! objects; see docs/scene-format.md for the format.

mod error;
mod geometry;
mod parse;
mod presets;
mod schema;
mod validate;

pub use error::SceneError;
pub use geometry::{environment_asset, environment_mesh, generate, prototype_asset, prototype_mesh};
pub use parse::SceneFile;
pub(crate) use parse::{fnv1a64, fnv1a64_extend};
pub use schema::{
    CameraDef, CameraKeyframeDef, ColliderKind, DisturbanceDef, DisturbanceKind, EnvironmentDef,
    GeneratorKind, KeyframeDef, KinematicDef, LightDef, LightKind, PhysicsSettings, PrototypeDef, RegionDef,
    RenderSettings, SceneDocument, SceneInfo, ShapeKind, SpawnPattern, SpawnerDef,
};
