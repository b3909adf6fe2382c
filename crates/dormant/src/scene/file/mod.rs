//! Scene files: parsing TOML text into a checked [`SceneSpec`] (the raw serde shape stays
//! private to the parser; the checked types hold validated values and prototype and camera
//! references as indices), errors by file, line and field, and the resolution of the
//! environment and prototypes into plain triangle meshes, and of structures and projectiles
//! into blocks and launches. Parsing builds plain data, never physics or render objects; see
//! docs/scene-format.md for the format.

mod animated_gltf;
mod asset_dir;
mod count;
mod error;
mod geometry;
mod location;
mod parse;
mod presets;
mod schema;
pub mod spec;
mod structure;
mod validate;

pub use error::SceneError;
pub(crate) use geometry::{environment_asset, prototype_asset};
pub use geometry::{environment_mesh, prototype_mesh};
pub(crate) use parse::fnv1a64;
pub use parse::SceneFile;
pub(crate) use spec::{
    AnimationDef, CameraDef, CameraKeyframeDef, CameraPlacement, ColliderKind, EnvironmentSource, LightDef,
    LightKind, Shape, SkyDef, SpawnPattern, SpawnerDef, StructureDef,
};
pub(crate) use spec::{DisturbanceDef, DisturbanceKind, KeyframeDef};
