//! dormant's lab: the experiments beside the product. Everything here uses the renderer
//! library's public API (`dormant`), and nothing in the library uses this crate.
//!
//! - [`bench`]: benchmarks that compose several domains and run side by side in one process,
//!   so ratios are comparable on a shared, noisy machine (accel, render, integration,
//!   instances, adaptive sampling, physics);
//! - [`crosscheck`]: Embree against the BVH on the same rays, each disagreement judged by an
//!   exact re-intersection (`dormant verify`);
//! - [`paper`]: `dormant bench paper`, the paper's experiments, with its report and figures;
//! - [`regimes`]: `dormant bench regimes`, where integration pays, with its map;
//! - [`report`]: what reports share (their error, the plotting helpers every figure uses).

pub mod bench;
pub mod crosscheck;
pub mod paper;
pub mod regimes;
pub mod report;
