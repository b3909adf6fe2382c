//! `dormant bench regimes`: where integration pays. One scene (the demolition by default) is
//! simulated at several body counts, and each simulation is rendered under `never`, `always`
//! and `auto` (with and without lookahead) by every backend at several per-frame ray budgets:
//! two shaded previews over the whole run, and path-traced production frames on a few
//! settled frames. Each cell reports settled and whole-run speed-ups of `auto` over `never`
//! next to its ceiling and the integration form's measured trace penalty
//! ([`bench_integration`] does the measuring; [`write_regimes`] the table and figure), and
//! the speed-ups of exact temporal reuse, of integration and of both over rendering every
//! frame in full (`reuse.rs`; production cells on consecutive frames, where reuse works).

mod report;
mod reuse;

pub use report::{regimes_markdown, write_regimes};
pub use reuse::ReuseCell;

use std::time::Instant;

use serde::Serialize;

use crate::bench::integration::{bench_integration, IntegrationBenchOptions, IntegrationRatios};
use dormant::accel::Backend;
use dormant::physics::SimulateOptions;
use dormant::render::{DirectLighting, Integrator, PathTracer};
use dormant::residency::IntegrationForm;
use dormant::scene::file::SceneFile;
use dormant::sequence::{FrameRange, FrameSelection, Sequence, SequenceError, SequenceSource};
use reuse::ReuseCellOptions;

/// A per-frame ray budget.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Budget {
    /// Shaded preview (camera and shadow rays), 320x180, 1 spp, over the whole run.
    Preview320,
    /// Shaded preview, 640x360, 1 spp, over the whole run.
    Preview640,
    /// Path traced, 960x540, 16 spp, on a few settled frames.
    Production,
}

impl Budget {
    pub const ALL: [Budget; 3] = [Budget::Preview320, Budget::Preview640, Budget::Production];

    /// Width, height and samples per pixel.
    pub fn image(self) -> (u32, u32, u32) {
        match self {
            Budget::Preview320 => (320, 180, 1),
            Budget::Preview640 => (640, 360, 1),
            Budget::Production => (960, 540, 16),
        }
    }

    fn integrator(self) -> Box<dyn Integrator> {
        match self {
            Budget::Production => Box::new(PathTracer::default()),
            _ => Box::new(DirectLighting),
        }
    }

    /// The frames a cell renders: previews about `preview_frames` over the whole run;
    /// production `production_frames` evenly spaced over the last quarter (settled, in a
    /// scene that settles).
    fn frames(self, sequence: &Sequence, sizes: &RegimeSizes) -> Result<FrameSelection, SequenceError> {
        let n = sequence.frame_count();
        match self {
            Budget::Production => {
                let range = FrameRange { start: n - n / 4, end: n };
                Ok(sequence.evenly_spaced_in(range, sizes.production_frames))
            }
            _ => sequence.select(None, Some((n / sizes.preview_frames.max(1)).max(1))),
        }
    }

    /// The frames of a cell's reuse measurement: the previews' frames, or for production
    /// `reuse_frames` consecutive frames from the start of the last quarter.
    fn reuse_frames(self, sequence: &Sequence, sizes: &RegimeSizes) -> Result<FrameSelection, SequenceError> {
        match self {
            Budget::Production => {
                let n = sequence.frame_count();
                let start = n - n / 4;
                let range = FrameRange { start, end: (start + sizes.reuse_frames.max(1)).min(n) };
                sequence.select(Some(range), Some(1))
            }
            _ => self.frames(sequence, sizes),
        }
    }
}

/// How much each cell renders.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct RegimeSizes {
    /// Frames rendered per preview cell (the step is chosen to give about this many).
    pub preview_frames: u32,
    /// Settled frames rendered per production cell.
    pub production_frames: u32,
    /// Consecutive frames of a production cell's reuse measurement.
    pub reuse_frames: u32,
}

pub struct RegimesOptions {
    pub scene: SceneFile,
    /// Dynamic bodies per simulation (`--count`).
    pub counts: Vec<u32>,
    /// Frames to simulate (default: the scene's).
    pub frame_count: Option<u32>,
    pub backends: Vec<Backend>,
    pub budgets: Vec<Budget>,
    pub form: IntegrationForm,
    pub sizes: RegimeSizes,
    /// Production frames at 160x90 instead of 960x540 (tests).
    pub quick: bool,
    pub threads: Option<usize>,
}

/// One cell of the map.
#[derive(Clone, Debug, Serialize)]
pub struct RegimeCell {
    pub count: u32,
    pub bodies: usize,
    pub backend: Backend,
    pub budget: Budget,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub frames_rendered: u32,
    pub settled_frames: usize,
    /// Mean whole-frame ms of `never` and `auto` over all rendered frames.
    pub never_frame_ms: f64,
    pub auto_frame_ms: f64,
    pub ratios: IntegrationRatios,
    /// Exact reuse, integration and both over every frame in full.
    pub reuse: ReuseCell,
    pub wall_s: f64,
}

/// One simulation of the scene.
#[derive(Clone, Debug, Serialize)]
pub struct RegimeScene {
    pub count: u32,
    pub bodies: usize,
    pub frames: u32,
    pub simulate_s: f64,
    pub asleep_fraction_at_end: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct RegimesReport {
    pub format: &'static str,
    pub scene: String,
    pub form: IntegrationForm,
    pub threads: usize,
    pub sizes: RegimeSizes,
    pub scenes: Vec<RegimeScene>,
    pub cells: Vec<RegimeCell>,
    pub wall_s: f64,
}

/// Runs the map; `log` gets a line per simulation and cell.
pub fn bench_regimes(
    options: &RegimesOptions,
    log: &mut dyn FnMut(&str),
) -> Result<RegimesReport, SequenceError> {
    let start = Instant::now();
    let (mut scenes, mut cells) = (Vec::new(), Vec::new());
    for &count in &options.counts {
        log(&format!("simulating {count} bodies"));
        let t = Instant::now();
        let simulate = SimulateOptions { count: Some(count), frames: options.frame_count };
        let sequence =
            Sequence::load(SequenceSource::scene(options.scene.clone(), simulate, None), &mut |_| {})?;
        let islands = sequence.trajectory.island_stats();
        let scene = RegimeScene {
            count,
            bodies: sequence.trajectory.bodies.len(),
            frames: sequence.frame_count(),
            simulate_s: t.elapsed().as_secs_f64(),
            asleep_fraction_at_end: islands.asleep_fraction_at_end,
        };
        log(&format!(
            "{count} bodies: simulated {} frames in {:.0} s, {:.0}% asleep at the end",
            scene.frames,
            scene.simulate_s,
            100.0 * scene.asleep_fraction_at_end
        ));
        for &backend in &options.backends {
            for &budget in &options.budgets {
                let cell = run_cell(&sequence, count, backend, budget, options)?;
                log(&format!(
                    "{count} bodies, {backend}, {budget:?}: settled {:.2} (ceiling {:.2}), run {:.2}, auto/best {:.3}, trace penalty {:.3}; reuse {:.2} (bound {:.1}), integration {:.2}, both {:.2}; {:.0} s",
                    cell.ratios.settled_speedup,
                    cell.ratios.ceiling,
                    cell.ratios.run_speedup,
                    cell.ratios.auto_over_best,
                    cell.ratios.trace_penalty,
                    cell.reuse.reuse_speedup,
                    cell.reuse.bound,
                    cell.reuse.integration_speedup,
                    cell.reuse.both_speedup,
                    cell.wall_s
                ));
                cells.push(cell);
            }
        }
        scenes.push(scene);
    }
    Ok(RegimesReport {
        format: "dormant-regimes",
        scene: options.scene.spec().scene.name.clone(),
        form: options.form,
        threads: options.threads.unwrap_or_else(rayon::current_num_threads),
        sizes: options.sizes,
        scenes,
        cells,
        wall_s: start.elapsed().as_secs_f64(),
    })
}

/// One backend and budget on one simulation.
fn run_cell(
    sequence: &Sequence,
    count: u32,
    backend: Backend,
    budget: Budget,
    options: &RegimesOptions,
) -> Result<RegimeCell, SequenceError> {
    let t = Instant::now();
    let (width, height, spp) = match (budget, options.quick) {
        (Budget::Production, true) => (160, 90, 4),
        (budget, _) => budget.image(),
    };
    let bench = IntegrationBenchOptions {
        backend,
        frames: budget.frames(sequence, &options.sizes)?,
        width,
        height,
        spp,
        threads: options.threads,
        static_variants: false,
        forms: vec![options.form],
        cache_variants: false,
        shutter: 0.0,
    };
    let integrator = budget.integrator();
    let report = bench_integration(sequence, integrator.as_ref(), &bench, &mut |_, _| {})?;
    let reuse_options = ReuseCellOptions {
        backend,
        frames: budget.reuse_frames(sequence, &options.sizes)?,
        image: (width, height, spp),
        form: options.form,
        threads: options.threads,
    };
    let reuse = reuse::reuse_cell(sequence, integrator.as_ref(), &reuse_options)?;
    let mean = |p| report.cache_on(p).map_or(f64::NAN, |r| r.all.frame_ms);
    Ok(RegimeCell {
        count,
        bodies: report.bodies,
        backend,
        budget,
        width,
        height,
        spp,
        frames_rendered: report.frames_rendered,
        settled_frames: report.settled_frames,
        never_frame_ms: mean(dormant::residency::IntegrationPolicy::Never),
        auto_frame_ms: mean(dormant::residency::IntegrationPolicy::Auto),
        ratios: report.ratios,
        reuse,
        wall_s: t.elapsed().as_secs_f64(),
    })
}
