//! Integration: turning simulated frames into scenes the accelerators hold. This first part
//! loads a scene file's meshes once ([`SceneAssets`]) and describes any frame of a
//! trajectory as a render [`SceneDescription`] with every present body as an instance.
//! (The scene manager that bakes sleeping islands, the geometry cache and the cost model
//! build on it.)

mod frame;

pub use frame::{describe_frame, SceneAssets};
