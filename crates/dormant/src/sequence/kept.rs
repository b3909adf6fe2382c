//! Frames an earlier run of the same configuration finished (`render --resume`). They are not
//! rendered again, but the scene manager is brought through each as that run brought it
//! (`Sequence::replay_kept`, beside the render loop): the same island events, the decisions it
//! recorded made again, the trace time it measured fed to the cost model. So the frames after
//! them start from the integration and cache state an uninterrupted run has there, and render
//! the same images.

use crate::physics::IslandId;
use crate::residency::TraceKind;

/// A frame an earlier run finished: its files are complete and its statistics kept.
#[derive(Clone, Debug, PartialEq)]
pub struct KeptFrame {
    pub index: u32,
    /// It reused the previous image (static-frame reuse): the manager was not touched.
    pub reused: bool,
    /// The islands decided on at this frame, and whether each was integrated.
    pub decisions: Vec<(IslandId, bool)>,
    /// The main image's trace as that run measured it, ms, and its rays.
    pub trace_ms: f64,
    pub rays: u64,
    /// What that trace said of the frames after it.
    pub trace_kind: TraceKind,
    /// What the scene held after the frame, checked against the replay.
    pub instances: usize,
    pub integrated_islands: usize,
    pub(crate) sleeping_islands: usize,
}
