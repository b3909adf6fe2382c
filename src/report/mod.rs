//! Run reports: the per-frame statistics of a rendered sequence (`stats.json`, `stats.csv`)
//! and their plot (`report.png`); and the output of `dormant bench paper` (`paper.json`,
//! `paper.md`, one figure per workload). Fed by the CLI from the scene manager's [`FrameStats`];
//! the schema is documented in docs/stats-format.md.
//!
//! [`FrameStats`]: crate::integrate::FrameStats

mod paper;
mod paper_plot;
mod plot;
mod stats;

pub use paper::{paper_markdown, write_paper};
pub use paper_plot::write_workload_png;
pub use plot::{write_report_png, PLOT_HEIGHT, PLOT_WIDTH};
pub use stats::{FrameRecord, RunInfo, RunStats, Summary, STATS_FORMAT, STATS_VERSION};

/// Failures writing a report file.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    #[error("cannot write {path}: {source}")]
    Write { path: std::path::PathBuf, source: std::io::Error },
    #[error("cannot draw {path}: {message}")]
    Plot { path: std::path::PathBuf, message: String },
}
