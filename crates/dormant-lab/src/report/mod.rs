//! What the lab's reports share: the error of writing a report or figure, and the plotting
//! helpers every figure (the paper's, the regime map's, the binary's `report.png`) is drawn
//! with.

pub mod figure;

/// Failures writing a report or a figure.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    #[error("cannot write {path}: {source}")]
    Write { path: std::path::PathBuf, source: std::io::Error },
    #[error("cannot read {path}: {source}")]
    Read { path: std::path::PathBuf, source: std::io::Error },
    #[error("cannot draw {path}: {message}")]
    Plot { path: std::path::PathBuf, message: String },
}
