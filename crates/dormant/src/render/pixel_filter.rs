//! [`PixelFilter`]: the reconstruction filter, applied by filter importance sampling (as in
//! pbrt-v4 and Cycles): each camera sample lands at an offset from the pixel's centre drawn
//! from the filter's own distribution and is weighted 1, so every pixel is computed alone and
//! the image is the filtered one.
//!
//! Every filter is separable (one draw per axis) and mirrors one half: a sample's `u < 0.5`
//! lands left of (above) the centre, the rest right (below), and the offset grows with `u`
//! across the whole support, so stratified `u` give stratified offsets. Widths follow Cycles'
//! "Pixel Filter" panel where Cycles has the filter: Blackman-Harris of width `w` reaches `w`
//! pixels either side (Cycles' default, 1.5); a Gaussian of width `w` has standard deviation
//! `w / 4` and is cut at `1.5 w`, six of them (Cycles' table); a box of width `w` spans `w` pixels. The
//! tent (dormant's default) reaches `w` pixels either side.

use std::sync::OnceLock;

use glam::Vec2;

use super::RenderError;
use crate::names::named_enum;

/// The reconstruction filter's shape and width, in pixels (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PixelFilter {
    Tent { radius: f32 },
    Box { width: f32 },
    Gaussian { width: f32 },
    BlackmanHarris { width: f32 },
}

named_enum! {
    /// The filter kinds, as the command line names them.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub enum FilterKind {
        Tent = "tent",
        Box = "box",
        Gaussian = "gaussian",
        BlackmanHarris = "blackman-harris",
    }
}

impl FilterKind {
    /// The width a filter of this kind has unless one is given: Cycles' defaults (box 1,
    /// Gaussian and Blackman-Harris 1.5) and the tent of radius 1.
    pub(crate) fn default_width(self) -> f32 {
        match self {
            FilterKind::Tent | FilterKind::Box => 1.0,
            FilterKind::Gaussian | FilterKind::BlackmanHarris => 1.5,
        }
    }
}

/// Widest filter accepted, pixels: far beyond any reconstruction filter in use.
pub(crate) const MAX_FILTER_WIDTH: f32 = 16.0;

impl Default for PixelFilter {
    fn default() -> Self {
        PixelFilter::Tent { radius: 1.0 }
    }
}

impl PixelFilter {
    /// A filter of `kind` and `width` pixels (`None`: the kind's default width). The width
    /// must be a number above 0 and at most [`MAX_FILTER_WIDTH`].
    pub fn new(kind: FilterKind, width: Option<f32>) -> Result<Self, RenderError> {
        let width = width.unwrap_or_else(|| kind.default_width());
        if !(width > 0.0 && width <= MAX_FILTER_WIDTH) {
            return Err(RenderError::InvalidFilterWidth(width));
        }
        Ok(match kind {
            FilterKind::Tent => PixelFilter::Tent { radius: width },
            FilterKind::Box => PixelFilter::Box { width },
            FilterKind::Gaussian => PixelFilter::Gaussian { width },
            FilterKind::BlackmanHarris => PixelFilter::BlackmanHarris { width },
        })
    }

    pub fn kind(&self) -> FilterKind {
        match self {
            PixelFilter::Tent { .. } => FilterKind::Tent,
            PixelFilter::Box { .. } => FilterKind::Box,
            PixelFilter::Gaussian { .. } => FilterKind::Gaussian,
            PixelFilter::BlackmanHarris { .. } => FilterKind::BlackmanHarris,
        }
    }

    /// The width as given (the tent's radius).
    pub fn width(&self) -> f32 {
        match *self {
            PixelFilter::Tent { radius } => radius,
            PixelFilter::Box { width }
            | PixelFilter::Gaussian { width }
            | PixelFilter::BlackmanHarris { width } => width,
        }
    }

    /// Farthest a sample lands from the pixel's centre along an axis, pixels.
    pub(crate) fn reach(&self) -> f32 {
        match *self {
            PixelFilter::Tent { radius } => radius,
            PixelFilter::Box { width } => 0.5 * width,
            PixelFilter::Gaussian { width } => 1.5 * width,
            PixelFilter::BlackmanHarris { width } => width,
        }
    }

    /// A sample's offset from the pixel's centre for the uniform pair `u`, distributed as the
    /// filter.
    #[inline]
    pub(crate) fn sample_offset(&self, u: Vec2) -> Vec2 {
        match *self {
            PixelFilter::Tent { radius } => tent_offset(u) * radius,
            PixelFilter::Box { width } => (u - Vec2::splat(0.5)) * width,
            PixelFilter::Gaussian { .. } => tabulated(gaussian_table(), u) * self.reach(),
            PixelFilter::BlackmanHarris { .. } => tabulated(blackman_harris_table(), u) * self.reach(),
        }
    }
}

/// Pixel offset distributed as a tent of radius one pixel per axis.
fn tent_offset(u: Vec2) -> Vec2 {
    // One square root and two selects rather than a branch on `u`, which is random, so such
    // a branch mispredicts often (same values).
    let tent = |u: f32| {
        let low = u < 0.5;
        let r = (if low { 2.0 * u } else { 2.0 - 2.0 * u }).sqrt();
        if low {
            r - 1.0
        } else {
            1.0 - r
        }
    };
    Vec2::new(tent(u.x), tent(u.y))
}

/// Bins of a tabulated half filter.
const BINS: usize = 256;

/// The cumulative distribution of one half of a filter over `t` in `[0, 1]` (the fraction of
/// its reach) at `BINS + 1` evenly spaced points, from 0 to 1: each bin holds the filter's
/// exact mass there (Simpson's rule on 16 steps), and within a bin the density is constant.
type HalfCdf = [f32; BINS + 1];

fn half_cdf(shape: impl Fn(f64) -> f64) -> Box<HalfCdf> {
    const STEPS: usize = 16;
    let mut cdf = Box::new([0.0f32; BINS + 1]);
    let mut sum = 0.0f64;
    let mut sums = [0.0f64; BINS + 1];
    for (i, s) in sums.iter_mut().enumerate().skip(1) {
        let (a, h) = ((i - 1) as f64 / BINS as f64, 1.0 / (BINS * STEPS) as f64);
        let simpson: f64 = (0..=STEPS)
            .map(|k| {
                let w = if k == 0 || k == STEPS {
                    1.0
                } else if k % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                w * shape(a + k as f64 * h)
            })
            .sum();
        sum += simpson * h / 3.0;
        *s = sum;
    }
    for (c, s) in cdf.iter_mut().zip(sums) {
        *c = (s / sum) as f32;
    }
    cdf[BINS] = 1.0;
    cdf
}

/// Blackman-Harris over its reach, as Cycles evaluates it (`filter_func_blackman_harris` at
/// twice the width): 1 at the centre, 6e-5 at the edge.
fn blackman_harris_table() -> &'static HalfCdf {
    static TABLE: OnceLock<Box<HalfCdf>> = OnceLock::new();
    TABLE.get_or_init(|| {
        use std::f64::consts::PI;
        half_cdf(|t| {
            0.35875
                + 0.48829 * (PI * t).cos()
                + 0.14128 * (2.0 * PI * t).cos()
                + 0.01168 * (3.0 * PI * t).cos()
        })
    })
}

/// A Gaussian of standard deviation `width / 4` cut at `1.5 width`: at `t` of the reach,
/// `exp(-2 (6 x / (3 w))^2)` with `x = 1.5 w t`, Cycles' `filter_func_gaussian`.
fn gaussian_table() -> &'static HalfCdf {
    static TABLE: OnceLock<Box<HalfCdf>> = OnceLock::new();
    TABLE.get_or_init(|| half_cdf(|t| (-18.0 * t * t).exp()))
}

/// Offsets in `[-1, 1]` per axis distributed as the mirrored half `cdf`.
#[inline]
fn tabulated(cdf: &HalfCdf, u: Vec2) -> Vec2 {
    Vec2::new(mirrored(cdf, u.x), mirrored(cdf, u.y))
}

/// `u < 0.5` maps to `[-1, 0]`, the rest to `[0, 1]`, increasing with `u`.
#[inline]
fn mirrored(cdf: &HalfCdf, u: f32) -> f32 {
    if u < 0.5 {
        -inverse(cdf, 1.0 - 2.0 * u)
    } else {
        inverse(cdf, 2.0 * u - 1.0)
    }
}

/// The `t` in `[0, 1]` where `cdf` reaches `v` (linear within a bin).
#[inline]
fn inverse(cdf: &HalfCdf, v: f32) -> f32 {
    // The last bin whose start is at most `v`.
    let i = cdf.partition_point(|&c| c <= v).clamp(1, BINS) - 1;
    let (lo, hi) = (cdf[i], cdf[i + 1]);
    let within = if hi > lo { ((v - lo) / (hi - lo)).clamp(0.0, 1.0) } else { 0.0 };
    (i as f32 + within) / BINS as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Offsets of `n` stratified `u` along one axis.
    fn offsets(filter: PixelFilter, n: usize) -> Vec<f32> {
        (0..n).map(|i| filter.sample_offset(Vec2::splat((i as f32 + 0.5) / n as f32)).x).collect()
    }

    #[test]
    fn offsets_grow_with_u_and_stay_within_the_reach() {
        for &kind in <FilterKind as crate::names::Named>::VALUES {
            let f = PixelFilter::new(kind, None).unwrap();
            let o = offsets(f, 4096);
            assert!(o.windows(2).all(|w| w[0] <= w[1]), "{kind:?} not monotone");
            assert!(o.iter().all(|x| x.abs() <= f.reach()), "{kind:?} beyond its reach");
            let mean: f32 = o.iter().sum::<f32>() / o.len() as f32;
            assert!(mean.abs() < 1e-4, "{kind:?} mean {mean}");
        }
    }

    #[test]
    fn the_default_tent_is_the_one_before_filters_were_chosen() {
        let f = PixelFilter::default();
        for u in [0.0, 0.1, 0.49, 0.5, 0.77, 0.999] {
            assert_eq!(f.sample_offset(Vec2::splat(u)), tent_offset(Vec2::splat(u)));
        }
    }

    #[test]
    fn the_gaussian_has_the_standard_deviation_of_a_quarter_width() {
        let f = PixelFilter::new(FilterKind::Gaussian, Some(2.0)).unwrap();
        let o = offsets(f, 100_000);
        let var: f32 = o.iter().map(|x| x * x).sum::<f32>() / o.len() as f32;
        // Cut at 6 sigma: the cut changes nothing measurable.
        assert!((var.sqrt() - 0.5).abs() < 1e-3, "sigma {}", var.sqrt());
    }

    #[test]
    fn blackman_harris_follows_its_window_bin_by_bin() {
        // Histogram of stratified offsets against the window's own mass per bin.
        let width = 1.5;
        let f = PixelFilter::new(FilterKind::BlackmanHarris, Some(width)).unwrap();
        let n = 200_000;
        let bins = 30;
        let mut hist = vec![0usize; bins];
        for x in offsets(f, n) {
            let b = (((x / width) + 1.0) * 0.5 * bins as f32) as usize;
            hist[b.min(bins - 1)] += 1;
        }
        let window = |x: f64| {
            let v = 2.0 * std::f64::consts::PI * (x / (2.0 * width as f64) + 0.5);
            0.35875 - 0.48829 * v.cos() + 0.14128 * (2.0 * v).cos() - 0.01168 * (3.0 * v).cos()
        };
        let edges: Vec<f64> =
            (0..=bins).map(|i| -(width as f64) + 2.0 * width as f64 * i as f64 / bins as f64).collect();
        let mass: Vec<f64> = edges
            .windows(2)
            .map(|e| (0..100).map(|k| window(e[0] + (e[1] - e[0]) * (k as f64 + 0.5) / 100.0)).sum::<f64>())
            .collect();
        let total: f64 = mass.iter().sum();
        for (i, (&h, m)) in hist.iter().zip(&mass).enumerate() {
            let expected = m / total * n as f64;
            assert!(
                (h as f64 - expected).abs() <= 0.01 * expected + 3.0,
                "bin {i}: {h} against {expected:.1}"
            );
        }
    }

    #[test]
    fn widths_out_of_range_are_refused() {
        for w in [0.0, -1.0, f32::NAN, f32::INFINITY, MAX_FILTER_WIDTH * 2.0] {
            assert!(PixelFilter::new(FilterKind::Gaussian, Some(w)).is_err(), "{w}");
        }
    }
}
