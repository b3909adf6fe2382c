//! Whether a run reuses earlier frames' work, and whether exact reuse fits its memory budget:
//! decided once, here ([`ReuseRequest::decide`]), for the command line (which asks before it
//! simulates anything) and for `Sequence::render` (before its first frame).

use super::store::ReuseStore;
use crate::render::{Aov, RenderError};

/// How frames reuse earlier frames' work (`--reuse`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ReuseMode {
    /// Trace every frame in full.
    Off,
    /// A frame where nothing moved and the camera stayed is the previous frame's image,
    /// copied instead of traced.
    #[value(alias = "on")]
    Static,
    /// Also within frames: trace only the samples that can see something that changed since
    /// they were traced; take the rest from the previous frames, bit for bit.
    #[default]
    Exact,
}

/// Memory exact reuse may keep by default: room for a per-pixel store of a 3840x2160 frame
/// with every AOV (538 MiB, `ReuseStore::bytes_for`), and for a per-sample
/// store of 1920x1080 at 16 spp or 960x540 at 64 spp.
pub const DEFAULT_REUSE_BYTES: usize = 576 << 20;

/// What a run asks of reuse: the mode, whether one seed serves every frame, and the frames
/// exact reuse would keep.
#[derive(Clone, Copy, Debug)]
pub struct ReuseRequest<'a> {
    pub mode: ReuseMode,
    /// One sampler seed for every frame (`--seed fixed`): without it no two frames trace the
    /// same samples, and nothing is reused.
    pub fixed_seed: bool,
    pub width: u32,
    pub height: u32,
    /// The run's AOV passes; the store keeps those that are traced.
    pub aovs: &'a [Aov],
    /// Bytes exact reuse may keep (`--reuse-mib`).
    pub budget: usize,
}

impl ReuseRequest<'_> {
    /// How the run reuses: [`ReuseMode::Off`] without a fixed seed, else the mode asked for;
    /// exact reuse only when a store of one value per pixel and pass fits the budget (the
    /// least the store works with), [`RenderError::ReuseBudget`] otherwise.
    pub fn decide(&self) -> Result<ReuseMode, RenderError> {
        if !self.fixed_seed {
            return Ok(ReuseMode::Off);
        }
        if self.mode != ReuseMode::Exact {
            return Ok(self.mode);
        }
        let needed = ReuseStore::bytes_for(self.width, self.height, self.aovs);
        if needed <= self.budget {
            return Ok(ReuseMode::Exact);
        }
        let mib = |bytes: usize| bytes.div_ceil(1 << 20);
        Err(RenderError::ReuseBudget {
            budget_mib: self.budget >> 20,
            needed_mib: mib(needed),
            width: self.width,
            height: self.height,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn request(mode: ReuseMode, fixed_seed: bool, budget: usize) -> ReuseRequest<'static> {
        ReuseRequest { mode, fixed_seed, width: 960, height: 540, aovs: &[], budget }
    }

    #[test]
    fn a_seed_per_frame_reuses_nothing_and_exact_reuse_needs_its_store() {
        assert_eq!(request(ReuseMode::Exact, false, 0).decide().unwrap(), ReuseMode::Off);
        assert_eq!(request(ReuseMode::Static, true, 0).decide().unwrap(), ReuseMode::Static);
        assert_eq!(request(ReuseMode::Exact, true, DEFAULT_REUSE_BYTES).decide().unwrap(), ReuseMode::Exact);
        let too_small = request(ReuseMode::Exact, true, 1 << 20).decide().unwrap_err();
        assert!(too_small.to_string().starts_with("1 MiB is too small for exact reuse of 960x540 frames"));
    }
}
