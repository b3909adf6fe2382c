//! Adaptive sampling: when a pixel has had enough camera samples. Each pixel keeps the sum
//! and the sum of squares of its samples; after a minimum and then every few samples its
//! estimated relative error (below) is compared with the noise threshold, and the pixel stops
//! once it is below. The decision reads only the pixel's own samples, in index order, so the
//! image is the same whatever the thread count or tile order. Also the per-frame summary of the
//! samples spent ([`SppStats`]).

use glam::Vec3;

use super::RenderError;
use crate::scene::limits::MAX_SAMPLES_PER_PIXEL;

/// After the minimum, a pixel's error is checked every this many samples.
pub const CHECK_EVERY: u32 = 4;

/// Radiance below which the error is measured against this absolute value instead of the
/// pixel's own (dark pixels would otherwise never converge). The same floor as the relative
/// MSE of docs/performance.md: `(x - ref)^2 / (ref^2 + 0.1^2)`.
pub const DARK_FLOOR: f32 = 0.1;

/// `--noise-threshold` and `--min-spp` (`[render] noise_threshold`, `min_spp`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AdaptiveSampling {
    /// Largest estimated relative error ([`relative_error`]) at which a pixel stops; 0: off,
    /// every pixel gets `spp` samples.
    pub noise_threshold: f32,
    /// Samples every pixel gets before its error is first checked; `None`: [`default_min_spp`].
    pub min_spp: Option<u32>,
}

/// The minimum when none is given: like Cycles' automatic minimum, the square root of the
/// sample count, here at least 8 (a variance from fewer samples misses too much), at most
/// `spp`.
pub fn default_min_spp(spp: u32) -> u32 {
    ((spp as f64).sqrt().ceil() as u32).max(8).min(spp)
}

impl AdaptiveSampling {
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
        self.is_on().then(|| Stopping::with_env(self.noise_threshold, self.min_spp(spp)))
    }
}

/// When a pixel stops: see the module docs.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Stopping {
    threshold: f32,
    pub(crate) min: u32,
    /// EXPERIMENT knobs (env, removed before the final commit).
    exponent: f32,
    pool: u8,
    pub(crate) check: u32,
}

impl Stopping {
    fn with_env(threshold: f32, min: u32) -> Self {
        let var = |k: &str| std::env::var(k).ok();
        Self {
            threshold,
            min,
            exponent: var("DORMANT_ADAPT_A").and_then(|v| v.parse().ok()).unwrap_or(0.0),
            pool: match var("DORMANT_ADAPT_POOL").as_deref() {
                Some("mean") => 1,
                Some("max") => 2,
                _ => 0,
            },
            check: var("DORMANT_ADAPT_CHECK").and_then(|v| v.parse().ok()).unwrap_or(CHECK_EVERY),
        }
    }

    /// Whether a pixel with `n` samples whose (pooled) per-sample relative variance is
    /// `variance` is done.
    pub(crate) fn done(&self, n: u32, variance: f32) -> bool {
        let t2 = self.threshold * self.threshold;
        // stderr^2 = variance / n <= t^2 * sigma^a
        n >= self.min && variance / (n as f32) < t2 * variance.max(0.0).sqrt().powf(self.exponent)
    }

    /// The variance a pixel is judged by: its own, or pooled over its 3x3 neighbourhood.
    pub(crate) fn pooled(&self, variances: &[f32], w: usize, h: usize, x: usize, y: usize) -> f32 {
        if self.pool == 0 {
            return variances[y * w + x];
        }
        let (mut sum, mut most, mut k) = (0.0f32, 0.0f32, 0);
        for yy in y.saturating_sub(1)..(y + 2).min(h) {
            for xx in x.saturating_sub(1)..(x + 2).min(w) {
                let v = variances[yy * w + xx];
                sum += v;
                most = most.max(v);
                k += 1;
                if v.is_nan() {
                    return f32::NAN;
                }
            }
        }
        if self.pool == 1 {
            sum / k as f32
        } else {
            most
        }
    }
}

/// Per-sample relative variance of a pixel after `n >= 2` samples summing to `sum`, their
/// squares to `squares`: per channel the sample variance over the squared mean plus
/// [`DARK_FLOOR`] squared, the mean over the channels.
pub fn relative_variance(n: u32, sum: Vec3, squares: Vec3) -> f32 {
    if n < 2 {
        return f32::INFINITY;
    }
    let n = n as f32;
    let mean = sum / n;
    let variance = ((squares - sum * mean) / (n - 1.0)).max(Vec3::ZERO);
    let relative = variance / (mean * mean + Vec3::splat(DARK_FLOOR * DARK_FLOOR));
    (relative.x + relative.y + relative.z) / 3.0
}

/// Estimated relative standard error of a pixel's mean after `n >= 2` samples summing to
/// `sum`, their squares to `squares`: the root of [`relative_variance`] over `n`. It
/// estimates the pixel's contribution to the relative MSE. Non-finite samples give NaN.
pub fn relative_error(n: u32, sum: Vec3, squares: Vec3) -> f32 {
    (relative_variance(n, sum, squares) / n as f32).sqrt()
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
    fn stops_only_after_the_minimum() {
        let s = AdaptiveSampling { noise_threshold: 0.1, min_spp: Some(8) }.stopping(64).unwrap();
        assert!(!s.done(4, 0.0));
        assert!(s.done(8, 0.0));
        assert!(!s.done(8, 1.0));
        assert!(!s.done(12, f32::NAN));
    }

    #[test]
    fn default_minimum_follows_the_square_root() {
        assert_eq!(default_min_spp(4), 4);
        assert_eq!(default_min_spp(64), 8);
        assert_eq!(default_min_spp(1024), 32);
    }
}
