//! The cost model: integrate an island only when what it saves before it wakes exceeds what
//! it costs. Per island `i`, over the `n_i` rendered frames it will still sleep:
//!
//! `net_i = n_i * (commit gain_i - trace penalty_i) - build_i - wake_i`
//!
//! and one frame's candidates go in together when their positive nets pay the frame's shared
//! fixed cost (a static build's overhead, or the second scene's trace penalty when the
//! resting scene is empty).
//!
//! - **`n_i`**: exact when the future is known ([`super::Lookahead`]: an offline render
//!   simulates first), counting only the frames that will be rendered; otherwise the mean
//!   residual sleep of islands that slept as long as this one already has, over every island
//!   seen (integrated or not: declined islands are "shadow" samples, so the estimate does not
//!   learn only from its own choices; islands still asleep count with their current age).
//! - **commit gain**: commit ms per top-level instance (the top level's rebuild is linear in
//!   its instances) times the island's bodies, weighted by how often frames commit at all.
//! - **trace penalty**: what integrated bodies cost the trace, measured by the scene manager's
//!   probes (the same rays traced just before and just after an integration):
//!   - baked: world-space triangles of rotated bodies are bounded more loosely than an
//!     instance's object-space BVH bounds them: a fraction of the trace per baked share of
//!     the bodies;
//!   - resting: a second scene per ray, a fixed fraction of the trace while it is non-empty.
//! - **build**: a least-squares line over recent builds, `a + b * triangles` (baked) or
//!   `c + d * instances` (rebuilding the resting level; an island pays its instances' share
//!   `d * bodies`, since the backends rebuild that level on their own schedule, when the
//!   waiting islands have cost a rebuild: `crate::accel::RestingSchedule`);
//! - **wake**: nothing at the wake itself: baked islands leave by a detach, resting ones leave
//!   ghosts that rays skip until the next scheduled rebuild.
//!
//! Before there are enough samples the model uses priors (below), which the measurements
//! replace as soon as they exist.

use std::collections::VecDeque;

use super::{IntegrationForm, TraceKind};

/// Samples kept per fit.
const WINDOW: usize = 64;
/// Prior build throughput before two builds were measured: 4 M triangles/s plus 0.5 ms.
const PRIOR_BUILD_MS: (f64, f64) = (0.5, 2.5e-4);
/// Prior commit ms per top-level instance before a commit of at least
/// [`MIN_COMMIT_INSTANCES`] was measured: about what both backends measured on large scenes
/// (docs/lab/integration.md#2026-12-01-the-cost-models-priors-and-its-first-frame).
const PRIOR_GAIN_MS_PER_INSTANCE: f64 = 5e-4;
/// Commits of fewer top-level instances do not measure the per-instance cost: a commit's
/// fixed part dominates them. Counted in, the few awake bodies left once everything else
/// rests made the ratio far too large, and `auto` integrated islands worth nothing (the same
/// entry).
const MIN_COMMIT_INSTANCES: usize = 1000;
/// Prior expected sleep, in frames, before any island has slept.
const PRIOR_SLEEP_FRAMES: f64 = 30.0;
/// Prior rebuild of the resting scene, ms: fixed, and per instance about what both backends
/// measured (docs/lab/integration.md#2026-12-01-the-cost-models-priors-and-its-first-frame).
const PRIOR_REST_MS: (f64, f64) = (0.2, 5e-4);
/// Prior trace penalties until a probe measured them: a second scene per ray costs little on
/// most scenes and more on the demolition; baking every body costs more:
/// docs/lab/integration.md#2026-12-01-the-cost-models-priors-and-its-first-frame
const PRIOR_RESTING_PENALTY: f64 = 0.10;
const PRIOR_BAKED_PENALTY: f64 = 0.15;

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
/// Weight of the newest trace time in the running mean of a frame's trace.
const TRACE_EMA: f64 = 0.2;

/// The numbers behind one decision.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct CostEstimate {
    /// This island's own share of the build, ms (baked: its triangles; resting: its
    /// instances in the rebuilt resting scene); the frame's shared cost is apart.
    pub build_ms: f64,
    /// The cost its wake adds while rendering, ms (resting: a rebuild of the resting scene not
    /// already due that frame; baked: nothing, removal is a detach).
    pub(crate) wake_ms: f64,
    /// Estimated saving per rendered frame while integrated, ms: commit gain minus trace
    /// penalty.
    pub(crate) gain_ms_per_frame: f64,
    /// Rendered frames it will still sleep: exact with lookahead, else expected.
    pub(crate) expected_frames: f64,
    /// Whether `expected_frames` is known (lookahead) rather than estimated.
    pub exact: bool,
}

impl CostEstimate {
    /// The total saving over the frames it sleeps.
    pub(crate) fn gain_ms(&self) -> f64 {
        self.gain_ms_per_frame * self.expected_frames
    }

    /// Saving minus its own costs (the frame's shared cost is not included).
    pub(crate) fn net_ms(&self) -> f64 {
        self.gain_ms() - self.build_ms - self.wake_ms
    }
}

/// Which of one frame's candidates to integrate: those with a positive net saving, if
/// together they also pay the frame's shared cost `fixed_ms`. Islands one by one would each
/// pay it, and many small islands that pay off together would be declined.
pub(crate) fn choose_batch(estimates: &[CostEstimate], fixed_ms: f64) -> Vec<bool> {
    let net: f64 = estimates.iter().map(|e| e.net_ms().max(0.0)).sum();
    let go = net > fixed_ms;
    estimates.iter().map(|e| go && e.net_ms() > 0.0).collect()
}

/// A sleeping island the manager could integrate this frame.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Candidate {
    pub bodies: usize,
    pub triangles: usize,
    /// Rendered frames it has slept so far.
    pub(crate) age: u32,
    /// Rendered frames it will still sleep, this one included (lookahead); `None`: estimate.
    pub(crate) remaining: Option<u32>,
}

/// The scene the candidates would join.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Situation {
    pub form: IntegrationForm,
    /// Dynamic bodies present this frame (baked penalty is per share of them).
    pub present_bodies: usize,
    /// Instances in the resting scene now.
    pub resting_instances: usize,
    /// Rendered frames left in the run, this one included.
    pub(crate) frames_left: f64,
}

/// The cost model's estimates for one frame (see [`CostModel::outlook`]).
#[derive(Clone, Debug)]
pub(crate) struct Outlook {
    situation: Situation,
    build_line: (f64, f64),
    rest_line: (f64, f64),
    /// Commit ms saved per instance and rendered frame.
    commit_gain_per_instance: f64,
    /// Trace ms of a frame (running mean).
    trace_ms: f64,
    penalty: Penalties,
    /// Sleep durations of ended islands and ages of live ones, ascending.
    durations: Vec<f64>,
    suffix: Vec<f64>,
}

impl Outlook {
    /// The estimate for one candidate.
    pub(crate) fn estimate(&self, c: &Candidate) -> CostEstimate {
        let sit = &self.situation;
        let frames = match c.remaining {
            Some(n) => f64::from(n),
            None => self.expected_frames(f64::from(c.age)),
        };
        let commit_gain = self.commit_gain_per_instance * c.bodies as f64;
        let (build_ms, penalty, wake_ms) = match sit.form {
            IntegrationForm::Baked => {
                let share = c.bodies as f64 / sit.present_bodies.max(1) as f64;
                (self.build_line.1 * c.triangles as f64, self.penalty.baked * self.trace_ms * share, 0.0)
            }
            IntegrationForm::Resting => (self.rest_line.1 * c.bodies as f64, 0.0, 0.0),
        };
        CostEstimate {
            build_ms,
            wake_ms,
            gain_ms_per_frame: commit_gain - penalty,
            expected_frames: frames,
            exact: c.remaining.is_some(),
        }
    }

    /// The frame's shared cost of integrating `chosen` (estimates of the candidates that net
    /// a saving): a static build's overhead, or, when the resting scene is empty, the second
    /// scene's trace penalty while it stays in use (its rebuilds are scheduled by the backend
    /// and priced per island).
    pub(crate) fn fixed_ms(&self, chosen: &[CostEstimate]) -> f64 {
        let sit = &self.situation;
        match sit.form {
            IntegrationForm::Baked => self.build_line.0,
            IntegrationForm::Resting if sit.resting_instances == 0 => {
                let frames = chosen.iter().map(|e| e.expected_frames).fold(0.0, f64::max);
                self.penalty.resting * self.trace_ms * frames
            }
            IntegrationForm::Resting => 0.0,
        }
    }

    /// Expected further rendered frames of sleep for an island asleep for `age` frames: the
    /// mean of `d - age` over the durations `d > age`, at most the frames left.
    pub(crate) fn expected_frames(&self, age: f64) -> f64 {
        let first = self.durations.partition_point(|&d| d <= age);
        let n = self.durations.len() - first;
        let expected =
            if n == 0 { PRIOR_SLEEP_FRAMES } else { (self.suffix[first] - age * n as f64) / n as f64 };
        expected.min(self.situation.frames_left.max(0.0))
    }
}

/// Measured trace penalties of the integration forms, as fractions of a frame's trace.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub(crate) struct Penalties {
    /// With every present body baked (scaled by the baked share).
    pub baked: f64,
    /// With a non-empty resting scene.
    pub resting: f64,
    /// Probes that measured them.
    pub(crate) probes: u32,
}

impl Default for Penalties {
    fn default() -> Self {
        Self { baked: PRIOR_BAKED_PENALTY, resting: PRIOR_RESTING_PENALTY, probes: 0 }
    }
}

/// What the model has learned so far (for the per-run report).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct CostModelState {
    pub(crate) build_ms_intercept: f64,
    pub(crate) build_ms_per_mtriangle: f64,
    pub(crate) rest_ms_intercept: f64,
    pub(crate) rest_ms_per_kinstance: f64,
    pub(crate) commit_ms_per_instance: f64,
    pub(crate) trace_ms_mean: f64,
    pub(crate) penalty: Penalties,
    pub(crate) sleep_samples: usize,
    pub(crate) shadow_islands: u64,
}

/// Estimates for the integrate-or-not decision; see the module docs.
#[derive(Clone, Debug, Default)]
pub(crate) struct CostModel {
    build: LineFit,
    rest: LineFit,
    commit: LineFit,
    /// Running mean of a frame's trace, ms.
    trace_ms: Option<f64>,
    /// `trace_ms` is an estimate made before any frame was traced ([`Self::assume_trace`]):
    /// the first measured frame replaces it.
    trace_assumed: bool,
    penalty: Penalties,
    /// Whether each recent frame committed (a frame where nothing moved commits nothing, so
    /// an instance fewer saves nothing there).
    committed: VecDeque<bool>,
    /// Frames each ended island slept (rendered frames).
    sleeps: VecDeque<f64>,
    shadow_islands: u64,
}

impl CostModel {
    pub(crate) fn new() -> Self {
        Self::default()
    }

    /// A static build of `triangles` took `ms`.
    pub(crate) fn record_build(&mut self, triangles: usize, ms: f64) {
        if triangles > 0 {
            self.build.push(triangles as f64, ms);
        }
    }

    /// A rebuild of the resting scene with `instances` took `ms`.
    pub(crate) fn record_rest_build(&mut self, instances: usize, ms: f64) {
        self.rest.push(instances as f64, ms);
    }

    /// A frame with `instances` in the top level took `commit_ms` to commit (only frames that
    /// rebuilt the top level) and `trace_ms` to trace, of `kind`.
    pub(crate) fn record_frame(
        &mut self,
        instances: usize,
        commit_ms: Option<f64>,
        trace_ms: f64,
        kind: TraceKind,
    ) {
        if let Some(ms) = commit_ms.filter(|_| instances >= MIN_COMMIT_INSTANCES) {
            self.commit.push(instances as f64, ms);
        }
        if self.committed.len() == WINDOW {
            self.committed.pop_front();
        }
        self.committed.push_back(commit_ms.is_some());
        if !trace_ms.is_finite() {
            return;
        }
        let mean = self.trace_ms.filter(|_| !self.trace_assumed);
        match (kind, mean) {
            (TraceKind::Typical, _) => {
                self.trace_ms = Some(mean.map_or(trace_ms, |m| m + TRACE_EMA * (trace_ms - m)));
                self.trace_assumed = false;
            }
            // Only an assumption yields to it, and it is one itself.
            (TraceKind::FullBeforeReuse, None) => {
                self.trace_ms = Some(trace_ms);
                self.trace_assumed = true;
            }
            (TraceKind::FullBeforeReuse, Some(_)) => {}
        }
    }

    /// A probe traced the same rays in `before_ms` and, after integrating, in `after_ms`;
    /// `share` is the share of present bodies the integration moved (baked), or 1 (the
    /// resting scene went from empty to in use).
    pub(crate) fn record_probe(&mut self, form: IntegrationForm, before_ms: f64, after_ms: f64, share: f64) {
        if !(before_ms > 0.0 && after_ms.is_finite() && share > 0.0) {
            return;
        }
        let penalty = ((after_ms / before_ms - 1.0) / share).clamp(-0.5, 2.0);
        match form {
            IntegrationForm::Baked => self.penalty.baked = penalty,
            IntegrationForm::Resting => self.penalty.resting = penalty,
        }
        self.penalty.probes += 1;
    }

    /// An island ended after sleeping `frames` rendered frames; `integrated` says whether it
    /// was (a declined island is a shadow sample).
    pub(crate) fn record_sleep(&mut self, frames: f64, integrated: bool) {
        if self.sleeps.len() == 4 * WINDOW {
            self.sleeps.pop_front();
        }
        self.sleeps.push_back(frames);
        if !integrated {
            self.shadow_islands += 1;
        }
    }

    /// A build line in use: the fit once it has enough samples (intercept clamped to the
    /// cheapest build seen, so one slow outlier cannot make every build look expensive), else
    /// the prior.
    fn line(fit: &LineFit, prior: (f64, f64)) -> (f64, f64) {
        match fit.fit_with(MIN_BUILD_SAMPLES, 0.0) {
            Some((a, b)) if b >= 0.0 => (a.clamp(0.0, fit.min_y()), b),
            _ => prior,
        }
    }

    /// Estimated ms to build `triangles` into the static scene.
    #[cfg(test)]
    pub(crate) fn build_ms(&self, triangles: usize) -> f64 {
        let (a, b) = Self::line(&self.build, PRIOR_BUILD_MS);
        (a + b * triangles as f64).max(0.0)
    }

    /// Whether a frame's trace time is known, measured or assumed (the trace penalty is
    /// priced in it).
    pub(crate) fn knows_trace(&self) -> bool {
        self.trace_ms.is_some()
    }

    /// Takes `ms` as a frame's trace until one is measured.
    pub(crate) fn assume_trace(&mut self, ms: f64) {
        if self.trace_ms.is_none() && ms.is_finite() && ms > 0.0 {
            self.trace_ms = Some(ms);
            self.trace_assumed = true;
        }
    }

    /// The model's current estimates, fixed for one frame's decisions: the fits are computed
    /// once and the sleep durations sorted, so each island's estimate is O(log n).
    pub(crate) fn outlook(&self, situation: Situation, live_ages: impl Iterator<Item = f64>) -> Outlook {
        let mut durations: Vec<f64> = self.sleeps.iter().copied().chain(live_ages).collect();
        durations.sort_by(f64::total_cmp);
        // suffix[i] = sum of durations[i..].
        let mut suffix = vec![0.0; durations.len() + 1];
        for i in (0..durations.len()).rev() {
            suffix[i] = suffix[i + 1] + durations[i];
        }
        Outlook {
            situation,
            build_line: Self::line(&self.build, PRIOR_BUILD_MS),
            rest_line: Self::line(&self.rest, PRIOR_REST_MS),
            commit_gain_per_instance: self.commit_gain_per_instance(),
            trace_ms: self.trace_ms.unwrap_or(0.0),
            penalty: self.penalty,
            durations,
            suffix,
        }
    }

    /// Commit ms one instance fewer saves per rendered frame: the top level's rebuild is
    /// linear in its instances, and frames where nothing moved commit nothing.
    fn commit_gain_per_instance(&self) -> f64 {
        let commit_rate = if self.committed.is_empty() {
            1.0
        } else {
            self.committed.iter().filter(|c| **c).count() as f64 / self.committed.len() as f64
        };
        self.commit.ratio().unwrap_or(PRIOR_GAIN_MS_PER_INSTANCE) * commit_rate
    }

    pub(crate) fn state(&self) -> CostModelState {
        let (a, b) = Self::line(&self.build, PRIOR_BUILD_MS);
        let (c, d) = Self::line(&self.rest, PRIOR_REST_MS);
        CostModelState {
            build_ms_intercept: a,
            build_ms_per_mtriangle: b * 1e6,
            rest_ms_intercept: c,
            rest_ms_per_kinstance: d * 1e3,
            commit_ms_per_instance: self.commit.ratio().unwrap_or(0.0),
            trace_ms_mean: self.trace_ms.unwrap_or(0.0),
            penalty: self.penalty,
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
            wake_ms: 0.0,
            gain_ms_per_frame,
            expected_frames: 10.0,
            exact: false,
        };
        // Each nets 0.9 ms, less than the 2 ms fixed cost alone, but three together pay it.
        assert_eq!(choose_batch(&[e(0.1, 0.1), e(0.1, 0.1)], 2.0), [false, false]);
        assert_eq!(
            choose_batch(&[e(0.1, 0.1), e(0.1, 0.1), e(0.1, 0.1), e(5.0, 0.1)], 2.0),
            [true, true, true, false]
        );
        assert!(choose_batch(&[], 2.0).is_empty());
    }

    fn situation(form: IntegrationForm, frames_left: f64) -> Situation {
        Situation { form, present_bodies: 1000, resting_instances: 0, frames_left }
    }

    #[test]
    fn expected_sleep_is_the_mean_residual() {
        let mut m = CostModel::new();
        for d in [10.0, 20.0, 90.0] {
            m.record_sleep(d, true);
        }
        let none = || std::iter::empty();
        let s = situation(IntegrationForm::Baked, 1e9);
        assert_eq!(m.outlook(s, none()).expected_frames(0.0), 40.0);
        assert_eq!(m.outlook(s, none()).expected_frames(15.0), 40.0, "(5 + 75) / 2");
        assert_eq!(m.outlook(s, [115.0].into_iter()).expected_frames(15.0), 60.0, "(5 + 75 + 100) / 3");
        let short = situation(IntegrationForm::Baked, 7.0);
        assert_eq!(m.outlook(short, none()).expected_frames(15.0), 7.0, "capped by the run");
        assert_eq!(m.outlook(s, none()).expected_frames(90.0), PRIOR_SLEEP_FRAMES, "older than all");
    }

    #[test]
    fn lookahead_replaces_the_estimate_and_resting_wakes_cost_nothing() {
        let mut m = CostModel::new();
        for k in 0..8 {
            m.record_frame(1000 + 100 * k, Some(1.0 + 0.1 * k as f64), 20.0, TraceKind::Typical);
        }
        let sit = situation(IntegrationForm::Resting, 100.0);
        let outlook = m.outlook(sit, std::iter::empty());
        let c = Candidate { bodies: 100, triangles: 1200, age: 0, remaining: Some(50) };
        let e = outlook.estimate(&c);
        assert!(e.exact && e.expected_frames == 50.0);
        assert_eq!(e.wake_ms, 0.0, "a woken resting island leaves ghosts, no rebuild");
        assert!(e.build_ms > 0.0, "it pays its share of the scheduled rebuild");
        // The second scene's penalty is a shared cost while the resting scene is empty.
        assert!(outlook.fixed_ms(std::slice::from_ref(&e)) > 0.0);
        let used = Situation { resting_instances: 500, ..sit };
        assert_eq!(m.outlook(used, std::iter::empty()).fixed_ms(&[e]), 0.0);
    }

    #[test]
    fn an_assumed_trace_stands_until_the_first_measured_frame() {
        let mut m = CostModel::new();
        assert!(!m.knows_trace());
        m.assume_trace(40.0);
        assert!(m.knows_trace() && m.trace_ms == Some(40.0));
        m.assume_trace(80.0);
        assert_eq!(m.trace_ms, Some(40.0), "a second estimate changes nothing");
        m.record_frame(2000, Some(1.0), 10.0, TraceKind::Typical);
        assert_eq!(m.trace_ms, Some(10.0), "the measured frame replaces it, not averaged in");
        m.record_frame(2000, Some(1.0), 20.0, TraceKind::Typical);
        assert!(m.trace_ms.unwrap() > 10.0 && m.trace_ms.unwrap() < 20.0);
    }

    #[test]
    fn a_full_frame_before_reuse_stands_only_until_a_reusing_frame_is_measured() {
        let mut m = CostModel::new();
        m.assume_trace(40.0);
        m.record_frame(2000, Some(1.0), 4000.0, TraceKind::FullBeforeReuse);
        assert_eq!(m.trace_ms, Some(4000.0), "it replaces the probe's estimate");
        m.record_frame(2000, Some(1.0), 150.0, TraceKind::Typical);
        assert_eq!(m.trace_ms, Some(150.0), "the first reusing frame replaces it, not averaged in");
        m.record_frame(2000, Some(1.0), 3000.0, TraceKind::FullBeforeReuse);
        assert_eq!(m.trace_ms, Some(150.0), "a later full frame leaves the mean alone");
        m.record_frame(2000, Some(1.0), 250.0, TraceKind::Typical);
        assert_eq!(m.trace_ms, Some(150.0 + TRACE_EMA * 100.0));
    }

    #[test]
    fn probes_set_the_penalty_of_their_form() {
        let mut m = CostModel::new();
        m.record_probe(IntegrationForm::Baked, 10.0, 10.5, 0.25);
        m.record_probe(IntegrationForm::Resting, 10.0, 10.2, 1.0);
        let p = m.state().penalty;
        assert!((p.baked - 0.2).abs() < 1e-9 && (p.resting - 0.02).abs() < 1e-9 && p.probes == 2);
    }
}
