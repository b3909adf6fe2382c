//! What a frame is rendered with ([`RenderSettings`]: size, samples, seed, adaptive sampling,
//! pixel filter) and what rendering it took ([`RenderStats`]: rays, time, samples per pixel).

use super::adaptive::{AdaptiveSampling, SppStats};
use super::{PixelFilter, RenderError};
use crate::scene::limits::{image_size_problem, MAX_SAMPLES_PER_PIXEL};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    /// Samples per pixel; with adaptive sampling, the most a pixel gets.
    pub spp: u32,
    /// Seeds the pixel sampler: a sequence passes the frame number so consecutive frames
    /// decorrelate, or one value for every frame (`--seed fixed`).
    pub seed: u32,
    /// When a pixel may stop before `spp` samples (off: never).
    pub adaptive: AdaptiveSampling,
    /// Where a pixel's samples land around its centre (filter importance sampling).
    pub filter: PixelFilter,
}

impl RenderSettings {
    /// `width` x `height` at `spp` samples per pixel, seed 0, no adaptive sampling, the
    /// default tent filter.
    pub fn new(width: u32, height: u32, spp: u32) -> Self {
        Self { width, height, spp, seed: 0, adaptive: AdaptiveSampling::OFF, filter: PixelFilter::default() }
    }

    /// The samples per pixel of [`RenderSettings::default`].
    pub(crate) const DEFAULT_SPP: u32 = 16;

    /// Checks the size, the samples per pixel and adaptive sampling.
    pub fn validate(&self) -> Result<(), RenderError> {
        if let Some(problem) = image_size_problem(self.width, self.height) {
            return Err(RenderError::InvalidSize(problem));
        }
        if !(1..=MAX_SAMPLES_PER_PIXEL).contains(&self.spp) {
            return Err(RenderError::InvalidSpp);
        }
        self.adaptive.validate(self.spp)
    }
}

/// The built-in default of `dormant render`: 960x540 at 16 samples per pixel (what a run uses
/// when neither a flag, a preset nor the scene file sets them).
impl Default for RenderSettings {
    fn default() -> Self {
        Self::new(960, 540, Self::DEFAULT_SPP)
    }
}

#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct RenderStats {
    pub rays: u64,
    pub seconds: f64,
    /// Camera samples per pixel: mean, least and most.
    #[serde(flatten)]
    pub spp: SppStats,
}

impl RenderStats {
    pub fn mrays_per_second(&self) -> f64 {
        self.rays as f64 / self.seconds.max(1e-9) / 1e6
    }

    /// The camera samples of a `width` x `height` image at these samples per pixel.
    pub(crate) fn camera_samples(&self, width: u32, height: u32) -> u64 {
        (self.spp.mean * f64::from(width) * f64::from(height)).round() as u64
    }
}
