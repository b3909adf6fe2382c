//! [`RayLog`]: what a pixel block's rays leave behind besides light: how many were traced and,
//! for exact temporal reuse, their horizon: the earliest later rendered frame whose changes
//! ([`ChangeIndex`]) any of their segments meets. Until that frame every one of the block's
//! samples computes the same bits, so the block's pixels can be reused.
//!
//! Integrators trace through [`FrameContext`](super::FrameContext)'s `intersect` and
//! `unoccluded`, which record every ray here: a closest-hit ray as the segment up to its hit
//! (to infinity when it escapes), an occlusion ray that nothing blocks over its whole
//! interval. A blocked occlusion ray stays blocked, whatever else moves along it, as long as
//! its blocker stays: static geometry does until the next frame traced in full, a body until
//! its next change; it is queried only when that comes before the horizon found so far.

use std::cell::Cell;
use std::sync::OnceLock;
use std::time::Instant;

use super::RenderScene;
use crate::accel::bvh::ChangeIndex;
use crate::accel::{Hit, Occluder};
use crate::geometry::Ray;

/// One query in this many is timed, and the time scaled up: timing every query would cost
/// about as much as the query.
const TIME_ONE_IN: u32 = 32;

thread_local! {
    /// The thread's queries so far, which pick the ones to time: counted per thread rather
    /// than per log, as a log of one sample often makes fewer queries than [`TIME_ONE_IN`].
    static QUERIES: Cell<u32> = const { Cell::new(0) };
}

/// Rays traced for a block of pixels, and their horizon when reuse is on.
pub struct RayLog<'a> {
    /// Rays traced (camera, bounce, shadow).
    pub rays: u64,
    horizon: Option<HorizonProbe<'a>>,
}

/// The horizon being found: the segments so far meet no change before `best`.
struct HorizonProbe<'a> {
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

impl<'a> RayLog<'a> {
    /// A log that only counts rays.
    pub(crate) fn counting() -> Self {
        Self { rays: 0, horizon: None }
    }

    /// A log that also finds the horizon of rays traced at ordinal `traced_at` in `scene`,
    /// against `index`; `until` is the horizon when nothing changes (the next frame traced in
    /// full, or the run's end).
    pub(crate) fn with_horizon(
        index: &'a ChangeIndex,
        scene: &'a RenderScene<'a>,
        traced_at: u32,
        until: u32,
    ) -> Self {
        let probe = HorizonProbe { index, scene, traced_at, best: until, queries: 0, seconds: 0.0 };
        Self { rays: 0, horizon: Some(probe) }
    }

    /// Records a closest-hit ray and its hit: the segment up to the hit, or the whole ray
    /// when it escaped. A hit on a body changes when the body next does, which bounds the
    /// query before it is made (and often ends it: most bodies that move, move every frame).
    #[inline]
    pub(crate) fn closest(&mut self, ray: &Ray, hit: Option<&Hit>) {
        self.rays += 1;
        if let Some(probe) = &mut self.horizon {
            let segment = match hit {
                Some(h) => {
                    probe.hit_body(h);
                    Ray { t_max: h.t, ..*ray }
                }
                None => *ray,
            };
            probe.meet(&segment, false);
        }
    }

    /// Whether the log finds horizons, and so needs to know what blocks occlusion rays.
    pub(crate) fn finds_horizon(&self) -> bool {
        self.horizon.is_some()
    }

    /// Records an occlusion ray and what blocks it (`None`: nothing). A ray that nothing
    /// blocks, or whose blocker is not known, is queried over its whole interval. A blocked
    /// one stays blocked, whatever else moves along it, while its blocker does: static
    /// geometry until the next frame traced in full (not queried), a body until a change of
    /// its own after which it may no longer block the ray.
    #[inline]
    pub(crate) fn any(&mut self, ray: &Ray, blocker: Option<Occluder>) {
        self.rays += 1;
        let Some(probe) = &mut self.horizon else { return };
        match blocker {
            Some(Occluder::Static) => {}
            Some(Occluder::Instance(id)) => match probe.scene.body_of_instance(id) {
                Some(body) => probe.query(|index, after, best| index.blocked_until(body, ray, after, best)),
                None => probe.meet(ray, true),
            },
            None | Some(Occluder::Unknown) => probe.meet(ray, true),
        }
    }

    /// Counts a camera ray traced in a packet for a sample that is not traced (its lane only
    /// keeps the packet as a full frame has it).
    pub(crate) fn count_untraced(&mut self) {
        self.rays += 1;
    }

    /// Adds the rays and horizon queries of `other` (a sample's log) to this one's counts.
    pub(crate) fn absorb(&mut self, other: &RayLog) {
        self.rays += other.rays;
        if let (Some(probe), Some(theirs)) = (&mut self.horizon, &other.horizon) {
            probe.queries += theirs.queries;
            probe.seconds += theirs.seconds;
        }
    }

    /// The earliest ordinal at which a change meets any recorded segment (the log's `until`
    /// when none does); `None` without horizons.
    pub(crate) fn horizon(&self) -> Option<u32> {
        self.horizon.as_ref().map(|p| p.best)
    }

    /// Horizon queries made and the seconds they took (estimated from a sample of them).
    pub(crate) fn query_cost(&self) -> (u32, f64) {
        self.horizon.as_ref().map_or((0, 0.0), |p| (p.queries, p.seconds))
    }
}

impl HorizonProbe<'_> {
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
