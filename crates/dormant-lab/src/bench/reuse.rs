//! `dormant bench reuse`: one sequence rendered every frame in full (`--reuse off`) and with
//! exact temporal reuse, in one process, in turn (the order alternates from run to run, so a
//! slower stretch of a shared machine falls on both), through [`Sequence::render`], the loop
//! `dormant render` runs. Per run it reports the speed-up of the whole sequence beside its
//! bound (1 / the share of camera samples traced), the first, fully traced frame against the
//! same frame without reuse, the horizon queries' share of the tracing they decide about, the
//! store's memory, and whether every frame's image and AOVs are the same bits in both modes.
//! With a denoiser, every frame is also denoised as `dormant render --denoise` does, within
//! its frame's time.

use std::time::Instant;

use serde::Serialize;

use dormant::accel::Backend;
use dormant::render::denoise::{Denoiser, GUIDE_AOVS};
use dormant::render::{AdaptiveSampling, Aov, Film, Integrator};
use dormant::residency::IntegrationSettings;
use dormant::sequence::stats::ReuseRecord;
use dormant::sequence::{
    FrameRenderer, FrameSelection, RenderedFrame, ReuseMode, SeedMode, Sequence, SequenceError,
};

/// What to run.
pub struct ReuseBenchOptions {
    pub backend: Backend,
    pub frames: FrameSelection,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub adaptive: AdaptiveSampling,
    pub aovs: Vec<Aov>,
    pub shutter: f32,
    pub integration: IntegrationSettings,
    /// The integration of the run without reuse, when it differs (the preview's target
    /// compares reuse and integration together against neither).
    pub off_integration: Option<IntegrationSettings>,
    pub reuse_budget: usize,
    pub threads: Option<usize>,
    /// Runs of each mode (the spread of the speed-up is over these).
    pub runs: usize,
    /// Denoise every frame (its guides are rendered with it).
    pub denoiser: Option<Denoiser>,
}

/// One frame of one mode's run.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct ReuseFrame {
    pub frame: u32,
    /// Wall time from the previous frame handed on to this one: replay, residency, tracing.
    pub frame_ms: f64,
    pub trace_ms: f64,
    pub samples_traced: u64,
    pub samples_reused: u64,
    /// Rays traced, and of them camera rays traced only as packet neighbours of due samples.
    pub rays: u64,
    pub neighbour_rays: u64,
    pub horizon_ms: f64,
    pub store_bytes: u64,
    /// Seconds the denoiser took, within `frame_ms`.
    pub denoise_ms: f64,
    /// FNV-1a of the image's and the AOVs' float bits.
    #[serde(skip)]
    pub digest: u64,
}

/// One run of both modes.
#[derive(Clone, Debug, Serialize)]
pub struct ReuseRun {
    pub off_ms: f64,
    pub exact_ms: f64,
    /// `off_ms` over `exact_ms`.
    pub speedup: f64,
    /// The first frame's time with exact reuse over without it (both trace it in full).
    pub first_frame_ratio: f64,
    /// Whether every frame's image and AOVs were the same bits in both modes.
    pub identical: bool,
}

/// Min, median and max over runs.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Spread {
    pub min: f64,
    pub median: f64,
    pub max: f64,
}

impl Spread {
    fn of(mut values: Vec<f64>) -> Self {
        values.sort_by(f64::total_cmp);
        match values.len() {
            0 => Self::default(),
            n => Self { min: values[0], median: values[n / 2], max: values[n - 1] },
        }
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct ReuseBenchReport {
    pub scene: String,
    pub backend: Backend,
    pub frames: Vec<u32>,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub adaptive: bool,
    /// The integration of the exact run and of the run without reuse.
    pub integration: IntegrationSettings,
    pub off_integration: IntegrationSettings,
    pub runs: Vec<ReuseRun>,
    pub speedup: Spread,
    /// 1 / the share of camera samples traced over the whole sequence: the speed-up if
    /// tracing were all a frame costs and reused samples cost nothing.
    pub bound: f64,
    /// The median speed-up over `bound`.
    pub of_bound: f64,
    pub traced_share: f64,
    pub first_frame_ratio: Spread,
    /// Horizon queries' CPU time over the rest of the tracing's CPU time (trace time times
    /// the threads), in the frames after the first: what deciding costs against what it
    /// decides about.
    pub horizon_share: f64,
    /// What the traced samples cost in rays, in the frames after the first.
    pub rays: RayCosts,
    pub store_bytes: u64,
    /// Every run's frames were the same bits with and without reuse.
    pub identical: bool,
    /// Per frame of the last run: the share of samples traced, and both modes' frame times.
    pub per_frame: Vec<FrameComparison>,
    /// With a denoiser, its label; the frame times include denoising.
    pub denoise: Option<&'static str>,
}

#[derive(Clone, Copy, Debug, Serialize)]
pub struct FrameComparison {
    pub frame: u32,
    pub traced_share: f64,
    pub off_ms: f64,
    pub exact_ms: f64,
    /// Of which the denoiser's, with one.
    pub off_denoise_ms: f64,
    pub exact_denoise_ms: f64,
    /// Rays the exact run traced, and of them camera rays of packet neighbours.
    pub exact_rays: u64,
    pub neighbour_rays: u64,
    /// The image and AOVs are the same bits in both modes.
    pub identical: bool,
}

/// Rays per camera sample in the frames after the first: a traced sample's under exact
/// reuse (its own rays, the neighbours' camera rays apart) against a sample's in a full frame.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct RayCosts {
    /// The exact run's rays but the neighbours', over its samples traced.
    pub per_traced_sample: f64,
    /// The run without reuse's rays over its samples.
    pub per_sample_off: f64,
    /// The neighbours' camera rays, of all the exact run's rays.
    pub neighbour_share: f64,
}

impl RayCosts {
    fn of(off: &[ReuseFrame], exact: &[ReuseFrame]) -> Self {
        let sum = |frames: &[ReuseFrame], f: fn(&ReuseFrame) -> u64| frames.iter().map(f).sum::<u64>() as f64;
        let (off, exact) = (off.get(1..).unwrap_or_default(), exact.get(1..).unwrap_or_default());
        let (rays, neighbours) = (sum(exact, |f| f.rays), sum(exact, |f| f.neighbour_rays));
        let samples_off = sum(off, |f| f.samples_traced + f.samples_reused);
        RayCosts {
            per_traced_sample: (rays - neighbours) / sum(exact, |f| f.samples_traced).max(1.0),
            per_sample_off: sum(off, |f| f.rays) / samples_off.max(1.0),
            neighbour_share: neighbours / rays.max(1.0),
        }
    }
}

/// See the module docs. `progress` gets (run, mode, frames done) as frames finish.
pub fn bench_reuse(
    sequence: &Sequence,
    integrator: &dyn Integrator,
    options: &ReuseBenchOptions,
    progress: &mut dyn FnMut(usize, ReuseMode, usize),
) -> Result<ReuseBenchReport, SequenceError> {
    let mut runs = Vec::new();
    let mut last = (Vec::new(), Vec::new());
    for run in 0..options.runs.max(1) {
        let order = if run % 2 == 0 {
            [ReuseMode::Off, ReuseMode::Exact]
        } else {
            [ReuseMode::Exact, ReuseMode::Off]
        };
        let (mut off, mut exact) = (Vec::new(), Vec::new());
        for mode in order {
            let frames = render_mode(sequence, integrator, options, mode, &mut |n| progress(run, mode, n))?;
            match mode {
                ReuseMode::Off => off = frames,
                _ => exact = frames,
            }
        }
        runs.push(compare(&off, &exact));
        last = (off, exact);
    }
    Ok(report(sequence, options, runs, &last.0, &last.1))
}

/// Renders the selection with `mode`; returns each frame's times, counts and digest.
fn render_mode(
    sequence: &Sequence,
    integrator: &dyn Integrator,
    options: &ReuseBenchOptions,
    mode: ReuseMode,
    progress: &mut dyn FnMut(usize),
) -> Result<Vec<ReuseFrame>, SequenceError> {
    let integration = match mode {
        ReuseMode::Off => options.off_integration.unwrap_or(options.integration),
        _ => options.integration,
    };
    let manager_options = sequence.manager_options(&options.frames, integration);
    let mut manager = sequence.manager(options.backend, options.threads, manager_options)?;
    // A denoiser's guides are rendered when the passes asked for do not include them.
    let guides = options.denoiser.as_ref().map_or(&[][..], |_| &GUIDE_AOVS[..]);
    let aovs: Vec<Aov> =
        options.aovs.iter().chain(guides.iter().filter(|g| !options.aovs.contains(g))).copied().collect();
    let renderer = FrameRenderer {
        aovs: &aovs,
        adaptive: options.adaptive,
        seed: SeedMode::Fixed,
        reuse: mode,
        reuse_budget: options.reuse_budget,
        shutter: options.shutter,
        ..FrameRenderer::new(integrator, options.width, options.height, options.spp)
    };
    let mut frames = Vec::new();
    let mut since = Instant::now();
    sequence.render::<SequenceError>(&options.frames, &mut manager, &renderer, &[], &mut |f, _, _| {
        let denoise_ms = match &options.denoiser {
            Some(denoiser) => denoise(denoiser, f)? * 1e3,
            None => 0.0,
        };
        let reuse = ReuseRecord::of(f);
        frames.push(ReuseFrame {
            frame: f.index,
            frame_ms: since.elapsed().as_secs_f64() * 1e3,
            trace_ms: f.render.seconds * 1e3,
            samples_traced: reuse.samples_traced,
            samples_reused: reuse.samples_reused,
            rays: f.render.rays,
            neighbour_rays: reuse.neighbour_rays,
            horizon_ms: reuse.horizon_ms,
            store_bytes: reuse.reuse_store_bytes,
            denoise_ms,
            digest: digest(&f.film, &f.aovs),
        });
        progress(frames.len());
        since = Instant::now();
        Ok(())
    })?;
    Ok(frames)
}

/// `frame`'s image through `denoiser`, guided by its albedo and normal passes: the seconds
/// that took (the image is dropped, as the frame times are what is measured).
fn denoise(denoiser: &Denoiser, frame: &RenderedFrame) -> Result<f64, SequenceError> {
    let guide = |kind: Aov| {
        frame.aovs.iter().find(|(a, _)| *a == kind).map(|(_, f)| f).expect("render_mode adds the guides")
    };
    Ok(denoiser.denoise(&frame.film, guide(Aov::Albedo), guide(Aov::Normal))?.1)
}

/// FNV-1a over the float bits of `film` and every AOV but `traced`, which differs by design.
fn digest(film: &Film, aovs: &[(Aov, Film)]) -> u64 {
    let films = std::iter::once(film).chain(aovs.iter().filter(|(a, _)| *a != Aov::Traced).map(|(_, f)| f));
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    for value in films.flat_map(|f| f.pixels.iter().flat_map(|p| p.to_array())) {
        for byte in value.to_bits().to_le_bytes() {
            hash = (hash ^ u64::from(byte)).wrapping_mul(0x0100_0000_01b3);
        }
    }
    hash
}

/// One run's comparison of the two modes.
fn compare(off: &[ReuseFrame], exact: &[ReuseFrame]) -> ReuseRun {
    let total = |frames: &[ReuseFrame]| frames.iter().map(|f| f.frame_ms).sum::<f64>();
    let (off_ms, exact_ms) = (total(off), total(exact));
    let first = |frames: &[ReuseFrame]| frames.first().map_or(f64::NAN, |f| f.frame_ms);
    ReuseRun {
        off_ms,
        exact_ms,
        speedup: off_ms / exact_ms,
        first_frame_ratio: first(exact) / first(off),
        identical: off.len() == exact.len() && off.iter().zip(exact).all(|(a, b)| a.digest == b.digest),
    }
}

/// The report of `runs`, with the per-frame table of the last run's `off` and `exact`.
fn report(
    sequence: &Sequence,
    options: &ReuseBenchOptions,
    runs: Vec<ReuseRun>,
    off: &[ReuseFrame],
    exact: &[ReuseFrame],
) -> ReuseBenchReport {
    let traced: u64 = exact.iter().map(|f| f.samples_traced).sum();
    let reused: u64 = exact.iter().map(|f| f.samples_reused).sum();
    let traced_share = traced as f64 / (traced + reused).max(1) as f64;
    let speedup = Spread::of(runs.iter().map(|r| r.speedup).collect());
    let later = exact.get(1..).unwrap_or_default();
    let horizon: f64 = later.iter().map(|f| f.horizon_ms).sum();
    let trace_cpu: f64 = later.iter().map(|f| f.trace_ms).sum::<f64>() * rayon::current_num_threads() as f64;
    let per_frame = off
        .iter()
        .zip(exact)
        .map(|(o, e)| FrameComparison {
            frame: e.frame,
            traced_share: e.samples_traced as f64 / (e.samples_traced + e.samples_reused).max(1) as f64,
            off_ms: o.frame_ms,
            exact_ms: e.frame_ms,
            off_denoise_ms: o.denoise_ms,
            exact_denoise_ms: e.denoise_ms,
            exact_rays: e.rays,
            neighbour_rays: e.neighbour_rays,
            identical: o.digest == e.digest,
        })
        .collect();
    ReuseBenchReport {
        scene: sequence.template.name.clone(),
        backend: options.backend,
        frames: options.frames.frames(),
        width: options.width,
        height: options.height,
        spp: options.spp,
        adaptive: options.adaptive.is_on(),
        integration: options.integration,
        off_integration: options.off_integration.unwrap_or(options.integration),
        identical: runs.iter().all(|r| r.identical),
        first_frame_ratio: Spread::of(runs.iter().map(|r| r.first_frame_ratio).collect()),
        runs,
        bound: 1.0 / traced_share,
        of_bound: speedup.median * traced_share,
        traced_share,
        speedup,
        horizon_share: if trace_cpu > horizon { horizon / (trace_cpu - horizon) } else { f64::NAN },
        rays: RayCosts::of(off, exact),
        store_bytes: exact.iter().map(|f| f.store_bytes).max().unwrap_or(0),
        per_frame,
        denoise: options.denoiser.as_ref().map(Denoiser::label),
    }
}
