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
use crate::geometry::{Aabb, InstanceMotion};
use crate::physics::trajectory::ReplayFrame;
use crate::render::{Emitters, ReuseStore};
use crate::residency::{FrameStats, IntegrationForm};

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
    pub fn name(self) -> &'static str {
        match self {
            FullFrame::First => "first",
            FullFrame::CameraMoved => "camera_moved",
            FullFrame::EmitterMoved => "emitter_moved",
            FullFrame::IslandsBaked => "islands_baked",
        }
    }
}

/// Exact reuse over one run: the change index, the rendered frames' ordinals, the frames that
/// must be traced in full, and the store.
pub(crate) struct ExactReuse {
    pub index: ChangeIndex,
    /// The selected frames, ascending: a frame's ordinal is its position here.
    frames: Vec<u32>,
    /// Per ordinal, why that frame cannot reuse samples of the frame before it (`None`: it can).
    full: Vec<Option<FullFrame>>,
    form: IntegrationForm,
    pub store: ReuseStore,
}

impl ExactReuse {
    /// Exact reuse for rendering `selection` with `renderer` in integration `form`, or `None`
    /// when the renderer does not ask for it (`--reuse off|static`, or a seed per frame).
    pub(crate) fn plan(
        sequence: &Sequence,
        selection: &FrameSelection,
        renderer: &FrameRenderer<'_>,
        form: IntegrationForm,
    ) -> Result<Option<Self>, SequenceError> {
        if renderer.reuse != ReuseMode::Exact || renderer.seed != SeedMode::Fixed {
            return Ok(None);
        }
        check_budget(renderer)?;
        let frames = selection.frames();
        let (boxes, full) = sequence.changes(&frames, renderer.shutter);
        let index = ChangeIndex::build(boxes, sequence.small_prototypes());
        Ok(Some(Self { index, frames, full, form, store: ReuseStore::default() }))
    }

    /// The ordinal of selected frame `frame`.
    pub(crate) fn ordinal(&self, frame: u32) -> u32 {
        self.frames.partition_point(|&f| f < frame) as u32
    }

    /// The latest horizon worth finding for a sample traced in frame `frame`: the next frame
    /// traced in full anyway (a camera cut, a moving light), else the end of the run. When
    /// that is the very next frame, as under a camera that moves every frame, no horizon
    /// query runs at all.
    pub(crate) fn horizon_limit(&self, frame: u32) -> u32 {
        let next = self.ordinal(frame) as usize + 1;
        let full = self.full.get(next..).unwrap_or_default().iter().position(Option::is_some);
        full.map_or(self.frames.len(), |k| next + k) as u32
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

/// Checks that exact reuse of `renderer`'s frames fits in its budget: a store of one value per
/// pixel and pass ([`ReuseStore::bytes_for`]).
pub fn check_budget(renderer: &FrameRenderer<'_>) -> Result<(), SequenceError> {
    let needed = ReuseStore::bytes_for(renderer.width, renderer.height, renderer.aovs);
    if needed <= renderer.reuse_budget {
        return Ok(());
    }
    let mib = |bytes: usize| bytes.div_ceil(1 << 20);
    Err(SequenceError::ReuseBudget {
        budget_mib: renderer.reuse_budget >> 20,
        needed_mib: mib(needed),
        width: renderer.width,
        height: renderer.height,
    })
}

/// What a body looks like to the rays of one frame: absent, at a pose, or moving over the
/// shutter.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Look {
    Absent,
    Still(glam::Affine3A),
    Moving(InstanceMotion),
}

impl Sequence {
    /// The changes between consecutive frames of `frames` (ascending) with a shutter of
    /// `shutter` frame intervals: a box for every body whose look differs from one frame to
    /// the next (its bounds at both, swept over the shutter when blurred), tagged with the
    /// ordinal of the later frame; and per ordinal whether the frame must be traced in full
    /// (the camera moved, or an emissive body changed).
    fn changes(&self, frames: &[u32], shutter: f32) -> (Vec<ChangeBox>, Vec<Option<FullFrame>>) {
        let local: Vec<Aabb> = self.template.prototypes.iter().map(|p| p.mesh.bounds()).collect();
        let emissive = Emitters::emissive_prototypes(&self.template);
        let body_prototype: Vec<usize> =
            self.trajectory.bodies.iter().map(|b| b.prototype as usize).collect();
        let mut boxes = Vec::new();
        let mut full = vec![None; frames.len()];
        let mut looks: Vec<Look> = Vec::new();
        let mut replay = self.trajectory.replay();
        let (mut ordinal, last) = (0usize, frames.last().copied());
        while let Some(frame) = replay.next_frame() {
            if ordinal >= frames.len() || Some(frame.index) > last {
                break;
            }
            if frame.index != frames[ordinal] {
                continue;
            }
            let now = body_looks(&frame, shutter);
            if ordinal == 0 {
                full[0] = Some(FullFrame::First);
            } else {
                let camera = self.shutter_cameras(frames[ordinal - 1], shutter)
                    != self.shutter_cameras(frame.index, shutter);
                let mut emitter = false;
                for (b, (before, after)) in looks.iter().zip(&now).enumerate() {
                    if before == after {
                        continue;
                    }
                    let p = body_prototype[b];
                    emitter |= emissive.get(p).copied().unwrap_or(false);
                    let bounds = look_bounds(before, &local[p]).union(look_bounds(after, &local[p]));
                    let shape = look_shape(before, after, p as u32);
                    boxes.push(ChangeBox { bounds, visible_at: ordinal as u32, shape });
                }
                full[ordinal] = match (camera, emitter) {
                    (true, _) => Some(FullFrame::CameraMoved),
                    (false, true) => Some(FullFrame::EmitterMoved),
                    (false, false) => None,
                };
            }
            looks = now;
            ordinal += 1;
        }
        (boxes, full)
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

/// Every body's look in `frame` with a shutter of `shutter` frame intervals.
fn body_looks(frame: &ReplayFrame<'_>, shutter: f32) -> Vec<Look> {
    let mut looks: Vec<Look> = (0..frame.poses.len())
        .map(|b| match frame.is_present(b) {
            true => Look::Still(frame.poses[b].to_affine()),
            false => Look::Absent,
        })
        .collect();
    for (b, motion) in frame.shutter_motions(shutter) {
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
