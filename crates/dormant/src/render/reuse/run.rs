//! Exact reuse over one run ([`ExactReuse`]): the change index of the window of frames being
//! rendered, the rendered frames' ordinals, which frames must be traced in full and why
//! ([`FullFrame`]), and the store; each frame rendered through them ([`ExactReuse::render`]),
//! and what reuse did in it ([`ExactFrame`]).

use super::changes::{ChangeStream, FullFrame, RunMotion};
use super::plan::{traced_passes, FramePlan, PlanTracer};
use super::store::{FrameReuse, ReuseStats, ReuseStore};
use crate::accel::bvh::{ChangeBox, ChangeIndex};
use crate::render::{Aov, AovPasses, Film, RenderError, RenderStats};

/// What exact temporal reuse did in a frame.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ExactFrame {
    #[serde(flatten)]
    pub stats: ReuseStats,
    /// Why every sample was traced (`None`: samples were reused where their horizons allowed).
    pub full: Option<FullFrame>,
}

/// Most of `--reuse-mib` that the change boxes of the frames ahead may take, and at most
/// this many bytes: the index covers a window of frames and is rebuilt for the next window
/// when rendering reaches its end, so its memory does not grow with the run's length.
const CHANGE_WINDOW_BYTES: usize = 64 << 20;

/// Exact reuse over one run: the change index of the window of frames being rendered, the
/// frames that must be traced in full, and the store.
pub(crate) struct ExactReuse<'s> {
    index: ChangeIndex,
    /// Per ordinal up to the end of the index's window (`full.len()`, which no horizon
    /// passes), why that frame cannot reuse samples of the frame before it (`None`: it can).
    full: Vec<Option<FullFrame>>,
    stream: ChangeStream<'s>,
    /// Change boxes a window holds at most (it holds at least one frame's).
    window_boxes: usize,
    /// Bytes the store may hold: with room for every sample it keeps samples.
    budget: usize,
    store: ReuseStore,
}

impl<'s> ExactReuse<'s> {
    /// Exact reuse over `run` within `budget` bytes (which [`ReuseMode::decide`] found
    /// enough), with the change index of its first window built.
    ///
    /// [`ReuseMode::decide`]: super::decision::ReuseMode::decide
    pub(crate) fn new(run: RunMotion<'s>, budget: usize) -> Self {
        let window_bytes = (budget / 8).min(CHANGE_WINDOW_BYTES);
        let mut reuse = Self {
            index: ChangeIndex::build(Vec::new(), Vec::new()),
            full: Vec::new(),
            stream: ChangeStream::new(run),
            window_boxes: (window_bytes / std::mem::size_of::<ChangeBox>()).max(1),
            budget,
            store: ReuseStore::default(),
        };
        reuse.advance_to(0);
        reuse
    }

    /// Moves the index on to the window of frames holding ordinal `ordinal`.
    fn advance_to(&mut self, ordinal: u32) {
        while ordinal as usize >= self.full.len() && self.full.len() < self.stream.run.frames().len() {
            let window_start = self.full.len();
            // The old window's index goes first, so that two are never held at once.
            self.index = ChangeIndex::build(Vec::new(), Vec::new());
            let boxes = self.stream.window(&mut self.full, self.window_boxes);
            if self.full.len() == window_start {
                debug_assert!(false, "the selected frames lie within the trajectory");
                break;
            }
            let (count, start) = (boxes.len(), std::time::Instant::now());
            self.index = ChangeIndex::build(boxes, self.stream.run.small_prototypes());
            let ms = start.elapsed().as_secs_f64() * 1e3;
            tracing::debug!(
                window_start,
                frames = self.full.len() - window_start,
                boxes = count,
                ms,
                "change index"
            );
        }
    }

    /// The ordinal of rendered frame `frame`.
    fn ordinal(&self, frame: u32) -> u32 {
        self.stream.run.frames().partition_point(|&f| f < frame) as u32
    }

    /// The latest horizon worth finding for a sample traced in frame `frame`: the next frame
    /// traced in full anyway (a camera cut, a moving light), else the end of the index's
    /// window (the end of the run but in long runs). When that is the very next frame, as
    /// under a camera that moves every frame, no horizon query runs at all.
    fn horizon_limit(&self, frame: u32) -> u32 {
        let next = self.ordinal(frame) as usize + 1;
        let ahead = self.full.get(next..).unwrap_or_default();
        ahead.iter().position(Option::is_some).map_or(self.full.len(), |k| next + k) as u32
    }

    /// Frame `frame`'s image and `aovs` through `tracer` (the tile loop bound to the frame),
    /// tracing only what its horizons say and keeping the store up to date. `islands_baked`:
    /// islands were baked into the static scene or left it for this frame (the scene
    /// manager's doing, which the caller knows). A frame traced in full whose next frame is
    /// traced in full too (a camera that moves every frame) keeps nothing: nothing it traces
    /// could be reused, so it renders as without reuse and the store is emptied.
    pub(crate) fn render(
        &mut self,
        tracer: &dyn PlanTracer,
        aovs: &[Aov],
        frame: u32,
        islands_baked: bool,
    ) -> Result<(Film, RenderStats, AovPasses, ExactFrame), RenderError> {
        self.advance_to(self.ordinal(frame));
        // An empty store (frames kept from an earlier run before this one) traces in full too.
        let full = self
            .full_frame(frame, islands_baked)
            .or_else(|| self.store.is_empty().then_some(FullFrame::First));
        let ordinal = self.ordinal(frame);
        let until = self.horizon_limit(frame);
        if full.is_some() && until <= ordinal + 1 {
            self.store = ReuseStore::default();
            let passes = traced_passes(aovs);
            let (film, render, aovs) =
                tracer.trace(&FramePlan { aovs: &passes, ..FramePlan::default() })?.into_image(aovs);
            let stats = ReuseStats::traced_in_full(&film, &render);
            return Ok((film, render, aovs, ExactFrame { stats, full }));
        }
        let plan =
            FrameReuse { index: &self.index, ordinal, until, full: full.is_some(), budget: self.budget };
        let (film, render, aovs, stats) = self.store.render_frame(tracer, aovs, plan)?;
        Ok((film, render, aovs, ExactFrame { stats, full }))
    }

    /// Why frame `frame` must be traced in full (`islands_baked`: see [`Self::render`]);
    /// `None` when it may reuse samples.
    fn full_frame(&self, frame: u32, islands_baked: bool) -> Option<FullFrame> {
        let ordinal = self.ordinal(frame) as usize;
        if let Some(reason) = self.full.get(ordinal).copied().flatten() {
            return Some(reason);
        }
        islands_baked.then_some(FullFrame::IslandsBaked)
    }
}
