//! Property tests of the accelerators against an f64 brute-force reference: the BVH on every
//! SIMD path this CPU runs (`bvh_props`), its parallel builder (`bvh_build`), and resting
//! instances on every compiled backend (`resting`). Here rather than in the workspace's
//! tests/, because the references are the BVH's own internals (`bvh::testing`).

mod bvh_build;
mod bvh_props;
mod common;
mod resting;
