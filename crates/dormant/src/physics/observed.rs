//! What a caller sees of a simulation while it runs: one [`SimulatedFrame`] per frame (for
//! progress and per-frame timings), from Rapier or from an animation alike.

/// One simulated frame, as [`super::simulate_observed`] reports it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SimulatedFrame {
    pub index: u32,
    /// Frames the whole run simulates.
    pub frames: u32,
    /// Wall-clock milliseconds of this frame's physics step.
    pub(crate) step_ms: f64,
}
