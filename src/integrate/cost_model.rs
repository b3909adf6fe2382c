//! The cost model: integrate an island only when its estimated build cost `C_i` is less than
//! the time it is expected to save before it wakes, `t_n = gain per frame x expected frames`.
//!
//! Every estimate comes from measurements of this run:
//! - **build cost**: a least-squares line `ms = a + b * triangles` over recent static builds;
//! - **gain per frame**: what one instance fewer saves: commit ms per instance (the top
//!   level's rebuild is linear in its instances) weighted by how often frames commit at all,
//!   plus the least-squares slope of trace time over instance count once the counts spread
//!   enough to measure it (negative where baked geometry traces slower than instances);
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

    /// `(intercept, slope)`, or `None` with fewer than `min_samples` or while the x values
    /// spread over less than `min_spread` of their mean.
    fn fit_with(&self, min_samples: usize, min_spread: f64) -> Option<(f64, f64)> {
        let n = self.samples.len() as f64;
        if self.samples.len() < min_samples.max(2) {
            return None;
        }
        let (lo, hi) =
            self.samples.iter().fold((f64::MAX, f64::MIN), |(lo, hi), (x, _)| (lo.min(*x), hi.max(*x)));
        let (sx, sy) = self.samples.iter().fold((0.0, 0.0), |(a, b), (x, y)| (a + x, b + y));
        let (mx, my) = (sx / n, sy / n);
        let (sxx, sxy) = self
            .samples
            .iter()
            .fold((0.0, 0.0), |(a, b), (x, y)| (a + (x - mx) * (x - mx), b + (x - mx) * (y - my)));
        if sxx <= 1e-9 * mx.abs().max(1.0) || hi - lo < min_spread * mx.abs() {
            return None;
        }
        let slope = sxy / sxx;
        Some((my - slope * mx, slope))
    }

    /// `sum(y) / sum(x)`: the slope of a line through the origin.
    fn ratio(&self) -> Option<f64> {
        let (sx, sy) = self.samples.iter().fold((0.0, 0.0), |(a, b), (x, y)| (a + x, b + y));
        (sx > 0.0).then(|| sy / sx)
    }

    fn min_y(&self) -> f64 {
        self.samples.iter().map(|s| s.1).fold(f64::INFINITY, f64::min)
    }
}

/// Build samples before the fitted line replaces the prior.
const MIN_BUILD_SAMPLES: usize = 6;
/// Trace samples, and the relative spread of their instance counts, before the trace slope
/// counts: the trace time of a frame varies with much more than the instance count, so a slope
/// over a narrow range is noise (and when `auto` integrates nothing the range stays narrow).
const MIN_TRACE_SAMPLES: usize = 16;
const MIN_TRACE_SPREAD: f64 = 0.2;

/// The numbers behind one decision.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct CostEstimate {
    /// Estimated build cost of this island's triangles, ms: `C_i` without the fixed cost of
    /// a static build, which one frame's integrations share.
    pub build_ms: f64,
    /// Fixed cost of the frame's static build (commit overhead), ms.
    pub fixed_ms: f64,
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

    /// `t_n - C_i` without the fixed cost.
    pub fn net_ms(&self) -> f64 {
        self.gain_ms() - self.build_ms
    }
}

/// Which of one frame's candidates to integrate: those with a positive net saving, if
/// together they also pay the static build's fixed cost (`estimates` share one `fixed_ms`).
/// Islands one by one would each pay the fixed cost and many small islands that pay off
/// together would be declined.
pub fn choose_batch(estimates: &[CostEstimate]) -> Vec<bool> {
    let fixed = estimates.first().map_or(0.0, |e| e.fixed_ms);
    let net: f64 = estimates.iter().map(|e| e.net_ms().max(0.0)).sum();
    let go = net > fixed;
    estimates.iter().map(|e| go && e.net_ms() > 0.0).collect()
}

/// The cost model's estimates for one frame (see [`CostModel::outlook`]).
#[derive(Clone, Debug)]
pub struct Outlook {
    fixed_ms: f64,
    ms_per_triangle: f64,
    gain_ms_per_instance: f64,
    /// Sleep durations of ended islands and ages of live ones, ascending.
    durations: Vec<f64>,
    suffix: Vec<f64>,
    frames_left: f64,
}

impl Outlook {
    /// The estimate for an island of `bodies` bodies and `triangles` triangles asleep for
    /// `age` rendered frames.
    pub fn estimate(&self, bodies: usize, triangles: usize, age: f64) -> CostEstimate {
        CostEstimate {
            build_ms: self.ms_per_triangle * triangles as f64,
            fixed_ms: self.fixed_ms,
            gain_ms_per_frame: self.gain_ms_per_instance * bodies as f64,
            expected_frames: self.expected_frames(age),
        }
    }

    /// Expected further rendered frames of sleep for an island asleep for `age` frames: the
    /// mean of `d - age` over the durations `d > age`, at most the frames left.
    pub fn expected_frames(&self, age: f64) -> f64 {
        let first = self.durations.partition_point(|&d| d <= age);
        let n = self.durations.len() - first;
        let expected =
            if n == 0 { PRIOR_SLEEP_FRAMES } else { (self.suffix[first] - age * n as f64) / n as f64 };
        expected.min(self.frames_left.max(0.0))
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
    /// Whether each recent frame committed (a frame where nothing moved commits nothing, so
    /// an instance fewer saves nothing there).
    committed: VecDeque<bool>,
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
        if self.committed.len() == WINDOW {
            self.committed.pop_front();
        }
        self.committed.push_back(commit_ms.is_some());
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

    /// The build line in use: the fit once it has enough samples (intercept clamped to the
    /// cheapest build seen, so one slow outlier cannot make every build look expensive), else
    /// the prior.
    fn build_line(&self) -> (f64, f64) {
        match self.build.fit_with(MIN_BUILD_SAMPLES, 0.0) {
            Some((a, b)) if b >= 0.0 => (a.clamp(0.0, self.build.min_y()), b),
            _ => PRIOR_BUILD_MS,
        }
    }

    /// Estimated ms to build `triangles` into the static scene.
    pub fn build_ms(&self, triangles: usize) -> f64 {
        let (a, b) = self.build_line();
        (a + b * triangles as f64).max(0.0)
    }

    /// The model's current estimates, fixed for one frame's decisions: the fits are computed
    /// once and the sleep durations sorted, so each island's estimate is O(log n).
    pub fn outlook(&self, live_ages: impl Iterator<Item = f64>, frames_left: f64) -> Outlook {
        let (fixed_ms, ms_per_triangle) = self.build_line();
        let mut durations: Vec<f64> = self.sleeps.iter().copied().chain(live_ages).collect();
        durations.sort_by(f64::total_cmp);
        // suffix[i] = sum of durations[i..].
        let mut suffix = vec![0.0; durations.len() + 1];
        for i in (0..durations.len()).rev() {
            suffix[i] = suffix[i + 1] + durations[i];
        }
        Outlook {
            fixed_ms,
            ms_per_triangle,
            gain_ms_per_instance: self.gain_ms_per_frame(1),
            durations,
            suffix,
            frames_left,
        }
    }

    /// Commit ms per instance: the top level's rebuild is linear in its instances.
    fn commit_per_instance(&self) -> Option<f64> {
        self.commit.ratio()
    }

    /// Trace ms per top-level instance. Not floored at 0: where baked geometry traces slower
    /// than instances (the BVH backend's many-block static tree), fewer instances cost time
    /// and integration must pay for that too.
    fn trace_per_instance(&self) -> Option<f64> {
        self.trace.fit_with(MIN_TRACE_SAMPLES, MIN_TRACE_SPREAD).map(|(_, b)| b)
    }

    /// Estimated ms saved per rendered frame by removing `instances` from the top level.
    pub fn gain_ms_per_frame(&self, instances: usize) -> f64 {
        let commit_rate = if self.committed.is_empty() {
            1.0
        } else {
            self.committed.iter().filter(|c| **c).count() as f64 / self.committed.len() as f64
        };
        let per_instance = match (self.commit_per_instance(), self.trace_per_instance()) {
            (None, None) => PRIOR_GAIN_MS_PER_INSTANCE,
            (c, t) => c.unwrap_or(0.0) * commit_rate + t.unwrap_or(0.0),
        };
        per_instance * instances as f64
    }

    pub fn state(&self) -> CostModelState {
        let (a, b) = self.build_line();
        CostModelState {
            build_ms_intercept: a,
            build_ms_per_mtriangle: b * 1e6,
            commit_ms_per_instance: self.commit_per_instance().unwrap_or(0.0),
            trace_ms_per_instance: self.trace_per_instance().unwrap_or(0.0),
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
        let (a, b) = f.fit_with(2, 0.0).unwrap();
        assert!((a - 2.0).abs() < 1e-9 && (b - 0.5).abs() < 1e-9);
    }

    #[test]
    fn build_cost_follows_measurements() {
        let mut m = CostModel::new();
        assert!(m.build_ms(1_000_000) > 0.0, "prior before samples");
        for k in 0..6 {
            m.record_build(1000 + 2000 * k, 1.0 + k as f64);
        }
        assert!((m.build_ms(21000) - 11.0).abs() < 1e-6);
        m.record_build(500, 60.0);
        assert!(
            m.state().build_ms_intercept <= 1.0,
            "an outlier cannot lift the intercept above the cheapest build"
        );
    }

    #[test]
    fn small_islands_pay_off_together() {
        let e = |build_ms, gain_ms_per_frame| CostEstimate {
            build_ms,
            fixed_ms: 2.0,
            gain_ms_per_frame,
            expected_frames: 10.0,
        };
        // Each nets 0.9 ms, less than the 2 ms fixed cost alone, but three together pay it.
        assert_eq!(choose_batch(&[e(0.1, 0.1), e(0.1, 0.1)]), [false, false]);
        assert_eq!(
            choose_batch(&[e(0.1, 0.1), e(0.1, 0.1), e(0.1, 0.1), e(5.0, 0.1)]),
            [true, true, true, false]
        );
        assert!(choose_batch(&[]).is_empty());
    }

    #[test]
    fn expected_sleep_is_the_mean_residual() {
        let mut m = CostModel::new();
        for d in [10.0, 20.0, 90.0] {
            m.record_sleep(d, true);
        }
        let none = || std::iter::empty();
        assert_eq!(m.outlook(none(), 1e9).expected_frames(0.0), 40.0);
        assert_eq!(m.outlook(none(), 1e9).expected_frames(15.0), 40.0, "(5 + 75) / 2");
        assert_eq!(m.outlook([115.0].into_iter(), 1e9).expected_frames(15.0), 60.0, "(5 + 75 + 100) / 3");
        assert_eq!(m.outlook(none(), 7.0).expected_frames(15.0), 7.0, "capped by the run");
        assert_eq!(m.outlook(none(), 1e9).expected_frames(90.0), PRIOR_SLEEP_FRAMES, "older than all");
    }
}
