//! dormant: an offline renderer for physics-simulated scenes that bakes sleeping islands into
//! the static acceleration structure.
//!
//! Data flows one way: [`scene`] (descriptions) → physics → integrate → [`accel`] (one
//! interface, Embree and BVH backends) → [`render`] → report. The [`cli`] only wires these
//! together.

pub mod accel;
pub mod cli;
pub mod geometry;
pub mod render;
pub mod scene;
