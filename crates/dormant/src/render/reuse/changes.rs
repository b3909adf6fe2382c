//! What changes between consecutive rendered frames, found from the trajectory before they are
//! rendered: [`RunMotion`], the facts of a run the sequence hands over (its trajectory, scene,
//! frames and cameras), and [`ChangeStream`], which replays the trajectory once, a window of
//! frames at a time, into the boxes of a [`ChangeIndex`](crate::accel::bvh::ChangeIndex) and
//! says which frames must be traced in full and why ([`FullFrame`]: the first, the camera
//! moved, an emissive body changed; or, as the run finds, islands were baked).

use serde::Serialize;

use crate::accel::bvh::{ChangeBox, ChangeShape, EXACT_MESH_TRIANGLES};
use crate::geometry::{Aabb, InstanceMotion};
use crate::physics::trajectory::{Replay, ReplayFrame, Trajectory, TrajectoryFrame};
use crate::physics::BodyId;
use crate::render::Emitters;
use crate::scene::{Camera, SceneDescription};

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
    pub(crate) fn name(self) -> &'static str {
        match self {
            FullFrame::First => "first",
            FullFrame::CameraMoved => "camera_moved",
            FullFrame::EmitterMoved => "emitter_moved",
            FullFrame::IslandsBaked => "islands_baked",
        }
    }
}

/// What exact reuse needs to know of a run, from the sequence: the trajectory its bodies
/// follow, the scene they are in (their meshes, which of them emit light), the frames it
/// renders, ascending, and the camera at each (at shutter open, and at close when blurred).
pub(crate) struct RunMotion<'s> {
    trajectory: &'s Trajectory,
    scene: &'s SceneDescription,
    frames: Vec<u32>,
    cameras: Vec<(Camera, Option<Camera>)>,
    /// The shutter in frame intervals (0: no motion blur).
    shutter: f32,
}

impl<'s> RunMotion<'s> {
    /// The run of `frames` (ascending, within `trajectory`) with `cameras[k]` the camera of
    /// `frames[k]`. `scene` is the sequence's template: the prototypes the trajectory's
    /// bodies instance.
    pub(crate) fn new(
        trajectory: &'s Trajectory,
        scene: &'s SceneDescription,
        frames: Vec<u32>,
        cameras: Vec<(Camera, Option<Camera>)>,
        shutter: f32,
    ) -> Self {
        assert_eq!(frames.len(), cameras.len(), "one camera per rendered frame");
        debug_assert!(frames.windows(2).all(|w| w[0] < w[1]), "rendered frames ascend");
        Self { trajectory, scene, frames, cameras, shutter }
    }

    /// The rendered frames, ascending: a frame's ordinal is its position here.
    pub(crate) fn frames(&self) -> &[u32] {
        &self.frames
    }

    /// Each prototype's triangles when it has few enough for the change index to test exactly
    /// ([`EXACT_MESH_TRIANGLES`]); empty otherwise (its changes are tested by their boxes).
    pub(crate) fn small_prototypes(&self) -> Vec<Vec<[glam::Vec3; 3]>> {
        self.scene
            .prototypes
            .iter()
            .map(|p| match p.mesh.triangle_count() <= EXACT_MESH_TRIANGLES {
                true => (0..p.mesh.triangle_count()).map(|i| p.mesh.triangle(i)).collect(),
                false => Vec::new(),
            })
            .collect()
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
pub(crate) struct ChangeStream<'s> {
    pub(super) run: RunMotion<'s>,
    replay: Replay<'s>,
    changes: FrameChanges,
}

impl<'s> ChangeStream<'s> {
    pub(crate) fn new(run: RunMotion<'s>) -> Self {
        let changes = FrameChanges::new(&run);
        Self { replay: run.trajectory.replay(), changes, run }
    }

    /// The change boxes of the next window of the run's frames, its first ordinal
    /// `full.len()`: frames are added until the boxes reach `max_boxes` or the frames end, and
    /// each one's reason to be traced in full is pushed onto `full`.
    pub(crate) fn window(&mut self, full: &mut Vec<Option<FullFrame>>, max_boxes: usize) -> Vec<ChangeBox> {
        let run = &self.run;
        while full.len() < run.frames.len() && self.changes.boxes.len() < max_boxes {
            let Some(frame) = self.replay.next_frame() else { break };
            self.changes.note(&run.trajectory.frames[frame.index as usize]);
            let ordinal = full.len();
            if frame.index != run.frames[ordinal] {
                continue;
            }
            let emitter = self.changes.compare(&frame, run.shutter, ordinal as u32);
            full.push(if ordinal == 0 {
                Some(FullFrame::First)
            } else if run.cameras[ordinal - 1] != run.cameras[ordinal] {
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
    fn new(run: &RunMotion) -> Self {
        let bodies = run.trajectory.bodies.len();
        Self {
            local: run.scene.prototypes.iter().map(|p| p.mesh.bounds()).collect(),
            emissive: Emitters::emissive_prototypes(run.scene),
            body_prototype: run.trajectory.bodies.iter().map(|b| b.prototype as usize).collect(),
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
