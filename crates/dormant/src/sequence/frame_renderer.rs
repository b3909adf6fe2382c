//! [`FrameRenderer`]: how every frame of a run is rendered (integrator, passes, size and
//! samples, sampling, pixel filter, seed, reuse, shutter).

use crate::names::named_enum;
use crate::render::{AdaptiveSampling, Aov, Integrator, PixelFilter, RenderSettings};

named_enum! {
    /// How frames reuse earlier frames' work (`--reuse`).
    #[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
    #[serde(rename_all = "lowercase")]
    pub enum ReuseMode {
        /// Trace every frame in full.
        Off = "off",
        /// A frame where nothing moved and the camera stayed is the previous frame's image,
        /// copied instead of traced.
        Static = "static" | "on",
        /// Also within frames: trace only the samples that can see something that changed since
        /// they were traced; take the rest from the previous frames, bit for bit.
        #[default]
        Exact = "exact",
    }
}

/// Memory exact reuse may keep by default: room for a per-pixel store of a 3840x2160 frame
/// with every AOV (538 MiB, `ReuseStore::bytes_for`), and for a per-sample
/// store of 1920x1080 at 16 spp or 960x540 at 64 spp.
pub const DEFAULT_REUSE_BYTES: usize = 576 << 20;

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
}
