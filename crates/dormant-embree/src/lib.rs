//! A safe wrapper over `embree4-sys` (Intel Embree 4): [`Device`], [`Scene`],
//! [`TriangleGeometry`], [`InstanceGeometry`], [`InstanceArrayGeometry`], and the ray queries
//! of a committed scene ([`SceneView`], single rays and packets). dormant's Embree backend
//! (`dormant::accel::embree`) is built on it; nothing here knows about dormant's scenes.
//!
//! All of dormant's `unsafe` for Embree lives in this crate. Its rules:
//! - every handle is reference-counted by Embree and released on drop (RAII);
//! - errors reported through Embree's error callback come back as [`EmbreeError`], never
//!   aborts;
//! - ray queries need a committed scene, which the type system enforces: queries go through
//!   [`SceneView`], which only a scene without staged changes hands out, and mutation needs
//!   `&mut Scene`.

mod device;
mod error;
mod filter;
mod frozen;
mod geometry;
mod instance_array;
mod motion;
mod packet;
mod quality;
mod scene;
mod view;

pub use device::{Device, Version};
pub use error::EmbreeError;
pub use filter::GeometrySet;
pub use frozen::FrozenScene;
pub use geometry::TriangleGeometry;
pub use instance_array::{ArrayEntry, InstanceArrayGeometry};
pub use motion::ShutterPoses;
pub use packet::{Coherence, PacketRay};
pub use quality::BuildQuality;
pub use scene::{Geometry, InstanceGeometry, Scene, SceneFlags};
pub use view::{EmbreeHit, EmbreeOccluder, SceneView};
