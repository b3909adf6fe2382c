//! Cross-checking accelerators: the same rays through two backends, classified as agreements,
//! ties (coincident or edge-shared triangles, where either answer is right) and mismatches.
//! `dormant verify` is built on this.

mod compare;
mod rays;

pub use compare::{compare, compare_mapped, MappedQuery, Mismatch, Tolerance, VerifyReport};
pub use rays::{camera_rays, surface_rays, with_random_times};
