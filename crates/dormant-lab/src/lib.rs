//! dormant's lab: the experiments beside the product. Everything here uses the renderer
//! library's public API (`dormant`), and nothing in the library uses this crate.
//!
//! - [`bench`]: benchmarks that compose several domains and run side by side in one process,
//!   so ratios are comparable on a shared, noisy machine (accel, render, integration,
//!   instances, adaptive sampling, physics, the paper and the regime map);
//! - [`crosscheck`]: Embree against the BVH on the same rays, each disagreement judged by an
//!   exact re-intersection (`dormant verify`);
//! - [`report`]: the paper's and the regime map's reports and figures, and the plotting helpers
//!   every figure shares.

pub mod bench;
pub mod crosscheck;
pub mod report;
