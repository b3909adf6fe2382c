//! A sequence's output files: which files a frame writes ([`OutputLayout`]), writing them
//! ([`FrameWriter`]: the image, denoised on request, the noisy image, the AOV passes, each
//! atomically), and which frames an interrupted run in the same directory finished
//! ([`kept_frames`], for `render --resume`).

mod layout;
mod resume;
mod writer;

pub use layout::OutputLayout;
pub use resume::kept_frames;
pub use writer::{FrameFiles, FrameWriter, WrittenFrame};

use std::path::PathBuf;

use super::stats::StatsError;
use crate::render::denoise::DenoiseError;
use crate::render::RenderError;

/// Failures writing a frame's files or reading what an earlier run left.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error(transparent)]
    Write(#[from] RenderError),
    #[error(transparent)]
    Denoise(#[from] DenoiseError),
    /// A reused frame's file could not be copied from the frame it repeats.
    #[error("cannot copy {from} to {to}: {source}")]
    Copy { from: PathBuf, to: PathBuf, source: std::io::Error },
    #[error("cannot remove the temporary files left in {dir}: {source}")]
    Stale { dir: PathBuf, source: std::io::Error },
    /// The directory's statistics are unreadable or from another run: the user's to fix.
    #[error(transparent)]
    Stats(#[from] StatsError),
}
