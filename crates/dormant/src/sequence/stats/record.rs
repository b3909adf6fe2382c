//! The statistics model of a rendered sequence: one [`FrameRecord`] per frame and a
//! [`Summary`], written as `stats.json` and `stats.csv` (docs/stats-format.md).

use std::io::Write;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::StatsError;
use crate::render::reuse::{FullFrame, ReuseGranularity};
use crate::render::{RenderStats, SppStats};
use crate::residency::{CacheStats, CostModelState, Decision, FrameStats, StageTimes};
use crate::sequence::{trace_kind, KeptFrame, PhysicsSource, RenderedFrame};

/// `format` field of stats.json.
pub(crate) const STATS_FORMAT: &str = "dormant-stats";
/// `version` field of stats.json; bumped when a field changes meaning or goes away.
pub(crate) const STATS_VERSION: u32 = 2;

/// One rendered frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrameRecord {
    pub frame: u32,
    /// Physics step of this frame, ms; `None` when the frames are replayed from a trajectory.
    pub physics_ms: Option<f64>,
    #[serde(flatten)]
    pub stages: StageTimes,
    /// update + integrate + reactivate + commit + trace (physics not included).
    pub frame_ms: f64,
    pub rays: u64,
    pub mrays_per_second: f64,
    /// Camera samples per pixel of the main image (`spp_mean`, `spp_min`, `spp_max`): with
    /// adaptive sampling the effective spp, else `spp` each; 0 for a reused frame. Absent in
    /// runs from before adaptive sampling (read as 0).
    #[serde(flatten, default)]
    pub samples: SppStats,
    pub(crate) committed: bool,
    pub instances: usize,
    pub integrated_islands: usize,
    pub(crate) sleeping_islands: usize,
    pub baked_bodies: usize,
    pub resting_bodies: usize,
    pub rest_rebuilt: bool,
    /// The previous image again: nothing visible changed, nothing was traced.
    pub reused: bool,
    pub(crate) islands_slept: u32,
    pub islands_woke: u32,
    pub islands_integrated: u32,
    pub islands_reactivated: u32,
    pub cache_full: u64,
    pub cache_partial: u64,
    pub cache_miss: u64,
    pub decisions: Vec<Decision>,
    /// What was traced and what reused. Absent in runs from before exact reuse (read as 0).
    #[serde(flatten, default)]
    pub reuse: ReuseRecord,
}

/// A frame's samples traced and reused, and with exact temporal reuse what that cost.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ReuseRecord {
    /// Camera samples traced this frame, and taken from earlier frames (every sample of a
    /// frame that reused the previous image).
    #[serde(default)]
    pub samples_traced: u64,
    #[serde(default)]
    pub samples_reused: u64,
    /// Pixels traced (exact reuse; every pixel without it).
    #[serde(default)]
    pub pixels_traced: u64,
    /// Time of the horizon queries, ms (exact reuse).
    #[serde(default)]
    pub horizon_ms: f64,
    /// Of the frame's `rays`, camera rays traced only because a due sample shared their
    /// packet, their own samples taken from the store; the rest are the traced samples' rays
    /// (exact reuse).
    #[serde(default)]
    pub neighbour_rays: u64,
    /// Bytes the reuse store holds (exact reuse).
    #[serde(default)]
    pub reuse_store_bytes: u64,
    /// Why exact reuse traced every pixel of this frame; `null` when it reused pixels, or
    /// without exact reuse.
    #[serde(default)]
    pub full_frame: Option<FullFrame>,
    /// What exact reuse's store kept, so what it retraced: every `sample`, or one value per
    /// `pixel` (adaptive sampling, or a budget too small for samples); `null` without it.
    #[serde(default)]
    pub reuse_granularity: Option<ReuseGranularity>,
}

impl ReuseRecord {
    /// What `frame` traced and reused.
    pub fn of(frame: &RenderedFrame) -> Self {
        if let Some(exact) = frame.reuse {
            let s = exact.stats;
            return Self {
                samples_traced: s.samples_traced,
                samples_reused: s.samples_reused,
                pixels_traced: s.pixels_traced,
                horizon_ms: s.horizon_ms,
                neighbour_rays: s.neighbour_rays,
                reuse_store_bytes: s.store_bytes,
                full_frame: exact.full,
                reuse_granularity: Some(s.granularity),
            };
        }
        let samples = frame.render.camera_samples(frame.film.width, frame.film.height);
        match frame.reused_from {
            Some(_) => Self { samples_reused: samples, ..Self::default() },
            None => Self { samples_traced: samples, ..Self::default() },
        }
    }

    /// The share of the frame's samples that were traced (1 when it has none).
    pub fn traced_share(&self) -> f64 {
        let total = self.samples_traced + self.samples_reused;
        if total == 0 {
            1.0
        } else {
            self.samples_traced as f64 / total as f64
        }
    }
}

impl FrameRecord {
    /// The record of `frame`: the manager's statistics, the renderer's (ray rate, samples per
    /// pixel, what was traced and reused) and, when the simulation ran in this process, its
    /// physics step time.
    pub fn of(frame: &RenderedFrame, stats: &FrameStats, physics_ms: Option<f64>) -> Self {
        Self { reuse: ReuseRecord::of(frame), ..Self::new(stats, &frame.render, physics_ms) }
    }

    /// The record of a frame from the manager's and the renderer's statistics, nothing reused.
    pub(crate) fn new(stats: &FrameStats, render: &RenderStats, physics_ms: Option<f64>) -> Self {
        FrameRecord {
            frame: stats.frame,
            physics_ms,
            stages: stats.stages,
            frame_ms: stats.frame_ms(),
            rays: stats.rays,
            mrays_per_second: render.mrays_per_second(),
            samples: render.spp,
            committed: stats.committed,
            instances: stats.instances,
            integrated_islands: stats.integrated_islands,
            sleeping_islands: stats.sleeping_islands,
            baked_bodies: stats.baked_bodies,
            resting_bodies: stats.resting_bodies,
            rest_rebuilt: stats.rest_rebuilt,
            reused: stats.reused,
            islands_slept: stats.islands_slept,
            islands_woke: stats.islands_woke,
            islands_integrated: stats.islands_integrated,
            islands_reactivated: stats.islands_reactivated,
            cache_full: stats.cache_full,
            cache_partial: stats.cache_partial,
            cache_miss: stats.cache_miss,
            decisions: stats.decisions.clone(),
            reuse: ReuseRecord::default(),
        }
    }

    /// What `render --resume` needs of this frame, finished by an earlier run, to bring the
    /// scene manager through it as that run did.
    pub fn kept(&self) -> KeptFrame {
        KeptFrame {
            index: self.frame,
            reused: self.reused,
            decisions: self.decisions.iter().map(|d| (d.island, d.integrate)).collect(),
            trace_ms: self.stages.trace_ms,
            rays: self.rays,
            trace_kind: trace_kind(self.reuse.full_frame),
            instances: self.instances,
            integrated_islands: self.integrated_islands,
            sleeping_islands: self.sleeping_islands,
        }
    }

    /// Decisions to integrate, and to decline.
    pub(crate) fn decision_counts(&self) -> (usize, usize) {
        let yes = self.decisions.iter().filter(|d| d.integrate).count();
        (yes, self.decisions.len() - yes)
    }

    /// The cost model's estimated net saving summed over this frame's decisions, ms.
    pub(crate) fn estimated_net_ms(&self) -> f64 {
        // `+ 0.0` turns an empty sum's -0 into 0.
        self.decisions.iter().filter_map(|d| d.estimate.map(|e| e.net_ms())).sum::<f64>() + 0.0
    }
}

/// What was rendered, for the header of stats.json: everything that decides a run's images
/// and statistics, so that `render --resume` continues only the same run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunInfo {
    pub scene: String,
    pub backend: String,
    pub mode: String,
    pub integration: String,
    /// `baked` or `resting`.
    pub integrate_as: String,
    pub cache_enabled: bool,
    pub lookahead: bool,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    /// `--noise-threshold` (adaptive sampling; 0 off). Absent in runs from before it: 0.
    #[serde(default)]
    pub noise_threshold: f32,
    /// Adaptive sampling's minimum samples per pixel; `None` when it is off.
    #[serde(default)]
    pub min_spp: Option<u32>,
    pub physics: PhysicsSource,
    /// The simulated scene (scene file and overrides): the trajectory's scene hash, 16 hex
    /// digits.
    pub scene_hash: String,
    /// Frames the trajectory holds.
    pub trajectory_frames: u32,
    /// The rendered frames: every `frame_step`-th frame of `frame_start..frame_end`, counted
    /// from frame 0.
    pub frame_start: u32,
    pub frame_end: u32,
    pub frame_step: u32,
    /// Longest path in `path` mode; `None` in the other modes.
    pub max_depth: Option<u32>,
    /// `--clamp-indirect` (0: off; used in `path` mode only). Absent in runs from before it,
    /// which clamped at 4.
    #[serde(default = "default_clamp_indirect")]
    pub clamp_indirect: f32,
    /// `--filter` and its width in pixels. Absent in runs from before them: the tent of
    /// radius 1.
    #[serde(default = "default_filter")]
    pub filter: String,
    #[serde(default = "default_filter_width")]
    pub filter_width: f32,
    /// `fixed` or `per-frame`.
    pub seed: String,
    /// `--seed-offset`. Absent in runs from before it: 0.
    #[serde(default)]
    pub seed_offset: u32,
    /// Any reuse: `--reuse static` or `exact`.
    pub reuse: bool,
    /// `--reuse`: `off`, `static` or `exact`. Absent in runs from before exact reuse, which
    /// reused only static frames.
    #[serde(default = "static_reuse")]
    pub reuse_mode: String,
    pub exposure: f32,
    /// Extra passes (`--aov`), in request order.
    pub aovs: Vec<String>,
    pub exr: bool,
    /// `--denoise`: `null` off, `oidn`, or `oidn-prefilter` (`--denoise-prefilter`), either
    /// followed by `-balanced` or `-fast` (`--denoise-quality`). Absent in runs from before
    /// denoising, which did not denoise.
    #[serde(default)]
    pub denoise: Option<String>,
    /// `--keep-noisy`.
    #[serde(default)]
    pub keep_noisy: bool,
    /// Motion blur's shutter (`--shutter` or the scene's `render.shutter`); 0 in runs from
    /// before motion blur, which had none.
    #[serde(default)]
    pub shutter: f32,
    /// Where each of `dormant render`'s settings came from, by setting (`size`, `spp`,
    /// `mode`, `frame_step`, `noise_threshold`, `min_spp`, `shutter`): `flag`, `preset`,
    /// `scene` or `default`. Not part of what `--resume` compares: the same values from
    /// elsewhere make the same images. Absent in runs from before it.
    #[serde(default)]
    pub settings_from: std::collections::BTreeMap<String, String>,
}

/// `clamp_indirect` of runs from before `--clamp-indirect`.
fn default_clamp_indirect() -> f32 {
    4.0
}

/// `filter` of runs from before `--filter`.
fn default_filter() -> String {
    "tent".into()
}

/// `filter_width` of runs from before `--filter-width`.
fn default_filter_width() -> f32 {
    1.0
}

/// `reuse_mode` of runs from before exact reuse.
fn static_reuse() -> String {
    "static".into()
}

/// Sums over the run.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub(crate) struct Totals {
    /// Physics of the whole simulation (every simulated frame, rendered or not), ms; `None`
    /// when replayed from a trajectory.
    pub physics_ms: Option<f64>,
    #[serde(flatten)]
    pub stages: StageTimes,
    pub frame_ms: f64,
    pub rays: u64,
    pub(crate) islands_slept: u64,
    pub islands_woke: u64,
    pub islands_integrated: u64,
    pub islands_reactivated: u64,
    /// Frames that rebuilt the resting scene.
    pub rest_rebuilds: u64,
    /// Frames that reused the previous image.
    pub(crate) reused_frames: u64,
    /// Camera samples traced and reused over the run.
    pub samples_traced: u64,
    pub samples_reused: u64,
    /// Horizon queries of exact reuse, ms.
    pub horizon_ms: f64,
    /// Of `rays`, camera rays traced only as packet neighbours of due samples (exact reuse).
    pub neighbour_rays: u64,
    pub cache_full: u64,
    pub cache_partial: u64,
    pub cache_miss: u64,
    pub decisions_integrate: u64,
    pub decisions_decline: u64,
}

/// Per-frame medians of each stage, ms.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Medians {
    pub physics_ms: Option<f64>,
    /// Each stage's own median.
    #[serde(flatten)]
    pub stages: StageTimes,
    /// The median frame (not the sum of the stages' medians).
    pub frame_ms: f64,
}

/// The geometry cache at the end of the run, with the labels of its histogram.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CacheSummary {
    #[serde(flatten)]
    pub stats: CacheStats,
    /// Labels of `fraction_histogram`'s buckets, in order.
    pub(crate) fraction_buckets: Vec<&'static str>,
}

/// The `summary` block of stats.json.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Summary {
    pub frames: usize,
    pub first_frame: Option<u32>,
    pub last_frame: Option<u32>,
    pub(crate) totals: Totals,
    pub median: Medians,
    pub cache: CacheSummary,
    pub cost_model: CostModelState,
}

/// Everything stats.json holds.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RunStats {
    pub format: &'static str,
    pub version: u32,
    pub run: RunInfo,
    pub frames: Vec<FrameRecord>,
    pub summary: Summary,
}

/// The median (the mean of the middle two for an even count); 0 for none.
pub fn median(mut values: Vec<f64>) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    }
}

/// How a CSV column's cell is written from a frame.
#[derive(Clone, Copy)]
enum Cell {
    /// A stage time, ms.
    Stage(fn(&StageTimes) -> f64),
    Text(fn(&FrameRecord) -> String),
}

/// The CSV columns, in order: the one list both the header and every row come from.
fn csv_columns() -> Vec<(&'static str, Cell)> {
    let mut columns: Vec<(&'static str, Cell)> = vec![
        ("frame", Cell::Text(|f| f.frame.to_string())),
        ("physics_ms", Cell::Text(|f| f.physics_ms.map(|v| format!("{v:.4}")).unwrap_or_default())),
    ];
    columns.extend(StageTimes::STAGES.map(|(name, get)| (name, Cell::Stage(get))));
    let rest: [(&'static str, Cell); 24] = [
        ("frame_ms", Cell::Text(|f| format!("{:.4}", f.frame_ms))),
        ("rays", Cell::Text(|f| f.rays.to_string())),
        ("mrays_per_second", Cell::Text(|f| format!("{:.3}", f.mrays_per_second))),
        ("spp_mean", Cell::Text(|f| format!("{:.3}", f.samples.mean))),
        ("spp_min", Cell::Text(|f| f.samples.min.to_string())),
        ("spp_max", Cell::Text(|f| f.samples.max.to_string())),
        ("committed", Cell::Text(|f| f.committed.to_string())),
        ("instances", Cell::Text(|f| f.instances.to_string())),
        ("integrated_islands", Cell::Text(|f| f.integrated_islands.to_string())),
        ("sleeping_islands", Cell::Text(|f| f.sleeping_islands.to_string())),
        ("baked_bodies", Cell::Text(|f| f.baked_bodies.to_string())),
        ("resting_bodies", Cell::Text(|f| f.resting_bodies.to_string())),
        ("rest_rebuilt", Cell::Text(|f| f.rest_rebuilt.to_string())),
        ("reused", Cell::Text(|f| f.reused.to_string())),
        ("islands_slept", Cell::Text(|f| f.islands_slept.to_string())),
        ("islands_woke", Cell::Text(|f| f.islands_woke.to_string())),
        ("islands_integrated", Cell::Text(|f| f.islands_integrated.to_string())),
        ("islands_reactivated", Cell::Text(|f| f.islands_reactivated.to_string())),
        ("cache_full", Cell::Text(|f| f.cache_full.to_string())),
        ("cache_partial", Cell::Text(|f| f.cache_partial.to_string())),
        ("cache_miss", Cell::Text(|f| f.cache_miss.to_string())),
        ("decisions", Cell::Text(|f| f.decisions.len().to_string())),
        ("decisions_integrate", Cell::Text(|f| f.decision_counts().0.to_string())),
        ("decisions_decline", Cell::Text(|f| f.decision_counts().1.to_string())),
    ];
    columns.extend(rest);
    columns.push(("estimated_net_ms", Cell::Text(|f| format!("{:.4}", f.estimated_net_ms()))));
    columns.extend([
        ("samples_traced", Cell::Text(|f| f.reuse.samples_traced.to_string())),
        ("samples_reused", Cell::Text(|f| f.reuse.samples_reused.to_string())),
        ("traced_share", Cell::Text(|f| format!("{:.5}", f.reuse.traced_share()))),
        ("pixels_traced", Cell::Text(|f| f.reuse.pixels_traced.to_string())),
        ("horizon_ms", Cell::Text(|f| format!("{:.4}", f.reuse.horizon_ms))),
        ("neighbour_rays", Cell::Text(|f| f.reuse.neighbour_rays.to_string())),
        ("reuse_store_bytes", Cell::Text(|f| f.reuse.reuse_store_bytes.to_string())),
        ("full_frame", Cell::Text(|f| f.reuse.full_frame.map(|r| r.name()).unwrap_or_default().to_string())),
        (
            "reuse_granularity",
            Cell::Text(|f| f.reuse.reuse_granularity.map(|g| g.name()).unwrap_or_default().to_string()),
        ),
    ]);
    columns
}

impl RunStats {
    /// The statistics of a run: its frames, the cache and cost model at the end, and the
    /// physics time of the whole simulation when it ran in this process.
    pub(crate) fn new(
        run: RunInfo,
        frames: Vec<FrameRecord>,
        cache: CacheStats,
        cost_model: CostModelState,
        physics_total_ms: Option<f64>,
    ) -> Self {
        let mut totals = Totals { physics_ms: physics_total_ms, ..Totals::default() };
        for f in &frames {
            totals.stages += f.stages;
            totals.frame_ms += f.frame_ms;
            totals.rays += f.rays;
            totals.islands_slept += u64::from(f.islands_slept);
            totals.islands_woke += u64::from(f.islands_woke);
            totals.islands_integrated += u64::from(f.islands_integrated);
            totals.islands_reactivated += u64::from(f.islands_reactivated);
            totals.rest_rebuilds += u64::from(f.rest_rebuilt);
            totals.reused_frames += u64::from(f.reused);
            totals.samples_traced += f.reuse.samples_traced;
            totals.samples_reused += f.reuse.samples_reused;
            totals.horizon_ms += f.reuse.horizon_ms;
            totals.neighbour_rays += f.reuse.neighbour_rays;
            totals.cache_full += f.cache_full;
            totals.cache_partial += f.cache_partial;
            totals.cache_miss += f.cache_miss;
            let (yes, no) = f.decision_counts();
            totals.decisions_integrate += yes as u64;
            totals.decisions_decline += no as u64;
        }
        let physics: Vec<f64> = frames.iter().filter_map(|f| f.physics_ms).collect();
        let median = Medians {
            physics_ms: (!physics.is_empty()).then(|| self::median(physics)),
            stages: StageTimes::from_fn(|get| self::median(frames.iter().map(|f| get(&f.stages)).collect())),
            frame_ms: self::median(frames.iter().map(|f| f.frame_ms).collect()),
        };
        let summary = Summary {
            frames: frames.len(),
            first_frame: frames.first().map(|f| f.frame),
            last_frame: frames.last().map(|f| f.frame),
            totals,
            median,
            cache: CacheSummary { stats: cache, fraction_buckets: CacheStats::FRACTION_BUCKETS.to_vec() },
            cost_model,
        };
        RunStats { format: STATS_FORMAT, version: STATS_VERSION, run, frames, summary }
    }

    /// One header line, then one line per frame (decisions as counts).
    /// Writes stats.csv's table: a header, then a row per frame.
    fn write_csv(&self, w: &mut dyn Write) -> std::io::Result<()> {
        let columns = csv_columns();
        let header = columns.iter().map(|(name, _)| *name).collect::<Vec<_>>().join(",");
        writeln!(w, "{header}")?;
        for f in &self.frames {
            for (i, (_, cell)) in columns.iter().enumerate() {
                let separator = if i == 0 { "" } else { "," };
                match cell {
                    Cell::Stage(get) => write!(w, "{separator}{:.4}", get(&f.stages))?,
                    Cell::Text(text) => write!(w, "{separator}{}", text(f))?,
                }
            }
            writeln!(w)?;
        }
        Ok(())
    }

    /// Writes `stats.json` and `stats.csv` into `dir`, each atomically and streamed to the
    /// file rather than built in memory: they are rewritten as a run's frames finish.
    pub(crate) fn write(&self, dir: &Path) -> Result<(), StatsError> {
        let write = |name: &str, contents: &dyn Fn(&mut dyn Write) -> std::io::Result<()>| {
            let path = dir.join(name);
            crate::atomic_file::write_atomic_with(&path, |w| contents(w))
                .map_err(|source| StatsError::Write { path, source })
        };
        write("stats.json", &|w| serde_json::to_writer_pretty(w, self).map_err(std::io::Error::from))?;
        write("stats.csv", &|w| self.write_csv(w))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn medians_of_odd_even_and_empty() {
        assert_eq!(median(vec![3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(vec![4.0, 1.0, 2.0, 3.0]), 2.5);
        assert_eq!(median(Vec::new()), 0.0);
    }

    #[test]
    fn csv_has_a_header_and_a_row_per_frame() {
        let frames: Vec<FrameRecord> = (0..3)
            .map(|i| {
                FrameRecord::new(
                    &FrameStats {
                        frame: i,
                        stages: StageTimes { trace_ms: 1.0, ..StageTimes::default() },
                        ..FrameStats::default()
                    },
                    &RenderStats { rays: 1, seconds: 1e-6, spp: SppStats { mean: 1.0, min: 1, max: 1 } },
                    None,
                )
            })
            .collect();
        let run = RunInfo {
            scene: "t".into(),
            backend: "bvh".into(),
            mode: "path".into(),
            integration: "auto".into(),
            integrate_as: "baked".into(),
            cache_enabled: true,
            lookahead: true,
            width: 1,
            height: 1,
            spp: 1,
            noise_threshold: 0.0,
            min_spp: None,
            physics: PhysicsSource::Trajectory,
            scene_hash: format!("{:016x}", 1),
            trajectory_frames: 3,
            frame_start: 0,
            frame_end: 3,
            frame_step: 1,
            max_depth: Some(6),
            clamp_indirect: 4.0,
            filter: "tent".into(),
            filter_width: 1.0,
            seed: "fixed".into(),
            seed_offset: 0,
            reuse: true,
            reuse_mode: "exact".into(),
            exposure: 1.0,
            aovs: Vec::new(),
            exr: false,
            denoise: None,
            keep_noisy: false,
            shutter: 0.0,
            settings_from: Default::default(),
        };
        let stats = RunStats::new(run, frames, CacheStats::default(), CostModelState::default(), None);
        let mut csv = Vec::new();
        stats.write_csv(&mut csv).unwrap();
        let csv = String::from_utf8(csv).unwrap();
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines.len(), 4);
        let n = csv_columns().len();
        assert_eq!(n, 41);
        assert_eq!(lines[0].split(',').count(), n);
        assert!(lines[1..].iter().all(|l| l.split(',').count() == n));
        assert_eq!(stats.summary.totals.stages.trace_ms, 3.0);
        assert_eq!(stats.summary.median.stages.trace_ms, 1.0);
    }
}
