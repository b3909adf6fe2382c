//! dormant: an offline renderer for physics-simulated scenes that takes sleeping islands out
//! of the per-frame acceleration build.
//!
//! Data flows one way: [`geometry`] → [`scene`] (descriptions) → [`physics`] (the simulated
//! trajectory) → [`accel`] (one interface, Embree and BVH backends, and what a hit means in
//! scene terms) → [`residency`] (where sleeping bodies reside: awake instances, the resting
//! scene, baked into the static scene) and [`render`] (pixels), which do not know each other →
//! [`sequence`] (the replay that drives both frame by frame, and its output files).
//!
//! [`prelude`] holds what a program needs to render a physics scene, with an example.

pub mod accel;
pub mod atomic_file;
pub mod geometry;
pub mod names;
pub mod physics;
pub mod prelude;
pub mod render;
pub mod residency;
pub mod rng;
pub mod scene;
pub mod sequence;
