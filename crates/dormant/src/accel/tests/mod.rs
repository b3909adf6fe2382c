//! Property tests of the accelerators against an f64 brute-force reference: the BVH on every
//! SIMD path this CPU runs (`bvh_props`), its parallel builder (`bvh_build`), resting
//! instances on every compiled backend (`resting`), and exact reuse's change index against
//! every box and every backend's hits (`change_index_props`). Here rather than in the workspace's
//! tests/, because the references are the BVH's own internals (`bvh::testing`).

mod bvh_build;
mod bvh_props;
mod change_index_props;
mod common;
mod resting;
