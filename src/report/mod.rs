//! Run reports: the per-frame statistics of a rendered sequence (`stats.json`, `stats.csv`,
//! written as frames finish and read back by `render --resume`) and their plot
//! (`report.png`); and the output of `dormant bench paper` (`paper.json`,
//! `paper.md`, one figure per workload). Fed by the CLI from the scene manager's [`FrameStats`];
//! the schema is documented in docs/stats-format.md.
//!
//! [`FrameStats`]: crate::integrate::FrameStats

mod paper;
mod paper_plot;
mod plot;
mod regimes;
mod stats;
mod stats_file;

pub(crate) use paper::write_paper;
pub(crate) use plot::write_report_png;
pub(crate) use regimes::write_regimes;
pub(crate) use stats::{median, FrameRecord, RunInfo};
pub(crate) use stats_file::{read_kept_frames, StatsFile};

/// `report` as JSON with `simd_path`, the BVH SIMD path that ran (`DORMANT_SIMD`): every
/// benchmark report carries it, whether printed by `--json` or written as a file.
pub(crate) fn bench_json(report: &impl serde::Serialize) -> serde_json::Value {
    let mut value = serde_json::to_value(report).expect("bench reports serialise");
    if let Some(map) = value.as_object_mut() {
        map.insert("simd_path".into(), serde_json::json!(crate::accel::bvh::SimdPath::current()));
    }
    value
}

/// Failures writing a report file.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    #[error("cannot write {path}: {source}")]
    Write { path: std::path::PathBuf, source: std::io::Error },
    #[error("cannot read {path}: {source}")]
    Read { path: std::path::PathBuf, source: std::io::Error },
    #[error("{path}: not a statistics file dormant can read: {source}")]
    Parse { path: std::path::PathBuf, source: serde_json::Error },
    /// `render --resume` found the statistics of another run configuration.
    #[error(
        "{path}: written by a run of another configuration ({differences}); --resume continues only \
         the same run: give another --out, or remove its files to start over"
    )]
    OtherRun { path: std::path::PathBuf, differences: String },
    #[error("cannot draw {path}: {message}")]
    Plot { path: std::path::PathBuf, message: String },
}
