//! [`RayLog`]: what a pixel block's (or a sample's) rays leave behind besides light: how many
//! were traced and, under exact temporal reuse, their horizon, which a
//! [`HorizonProbe`] (`render/reuse/horizon.rs`) finds from every ray recorded here.
//!
//! Integrators trace through [`FrameContext`](super::FrameContext)'s `intersect` and
//! `unoccluded`, which record every ray here; the tile loop records the camera rays.

use crate::accel::bvh::ChangeIndex;
use crate::accel::{Hit, Occluder};
use crate::geometry::Ray;
use crate::render::reuse::HorizonProbe;
use crate::render::RenderScene;

/// Rays traced for a block of pixels, and their horizon when reuse is on.
pub struct RayLog<'a> {
    /// Rays traced (camera, bounce, shadow).
    pub rays: u64,
    /// Of `rays`, camera rays traced only because a due sample shared their packet (exact
    /// reuse): their samples are taken from the store.
    pub neighbour_rays: u64,
    horizon: Option<HorizonProbe<'a>>,
}

impl<'a> RayLog<'a> {
    /// A log that only counts rays.
    pub(crate) fn counting() -> Self {
        Self { rays: 0, neighbour_rays: 0, horizon: None }
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
        Self { rays: 0, neighbour_rays: 0, horizon: Some(HorizonProbe::new(index, scene, traced_at, until)) }
    }

    /// Records a closest-hit ray and its hit (`None`: it escaped).
    #[inline]
    pub(crate) fn closest(&mut self, ray: &Ray, hit: Option<&Hit>) {
        self.rays += 1;
        if let Some(probe) = &mut self.horizon {
            probe.closest(ray, hit);
        }
    }

    /// Whether the log finds horizons, and so needs to know what blocks occlusion rays.
    pub(crate) fn finds_horizon(&self) -> bool {
        self.horizon.is_some()
    }

    /// Records an occlusion ray and what blocks it (`None`: nothing).
    #[inline]
    pub(crate) fn any(&mut self, ray: &Ray, blocker: Option<Occluder>) {
        self.rays += 1;
        if let Some(probe) = &mut self.horizon {
            probe.occlusion(ray, blocker);
        }
    }

    /// Counts a camera ray traced in a packet for a sample that is not traced (its lane only
    /// keeps the packet as a full frame has it): a ray, and a neighbour's.
    pub(crate) fn count_neighbour(&mut self) {
        self.rays += 1;
        self.neighbour_rays += 1;
    }

    /// Adds the rays and horizon queries of `other` (a sample's log) to this one's counts.
    pub(crate) fn absorb(&mut self, other: &RayLog) {
        self.rays += other.rays;
        self.neighbour_rays += other.neighbour_rays;
        if let (Some(probe), Some(theirs)) = (&mut self.horizon, &other.horizon) {
            probe.absorb_cost(theirs);
        }
    }

    /// The earliest ordinal at which a change meets any recorded segment (the log's `until`
    /// when none does); `None` without horizons.
    pub(crate) fn horizon(&self) -> Option<u32> {
        self.horizon.as_ref().map(HorizonProbe::horizon)
    }

    /// Horizon queries made and the seconds they took (estimated from a sample of them).
    pub(crate) fn query_cost(&self) -> (u32, f64) {
        self.horizon.as_ref().map_or((0, 0.0), HorizonProbe::cost)
    }
}
