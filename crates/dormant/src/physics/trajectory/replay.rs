//! Frames as changes, both ways: [`FrameRecorder`] turns each frame's body states and poses
//! into a [`TrajectoryFrame`] of what changed, and [`Replay`] applies those changes to give
//! every body's state and pose frame by frame.

use bit_set::BitSet;
use glam::{Quat, Vec3};

use crate::geometry::{InstanceMotion, RigidTransform};

use super::TrajectoryFrame;
use crate::physics::body::{BodyId, BodyPose, BodyState};
use crate::physics::island::IslandEvent;

/// Every body's state and pose as of the last frame recorded or replayed. Before the first
/// frame every body is absent at the origin.
#[derive(Clone, Debug)]
struct BodyTable {
    states: Vec<BodyState>,
    poses: Vec<BodyPose>,
}

/// Whether a body in `state` at `pose` is in the world: spawned, not removed, at a finite
/// pose. The one place that decides which bodies a frame shows.
fn is_present(state: BodyState, pose: &BodyPose) -> bool {
    state != BodyState::Absent && pose.translation.is_finite()
}

/// What a replay keeps, once its owner first restarts its changes, besides every body's
/// state and pose.
#[derive(Clone, Debug)]
struct Tracked {
    /// The bodies whose state or pose changed in frames `since..` the replay's next.
    changed: BitSet,
    since: u32,
    /// How many bodies are present, kept as changes apply: counting them afresh for each
    /// rendered frame read every state and pose (megabytes on the demolition).
    present: usize,
}

impl Tracked {
    /// Body `b` changed, present before as `was` and now as `is`.
    fn record(&mut self, b: usize, was: bool, is: bool) {
        self.present = self.present + usize::from(is) - usize::from(was);
        self.changed.insert(b);
    }
}

impl BodyTable {
    fn new(body_count: usize) -> Self {
        let origin = BodyPose { translation: Vec3::ZERO, rotation: Quat::IDENTITY };
        Self { states: vec![BodyState::Absent; body_count], poses: vec![origin; body_count] }
    }

    fn present(&self, b: usize) -> bool {
        is_present(self.states[b], &self.poses[b])
    }

    /// Applies `frame`'s changes, keeping `tracked` up to date with them.
    fn apply(&mut self, frame: &TrajectoryFrame, tracked: Option<&mut Tracked>) {
        let Some(t) = tracked else {
            for &(body, state) in &frame.state_changes {
                self.states[body.0 as usize] = state;
            }
            for &(body, pose) in &frame.pose_changes {
                self.poses[body.0 as usize] = pose;
            }
            return;
        };
        for &(body, state) in &frame.state_changes {
            let (b, was) = (body.0 as usize, self.present(body.0 as usize));
            self.states[b] = state;
            t.record(b, was, self.present(b));
        }
        for &(body, pose) in &frame.pose_changes {
            let (b, was) = (body.0 as usize, self.present(body.0 as usize));
            self.poses[b] = pose;
            t.record(b, was, self.present(b));
        }
    }

    /// The poses `frame` replaces of bodies present before it (ascending), into `before`.
    fn replaced(&self, frame: &TrajectoryFrame, before: &mut Vec<(BodyId, BodyPose)>) {
        before.clear();
        before.extend(
            frame
                .pose_changes
                .iter()
                .filter(|(b, _)| self.present(b.0 as usize))
                .map(|&(b, _)| (b, self.poses[b.0 as usize])),
        );
    }
}

/// Records frames as changes against every body's last recorded state and pose: feed each
/// body's state and the poses to store with [`state`](Self::state) and [`pose`](Self::pose),
/// then [`finish`](Self::finish) the frame.
#[derive(Clone, Debug)]
pub(crate) struct FrameRecorder {
    last: BodyTable,
    frame: TrajectoryFrame,
}

impl FrameRecorder {
    pub(crate) fn new(body_count: usize) -> Self {
        Self { last: BodyTable::new(body_count), frame: TrajectoryFrame::default() }
    }

    /// `body` ends the frame in `state`; recorded if that is a change.
    pub(crate) fn state(&mut self, body: BodyId, state: BodyState) {
        let last = &mut self.last.states[body.0 as usize];
        if *last != state {
            *last = state;
            self.frame.state_changes.push((body, state));
        }
    }

    /// `body` ends the frame at `pose`; recorded unless it is bit for bit the body's last
    /// recorded pose (so replay gives exactly the poses it was given).
    pub(crate) fn pose(&mut self, body: BodyId, pose: BodyPose) {
        let last = &mut self.last.poses[body.0 as usize];
        if pose_bits(last) != pose_bits(&pose) {
            *last = pose;
            self.frame.pose_changes.push((body, pose));
        }
    }

    /// The frame's changes, with its island events; the next frame starts empty.
    pub(crate) fn finish(&mut self, events: Vec<IslandEvent>) -> TrajectoryFrame {
        TrajectoryFrame { events, ..std::mem::take(&mut self.frame) }
    }
}

/// A pose as the bits of its seven floats (equal bits: the same pose, bit for bit).
pub(crate) fn pose_bits(p: &BodyPose) -> [u32; 7] {
    let [x, y, z] = p.translation.to_array();
    let [i, j, k, w] = p.rotation.to_array();
    [x, y, z, i, j, k, w].map(f32::to_bits)
}

/// A cursor over a trajectory's frames that keeps every body's current state and pose and,
/// from the first time its owner restarts its changes ([`restart_changes`](Self::restart_changes)),
/// which bodies changed since the last restart and how many are present. Until then applying
/// a frame costs no more than its changes: a run that renders a slice late in a trajectory
/// replays every frame before it.
pub struct Replay<'a> {
    frames: &'a [TrajectoryFrame],
    next: usize,
    table: BodyTable,
    before: Vec<(BodyId, BodyPose)>,
    tracked: Option<Tracked>,
}

/// One replayed frame: every body's state and pose at its end (`poses[i]` is meaningless
/// while body `i` is absent) and the frame's island events. For motion blur, the poses around
/// it: `before`, the previous frame's poses of the bodies that moved during this one (present
/// then too), and `after`, the next frame's poses of the bodies that move during it (the
/// next frame's pose changes; empty at the last frame). A body in neither is still on both
/// sides of the frame.
pub struct ReplayFrame<'a> {
    pub index: u32,
    pub states: &'a [BodyState],
    pub poses: &'a [BodyPose],
    pub events: &'a [IslandEvent],
    pub before: &'a [(BodyId, BodyPose)],
    pub after: &'a [(BodyId, BodyPose)],
    /// `present_bodies().count()`, when the replay keeps it.
    present: Option<usize>,
    /// The first frame of a run of frames up to this one, and the bodies whose state or pose
    /// changed in them.
    changed: Option<(u32, &'a BitSet)>,
}

impl<'a> ReplayFrame<'a> {
    /// A frame of every body's `states` and `poses` (of equal length) with island `events`
    /// and no poses around it (no motion blur): for driving a scene manager from a world
    /// other than a trajectory's replay.
    pub fn still(
        index: u32,
        states: &'a [BodyState],
        poses: &'a [BodyPose],
        events: &'a [IslandEvent],
    ) -> Self {
        debug_assert_eq!(states.len(), poses.len());
        Self { index, states, poses, events, before: &[], after: &[], present: None, changed: None }
    }
}

impl ReplayFrame<'_> {
    /// Whether body `b` is in the world this frame: spawned, not removed, at a finite pose.
    pub(crate) fn is_present(&self, b: usize) -> bool {
        is_present(self.states[b], &self.poses[b])
    }

    /// The bodies present this frame, ascending.
    pub fn present_bodies(&self) -> impl Iterator<Item = BodyId> + '_ {
        (0..self.states.len()).filter(|&b| self.is_present(b)).map(|b| BodyId(b as u32))
    }

    /// The bodies whose state or pose changed after frame `earlier` up to this one, when the
    /// replay kept them from there ([`Sequence::replay`](crate::sequence::Sequence::replay)
    /// keeps them from one selected frame to the next); `None` otherwise.
    pub(crate) fn changed_after(&self, earlier: u32) -> Option<&BitSet> {
        self.changed.filter(|(since, _)| earlier.checked_add(1) == Some(*since)).map(|(_, set)| set)
    }

    /// How many bodies are present this frame (`present_bodies().count()`, without reading
    /// every body when the replay keeps the count).
    pub(crate) fn present_count(&self) -> usize {
        debug_assert!(self.present.is_none_or(|n| n == self.present_bodies().count()));
        self.present.unwrap_or_else(|| self.present_bodies().count())
    }

    /// The motion over a shutter of `shutter` frame intervals centred on this frame of each present
    /// body that moves within it, ascending by body: its pose at shutter open interpolated
    /// between the previous frame's pose and this one's, at close between this one's and the
    /// next frame's ([`RigidTransform::interpolate`]). Empty without a shutter.
    pub fn shutter_motions(&self, shutter: f32) -> Vec<(usize, InstanceMotion)> {
        if shutter <= 0.0 {
            return Vec::new();
        }
        let half = 0.5 * shutter;
        let (mut before, mut after) = (self.before.iter().peekable(), self.after.iter().peekable());
        let mut motions = Vec::new();
        loop {
            let b = match (before.peek(), after.peek()) {
                (None, None) => break,
                (Some(p), None) => p.0,
                (None, Some(n)) => n.0,
                (Some(p), Some(n)) => p.0.min(n.0),
            };
            let prev = before.next_if(|p| p.0 == b).map(|p| p.1);
            let next = after.next_if(|n| n.0 == b).map(|n| n.1).filter(|n| n.translation.is_finite());
            let b = b.0 as usize;
            if !self.is_present(b) {
                continue;
            }
            let now = self.poses[b].rigid();
            let open = prev.map_or(now, |p| RigidTransform::interpolate(&p.rigid(), &now, 1.0 - half));
            let close = next.map_or(now, |n| RigidTransform::interpolate(&now, &n.rigid(), half));
            if open != now || close != now {
                motions.push((b, InstanceMotion { open, close }));
            }
        }
        motions
    }
}

impl<'a> Replay<'a> {
    pub(super) fn new(frames: &'a [TrajectoryFrame], body_count: usize) -> Self {
        Self { frames, next: 0, table: BodyTable::new(body_count), before: Vec::new(), tracked: None }
    }

    /// Forgets which bodies changed: the frames from the next one on start a new run of them.
    pub(crate) fn restart_changes(&mut self) {
        let since = self.next as u32;
        match &mut self.tracked {
            Some(t) => {
                t.changed.make_empty();
                t.since = since;
            }
            None => {
                let n = self.table.states.len();
                let present = (0..n).filter(|&b| self.table.present(b)).count();
                self.tracked = Some(Tracked { changed: BitSet::with_capacity(n), since, present });
            }
        }
    }

    pub fn next_frame(&mut self) -> Option<ReplayFrame<'_>> {
        let frame = self.frames.get(self.next)?;
        self.table.replaced(frame, &mut self.before);
        self.table.apply(frame, self.tracked.as_mut());
        self.next += 1;
        Some(ReplayFrame {
            index: (self.next - 1) as u32,
            states: &self.table.states,
            poses: &self.table.poses,
            events: &frame.events,
            before: &self.before,
            after: self.frames.get(self.next).map_or(&[], |f| &f.pose_changes),
            present: self.tracked.as_ref().map(|t| t.present),
            changed: self.tracked.as_ref().map(|t| (t.since, &t.changed)),
        })
    }
}
