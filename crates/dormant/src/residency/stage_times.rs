//! The stages of a rendered frame and their times: the one type every per-frame record,
//! total, mean and CSV column of stage times is made of.

use std::ops::{AddAssign, Div};

use serde::{Deserialize, Serialize};

/// Milliseconds spent in each stage of a frame (or summed, or averaged, over frames), in the
/// order the scene manager runs them: structure updates, then the trace. Serialised as
/// `update_ms`, `integrate_ms`, `reactivate_ms`, `commit_ms`, `trace_ms`; records that also
/// report the whole frame add `frame_ms` beside it ([`Self::frame_ms`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StageTimes {
    /// Instances follow the awake bodies (added, moved, removed).
    pub update_ms: f64,
    /// Sleeping islands go into the static scene.
    pub integrate_ms: f64,
    /// Woken islands leave the static scene.
    pub reactivate_ms: f64,
    /// The top level (and whatever changed below it) is built.
    pub commit_ms: f64,
    /// Rays are traced and shaded.
    pub trace_ms: f64,
}

/// A stage's name (its field in JSON and its CSV column) and how to read it.
pub(crate) type StageColumn = (&'static str, fn(&StageTimes) -> f64);

impl StageTimes {
    /// Every stage, in serialisation order: CSV headers and plots are generated from this.
    pub const STAGES: [StageColumn; 5] = [
        ("update_ms", |s| s.update_ms),
        ("integrate_ms", |s| s.integrate_ms),
        ("reactivate_ms", |s| s.reactivate_ms),
        ("commit_ms", |s| s.commit_ms),
        ("trace_ms", |s| s.trace_ms),
    ];

    /// The whole frame: every stage, the trace included.
    pub fn frame_ms(&self) -> f64 {
        self.reactivate_ms + self.integrate_ms + self.update_ms + self.commit_ms + self.trace_ms
    }

    /// Everything but the trace: the work integration adds or saves.
    pub fn structure_ms(&self) -> f64 {
        self.reactivate_ms + self.integrate_ms + self.update_ms
    }

    /// The mean of `frames` and how many there were (zero times for none).
    pub fn mean<'a>(frames: impl IntoIterator<Item = &'a StageTimes>) -> (StageTimes, usize) {
        let mut sum = StageTimes::default();
        let mut n = 0;
        for f in frames {
            sum += *f;
            n += 1;
        }
        (sum / n.max(1) as f64, n)
    }

    /// Each stage's value through `f` (e.g. a median over frames).
    pub(crate) fn from_fn(mut f: impl FnMut(fn(&StageTimes) -> f64) -> f64) -> StageTimes {
        StageTimes {
            update_ms: f(|s| s.update_ms),
            integrate_ms: f(|s| s.integrate_ms),
            reactivate_ms: f(|s| s.reactivate_ms),
            commit_ms: f(|s| s.commit_ms),
            trace_ms: f(|s| s.trace_ms),
        }
    }
}

impl AddAssign for StageTimes {
    fn add_assign(&mut self, o: StageTimes) {
        self.update_ms += o.update_ms;
        self.integrate_ms += o.integrate_ms;
        self.reactivate_ms += o.reactivate_ms;
        self.commit_ms += o.commit_ms;
        self.trace_ms += o.trace_ms;
    }
}

impl Div<f64> for StageTimes {
    type Output = StageTimes;
    fn div(self, d: f64) -> StageTimes {
        StageTimes::from_fn(|get| get(&self) / d)
    }
}

#[cfg(test)]
mod tests {
    use super::StageTimes;

    #[test]
    fn sums_means_and_columns_agree() {
        let a = StageTimes {
            update_ms: 1.0,
            integrate_ms: 2.0,
            reactivate_ms: 3.0,
            commit_ms: 4.0,
            trace_ms: 5.0,
        };
        let b = StageTimes { trace_ms: 7.0, ..StageTimes::default() };
        let (mean, n) = StageTimes::mean([&a, &b]);
        assert_eq!(n, 2);
        assert_eq!(mean.trace_ms, 6.0);
        assert_eq!(mean.update_ms, 0.5);
        assert_eq!(a.frame_ms(), 15.0);
        assert_eq!(a.structure_ms(), 6.0);
        let json = serde_json::to_value(a).unwrap();
        for (name, get) in StageTimes::STAGES {
            assert_eq!(json[name].as_f64(), Some(get(&a)), "{name}");
        }
        assert_eq!(StageTimes::mean(std::iter::empty()), (StageTimes::default(), 0));
    }
}
