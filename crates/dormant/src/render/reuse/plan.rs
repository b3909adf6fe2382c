//! What the tile loop is asked to trace of a frame ([`FramePlan`]: which samples, at what
//! sample counts, finding which horizons, shading which AOV passes) and what it gives back
//! ([`PlannedFrame`]); and [`PlanTracer`], the tile loop bound to one frame as exact reuse
//! sees it. A plain frame is the default plan: every sample, no horizons.
//!
//! For exact reuse a sample must be traced exactly as a full frame traces it: its camera ray
//! goes in the same packet, with the same neighbours, as in a full frame, so a block with a
//! sample to trace traces that sample's camera packet and continues only the paths of the
//! samples it traces (`render/tiles/tile_loop.rs`).

use glam::Vec3;

use crate::accel::bvh::ChangeIndex;
use crate::render::{Aov, AovPasses, Film, RenderError, RenderSettings, RenderStats, SppStats};

/// Which of a frame's pixels (or samples) to render, and how.
#[derive(Clone, Copy, Default)]
pub(crate) struct FramePlan<'a> {
    /// Fixed samples per pixel (row-major) instead of `spp` and adaptive sampling.
    pub samples: Option<&'a [u32]>,
    /// Which samples to trace.
    pub due: Due<'a>,
    /// Find each traced pixel's (or sample's) horizon against this index: the frame's ordinal
    /// and the horizon of what meets no change (the run's number of rendered frames).
    pub horizons: Option<(&'a ChangeIndex, u32, u32)>,
    /// AOV passes shaded at the traced samples' camera hits as they are traced, each pixel
    /// averaged over its traced samples ([`PlannedFrame::aovs`]): a pixel whose every sample
    /// is traced gets the value an [`AovIntegrator`](crate::render::AovIntegrator) pass would
    /// give.
    pub aovs: &'a [Aov],
}

impl FramePlan<'_> {
    /// Whether the frame keeps its AOV passes' camera horizons ([`PlannedFrame::camera_horizons`]).
    pub(crate) fn keeps_camera_horizons(&self) -> bool {
        !self.aovs.is_empty() && self.horizons.is_some() && matches!(self.due, Due::Samples { .. })
    }
}

/// Which samples a frame traces (row-major pixels).
#[derive(Clone, Copy, Default)]
pub(crate) enum Due<'a> {
    /// Every sample of every pixel.
    #[default]
    All,
    /// Every sample of the pixels marked; the other pixels take their lanes in the camera
    /// packets from their `stored` sample counts. They come back black with no samples.
    Pixels { due: &'a [bool], stored: &'a [u32] },
    /// The samples whose horizon has come by `ordinal` and those never traced (`pixels`:
    /// whether a pixel has any); the others are taken from `stored`. Traced samples come
    /// back one by one ([`PlannedFrame::samples`]); the pixels with any, as values and counts.
    Samples { stored: StoredSamples<'a>, pixels: &'a [bool], ordinal: u32 },
}

/// The samples kept from earlier frames: `spp` slots per pixel, pixel by pixel.
#[derive(Clone, Copy)]
pub(crate) struct StoredSamples<'a> {
    /// Each slot's radiance and horizon.
    pub values: &'a [Vec3],
    pub horizons: &'a [u32],
    /// Per pixel, how many of its slots hold samples: all but where adaptive sampling stopped
    /// the pixel early.
    pub counts: &'a [u32],
}

/// A planned frame: the traced pixels' values and sample counts and horizons (row-major; zero
/// elsewhere), or with [`Due::Samples`] the traced samples; the rays traced, and what the
/// horizon queries cost.
pub(crate) struct PlannedFrame {
    pub film: Film,
    pub counts: Vec<u32>,
    pub horizons: Vec<u32>,
    /// The plan's AOV passes, in order, over the traced samples.
    pub aovs: Vec<Film>,
    /// With AOV passes, horizons and [`Due::Samples`]: per pixel, the horizon of its traced
    /// samples' camera rays alone (what the passes see).
    pub camera_horizons: Vec<u32>,
    /// With [`Due::Samples`], the traced samples tile by tile: kept apart, since a full
    /// frame's (8.3 M at 960x540, 16 spp) would be copied into ever larger buffers to join.
    pub samples: Vec<Vec<TracedSample>>,
    pub rays: u64,
    /// Of `rays`, the camera rays of packet lanes whose samples were not due.
    pub neighbour_rays: u64,
    pub seconds: f64,
    pub horizon_queries: u64,
    pub horizon_seconds: f64,
}

/// One sample traced under [`Due::Samples`]: its pixel (row-major), index, radiance and
/// horizon.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TracedSample {
    pub pixel: u32,
    pub index: u32,
    pub li: Vec3,
    pub horizon: u32,
}

impl PlannedFrame {
    /// The frame's rays, time and samples per pixel.
    pub(crate) fn stats(&self) -> RenderStats {
        RenderStats { rays: self.rays, seconds: self.seconds, spp: SppStats::of(&self.counts) }
    }

    /// A whole frame traced with its [`traced_passes`] of `aovs` as the plan's passes: its
    /// image, statistics and every pass of `aovs` in order (`spp` and `traced` from the
    /// sample counts).
    pub(crate) fn into_image(self, aovs: &[Aov]) -> (Film, RenderStats, AovPasses) {
        let stats = self.stats();
        let (w, h) = (self.film.width, self.film.height);
        let mut shaded = self.aovs.into_iter();
        let passes = aovs
            .iter()
            .map(|&aov| match aov {
                Aov::Spp | Aov::Traced => (aov, Film::from_counts(w, h, &self.counts)),
                _ => (aov, shaded.next().expect("one film per traced pass, in order")),
            })
            .collect();
        (self.film, stats, passes)
    }
}

/// The passes of `aovs` a plan shades at the camera hits: those not made from sample counts.
pub(crate) fn traced_passes(aovs: &[Aov]) -> Vec<Aov> {
    aovs.iter().copied().filter(|a| a.is_traced()).collect()
}

/// The tile loop bound to one frame (its scene, geometry, integrator and settings:
/// `render::tiles::FrameTracer`), as exact reuse asks it to trace. A trait, so that reuse,
/// whose plans and horizons the tracing reads, does not import the tracing back.
pub(crate) trait PlanTracer {
    /// The frame's size, samples, seed, sampling and filter.
    fn settings(&self) -> &RenderSettings;

    /// `plan` traced with the frame's integrator.
    fn trace(&self, plan: &FramePlan) -> Result<PlannedFrame, RenderError>;

    /// `plan` traced with AOV pass `aov` as the integrator (the plan's own passes shaded at
    /// the same camera hits).
    fn trace_pass(&self, aov: Aov, plan: &FramePlan) -> Result<PlannedFrame, RenderError>;
}
