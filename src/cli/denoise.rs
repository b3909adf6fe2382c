//! The denoiser's flags, shared by `render`, `bench adaptive` and `bench reuse`, and the
//! denoiser they ask for.

use clap::Args;
use dormant::render::denoise::{DenoiseError, DenoiseQuality, Denoiser};

use super::named::named;
use super::CliError;

/// `--denoise` and how it filters.
#[derive(Args, Clone, Debug)]
pub(crate) struct DenoiseArgs {
    /// Denoise each image with Intel Open Image Denoise (OIDN 2, CPU), guided by the albedo and
    /// normal passes (rendered for it even when --aov does not ask for them). Needs the
    /// `oidn` feature, which `scripts/setup.sh` makes available.
    #[arg(long)]
    pub denoise: bool,
    // Its cost: docs/lab/sampling.md#2026-12-02-prefiltered-guides---denoise-prefilter
    /// With --denoise: denoise the albedo and normal guides first (like Cycles' "Accurate"
    /// prefilter): less error on fine texture edges, about six times the denoising time.
    #[arg(long, requires = "denoise")]
    pub denoise_prefilter: bool,
    // Its cost: docs/lab/reuse.md#2026-12-06-the-stores-passes-in-one-trace-the-denoisers-filter-kept---denoise-quality
    /// With --denoise: OIDN's filter quality, like Cycles' "Denoising Quality": `fast` filters
    /// with a smaller network, in about half the time and with more error.
    #[arg(long, value_parser = named::<DenoiseQuality>(), default_value_t, requires = "denoise")]
    pub denoise_quality: DenoiseQuality,
}

impl DenoiseArgs {
    /// The denoiser asked for (`None` without `--denoise`), with `threads` worker threads.
    pub(crate) fn denoiser(&self, threads: Option<usize>) -> Result<Option<Denoiser>, CliError> {
        let make = || {
            Denoiser::new(threads).map(|d| d.prefilter(self.denoise_prefilter).quality(self.denoise_quality))
        };
        self.denoise.then(make).transpose().map_err(denoise_error)
    }
}

/// A denoiser that cannot start: a missing library (or a build without it) is the user's to
/// fix (exit 2), anything else a runtime failure.
pub(crate) fn denoise_error(e: DenoiseError) -> CliError {
    if e.is_missing_library() {
        CliError::Input(e.to_string())
    } else {
        CliError::Runtime(e.to_string())
    }
}
