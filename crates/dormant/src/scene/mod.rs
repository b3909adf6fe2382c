//! Scene descriptions: plain data saying what is in a scene (meshes, materials, bodies,
//! camera, lights). Nothing here builds physics, acceleration or render objects.

mod animated;
mod animated_assets;
mod assets;
mod builtin;
mod description;
pub mod file;
pub mod gltf;
pub mod limits;
mod pile;
pub mod texture;

pub(crate) use animated::AnimatedScene;
pub(crate) use assets::MeshSource;
pub use assets::SceneAssets;
pub use builtin::default_scene;
pub use description::{Body, Camera, Light, Material, Prototype, SceneDescription, Sky, StaticMesh, Sun};
pub use pile::asset_pile;
pub(crate) use texture::Texture;
