//! Whether a run reuses earlier frames' work, and whether exact reuse fits its memory budget:
//! decided once, here ([`ReuseMode::decide`]), for the command line (which asks before it
//! simulates anything) and for `Sequence::render` (before its first frame).

use super::store::ReuseStore;
use crate::names::named_enum;
use crate::render::{Aov, ImageSize, RenderError};

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

impl ReuseMode {
    /// How a run that asks for this mode reuses: [`ReuseMode::Off`] without `fixed_seed` (one
    /// sampler seed for every frame, `--seed fixed`: without it no two frames trace the same
    /// samples), else this mode. Exact reuse only when its store fits `budget` bytes at the
    /// least it works with, one value per pixel and pass for `size` frames with `aovs`;
    /// [`RenderError::ReuseBudget`] otherwise.
    pub fn decide(
        self,
        fixed_seed: bool,
        size: ImageSize,
        aovs: &[Aov],
        budget: usize,
    ) -> Result<Self, RenderError> {
        if !fixed_seed {
            return Ok(ReuseMode::Off);
        }
        if self != ReuseMode::Exact {
            return Ok(self);
        }
        let needed = ReuseStore::bytes_for(size.width, size.height, aovs);
        if needed <= budget {
            return Ok(ReuseMode::Exact);
        }
        let mib = |bytes: usize| bytes.div_ceil(1 << 20);
        Err(RenderError::ReuseBudget {
            budget_mib: budget >> 20,
            needed_mib: mib(needed),
            width: size.width,
            height: size.height,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decide(mode: ReuseMode, fixed_seed: bool, budget: usize) -> Result<ReuseMode, RenderError> {
        mode.decide(fixed_seed, ImageSize { width: 960, height: 540 }, &[], budget)
    }

    #[test]
    fn a_seed_per_frame_reuses_nothing_and_exact_reuse_needs_its_store() {
        assert_eq!(decide(ReuseMode::Exact, false, 0).unwrap(), ReuseMode::Off);
        assert_eq!(decide(ReuseMode::Static, true, 0).unwrap(), ReuseMode::Static);
        assert_eq!(decide(ReuseMode::Exact, true, DEFAULT_REUSE_BYTES).unwrap(), ReuseMode::Exact);
        let too_small = decide(ReuseMode::Exact, true, 1 << 20).unwrap_err();
        assert!(too_small.to_string().starts_with("1 MiB is too small for exact reuse of 960x540 frames"));
    }
}
