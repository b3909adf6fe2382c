//! dormant: an offline renderer for physics-simulated scenes that takes sleeping islands out
//! of the per-frame acceleration build.
//!
//! Data flows one way: [`geometry`] → [`scene`] (descriptions) → [`physics`] (the simulated
//! trajectory) → [`accel`] (one interface, Embree and BVH backends) → [`integrate`] (where
//! sleeping bodies reside) and [`render`] (pixels) → [`sequence`] (the replay that drives them
//! frame by frame).

pub mod accel;
pub mod atomic_file;
pub mod geometry;
pub mod integrate;
pub mod physics;
pub mod render;
pub mod rng;
pub mod scene;
pub mod sequence;
