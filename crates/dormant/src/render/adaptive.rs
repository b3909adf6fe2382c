//! Adaptive sampling: when a pixel has had enough camera samples. Each pixel keeps the sum
//! and the sum of squares of its samples; after a minimum and then every few samples its
//! estimated relative error (the standard error of its mean over its value)
//! is compared with a bound that depends on the noise threshold and on how much the pixel's
//! samples spread ([`Stopping::converged`]), and the pixel stops once it is below. The decision
//! reads only the pixel's own samples, in index order, so the image is the same whatever the
//! thread count or tile order. Also the per-frame summary of the samples spent ([`SppStats`]).
//!
//! Why the bound grows with the spread: the image's error (the relative MSE of
//! docs/performance.md#denoising-render---denoise, the mean over pixels of each one's variance
//! of the mean σ²/n) is least for a given total of samples when each pixel gets n ∝ σ (σ: the
//! relative standard deviation of one sample), not when every pixel reaches the same error
//! (n ∝ σ², which puts the samples into the noisiest pixels up to the cap). Stopping once
//! σ²/n ≤ t²·σ gives n ∝ σ: on the default scene it reaches uniform sampling's error with
//! fewer samples than the equal-error rule. Pooling σ over
//! neighbours, other exponents, one threshold for the frame, and other check intervals and
//! minimums measured no better: docs/lab/sampling.md#2026-12-02-adaptive-samplings-stopping-rule-n--σ

use glam::Vec3;

use super::RenderError;
use crate::scene::limits::MAX_SAMPLES_PER_PIXEL;

/// After the minimum, a pixel's error is checked every this many samples.
pub(crate) const CHECK_EVERY: u32 = 4;

/// `--noise-threshold` and `--min-spp` (`[render] noise_threshold`, `min_spp`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AdaptiveSampling {
    /// The relative noise left in a pixel whose samples spread by their mean (relative
    /// standard deviation 1); a pixel of spread σ stops at `noise_threshold * sqrt(σ)`
    /// ([`Stopping::converged`]). 0: off, every pixel gets `spp` samples.
    pub noise_threshold: f32,
    /// Samples every pixel gets before its error is first checked; `None`: [`default_min_spp`].
    pub min_spp: Option<u32>,
}

/// The minimum when none is given: like Cycles' automatic minimum, the square root of the
/// sample count, here at least 8 (a variance from fewer samples misses too much), at most
/// `spp`.
pub(crate) fn default_min_spp(spp: u32) -> u32 {
    ((spp as f64).sqrt().ceil() as u32).max(8).min(spp)
}

impl AdaptiveSampling {
    /// Radiance below which the error is measured against this absolute value instead of the
    /// pixel's own (dark pixels would otherwise never converge). The same floor as the relative
    /// MSE of docs/performance.md#denoising-render---denoise: `(x - ref)^2 / (ref^2 + 0.1^2)`.
    pub const DARK_FLOOR: f32 = 0.1;

    /// Uniform sampling: every pixel gets `spp` samples.
    pub const OFF: Self = Self { noise_threshold: 0.0, min_spp: None };

    pub fn is_on(&self) -> bool {
        self.noise_threshold > 0.0
    }

    /// The minimum for `spp` samples at most.
    pub fn min_spp(&self, spp: u32) -> u32 {
        self.min_spp.unwrap_or_else(|| default_min_spp(spp))
    }

    pub(crate) fn validate(&self, spp: u32) -> Result<(), RenderError> {
        if !(self.noise_threshold.is_finite() && self.noise_threshold >= 0.0) {
            return Err(RenderError::InvalidNoiseThreshold(self.noise_threshold));
        }
        if let Some(min) = self.min_spp.filter(|_| self.is_on()) {
            if !(1..=spp.min(MAX_SAMPLES_PER_PIXEL)).contains(&min) {
                return Err(RenderError::InvalidMinSpp { min, spp });
            }
        }
        Ok(())
    }

    /// The stopping rule for frames of `spp` samples; `None` when off.
    pub(crate) fn stopping(&self, spp: u32) -> Option<Stopping> {
        self.is_on().then(|| Stopping { threshold: self.noise_threshold, min: self.min_spp(spp) })
    }
}

/// When a pixel stops: see the module docs.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Stopping {
    threshold: f32,
    min: u32,
}

impl Stopping {
    /// Whether a pixel with `n` samples summing to `sum` (squares: `squares`) is done: at a
    /// check after the minimum, its estimated relative error (σ/√n) is at
    /// most the threshold times √σ (σ: [`relative_spread`]), i.e. n ≥ σ / threshold².
    pub(crate) fn converged(&self, n: u32, sum: Vec3, squares: Vec3) -> bool {
        if n < self.min || (n - self.min) % CHECK_EVERY != 0 {
            return false;
        }
        let spread = relative_spread(n, sum, squares);
        // NaN (a non-finite sample) never converges.
        spread <= n as f32 * self.threshold * self.threshold
    }
}

/// Relative standard deviation of one sample of a pixel after `n >= 2` samples summing to
/// `sum`, their squares to `squares`: per channel the sample variance over the squared mean
/// plus [`AdaptiveSampling::DARK_FLOOR`] squared; the root of the mean over the channels.
/// Non-finite samples give NaN; fewer than 2 samples infinity.
pub(crate) fn relative_spread(n: u32, sum: Vec3, squares: Vec3) -> f32 {
    if n < 2 {
        return f32::INFINITY;
    }
    let n = n as f32;
    let mean = sum / n;
    let variance = ((squares - sum * mean) / (n - 1.0)).max(Vec3::ZERO);
    let floor = AdaptiveSampling::DARK_FLOOR;
    let relative = variance / (mean * mean + Vec3::splat(floor * floor));
    ((relative.x + relative.y + relative.z) / 3.0).sqrt()
}

/// Camera samples per pixel over a frame: the effective spp of adaptive sampling (with it off
/// every pixel has `spp`). All 0 for a frame that was not traced.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SppStats {
    #[serde(rename = "spp_mean")]
    pub mean: f64,
    #[serde(rename = "spp_min")]
    pub min: u32,
    #[serde(rename = "spp_max")]
    pub max: u32,
}

impl SppStats {
    pub(crate) fn of(counts: &[u32]) -> Self {
        if counts.is_empty() {
            return Self::default();
        }
        let total: u64 = counts.iter().map(|&c| u64::from(c)).sum();
        Self {
            mean: total as f64 / counts.len() as f64,
            min: counts.iter().copied().min().unwrap_or(0),
            max: counts.iter().copied().max().unwrap_or(0),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The estimated relative standard error of a pixel's mean: the spread over √n.
    fn relative_error(n: u32, sum: Vec3, squares: Vec3) -> f32 {
        relative_spread(n, sum, squares) / (n as f32).sqrt()
    }

    #[test]
    fn constant_samples_have_no_error_and_spread_ones_do() {
        let v = Vec3::new(0.5, 0.2, 0.1);
        assert_eq!(relative_error(8, v * 8.0, v * v * 8.0), 0.0);
        // Samples 0 and 1 alternating: variance 2/7 * 4/... checked against the formula.
        let (sum, squares) = (Vec3::splat(4.0), Vec3::splat(4.0));
        let expected = ((8.0 * 0.25 / 7.0) / 8.0 / (0.25 + 0.01f32)).sqrt();
        assert!((relative_error(8, sum, squares) - expected).abs() < 1e-6);
        assert!(relative_error(8, Vec3::splat(f32::NAN), squares).is_nan());
    }

    #[test]
    fn stops_only_at_check_rounds_after_the_minimum() {
        let s = AdaptiveSampling { noise_threshold: 0.1, min_spp: Some(8) }.stopping(64).unwrap();
        let v = Vec3::ONE;
        assert!(!s.converged(4, v * 4.0, v * 4.0));
        assert!(s.converged(8, v * 8.0, v * 8.0));
        assert!(!s.converged(9, v * 9.0, v * 9.0));
        assert!(s.converged(12, v * 12.0, v * 12.0));
    }

    #[test]
    fn noisier_pixels_need_samples_in_proportion_to_their_spread() {
        // Samples 0 and 2 alternating: mean 1, spread sqrt(n/(n-1)) / sqrt(1.01), about 1.
        let s = AdaptiveSampling { noise_threshold: 0.25, min_spp: Some(8) }.stopping(1024).unwrap();
        let alternating = |n: u32| (Vec3::splat(n as f32), Vec3::splat(2.0 * n as f32));
        let first = (8..1024).step_by(4).find(|&n| {
            let (sum, squares) = alternating(n);
            s.converged(n, sum, squares)
        });
        // n >= spread / threshold^2 = 16 * spread, spread a little above 1: the first check
        // from 17 on.
        assert_eq!(first, Some(20));
        // A quarter of the spread (0.75 and 1.25 around 1) needs a quarter of the samples:
        // the minimum bounds it.
        let (sum, squares) = (Vec3::splat(8.0), Vec3::splat(8.0 * (0.75f32 * 0.75 + 1.25 * 1.25) / 2.0));
        assert!(s.converged(8, sum, squares));
        assert!(!s.converged(8, Vec3::splat(f32::NAN), squares));
    }

    #[test]
    fn default_minimum_follows_the_square_root() {
        assert_eq!(default_min_spp(4), 4);
        assert_eq!(default_min_spp(64), 8);
        assert_eq!(default_min_spp(1024), 32);
    }
}
