//! dormant: an offline renderer for physics-simulated scenes that bakes sleeping islands into
//! the static acceleration structure.
//!
//! Data flows one way: [`scene`] (descriptions) → physics → integrate → [`accel`] (one
//! interface, Embree and BVH backends) → [`render`] → report. The [`cli`] only wires these
//! together.

pub mod accel;
pub mod atomic_file;
pub(crate) mod bench;
pub mod cli;
pub mod crosscheck;
pub mod geometry;
pub mod integrate;
pub mod physics;
pub mod render;
pub(crate) mod report;
pub(crate) mod rng;
pub mod scene;
pub mod sequence;
