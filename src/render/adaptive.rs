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
    mode: u8,
    pub(crate) check: u32,
}

impl Stopping {
    fn with_env(threshold: f32, min: u32) -> Self {
        let var = |k: &str| std::env::var(k).ok();
        Self {
            threshold,
            min,
            mode: match var("DORMANT_ADAPT_MODE").as_deref() {
                Some("pixel0") => 0,
                Some("pixel1") => 1,
                Some("every") => 3,
                _ => 2,
            },
            check: var("DORMANT_ADAPT_CHECK").and_then(|v| v.parse().ok()).unwrap_or(CHECK_EVERY),
        }
    }

    /// After a round: clears `active` for the pixels that are done, given every pixel's
    /// per-sample relative variance and sample count (row-major); whether any still samples.
    pub(crate) fn judge(
        &self,
        variances: &[f32],
        counts: &[u32],
        active: &mut [bool],
        spp: u32,
        once: &mut Option<f32>,
    ) -> bool {
        let t2 = self.threshold * self.threshold;
        let lambda = match self.mode {
            0 | 1 => t2,
            2 => *once.get_or_insert_with(|| calibrate(variances, counts, active, spp, f64::from(t2)) as f32),
            _ => calibrate(variances, counts, active, spp, f64::from(t2)) as f32,
        };
        let mut any = false;
        for ((a, &v), &n) in active.iter_mut().zip(variances).zip(counts) {
            if *a && n >= self.min {
                let done = match self.mode {
                    0 => v / (n as f32) < lambda,
                    _ => v.sqrt() / (n as f32) <= lambda,
                };
                *a = !done;
            }
            any |= *a;
        }
        any
    }
}

/// The `lambda` for which sampling every pixel still active to `sqrt(v) / lambda` samples
/// (between its count and `spp`) predicts a relative MSE of `target`.
fn calibrate(variances: &[f32], counts: &[u32], active: &[bool], spp: u32, target: f64) -> f64 {
    use rayon::prelude::*;
    const CHUNK: usize = 4096;
    let error = |lambda: f64| -> f64 {
        let chunks: Vec<f64> = (0..variances.len().div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| {
                let range = c * CHUNK..((c + 1) * CHUNK).min(variances.len());
                let mut sum = 0.0;
                for i in range {
                    let v = f64::from(variances[i]);
                    if !v.is_finite() {
                        continue;
                    }
                    let n = f64::from(counts[i]);
                    let n = if active[i] { (v.sqrt() / lambda).clamp(n, f64::from(spp)) } else { n };
                    sum += v / n;
                }
                sum
            })
            .collect();
        chunks.iter().sum::<f64>() / variances.len().max(1) as f64
    };
    if error(f64::INFINITY) <= target {
        return f64::INFINITY;
    }
    if error(0.0) > target {
        return 0.0;
    }
    let (mut lo, mut hi) = ((1e-9f64).ln(), (1e4f64).ln());
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if error(mid.exp()) > target {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    lo.exp()
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
    fn default_minimum_follows_the_square_root() {
        assert_eq!(default_min_spp(4), 4);
        assert_eq!(default_min_spp(64), 8);
        assert_eq!(default_min_spp(1024), 32);
    }
}
