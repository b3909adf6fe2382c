//! When a backend rebuilds its resting level: [`RestingSchedule`], shared by every backend so
//! both make the same decision from their own measured costs.
//!
//! The resting level is organised like the two generations of a log-structured merge tree.
//! An instance set to rest does not enter the resting level at once: it *waits* in the
//! per-frame top level, where it costs what it cost while awake. An instance of the resting
//! level that wakes (or moves, or is removed) is not taken out: its copy stays behind as a
//! *ghost* that rays skip, and the instance itself joins the top level. The level is rebuilt
//! (the waiting join it, the ghosts leave it) only when the schedule says so:
//! - when what the waiting instances have cost in top-level builds since the last rebuild
//!   reaches what a rebuild is predicted to cost (ski rental: the waiting never cost more than
//!   twice the best schedule in hindsight, whatever the future holds);
//! - when ghosts make up a quarter of the level (rays pay for their bounds);
//! - when the waiting are most of the top level ([`WAITING_OVER_AWAKE`] times the awake
//!   bodies or more): the top level then costs rays more than its builds cost, and a settled
//!   scene may not commit at all, so the waiting would never be charged;
//! - when the level is empty (the first build costs only the waiting instances, which the
//!   cost model chose to integrate) or holds only ghosts (a rebuild of nothing is free).
//!
//! Rebuilding at every island event instead cost more than the per-frame top-level build the
//! level replaces, on scenes where a few islands fall asleep and wake in every frame:
//! docs/lab/integration.md#2026-12-01-the-resting-form-with-a-scheduled-resting-level

/// Prior cost of a resting-level rebuild per instance, ms: about what Embree's HIGH instance
/// build measured (docs/lab/integration.md#2026-12-01-the-cost-models-priors-and-its-first-frame).
const PRIOR_REBUILD_MS_PER_INSTANCE: f64 = 0.4e-3;

/// Weight of a new measurement in the running mean of the rebuild cost.
const REBUILD_WEIGHT: f64 = 0.3;

/// Rebuild when ghosts are more than this share of the level's instances.
const MAX_GHOST_SHARE: f64 = 0.25;

/// Rebuild when the waiting instances are at least this many times the awake ones.
const WAITING_OVER_AWAKE: usize = 4;

/// What the resting level holds and what waits for it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct RestingCounts {
    /// Resting instances in the level.
    pub live: usize,
    /// Copies in the level that rays skip (their instances woke, moved or were removed).
    pub(crate) ghosts: usize,
    /// Resting instances still in the top level, waiting for the next rebuild.
    pub(crate) waiting: usize,
}

/// Decides when to rebuild a resting level (see the module documentation).
#[derive(Clone, Debug)]
pub(crate) struct RestingSchedule {
    /// Running mean of a rebuild's cost per instance, ms.
    rebuild_ms_per_instance: f64,
    /// What the waiting instances cost in top-level builds since the last rebuild, ms.
    waited_ms: f64,
}

impl Default for RestingSchedule {
    fn default() -> Self {
        Self { rebuild_ms_per_instance: PRIOR_REBUILD_MS_PER_INSTANCE, waited_ms: 0.0 }
    }
}

impl RestingSchedule {
    /// A top-level build over `instances` took `ms`; `waiting` of them wait for the resting
    /// level and are charged their share.
    pub(crate) fn record_top_build(&mut self, instances: usize, waiting: usize, ms: f64) {
        if instances > 0 && waiting > 0 {
            self.waited_ms += ms * waiting.min(instances) as f64 / instances as f64;
        }
    }

    /// A rebuild of the resting level over `instances` took `ms`.
    pub(crate) fn record_rebuild(&mut self, instances: usize, ms: f64) {
        self.waited_ms = 0.0;
        if instances > 0 {
            let per = ms / instances as f64;
            self.rebuild_ms_per_instance += REBUILD_WEIGHT * (per - self.rebuild_ms_per_instance);
        }
    }

    /// The predicted cost of rebuilding the level for `counts`, ms.
    pub(crate) fn predicted_rebuild_ms(&self, counts: RestingCounts) -> f64 {
        self.rebuild_ms_per_instance * (counts.live + counts.waiting) as f64
    }

    /// Whether the level should be rebuilt now, with `awake` instances in the top level
    /// beside the waiting ones.
    pub(crate) fn rebuild_due(&self, counts: RestingCounts, awake: usize) -> bool {
        if counts.waiting == 0 && counts.ghosts == 0 {
            return false;
        }
        let level = counts.live + counts.ghosts;
        let first = level == 0;
        let only_ghosts = counts.live == 0 && counts.waiting == 0;
        let mostly_waiting = counts.waiting > 0 && counts.waiting >= WAITING_OVER_AWAKE * awake;
        first
            || only_ghosts
            || mostly_waiting
            || counts.ghosts as f64 > MAX_GHOST_SHARE * level as f64
            || (counts.waiting > 0 && self.waited_ms >= self.predicted_rebuild_ms(counts))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn counts(live: usize, ghosts: usize, waiting: usize) -> RestingCounts {
        RestingCounts { live, ghosts, waiting }
    }

    #[test]
    fn nothing_to_do_is_never_due() {
        assert!(!RestingSchedule::default().rebuild_due(counts(1000, 0, 0), 10));
    }

    #[test]
    fn waiting_is_rebuilt_once_it_has_cost_a_rebuild() {
        let mut s = RestingSchedule::default();
        assert!(s.rebuild_due(counts(0, 0, 100), 100), "the first build is not delayed");
        let c = counts(10_000, 0, 100);
        assert!(!s.rebuild_due(c, 1000));
        // 4 ms predicted; each top build of 1,100 instances charges the 100 waiting 1/11.
        for _ in 0..44 {
            s.record_top_build(1100, 100, 1.0);
        }
        assert!(!s.rebuild_due(c, 1000), "{} ms waited", s.waited_ms);
        s.record_top_build(1100, 100, 1.0);
        assert!(s.rebuild_due(c, 1000));
        s.record_rebuild(10_100, 4.04);
        assert!(!s.rebuild_due(counts(10_100, 0, 1), 1000));
    }

    #[test]
    fn ghosts_are_dropped_at_a_quarter_of_the_level() {
        let s = RestingSchedule::default();
        assert!(!s.rebuild_due(counts(750, 250, 0), 10));
        assert!(s.rebuild_due(counts(749, 251, 0), 10));
        assert!(s.rebuild_due(counts(0, 1, 0), 10));
    }

    #[test]
    fn a_top_level_of_mostly_waiting_instances_is_rebuilt() {
        let s = RestingSchedule::default();
        assert!(!s.rebuild_due(counts(10_000, 0, 399), 100));
        assert!(s.rebuild_due(counts(10_000, 0, 400), 100));
        assert!(s.rebuild_due(counts(10_000, 0, 1), 0), "a settled scene");
    }

    #[test]
    fn measured_rebuilds_replace_the_prior() {
        let mut s = RestingSchedule::default();
        for _ in 0..30 {
            s.record_rebuild(1000, 1.0);
        }
        assert!((s.predicted_rebuild_ms(counts(1000, 0, 0)) - 1.0).abs() < 1e-3);
    }
}
