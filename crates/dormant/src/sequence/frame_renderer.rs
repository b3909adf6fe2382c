//! [`FrameRenderer`]: how every frame of a run is rendered (integrator, passes, size and
//! samples, sampling, pixel filter, seed, reuse, shutter). Its reuse mode and budget are
//! `render/reuse/`'s ([`ReuseMode`], decided by [`ReuseMode::decide`]).

use super::{ReuseMode, DEFAULT_REUSE_BYTES};
use crate::names::named_enum;
use crate::render::{AdaptiveSampling, Aov, ImageSize, Integrator, PixelFilter, RenderError, RenderSettings};

named_enum! {
    /// How the pixel sampler is seeded across a sequence (`--seed`).
    #[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
    #[serde(rename_all = "kebab-case")]
    pub enum SeedMode {
        /// One seed for every frame, as Cycles does by default: a frame that shows the same scene
        /// as the one before is the same image, so it is not traced again but copied.
        #[default]
        Fixed = "fixed",
        /// The frame number seeds each frame: noise decorrelates from frame to frame (like
        /// Cycles' animated seed), and every frame is traced.
        PerFrame = "per-frame",
    }
}

/// How every frame of a run is rendered.
#[derive(Clone, Copy)]
pub struct FrameRenderer<'a> {
    pub integrator: &'a dyn Integrator,
    /// Extra passes, rendered after the beauty image in this order.
    pub aovs: &'a [Aov],
    pub width: u32,
    pub height: u32,
    /// Samples per pixel; with adaptive sampling, the most a pixel gets.
    pub spp: u32,
    pub adaptive: AdaptiveSampling,
    /// Where each pixel's samples land around its centre.
    pub filter: PixelFilter,
    pub seed: SeedMode,
    /// Added to every frame's seed (Cycles' Seed value): renders of one frame with different
    /// offsets are independent.
    pub seed_offset: u32,
    /// With a fixed seed, how frames reuse earlier frames' work (see [`ReuseMode`]).
    pub reuse: ReuseMode,
    /// Bytes exact reuse may keep ([`DEFAULT_REUSE_BYTES`] by default).
    pub reuse_budget: usize,
    /// Motion blur: the shutter in frame intervals, centred on each frame (0: off). The
    /// manager must have been made with the same (`ManagerOptions::shutter`): it moves the
    /// instances; the renderer moves the camera and gives each camera sample a time.
    pub shutter: f32,
}

impl<'a> FrameRenderer<'a> {
    /// `integrator` at `width` x `height` and `spp` samples per pixel; no AOVs, no adaptive
    /// sampling, the default tent filter, one seed for every frame with exact temporal reuse,
    /// no motion blur.
    pub fn new(integrator: &'a dyn Integrator, width: u32, height: u32, spp: u32) -> Self {
        Self {
            integrator,
            aovs: &[],
            width,
            height,
            spp,
            adaptive: AdaptiveSampling::OFF,
            filter: PixelFilter::default(),
            seed: SeedMode::Fixed,
            seed_offset: 0,
            reuse: ReuseMode::Exact,
            reuse_budget: DEFAULT_REUSE_BYTES,
            shutter: 0.0,
        }
    }

    pub(super) fn settings(&self, frame: u32) -> RenderSettings {
        let seed = match self.seed {
            SeedMode::Fixed => 0,
            SeedMode::PerFrame => frame,
        }
        .wrapping_add(self.seed_offset);
        RenderSettings {
            width: self.width,
            height: self.height,
            spp: self.spp,
            seed,
            adaptive: self.adaptive,
            filter: self.filter,
        }
    }

    /// How this renderer's frames reuse ([`ReuseMode::decide`]).
    pub(super) fn decide_reuse(&self) -> Result<ReuseMode, RenderError> {
        let size = ImageSize { width: self.width, height: self.height };
        self.reuse.decide(self.seed == SeedMode::Fixed, size, self.aovs, self.reuse_budget)
    }
}
