//! The pure-Rust BVH backend ([`BvhAccel`]), a cross-check and fallback for Embree.
//!
//! Layout, one folder per BVH type and one file per operation (all crate-private; the API is
//! the backend, its [`BuildParams`] and the persistent static tree, [`StaticBvh`]):
//! - `params`: [`BuildParams`] and its presets;
//! - `triangle`: stored triangles and the watertight ray-triangle test;
//! - `flat`: the flattened binned-SAH BVH (prototypes, top level, static blocks), its 4-wide
//!   traversal copy, and the traversal stack every ray query uses;
//! - `persistent`: the static tree with incremental insertion/removal and O(1) snapshots;
//! - `two_level`: instances, the top level, the resting level, and the
//!   [`crate::accel::Accelerator`] impl;
//! - [`testing`] (hidden): the internals the property tests check.
//!
//! SIMD: only through glam's `Vec3A`/`Vec4` (SSE2 on x86-64, NEON on aarch64, plain scalar
//! code elsewhere: the same source is the scalar path). There are no intrinsics.
//!
//! Hits follow Embree's conventions: `t` in units of the (unnormalised) direction, both sides
//! of triangles, barycentrics `(1-u-v)*p0 + u*p1 + v*p2`, unit world-space `ng`.

mod flat;
mod params;
mod persistent;
pub mod testing;
mod triangle;
mod two_level;

pub use params::BuildParams;
pub use persistent::{SnapshotMemory, StaticBvh, StaticSnapshot, StaticUpdate};
pub use two_level::BvhAccel;
