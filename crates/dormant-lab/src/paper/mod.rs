//! `dormant bench paper`: the paper's experiments side by side in one process. Each workload
//! (the atrium with 8,000 objects; an asset rain over a given environment, the monastery
//! variant) is simulated once, and the same trajectory is then rendered by every compiled
//! backend under `never`, `always` and `auto` with the cache on and off
//! ([`bench_integration`]), and its last frame is measured by [`bench_accel`]. The claims the
//! paper makes are checked against the measured ratios; [`write_paper`] (`report.rs`, figures in
//! `plot.rs`) turns the result into `paper.json`, `paper.md` and figures.

mod plot;
mod report;

pub use report::{paper_markdown, write_paper};

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;

use serde::Serialize;

use crate::bench::accel::{bench_accel, AccelBenchOptions, AccelBenchReport, AccelRatios};
use crate::bench::integration::{
    bench_integration, IntegrationBenchOptions, IntegrationBenchReport, IntegrationRatios,
};
use dormant::accel::Backend;
use dormant::physics::{self, IslandStats, SimulateOptions};
use dormant::render::DirectLighting;
use dormant::residency::IntegrationForm;
use dormant::scene::file::SceneFile;
use dormant::sequence::{FrameRange, Sequence, SequenceError, SequenceSource};

/// How big a run is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum PaperPreset {
    /// The paper's sizes: under 20 minutes on a 2-core machine.
    Full,
    /// Scaled down to about two minutes, for tests and a first look.
    Quick,
}

/// One workload's size.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct WorkloadSize {
    /// Dynamic objects.
    pub count: u32,
    /// Simulated frames.
    pub frames: u32,
    /// Every `frame_step`-th frame is rendered.
    pub frame_step: u32,
    /// Image of each rendered frame (shaded preview: camera and shadow rays, 1 spp).
    pub width: u32,
    pub height: u32,
    /// Primary-ray image of the accelerator benchmark on the last frame.
    pub accel_width: u32,
    pub accel_height: u32,
}

impl PaperPreset {
    /// The atrium: 8,000 objects for 1,500 frames (25 s), every third frame rendered.
    pub fn atrium(self) -> WorkloadSize {
        match self {
            PaperPreset::Full => WorkloadSize {
                count: 8000,
                frames: 1500,
                frame_step: 3,
                width: 320,
                height: 180,
                accel_width: 640,
                accel_height: 360,
            },
            // Long enough for 1,000 objects to settle, though in small islands:
            // docs/lab/paper.md#2026-11-22-the-first-committed-bench-paper-run
            PaperPreset::Quick => WorkloadSize {
                count: 1000,
                frames: 1200,
                frame_step: 6,
                width: 160,
                height: 90,
                accel_width: 160,
                accel_height: 90,
            },
        }
    }

    /// The asset rain. 2,000 objects, not the monastery scene's 8,000, which are still falling
    /// when the run ends (it would measure the fall, not the settling):
    /// docs/lab/integration.md#2026-11-22-the-baked-form-only-atrium-and-monastery-variant
    pub fn rain(self) -> WorkloadSize {
        match self {
            PaperPreset::Full => WorkloadSize {
                count: 2000,
                frames: 1800,
                frame_step: 6,
                width: 320,
                height: 180,
                accel_width: 640,
                accel_height: 360,
            },
            PaperPreset::Quick => WorkloadSize {
                count: 150,
                frames: 480,
                frame_step: 6,
                width: 160,
                height: 90,
                accel_width: 160,
                accel_height: 90,
            },
        }
    }
}

/// The assets of the monastery variant.
#[derive(Clone, Debug)]
pub struct RainAssets {
    pub env: PathBuf,
    pub objects: Vec<PathBuf>,
}

pub struct PaperBenchOptions {
    pub preset: PaperPreset,
    /// Adds the asset-rain workload.
    pub rain: Option<RainAssets>,
    /// Backends to compare (every compiled one by default).
    pub backends: Vec<Backend>,
    pub threads: Option<usize>,
}

/// One backend's run of one workload.
#[derive(Clone, Debug, Serialize)]
pub struct BackendRun {
    pub backend: Backend,
    pub wall_s: f64,
    pub integration: IntegrationBenchReport,
}

/// The ratios the integration and BVH issues name, for one workload.
#[derive(Clone, Debug, Serialize)]
pub struct WorkloadRatios {
    /// Per backend name: settled and run speedups, `auto_over_best`, `rebuild_over_insert`
    /// and the 90-99% partial-hit share.
    pub integration: BTreeMap<&'static str, IntegrationRatios>,
    /// BVH against Embree on the last frame (NaN where Embree is not compiled in).
    pub accel: AccelRatios,
}

#[derive(Clone, Debug, Serialize)]
pub struct WorkloadReport {
    pub name: String,
    pub description: String,
    pub size: WorkloadSize,
    pub bodies: usize,
    pub simulate_s: f64,
    pub islands: IslandStats,
    pub runs: Vec<BackendRun>,
    pub accel: AccelBenchReport,
    pub accel_wall_s: f64,
    pub ratios: WorkloadRatios,
}

/// How far a measurement bears a claim out.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Reproduction {
    Reproduced,
    Partly,
    NotReproduced,
    /// Nothing to measure (e.g. no cache requests).
    NoData,
}

/// One of the paper's claims against one measurement.
#[derive(Clone, Debug, Serialize)]
pub struct ClaimCheck {
    pub claim: &'static str,
    /// What the paper reports.
    pub paper: &'static str,
    /// The ratio compared, as named in paper.json.
    pub metric: &'static str,
    pub workload: String,
    pub backend: Backend,
    pub measured: f64,
    /// How the verdict is decided.
    pub rule: &'static str,
    pub verdict: Reproduction,
}

#[derive(Clone, Debug, Serialize)]
pub struct PaperReport {
    pub format: &'static str,
    pub version: u32,
    pub preset: PaperPreset,
    pub threads: usize,
    /// 1-minute load average at the start and the end (Linux), to judge the noise.
    pub load_average: [Option<f64>; 2],
    pub wall_s: f64,
    /// Each workload's ratios by name (also inside `workloads`), for scripts.
    pub ratios: BTreeMap<String, WorkloadRatios>,
    pub workloads: Vec<WorkloadReport>,
    pub claims: Vec<ClaimCheck>,
}

pub const PAPER_FORMAT: &str = "dormant-paper";
pub const PAPER_VERSION: u32 = 1;

/// Failures of a paper run, naming the workload.
#[derive(Debug, thiserror::Error)]
pub enum PaperError {
    #[error("{workload}: {source}")]
    Scene {
        workload: String,
        #[source]
        source: dormant::scene::file::SceneError,
    },
    #[error("{workload}: simulation failed: {source}")]
    Physics {
        workload: String,
        #[source]
        source: physics::PhysicsError,
    },
    #[error("{workload}, {backend}: {message}")]
    Run { workload: String, backend: String, message: String },
}

impl PaperError {
    /// Whether the input (scene or asset files) was at fault rather than the run.
    pub fn is_input(&self) -> bool {
        match self {
            // Every physics error is about the scene: a bad value, option or collider.
            PaperError::Scene { .. } | PaperError::Physics { .. } => true,
            PaperError::Run { .. } => false,
        }
    }
}

/// Runs every workload; `log` gets one line per phase and progress within renders.
pub fn bench_paper(
    options: &PaperBenchOptions,
    log: &mut dyn FnMut(&str),
) -> Result<PaperReport, PaperError> {
    let start = Instant::now();
    let load_start = load_average();
    let mut workloads = Vec::new();
    let atrium = Workload {
        name: "atrium".into(),
        description: "Sponza-like atrium, objects raining onto eight bays, a sweeper waking piles".into(),
        file: SceneFile::atrium(),
        size: options.preset.atrium(),
    };
    workloads.push(run_workload(&atrium, options, log)?);
    if let Some(rain) = &options.rain {
        let size = options.preset.rain();
        let file = SceneFile::asset_rain(&rain.env, &rain.objects, size.count, size.frames)
            .map_err(|source| PaperError::Scene { workload: "asset rain".into(), source })?;
        let names: Vec<String> =
            rain.objects.iter().map(|p| p.file_name().unwrap_or_default().to_string_lossy().into()).collect();
        let rain_workload = Workload {
            name: "rain".into(),
            description: format!(
                "{} raining onto {}",
                names.join(", "),
                rain.env.file_name().unwrap_or_default().to_string_lossy()
            ),
            file,
            size,
        };
        workloads.push(run_workload(&rain_workload, options, log)?);
    }
    let claims = workloads.iter().flat_map(check_claims).collect();
    Ok(PaperReport {
        format: PAPER_FORMAT,
        version: PAPER_VERSION,
        preset: options.preset,
        threads: options.threads.unwrap_or_else(rayon::current_num_threads),
        load_average: [load_start, load_average()],
        wall_s: start.elapsed().as_secs_f64(),
        ratios: workloads.iter().map(|w| (w.name.clone(), w.ratios.clone())).collect(),
        workloads,
        claims,
    })
}

struct Workload {
    name: String,
    description: String,
    file: SceneFile,
    size: WorkloadSize,
}

impl Workload {
    /// A failure to simulate or replay this workload.
    fn error(&self, e: SequenceError) -> PaperError {
        let workload = self.name.clone();
        match e {
            SequenceError::Scene(source) => PaperError::Scene { workload, source },
            SequenceError::Physics(source) => PaperError::Physics { workload, source },
            e => PaperError::Run { workload, backend: "all".into(), message: e.to_string() },
        }
    }
}

fn run_workload(
    w: &Workload,
    options: &PaperBenchOptions,
    log: &mut dyn FnMut(&str),
) -> Result<WorkloadReport, PaperError> {
    let size = w.size;
    log(&format!("{}: simulating {} objects for {} frames", w.name, size.count, size.frames));
    let t = Instant::now();
    let source = SequenceSource::scene(
        w.file.clone(),
        SimulateOptions { count: Some(size.count), frames: Some(size.frames) },
        None,
    );
    let sequence = Sequence::load(source, &mut |_| {}).map_err(|e| w.error(e))?;
    let simulate_s = t.elapsed().as_secs_f64();
    let islands = sequence.trajectory.island_stats();
    log(&format!(
        "{}: simulated in {simulate_s:.0} s; {:.0}% asleep at the end, {} islands formed, {} woken",
        w.name,
        100.0 * islands.asleep_fraction_at_end,
        islands.islands_formed,
        islands.islands_woken
    ));
    let mut runs = Vec::new();
    for &backend in &options.backends {
        runs.push(run_backend(w, &sequence, backend, options, log)?);
    }
    log(&format!("{}: accelerator benchmark on the last frame", w.name));
    let mut last = None;
    sequence
        .replay(&sequence.last_frame(), &mut [], &mut |frame, _| {
            last = Some(sequence.describe_frame(frame));
            Ok::<(), SequenceError>(())
        })
        .map_err(|e| w.error(e))?;
    let last = last.unwrap_or_else(|| sequence.assets.describe(0.0));
    let accel_options = AccelBenchOptions {
        width: size.accel_width,
        height: size.accel_height,
        runs: 2,
        threads: options.threads,
        ..AccelBenchOptions::default()
    };
    let t = Instant::now();
    let accel = bench_accel(&last, &accel_options).map_err(|e| PaperError::Run {
        workload: w.name.clone(),
        backend: "all".into(),
        message: e.to_string(),
    })?;
    let accel_wall_s = t.elapsed().as_secs_f64();
    let ratios = WorkloadRatios {
        integration: runs.iter().map(|r| (r.backend.name(), r.integration.ratios)).collect(),
        accel: accel.ratios.clone(),
    };
    Ok(WorkloadReport {
        name: w.name.clone(),
        description: w.description.clone(),
        size,
        bodies: sequence.trajectory.bodies.len(),
        simulate_s,
        islands,
        runs,
        accel,
        accel_wall_s,
        ratios,
    })
}

/// One backend's integration benchmark of a workload's sequence.
fn run_backend(
    w: &Workload,
    sequence: &Sequence,
    backend: Backend,
    options: &PaperBenchOptions,
    log: &mut dyn FnMut(&str),
) -> Result<BackendRun, PaperError> {
    let size = w.size;
    let frames = sequence
        .select(Some(FrameRange { start: 0, end: sequence.frame_count() }), Some(size.frame_step))
        .map_err(|e| w.error(e))?;
    let bench_options = IntegrationBenchOptions {
        backend,
        frames,
        width: size.width,
        height: size.height,
        spp: 1,
        threads: options.threads,
        static_variants: false,
        forms: IntegrationForm::ALL.to_vec(),
        cache_variants: true,
        shutter: 0.0,
    };
    let t = Instant::now();
    let mut progress = |done: u32, total: u32| {
        if done % 100 == 0 {
            log(&format!("{}, {backend}: frame {done} of {total}, every configuration", w.name));
        }
    };
    let integration =
        bench_integration(sequence, &DirectLighting, &bench_options, &mut progress).map_err(|e| {
            PaperError::Run { workload: w.name.clone(), backend: backend.to_string(), message: e.to_string() }
        })?;
    let wall_s = t.elapsed().as_secs_f64();
    log(&format!(
        "{}, {backend}: {} frames in {wall_s:.0} s; settled speedup {:.2}, run speedup {:.2}",
        w.name,
        integration.frames_rendered,
        integration.ratios.settled_speedup,
        integration.ratios.run_speedup
    ));
    Ok(BackendRun { backend, wall_s, integration })
}

/// The paper's three claims against one workload's measurements, for every backend run.
fn check_claims(w: &WorkloadReport) -> Vec<ClaimCheck> {
    let mut claims = Vec::new();
    for run in &w.runs {
        let r = &run.integration.ratios;
        let check = |claim, paper, metric, measured: f64, rule, verdict| ClaimCheck {
            claim,
            paper,
            metric,
            workload: w.name.clone(),
            backend: run.backend,
            measured,
            rule,
            verdict,
        };
        claims.push(check(
            "Integrating sleeping objects into the static scene gives a substantial frame-rate gain",
            "substantial gain once objects rest (Figure 2)",
            "settled_speedup",
            r.settled_speedup,
            "reproduced at >= 1.5, partly above 1.05",
            grade(r.settled_speedup, 1.5, 1.05),
        ));
        claims.push(check(
            "The whole run is faster with integration",
            "substantial gain",
            "run_speedup",
            r.run_speedup,
            "reproduced at >= 1.5, partly above 1.05",
            grade(r.run_speedup, 1.5, 1.05),
        ));
        claims.push(check(
            "Inserting an island is orders of magnitude faster than rebuilding the static scene",
            "orders of magnitude",
            "rebuild_over_insert",
            r.rebuild_over_insert,
            "reproduced at >= 100, partly at >= 10",
            grade(r.rebuild_over_insert, 100.0, 10.0),
        ));
        let requests = run
            .integration
            .run_of(dormant::residency::IntegrationPolicy::Auto, dormant::residency::IntegrationForm::Baked)
            .map_or(0, |p| p.cache_stats.requests);
        claims.push(check(
            "Most cache requests find 90-99% of the requested islands already integrated",
            "52% of requests at 90-99%",
            "partial_hit_90_99_fraction",
            r.partial_hit_90_99_fraction,
            "reproduced within 0.37-0.67, partly at >= 0.2",
            if requests == 0 {
                Reproduction::NoData
            } else if (0.37..=0.67).contains(&r.partial_hit_90_99_fraction) {
                Reproduction::Reproduced
            } else {
                grade(r.partial_hit_90_99_fraction, f64::INFINITY, 0.2)
            },
        ));
    }
    claims
}

fn grade(measured: f64, reproduced: f64, partly: f64) -> Reproduction {
    if measured.is_nan() {
        Reproduction::NoData
    } else if measured >= reproduced {
        Reproduction::Reproduced
    } else if measured >= partly {
        Reproduction::Partly
    } else {
        Reproduction::NotReproduced
    }
}

fn load_average() -> Option<f64> {
    std::fs::read_to_string("/proc/loadavg").ok()?.split_whitespace().next()?.parse().ok()
}
