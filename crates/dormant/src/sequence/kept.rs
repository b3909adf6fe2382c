//! Frames an earlier run of the same configuration finished (`render --resume`). They are not
//! rendered again, but the scene manager is brought through each as that run brought it: the
//! same island events, the decisions it recorded made again, the trace time it measured fed to
//! the cost model. So the frames after them start from the integration and cache state an
//! uninterrupted run has there, and render the same images.

use super::{FrameRenderer, Sequence, SequenceError};
use crate::physics::{IslandId, ReplayFrame};
use crate::residency::{FrameStats, SceneManager};

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
    /// What the scene held after the frame, checked against the replay.
    pub instances: usize,
    pub integrated_islands: usize,
    pub sleeping_islands: usize,
}

impl Sequence {
    /// Brings `manager` through `kept` (the frame `frame`) as the earlier run did, without
    /// tracing; `reused`: whether this run reuses the previous image here. Fails when the
    /// replay does not reach the state that run recorded.
    pub(super) fn replay_kept(
        &self,
        manager: &mut SceneManager,
        frame: &ReplayFrame<'_>,
        renderer: &FrameRenderer<'_>,
        kept: &KeptFrame,
        reused: bool,
    ) -> Result<(), SequenceError> {
        let mismatch = |what: &'static str, recorded: String, replayed: String| SequenceError::KeptMismatch {
            frame: frame.index,
            what,
            recorded,
            replayed,
        };
        if kept.reused != reused {
            return Err(mismatch("reused", kept.reused.to_string(), reused.to_string()));
        }
        if reused {
            return Ok(());
        }
        self.aim_probes(manager, frame, renderer);
        manager.prepare_decided(frame, &kept.decisions)?;
        let stats: &FrameStats = manager.record_trace(kept.trace_ms, kept.rays);
        for (what, recorded, replayed) in [
            ("instances", kept.instances, stats.instances),
            ("integrated_islands", kept.integrated_islands, stats.integrated_islands),
            ("sleeping_islands", kept.sleeping_islands, stats.sleeping_islands),
        ] {
            if recorded != replayed {
                return Err(mismatch(what, recorded.to_string(), replayed.to_string()));
            }
        }
        Ok(())
    }
}
