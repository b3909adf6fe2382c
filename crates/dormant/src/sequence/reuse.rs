//! Reuse across a sequence's frames (`--reuse`): whole frames where nothing moved (`static`),
//! or, with exact temporal reuse (`exact`), every sample that cannot see what changed. This
//! module owns the sequence's side of exact reuse: the changes between consecutive rendered
//! frames, indexed in space and time ([`ChangeIndex`]) from the trajectory before the first
//! frame; which frames must be traced in full and why (a moving camera, a moving light or
//! emissive body, baked islands coming or going); and the store of samples (or pixels) kept
//! from frame to frame ([`ReuseStore`]), within its budget.

use serde::Serialize;

use super::frame_renderer::{FrameRenderer, ReuseMode, SeedMode};
use super::{FrameSelection, Sequence, SequenceError};
use crate::accel::bvh::{ChangeBox, ChangeIndex, ChangeShape, EXACT_MESH_TRIANGLES};
use crate::accel::SceneQuery;
use crate::geometry::{Aabb, InstanceMotion};
use crate::physics::trajectory::{Replay, ReplayFrame, TrajectoryFrame};
use crate::physics::BodyId;
use crate::render::{
    render_reusing, render_with_aovs, AovPasses, Emitters, Film, FrameReuse, RenderError, RenderScene,
    RenderStats, ReuseStats, ReuseStore,
};
use crate::residency::{FrameStats, IntegrationForm, TraceKind};

/// Why a frame traced every sample instead of reusing samples of earlier frames.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FullFrame {
    /// The first rendered frame, or the first after frames kept from an earlier run.
    First,
    /// The camera is not where it was.
    CameraMoved,
    /// A body that emits light moved, appeared or left: every sample's light sampling changes.
    EmitterMoved,
    /// Islands were baked into the static scene or left it: their triangles are now hit in
    /// another form, whose rounding differs.
    IslandsBaked,
}

impl FullFrame {
    /// What the trace of a frame of an exact-reuse run that was traced in full for `full`
    /// (`None`: it reused samples, or reuse was off) says of the frames after it.
    pub(crate) fn trace_kind(full: Option<FullFrame>) -> TraceKind {
        match full {
            Some(_) => TraceKind::FullBeforeReuse,
            None => TraceKind::Typical,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            FullFrame::First => "first",
            FullFrame::CameraMoved => "camera_moved",
            FullFrame::EmitterMoved => "emitter_moved",
            FullFrame::IslandsBaked => "islands_baked",
        }
    }
}

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
/// rendered frames' ordinals, the frames that must be traced in full, and the store.
pub(crate) struct ExactReuse<'s> {
    pub index: ChangeIndex,
    /// The selected frames, ascending: a frame's ordinal is its position here.
    frames: Vec<u32>,
    /// Per ordinal up to the end of the index's window (`full.len()`, which no horizon
    /// passes), why that frame cannot reuse samples of the frame before it (`None`: it can).
    full: Vec<Option<FullFrame>>,
    stream: ChangeStream<'s>,
    /// Change boxes a window holds at most (it holds at least one frame's).
    window_boxes: usize,
    form: IntegrationForm,
    pub store: ReuseStore,
}

impl<'s> ExactReuse<'s> {
    /// Exact reuse for rendering `selection` with `renderer` in integration `form`, or `None`
    /// when the renderer does not ask for it (`--reuse off|static`, or a seed per frame).
    pub(crate) fn plan(
        sequence: &'s Sequence,
        selection: &FrameSelection,
        renderer: &FrameRenderer<'_>,
        form: IntegrationForm,
    ) -> Result<Option<Self>, SequenceError> {
        if renderer.reuse != ReuseMode::Exact || renderer.seed != SeedMode::Fixed {
            return Ok(None);
        }
        renderer.check_reuse_budget()?;
        let window_bytes = (renderer.reuse_budget / 8).min(CHANGE_WINDOW_BYTES);
        let mut reuse = Self {
            index: ChangeIndex::build(Vec::new(), Vec::new()),
            frames: selection.frames(),
            full: Vec::new(),
            stream: ChangeStream::new(sequence, renderer.shutter),
            window_boxes: (window_bytes / std::mem::size_of::<ChangeBox>()).max(1),
            form,
            store: ReuseStore::default(),
        };
        reuse.advance_to(0);
        Ok(Some(reuse))
    }

    /// Moves the index on to the window of frames holding ordinal `ordinal`.
    fn advance_to(&mut self, ordinal: u32) {
        while ordinal as usize >= self.full.len() && self.full.len() < self.frames.len() {
            let window_start = self.full.len();
            // The old window's index goes first, so that two are never held at once.
            self.index = ChangeIndex::build(Vec::new(), Vec::new());
            let boxes = self.stream.window(&self.frames, &mut self.full, self.window_boxes);
            if self.full.len() == window_start {
                debug_assert!(false, "the selected frames lie within the trajectory");
                break;
            }
            let (count, start) = (boxes.len(), std::time::Instant::now());
            self.index = ChangeIndex::build(boxes, self.stream.sequence.small_prototypes());
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

    /// The ordinal of selected frame `frame`.
    pub(crate) fn ordinal(&self, frame: u32) -> u32 {
        self.frames.partition_point(|&f| f < frame) as u32
    }

    /// The latest horizon worth finding for a sample traced in frame `frame`: the next frame
    /// traced in full anyway (a camera cut, a moving light), else the end of the index's
    /// window (the end of the run but in long runs). When that is the very next frame, as
    /// under a camera that moves every frame, no horizon query runs at all.
    pub(crate) fn horizon_limit(&self, frame: u32) -> u32 {
        let next = self.ordinal(frame) as usize + 1;
        let ahead = self.full.get(next..).unwrap_or_default();
        ahead.iter().position(Option::is_some).map_or(self.full.len(), |k| next + k) as u32
    }

    /// Frame `frame`'s image and AOVs through `renderer`, tracing only what its horizons
    /// say and keeping the store up to date; `stats` is what the scene manager did for it.
    /// A frame traced in full whose next frame is traced in full too (a camera that moves
    /// every frame) keeps nothing: nothing it traces could be reused, so it renders as
    /// without reuse and the store is emptied.
    pub(crate) fn render(
        &mut self,
        scene: &RenderScene,
        query: &dyn SceneQuery,
        renderer: &FrameRenderer<'_>,
        frame: u32,
        stats: &FrameStats,
    ) -> Result<(Film, RenderStats, AovPasses, ExactFrame), RenderError> {
        self.advance_to(self.ordinal(frame));
        // An empty store (frames kept from an earlier run before this one) traces in full too.
        let full =
            self.full_frame(frame, stats).or_else(|| self.store.is_empty().then_some(FullFrame::First));
        let settings = renderer.settings(frame);
        let ordinal = self.ordinal(frame);
        let until = self.horizon_limit(frame);
        if full.is_some() && until <= ordinal + 1 {
            self.store = ReuseStore::default();
            let (film, render, aovs) =
                render_with_aovs(scene, query, renderer.integrator, &settings, renderer.aovs)?;
            let stats = ReuseStats::traced_in_full(&film, &render);
            return Ok((film, render, aovs, ExactFrame { stats, full }));
        }
        let plan = FrameReuse {
            index: &self.index,
            ordinal,
            until,
            full: full.is_some(),
            budget: renderer.reuse_budget,
        };
        let (film, render, aovs, stats) = render_reusing(
            scene,
            query,
            renderer.integrator,
            &settings,
            renderer.aovs,
            plan,
            &mut self.store,
        )?;
        Ok((film, render, aovs, ExactFrame { stats, full }))
    }

    /// Why frame `frame`, whose scene manager did `stats`, must be traced in full; `None` when
    /// it may reuse blocks.
    pub(crate) fn full_frame(&self, frame: u32, stats: &FrameStats) -> Option<FullFrame> {
        let ordinal = self.ordinal(frame) as usize;
        if let Some(reason) = self.full.get(ordinal).copied().flatten() {
            return Some(reason);
        }
        let rebaked = stats.islands_integrated + stats.islands_reactivated > 0;
        (self.form == IntegrationForm::Baked && rebaked).then_some(FullFrame::IslandsBaked)
    }
}

impl FrameRenderer<'_> {
    /// Checks that exact reuse of this renderer's frames fits in its budget: a store of one
    /// value per pixel and pass (`ReuseStore::bytes_for`).
    pub fn check_reuse_budget(&self) -> Result<(), SequenceError> {
        let needed = ReuseStore::bytes_for(self.width, self.height, self.aovs);
        if needed <= self.reuse_budget {
            return Ok(());
        }
        let mib = |bytes: usize| bytes.div_ceil(1 << 20);
        Err(SequenceError::ReuseBudget {
            budget_mib: self.reuse_budget >> 20,
            needed_mib: mib(needed),
            width: self.width,
            height: self.height,
        })
    }
}

/// What a body looks like to the rays of one frame: absent, at a pose, or moving over the
/// shutter.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Look {
    Absent,
    Still(glam::Affine3A),
    Moving(InstanceMotion),
}

/// The changes between consecutive selected frames, found window by window by one replay of
/// the trajectory: a box for every body whose look differs from one frame to the next (its
/// bounds at both, swept over the shutter when blurred), tagged with the ordinal of the later
/// frame; and per ordinal whether the frame must be traced in full (the camera moved, or an
/// emissive body changed). Only bodies the trajectory records a change for since the last
/// selected frame (or that move over a shutter) are looked at.
struct ChangeStream<'s> {
    sequence: &'s Sequence,
    replay: Replay<'s>,
    changes: FrameChanges,
    /// The shutter in frame intervals.
    shutter: f32,
}

impl<'s> ChangeStream<'s> {
    fn new(sequence: &'s Sequence, shutter: f32) -> Self {
        let changes = FrameChanges::new(sequence);
        Self { sequence, replay: sequence.trajectory.replay(), changes, shutter }
    }

    /// The change boxes of the next window of `frames` (ascending), its first ordinal
    /// `full.len()`: frames are added until the boxes reach `max_boxes` or `frames` ends, and
    /// each one's reason to be traced in full is pushed onto `full`.
    fn window(
        &mut self,
        frames: &[u32],
        full: &mut Vec<Option<FullFrame>>,
        max_boxes: usize,
    ) -> Vec<ChangeBox> {
        let sequence = self.sequence;
        while full.len() < frames.len() && self.changes.boxes.len() < max_boxes {
            let Some(frame) = self.replay.next_frame() else { break };
            self.changes.note(&sequence.trajectory.frames[frame.index as usize]);
            let ordinal = full.len();
            if frame.index != frames[ordinal] {
                continue;
            }
            let emitter = self.changes.compare(&frame, self.shutter, ordinal as u32);
            full.push(if ordinal == 0 {
                Some(FullFrame::First)
            } else if sequence.shutter_cameras(frames[ordinal - 1], self.shutter)
                != sequence.shutter_cameras(frame.index, self.shutter)
            {
                Some(FullFrame::CameraMoved)
            } else {
                emitter.then_some(FullFrame::EmitterMoved)
            });
        }
        std::mem::take(&mut self.changes.boxes)
    }
}

/// The looks of a sequence's bodies at the last selected frame, the bodies recorded as changed
/// since, and the change boxes found so far.
struct FrameChanges {
    local: Vec<Aabb>,
    emissive: Vec<bool>,
    body_prototype: Vec<usize>,
    /// Every body's look at the last selected frame; empty before the first.
    looks: Vec<Look>,
    /// Bodies to look at again at the next selected frame (`dirty` flags them once).
    changed: Vec<usize>,
    dirty: Vec<bool>,
    /// Bodies moving over the last selected frame's shutter: their look there was a motion.
    moving: Vec<usize>,
    boxes: Vec<ChangeBox>,
}

impl FrameChanges {
    fn new(sequence: &Sequence) -> Self {
        let bodies = sequence.trajectory.bodies.len();
        Self {
            local: sequence.template.prototypes.iter().map(|p| p.mesh.bounds()).collect(),
            emissive: Emitters::emissive_prototypes(&sequence.template),
            body_prototype: sequence.trajectory.bodies.iter().map(|b| b.prototype as usize).collect(),
            looks: Vec::new(),
            changed: Vec::new(),
            dirty: vec![false; bodies],
            moving: Vec::new(),
            boxes: Vec::new(),
        }
    }

    /// Marks the bodies whose state or pose `frame` changed.
    fn note(&mut self, frame: &TrajectoryFrame) {
        let ids = frame.state_changes.iter().map(|c| c.0).chain(frame.pose_changes.iter().map(|c| c.0));
        for BodyId(b) in ids {
            self.mark(b as usize);
        }
    }

    fn mark(&mut self, b: usize) {
        if !std::mem::replace(&mut self.dirty[b], true) {
            self.changed.push(b);
        }
    }

    /// Brings the looks to selected frame `frame` (ordinal `ordinal`), with a box for every
    /// body whose look changed; whether an emissive body's did.
    fn compare(&mut self, frame: &ReplayFrame<'_>, shutter: f32, ordinal: u32) -> bool {
        let mut motions = frame.shutter_motions(shutter);
        motions.sort_unstable_by_key(|m| m.0);
        if self.looks.is_empty() {
            self.looks = body_looks(frame, &motions);
            self.end_frame(&motions);
            return false;
        }
        for b in std::mem::take(&mut self.moving) {
            self.mark(b);
        }
        for &(b, _) in &motions {
            self.mark(b);
        }
        let look = |b: usize| match motions.binary_search_by_key(&b, |m| m.0) {
            Ok(k) => Look::Moving(motions[k].1),
            Err(_) => still_look(frame, b),
        };
        let now: Vec<(usize, Look)> = self.changed.iter().map(|&b| (b, look(b))).collect();
        let mut emitter = false;
        for (b, after) in now {
            let before = std::mem::replace(&mut self.looks[b], after);
            if before == after {
                continue;
            }
            let p = self.body_prototype[b];
            emitter |= self.emissive.get(p).copied().unwrap_or(false);
            let bounds = look_bounds(&before, &self.local[p]).union(look_bounds(&after, &self.local[p]));
            let shape = look_shape(&before, &after, p as u32);
            self.boxes.push(ChangeBox { bounds, visible_at: ordinal, body: Some(b as u32), shape });
        }
        self.end_frame(&motions);
        emitter
    }

    /// Clears the changed set after a selected frame; remembers who moved over its shutter.
    fn end_frame(&mut self, motions: &[(usize, InstanceMotion)]) {
        for b in self.changed.drain(..) {
            self.dirty[b] = false;
        }
        self.moving = motions.iter().map(|m| m.0).collect();
    }
}

impl Sequence {
    /// Each prototype's triangles when it has few enough for the change index to test exactly
    /// ([`EXACT_MESH_TRIANGLES`]); empty otherwise (its changes are tested by their boxes).
    fn small_prototypes(&self) -> Vec<Vec<[glam::Vec3; 3]>> {
        self.template
            .prototypes
            .iter()
            .map(|p| match p.mesh.triangle_count() <= EXACT_MESH_TRIANGLES {
                true => (0..p.mesh.triangle_count()).map(|i| p.mesh.triangle(i)).collect(),
                false => Vec::new(),
            })
            .collect()
    }
}

/// The shape of a body of prototype `prototype` that changed from `before` to `after`, when
/// neither look moves over a shutter (a swept body is tested by its box).
fn look_shape(before: &Look, after: &Look, prototype: u32) -> Option<ChangeShape> {
    let pose = |look: &Look| match look {
        Look::Absent => Some(None),
        Look::Still(transform) => Some(Some(*transform)),
        Look::Moving(_) => None,
    };
    Some(ChangeShape { mesh: prototype, poses: [pose(before)?, pose(after)?] })
}

/// Body `b`'s look in `frame` without a shutter.
fn still_look(frame: &ReplayFrame<'_>, b: usize) -> Look {
    match frame.is_present(b) {
        true => Look::Still(frame.poses[b].to_affine()),
        false => Look::Absent,
    }
}

/// Every body's look in `frame`, `motions` the bodies moving over its shutter.
fn body_looks(frame: &ReplayFrame<'_>, motions: &[(usize, InstanceMotion)]) -> Vec<Look> {
    let mut looks: Vec<Look> = (0..frame.poses.len()).map(|b| still_look(frame, b)).collect();
    for &(b, motion) in motions {
        looks[b] = Look::Moving(motion);
    }
    looks
}

/// The world bounds of a body whose prototype's bounds are `local`, looking as `look`.
fn look_bounds(look: &Look, local: &Aabb) -> Aabb {
    match look {
        Look::Absent => Aabb::EMPTY,
        Look::Still(transform) => local.transformed(transform),
        Look::Moving(motion) => motion.bounds(local),
    }
}
