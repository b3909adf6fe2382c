//! Benchmarks that compose several domains, run side by side in one process so ratios are
//! comparable on a shared, noisy machine. Each returns a serialisable report; the CLI writes
//! it. (Domain-internal benchmarks, like physics stepping, live in their domain.)

pub mod accel;
pub mod adaptive;
mod frame_rays;
#[cfg(feature = "embree")]
pub mod instances;
pub mod integration;
pub mod paper;
pub mod regimes;
pub mod render;

pub(crate) use accel::{bench_accel, AccelBenchOptions};
pub(crate) use adaptive::{bench_adaptive, AdaptiveBenchOptions};
#[cfg(feature = "embree")]
pub(crate) use instances::{bench_instances, InstancesBenchOptions};
pub(crate) use integration::{bench_integration, IntegrationBenchOptions};
pub(crate) use paper::{bench_paper, PaperBenchOptions, PaperPreset, RainAssets};
pub(crate) use regimes::{bench_regimes, Budget, RegimeSizes, RegimesOptions};
pub(crate) use render::{bench_render, RenderBenchOptions};

use std::time::Instant;

/// Milliseconds `f` took, with its result.
pub(crate) fn timed<R>(f: impl FnOnce() -> R) -> (R, f64) {
    let start = Instant::now();
    let r = f();
    (r, start.elapsed().as_secs_f64() * 1e3)
}
