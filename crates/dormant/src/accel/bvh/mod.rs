//! The pure-Rust BVH backend ([`BvhAccel`]), a cross-check and fallback for Embree.
//!
//! Layout, one folder per BVH type and one file per operation (all crate-private; the API is
//! the backend, its [`BuildParams`] and the persistent static tree, [`StaticBvh`]):
//! - `params`: [`BuildParams`] and its presets;
//! - `triangle`: stored triangles and the watertight ray-triangle test;
//! - `flat`: the flattened binned-SAH BVH (prototypes, top level, static blocks), its 8-wide
//!   traversal copy (boxes in structure-of-arrays layout, children nearest first for closest
//!   hits and in slot order for any-hit queries; triangle leaves in packets of four), and the
//!   traversal stack every ray query uses;
//! - [`simd`]: the SIMD paths (portable, AVX2, AVX-512), chosen at run time
//!   (`is_x86_feature_detected!`, or the `DORMANT_SIMD` environment variable) once per query,
//!   and their 8-wide box kernels;
//! - `persistent`: the static tree with incremental insertion/removal and O(1) snapshots;
//! - `two_level`: instances, the top level, the resting level, and the
//!   [`crate::accel::Accelerator`] impl;
//! - `testing` (tests only): the internals the property tests in `accel/tests/` check.
//!
//! SIMD: each query runs as one function compiled for its path (`simd::dispatch!`): the box test
//! of the 8-wide nodes uses `std::arch` AVX2 or AVX-512 intrinsics, or glam's `Vec4` on the
//! portable path; the 4-triangle leaf test is glam's `Vec4` on every path (SSE2 on x86-64,
//! VEX-encoded inside the AVX paths, NEON on aarch64, scalar elsewhere), bit for bit the
//! one-triangle watertight test.
//!
//! Hits follow Embree's conventions: `t` in units of the (unnormalised) direction, both sides
//! of triangles, barycentrics `(1-u-v)*p0 + u*p1 + v*p2`, unit world-space `ng`.

mod change_index;
mod flat;
mod params;
mod persistent;
pub(crate) mod simd;
#[cfg(test)]
pub(crate) mod testing;
mod triangle;
mod two_level;

pub(crate) use change_index::{ChangeBox, ChangeIndex, ChangeShape, EXACT_MESH_TRIANGLES};
pub use params::BuildParams;
pub use persistent::{StaticBvh, StaticSnapshot};
pub use simd::SimdPath;
pub use two_level::BvhAccel;
