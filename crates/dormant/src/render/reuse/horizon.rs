//! [`HorizonProbe`]: a traced sample's horizon, the earliest later rendered frame whose changes
//! ([`ChangeIndex`]) any of its rays' segments meets. Until that frame every one of the
//! sample's rays sees the same geometry, so the sample computes the same bits.
//!
//! The integrators' [`RayLog`](crate::render::RayLog) hands each ray it records to its probe: a
//! closest-hit ray as the segment up to its hit (to infinity when it escapes), an occlusion
//! ray that nothing blocks over its whole interval. A blocked occlusion ray stays blocked,
//! whatever else moves along it, as long as its blocker stays: static geometry does until the
//! next frame traced in full, a body until its next change; it is queried only when that comes
//! before the horizon found so far.

use std::cell::Cell;
use std::sync::OnceLock;
use std::time::Instant;

use crate::accel::bvh::ChangeIndex;
use crate::accel::{Hit, Occluder};
use crate::geometry::Ray;
use crate::render::RenderScene;

/// One query in this many is timed, and the time scaled up: timing every query would cost
/// about as much as the query.
const TIME_ONE_IN: u32 = 32;

thread_local! {
    /// The thread's queries so far, which pick the ones to time: counted per thread rather
    /// than per probe, as a probe of one sample often makes fewer queries than [`TIME_ONE_IN`].
    static QUERIES: Cell<u32> = const { Cell::new(0) };
}

/// The horizon being found: the segments so far meet no change before `best`.
pub(crate) struct HorizonProbe<'a> {
    index: &'a ChangeIndex,
    /// Names the body a hit lies on.
    scene: &'a RenderScene<'a>,
    /// The ordinal of the frame being traced.
    traced_at: u32,
    best: u32,
    queries: u32,
    /// Seconds of the timed queries, scaled by [`TIME_ONE_IN`].
    seconds: f64,
}

impl<'a> HorizonProbe<'a> {
    /// A probe for rays traced at ordinal `traced_at` in `scene`, against `index`; `until` is
    /// the horizon when nothing changes (the next frame traced in full, or the run's end).
    pub(crate) fn new(
        index: &'a ChangeIndex,
        scene: &'a RenderScene<'a>,
        traced_at: u32,
        until: u32,
    ) -> Self {
        Self { index, scene, traced_at, best: until, queries: 0, seconds: 0.0 }
    }

    /// A closest-hit ray and its hit: the segment up to the hit, or the whole ray when it
    /// escaped. A hit on a body changes when the body next does, which bounds the query
    /// before it is made (and often ends it: most bodies that move, move every frame).
    #[inline]
    pub(crate) fn closest(&mut self, ray: &Ray, hit: Option<&Hit>) {
        let segment = match hit {
            Some(h) => {
                self.hit_body(h);
                Ray { t_max: h.t, ..*ray }
            }
            None => *ray,
        };
        self.meet(&segment, false);
    }

    /// An occlusion ray and what blocks it (`None`: nothing). A ray that nothing blocks, or
    /// whose blocker is not known, is queried over its whole interval. A blocked one stays
    /// blocked, whatever else moves along it, while its blocker does: static geometry until
    /// the next frame traced in full (not queried), a body until a change of its own after
    /// which it may no longer block the ray.
    #[inline]
    pub(crate) fn occlusion(&mut self, ray: &Ray, blocker: Option<Occluder>) {
        match blocker {
            Some(Occluder::Static) => {}
            Some(Occluder::Instance(id)) => match self.scene.body_of_instance(id) {
                Some(body) => self.query(|index, after, best| index.blocked_until(body, ray, after, best)),
                None => self.meet(ray, true),
            },
            None | Some(Occluder::Unknown) => self.meet(ray, true),
        }
    }

    /// Adds the queries of `other` (a sample's probe) to this one's cost.
    pub(crate) fn absorb_cost(&mut self, other: &HorizonProbe) {
        self.queries += other.queries;
        self.seconds += other.seconds;
    }

    /// The earliest ordinal at which a change meets any segment so far (`until` when none
    /// does).
    pub(crate) fn horizon(&self) -> u32 {
        self.best
    }

    /// Queries made and the seconds they took (estimated from a sample of them).
    pub(crate) fn cost(&self) -> (u32, f64) {
        (self.queries, self.seconds)
    }

    /// Brings the horizon to the next change of the body `hit` lies on, if sooner.
    #[inline]
    fn hit_body(&mut self, hit: &Hit) {
        if self.best <= self.traced_at + 1 {
            return;
        }
        if let Some(next) = self.scene.body_of(hit).and_then(|b| self.index.next_change_of(b, self.traced_at))
        {
            self.best = self.best.min(next);
        }
    }

    /// Brings the horizon to the earliest change that meets `segment`, if sooner.
    #[inline]
    fn meet(&mut self, segment: &Ray, occlusion: bool) {
        self.query(|index, after, best| index.first_change(segment, after, best, occlusion));
    }

    /// Brings the horizon to what `query` finds, given the traced frame's ordinal and the
    /// horizon so far; one query in [`TIME_ONE_IN`] is timed.
    #[inline]
    fn query(&mut self, query: impl FnOnce(&ChangeIndex, u32, u32) -> u32) {
        // The frame right after this one is the soonest a change can be: once there, no
        // further segment can bring the horizon nearer.
        if self.best <= self.traced_at + 1 {
            return;
        }
        self.queries += 1;
        let nth = QUERIES.with(|q| {
            q.set(q.get().wrapping_add(1));
            q.get()
        });
        if nth % TIME_ONE_IN == 0 {
            let start = Instant::now();
            self.best = query(self.index, self.traced_at, self.best);
            let seconds = start.elapsed().as_secs_f64() - clock_seconds();
            self.seconds += seconds.max(0.0) * f64::from(TIME_ONE_IN);
        } else {
            self.best = query(self.index, self.traced_at, self.best);
        }
    }
}

/// What reading the clock twice costs, which a timed query's time includes: the least of a
/// few tries, measured once per process (as much as a short query:
/// docs/lab/reuse.md#2026-12-06-blocked-shadow-rays-and-what-the-horizon-timings-counted).
fn clock_seconds() -> f64 {
    static CLOCK: OnceLock<f64> = OnceLock::new();
    *CLOCK.get_or_init(|| {
        (0..64)
            .map(|_| {
                let start = Instant::now();
                std::hint::black_box(start.elapsed()).as_secs_f64()
            })
            .fold(f64::INFINITY, f64::min)
    })
}
