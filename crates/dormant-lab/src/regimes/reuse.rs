//! A regime cell's reuse columns: the same frames rendered four ways through
//! [`Sequence::render`] (every frame in full under `never`, with exact temporal reuse, with
//! integration (`auto`), with both), so the speed-up of each over the first sits beside the
//! others. [`bench_reuse`] renders each pair in one process, in turn.

use serde::Serialize;

use crate::bench::reuse::{bench_reuse, ReuseBenchOptions, ReuseBenchReport};
use dormant::accel::Backend;
use dormant::render::{AdaptiveSampling, Integrator};
use dormant::residency::{IntegrationForm, IntegrationPolicy, IntegrationSettings};
use dormant::sequence::{FrameSelection, Sequence, SequenceError, DEFAULT_REUSE_BYTES};

/// What a cell's reuse measurement renders.
pub(super) struct ReuseCellOptions {
    pub backend: Backend,
    pub frames: FrameSelection,
    /// Width, height and samples per pixel.
    pub image: (u32, u32, u32),
    pub form: IntegrationForm,
    pub threads: Option<usize>,
}

/// Speed-ups over rendering every frame in full under `never`, on the same frames.
#[derive(Clone, Debug, Serialize)]
pub struct ReuseCell {
    pub frames: usize,
    /// Mean frame, ms: in full under `never`, with exact reuse, with `auto`, with both.
    pub full_ms: f64,
    pub reuse_ms: f64,
    pub integration_ms: f64,
    pub both_ms: f64,
    pub reuse_speedup: f64,
    pub integration_speedup: f64,
    pub both_speedup: f64,
    /// The share of camera samples exact reuse traced (under `never`), and its bound (1 over it).
    pub traced_share: f64,
    pub bound: f64,
    /// The reuse store's largest size.
    pub store_bytes: u64,
    /// Every frame with reuse was the same bits as without it, under both policies.
    pub identical: bool,
}

/// Measures `options`' frames of `sequence` the four ways.
pub(super) fn reuse_cell(
    sequence: &Sequence,
    integrator: &dyn Integrator,
    options: &ReuseCellOptions,
) -> Result<ReuseCell, SequenceError> {
    let settings =
        |policy| IntegrationSettings { policy, form: options.form, ..IntegrationSettings::default() };
    let run = |policy| {
        let (width, height, spp) = options.image;
        let bench = ReuseBenchOptions {
            backend: options.backend,
            frames: options.frames.clone(),
            width,
            height,
            spp,
            adaptive: AdaptiveSampling::OFF,
            aovs: Vec::new(),
            shutter: 0.0,
            integration: settings(policy),
            off_integration: None,
            reuse_budget: DEFAULT_REUSE_BYTES,
            threads: options.threads,
            runs: 1,
            denoiser: None,
        };
        bench_reuse(sequence, integrator, &bench, &mut |_, _, _| {})
    };
    let never = run(IntegrationPolicy::Never)?;
    let auto = run(IntegrationPolicy::Auto)?;
    Ok(cell(&never, &auto))
}

/// The cell from the runs under `never` and `auto` (each without and with reuse).
fn cell(never: &ReuseBenchReport, auto: &ReuseBenchReport) -> ReuseCell {
    let frames = never.frames.len().max(1);
    let mean = |report: &ReuseBenchReport, exact: bool| {
        report.runs.first().map_or(f64::NAN, |r| if exact { r.exact_ms } else { r.off_ms }) / frames as f64
    };
    let full_ms = mean(never, false);
    let (reuse_ms, integration_ms, both_ms) = (mean(never, true), mean(auto, false), mean(auto, true));
    ReuseCell {
        frames,
        full_ms,
        reuse_ms,
        integration_ms,
        both_ms,
        reuse_speedup: full_ms / reuse_ms,
        integration_speedup: full_ms / integration_ms,
        both_speedup: full_ms / both_ms,
        traced_share: never.traced_share,
        bound: never.bound,
        store_bytes: never.store_bytes.max(auto.store_bytes),
        identical: never.identical && auto.identical,
    }
}
