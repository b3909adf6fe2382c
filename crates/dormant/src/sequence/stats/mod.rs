//! Run statistics: the per-frame records of a rendered sequence and the files they live in
//! (`stats.json`, `stats.csv`), written as frames finish and read back by `render --resume`.
//! The schema is documented in docs/stats-format.md.

mod file;
mod record;

pub(crate) use file::read_kept_frames;
pub use file::StatsFile;
pub use record::{median, FrameRecord, ReuseRecord, RunInfo, RunStats};

use std::path::PathBuf;

/// Failures reading or writing a statistics file.
#[derive(Debug, thiserror::Error)]
pub enum StatsError {
    #[error("cannot write {path}: {source}")]
    Write { path: PathBuf, source: std::io::Error },
    #[error("cannot read {path}: {source}")]
    Read { path: PathBuf, source: std::io::Error },
    #[error("{path}: not a statistics file dormant can read: {source}")]
    Parse { path: PathBuf, source: serde_json::Error },
    /// `render --resume` found the statistics of another run configuration.
    #[error(
        "{path}: written by a run of another configuration ({differences}); --resume continues only \
         the same run: give another --out, or remove its files to start over"
    )]
    OtherRun { path: PathBuf, differences: String },
}
