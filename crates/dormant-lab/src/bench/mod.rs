//! Benchmarks that compose several domains, run side by side in one process so ratios are
//! comparable on a shared, noisy machine. Each returns a serialisable report; the CLI writes
//! it.

pub mod accel;
pub mod adaptive;
mod frame_rays;
#[cfg(feature = "embree")]
pub mod instances;
pub mod integration;
pub mod paper;
pub mod persistent_tree;
pub mod physics;
pub mod regimes;
pub mod render;

pub use accel::{bench_accel, AccelBenchOptions};
pub use adaptive::{bench_adaptive, AdaptiveBenchOptions};
#[cfg(feature = "embree")]
pub use instances::{bench_instances, InstancesBenchOptions};
pub use integration::{bench_integration, IntegrationBenchOptions};
pub use paper::{bench_paper, PaperBenchOptions, PaperPreset, RainAssets};
pub use physics::{bench_physics, PhysicsBenchOptions, PhysicsBenchReport};
pub use regimes::{bench_regimes, Budget, RegimeSizes, RegimesOptions};
pub use render::{bench_render, RenderBenchOptions};

use std::time::Instant;

/// Embree with `params` (quality per scene, robust mode) on its own device, for benchmarks
/// that compare its configurations.
#[cfg(feature = "embree")]
pub(crate) fn embree_with(
    params: dormant::accel::embree::EmbreeBuildParams,
    threads: Option<usize>,
) -> Result<Box<dyn dormant::accel::Accelerator>, dormant::accel::AccelError> {
    use dormant::accel::embree::{Device, EmbreeAccel};
    Ok(Box::new(EmbreeAccel::with_device(Device::new(threads)?, params)?))
}

/// Milliseconds `f` took, with its result.
pub(crate) fn timed<R>(f: impl FnOnce() -> R) -> (R, f64) {
    let start = Instant::now();
    let r = f();
    (r, start.elapsed().as_secs_f64() * 1e3)
}
