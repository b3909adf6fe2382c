//! Embree 4: the safe wrapper over `embree4-sys` ([`Device`], [`Scene`], [`TriangleGeometry`],
//! [`InstanceGeometry`]) and the [`EmbreeAccel`] backend built on it.
//!
//! All of dormant's `unsafe` for Embree lives in this folder. The wrapper's rules:
//! - every handle is reference-counted by Embree and released on drop (RAII);
//! - errors reported through Embree's error callback come back as [`EmbreeError`], never
//!   aborts;
//! - ray queries need a committed scene, which the type system enforces: queries go through
//!   [`SceneView`], which only a scene without staged changes hands out, and mutation needs
//!   `&mut Scene`.

mod accel;
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

pub use accel::{EmbreeAccel, EmbreeBuildParams};
pub use device::{Device, Version};
pub use error::EmbreeError;
pub(crate) use filter::GeometrySet;
pub use frozen::FrozenScene;
pub use geometry::TriangleGeometry;
pub use instance_array::InstanceArrayGeometry;
pub use packet::Coherence;
pub use quality::BuildQuality;
pub use scene::{Geometry, InstanceGeometry, Scene, SceneFlags};
pub use view::{EmbreeHit, SceneView};
