//! Benchmarks that compose several domains, run side by side in one process so ratios are
//! comparable on a shared, noisy machine. Each returns a serialisable report; the CLI writes
//! it.

pub mod accel;
pub mod adaptive;
mod frame_rays;
#[cfg(feature = "embree")]
pub mod instances;
pub mod integration;
pub mod persistent_tree;
pub mod physics;
pub mod render;
pub mod reuse;

pub use accel::{bench_accel, AccelBenchOptions};
pub use adaptive::{bench_adaptive, AdaptiveBenchOptions};
#[cfg(feature = "embree")]
pub use instances::{bench_instances, InstancesBenchOptions};
pub use integration::{bench_integration, IntegrationBenchOptions};
pub use physics::{bench_physics, PhysicsBenchOptions, PhysicsBenchReport};
pub use render::{bench_render, RenderBenchOptions};
pub use reuse::{bench_reuse, ReuseBenchOptions};

use std::time::Instant;

/// `report` as JSON with `simd_path`, the BVH SIMD path that ran (`DORMANT_SIMD`): every
/// benchmark report carries it, whether printed by `--json` or written as a file.
pub fn bench_json(report: &impl serde::Serialize) -> serde_json::Value {
    let mut value = serde_json::to_value(report).expect("bench reports serialise");
    if let Some(map) = value.as_object_mut() {
        map.insert("simd_path".into(), serde_json::json!(dormant::accel::bvh::SimdPath::current()));
    }
    value
}

/// Embree with `params` (quality per scene, robust mode) on its own device, for benchmarks
/// that compare its configurations.
#[cfg(feature = "embree")]
pub(crate) fn embree_with(
    params: dormant::accel::embree::EmbreeBuildParams,
    threads: Option<usize>,
) -> Result<Box<dyn dormant::accel::Accelerator>, dormant::accel::AccelError> {
    use dormant::accel::embree::EmbreeAccel;
    use dormant_embree::Device;
    Ok(Box::new(EmbreeAccel::with_device(Device::new(threads)?, params)?))
}

/// Milliseconds `f` took, with its result.
pub(crate) fn timed<R>(f: impl FnOnce() -> R) -> (R, f64) {
    let start = Instant::now();
    let r = f();
    (r, start.elapsed().as_secs_f64() * 1e3)
}
