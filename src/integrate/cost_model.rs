//! The cost model: integrate an island only when its estimated build cost `C_i` is less than
//! the time it is expected to save before it wakes, `t_n = gain per frame x expected frames`.
//!
//! Every estimate comes from measurements of this run:
//! - **build cost**: a least-squares line `ms = a + b * triangles` over recent static builds;
//! - **gain per frame**: least-squares slopes of commit and trace time over the number of
//!   instances in the top level (what one body fewer saves per frame), floored at 0;
//! - **expected remaining sleep**: the mean residual sleep of islands that slept as long as
//!   this one already has, over every island seen (integrated or not: declined islands are
//!   "shadow" samples, so the estimate does not learn only from its own choices). Islands still
//!   asleep count with their current age, a lower bound.
//!
//! Before there are enough samples the model uses priors (below), which the measurements
//! replace as soon as they exist.

use std::collections::VecDeque;

/// Samples kept per fit.
const WINDOW: usize = 64;
/// Prior build throughput before two builds were measured: 4 M triangles/s plus 0.5 ms.
const PRIOR_BUILD_MS: (f64, f64) = (0.5, 2.5e-4);
/// Prior gain per instance and frame before the fits have spread in instance counts.
const PRIOR_GAIN_MS_PER_INSTANCE: f64 = 2e-3;
/// Prior expected sleep, in frames, before any island has slept.
const PRIOR_SLEEP_FRAMES: f64 = 30.0;

/// A running least-squares line over the last [`WINDOW`] samples.
#[derive(Clone, Debug, Default)]
struct LineFit {
    samples: VecDeque<(f64, f64)>,
}

impl LineFit {
    fn push(&mut self, x: f64, y: f64) {
        if !(x.is_finite() && y.is_finite()) {
            return;
        }
        if self.samples.len() == WINDOW {
            self.samples.pop_front();
        }
        self.samples.push_back((x, y));
    }

    /// `(intercept, slope)`, or `None` while the x values do not spread.
    fn fit(&self) -> Option<(f64, f64)> {
        let n = self.samples.len() as f64;
        if n < 2.0 {
            return None;
        }
        let (sx, sy) = self.samples.iter().fold((0.0, 0.0), |(a, b), (x, y)| (a + x, b + y));
        let (mx, my) = (sx / n, sy / n);
        let (sxx, sxy) = self
            .samples
            .iter()
            .fold((0.0, 0.0), |(a, b), (x, y)| (a + (x - mx) * (x - mx), b + (x - mx) * (y - my)));
        if sxx <= 1e-9 * mx.abs().max(1.0) {
            return None;
        }
        let slope = sxy / sxx;
        Some((my - slope * mx, slope))
    }
}

/// The numbers behind one decision.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct CostEstimate {
    /// Estimated build cost `C_i`, ms.
    pub build_ms: f64,
    /// Estimated saving per rendered frame while integrated, ms.
    pub gain_ms_per_frame: f64,
    /// Expected further frames asleep.
    pub expected_frames: f64,
}

impl CostEstimate {
    /// `t_n`: the total expected saving.
    pub fn gain_ms(&self) -> f64 {
        self.gain_ms_per_frame * self.expected_frames
    }

    pub fn pays_off(&self) -> bool {
        self.build_ms < self.gain_ms()
    }
}

/// What the model has learned so far (for the per-run report).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct CostModelState {
    pub build_ms_intercept: f64,
    pub build_ms_per_mtriangle: f64,
    pub commit_ms_per_instance: f64,
    pub trace_ms_per_instance: f64,
    pub sleep_samples: usize,
    pub shadow_islands: u64,
}

/// Estimates for the integrate-or-not decision; see the module docs.
#[derive(Clone, Debug, Default)]
pub struct CostModel {
    build: LineFit,
    commit: LineFit,
    trace: LineFit,
    /// Frames each ended island slept (rendered frames).
    sleeps: VecDeque<f64>,
    shadow_islands: u64,
}

impl CostModel {
    pub fn new() -> Self {
        Self::default()
    }

    /// A static build of `triangles` took `ms`.
    pub fn record_build(&mut self, triangles: usize, ms: f64) {
        if triangles > 0 {
            self.build.push(triangles as f64, ms);
        }
    }

    /// A frame with `instances` in the top level took `commit_ms` to commit (only frames that
    /// rebuilt the top level) and `trace_ms` to trace.
    pub fn record_frame(&mut self, instances: usize, commit_ms: Option<f64>, trace_ms: f64) {
        if let Some(ms) = commit_ms {
            self.commit.push(instances as f64, ms);
        }
        self.trace.push(instances as f64, trace_ms);
    }

    /// An island ended after sleeping `frames` rendered frames; `integrated` says whether it
    /// was (a declined island is a shadow sample).
    pub fn record_sleep(&mut self, frames: f64, integrated: bool) {
        if self.sleeps.len() == 4 * WINDOW {
            self.sleeps.pop_front();
        }
        self.sleeps.push_back(frames);
        if !integrated {
            self.shadow_islands += 1;
        }
    }

    /// Estimated ms to build `triangles` into the static scene.
    pub fn build_ms(&self, triangles: usize) -> f64 {
        let (a, b) = self.build.fit().filter(|(_, b)| *b > 0.0).unwrap_or(PRIOR_BUILD_MS);
        (a + b * triangles as f64).max(0.0)
    }

    /// Estimated ms saved per rendered frame by removing `instances` from the top level.
    pub fn gain_ms_per_frame(&self, instances: usize) -> f64 {
        let slope = |f: &LineFit| f.fit().map(|(_, b)| b.max(0.0));
        let per_instance = match (slope(&self.commit), slope(&self.trace)) {
            (None, None) => PRIOR_GAIN_MS_PER_INSTANCE,
            (c, t) => c.unwrap_or(0.0) + t.unwrap_or(0.0),
        };
        per_instance * instances as f64
    }

    /// Expected further rendered frames of sleep for an island asleep for `age` frames,
    /// given the ages of islands still asleep (censored samples), at most `frames_left`.
    pub fn expected_frames(&self, age: f64, live_ages: impl Iterator<Item = f64>, frames_left: f64) -> f64 {
        let (mut sum, mut n) = (0.0, 0usize);
        for d in self.sleeps.iter().copied().chain(live_ages) {
            if d > age {
                sum += d - age;
                n += 1;
            }
        }
        let expected = if n == 0 { PRIOR_SLEEP_FRAMES } else { sum / n as f64 };
        expected.min(frames_left.max(0.0))
    }

    pub fn state(&self) -> CostModelState {
        let (a, b) = self.build.fit().unwrap_or(PRIOR_BUILD_MS);
        let slope = |f: &LineFit| f.fit().map_or(0.0, |(_, b)| b);
        CostModelState {
            build_ms_intercept: a,
            build_ms_per_mtriangle: b * 1e6,
            commit_ms_per_instance: slope(&self.commit),
            trace_ms_per_instance: slope(&self.trace),
            sleep_samples: self.sleeps.len(),
            shadow_islands: self.shadow_islands,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_fit_recovers_a_line() {
        let mut f = LineFit::default();
        for x in 0..10 {
            f.push(x as f64, 2.0 + 0.5 * x as f64);
        }
        let (a, b) = f.fit().unwrap();
        assert!((a - 2.0).abs() < 1e-9 && (b - 0.5).abs() < 1e-9);
    }

    #[test]
    fn build_cost_follows_measurements() {
        let mut m = CostModel::new();
        assert!(m.build_ms(1_000_000) > 0.0, "prior before samples");
        m.record_build(1000, 1.0);
        m.record_build(11000, 6.0);
        assert!((m.build_ms(21000) - 11.0).abs() < 1e-6);
    }

    #[test]
    fn expected_sleep_is_the_mean_residual() {
        let mut m = CostModel::new();
        for d in [10.0, 20.0, 90.0] {
            m.record_sleep(d, true);
        }
        assert_eq!(m.expected_frames(0.0, std::iter::empty(), 1e9), 40.0);
        assert_eq!(m.expected_frames(15.0, std::iter::empty(), 1e9), 40.0, "(5 + 75) / 2");
        assert_eq!(m.expected_frames(15.0, [115.0].into_iter(), 1e9), 60.0, "(5 + 75 + 100) / 3");
        assert_eq!(m.expected_frames(15.0, std::iter::empty(), 7.0), 7.0, "capped by the run");
    }
}
