//! The animation `dormant`: per body node translation and rotation (LINEAR) and a presence
//! scale (STEP), and the camera node's translation and rotation, keyed at the frames where a
//! value changes (a stretch of bit-identical values keeps only its first and last key).

use serde::Serialize;

use super::buffer::{BufferBuilder, Kind};
use crate::scene::gltf::animated::frame_time;

/// A pose as glTF writes it: translation xyz, then rotation quaternion xyzw.
pub(super) type Pose = [f32; 7];

/// The identity pose, for a body that is never in the world.
const IDENTITY: Pose = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0];

/// One node's value over the frames, run-length encoded: `(first frame, value)` for every
/// frame whose value differs bit for bit from the frame before (`None`: the body is absent).
#[derive(Clone, Debug, Default)]
pub(super) struct Track {
    runs: Vec<(u32, Option<Pose>)>,
}

fn bits(p: &Option<Pose>) -> Option<[u32; 7]> {
    p.map(|p| p.map(f32::to_bits))
}

impl Track {
    /// Records the value of frame `frame` (frames are pushed in order, from 0).
    pub(super) fn push(&mut self, frame: u32, value: Option<Pose>) {
        if self.runs.last().is_none_or(|(_, last)| bits(last) != bits(&value)) {
            self.runs.push((frame, value));
        }
    }

    /// Runs of the pose with absent frames holding the nearest present pose (the earlier on
    /// a tie, the identity when never present), equal neighbours merged.
    fn filled(&self) -> Vec<(u32, Pose)> {
        let mut out: Vec<(u32, Pose)> = Vec::with_capacity(self.runs.len());
        let mut push = |frame: u32, pose: Pose| {
            if out.last().is_none_or(|(_, last)| bits(&Some(*last)) != bits(&Some(pose))) {
                out.push((frame, pose));
            }
        };
        for (i, &(start, value)) in self.runs.iter().enumerate() {
            if let Some(pose) = value {
                push(start, pose);
                continue;
            }
            let before = i.checked_sub(1).and_then(|j| self.runs[j].1);
            let after = self.runs.get(i + 1).and_then(|r| r.1.map(|p| (r.0, p)));
            match (before, after) {
                (Some(b), Some((end, a))) => {
                    // Frames start..end are absent: the first half holds `b`, the rest `a`.
                    let last = end - 1;
                    push(start, b);
                    if (start + last) / 2 < last {
                        push((start + last) / 2 + 1, a);
                    }
                }
                (Some(b), None) => push(start, b),
                (None, Some((_, a))) => push(start, a),
                (None, None) => push(start, IDENTITY),
            }
        }
        out
    }

    /// The key frames and poses of the pose channels over `frames` frames: the first and
    /// last frame of every run.
    pub(super) fn pose_keys(&self, frames: u32) -> Vec<(u32, Pose)> {
        run_keys(&self.filled(), frames)
    }

    /// The key frames of the presence channel: frame 0 and every frame where presence
    /// changes, with whether the body is present from there.
    pub(super) fn presence_keys(&self) -> Vec<(u32, bool)> {
        let mut keys: Vec<(u32, bool)> = Vec::new();
        for &(start, value) in &self.runs {
            if keys.last().is_none_or(|&(_, present)| present != value.is_some()) {
                keys.push((start, value.is_some()));
            }
        }
        keys
    }
}

/// The first and last frame of each run (`runs` starts at frame 0; the last run ends at
/// `frames - 1`).
fn run_keys(runs: &[(u32, Pose)], frames: u32) -> Vec<(u32, Pose)> {
    let mut keys = Vec::with_capacity(2 * runs.len());
    for (i, &(start, pose)) in runs.iter().enumerate() {
        let end = runs.get(i + 1).map_or(frames.max(1) - 1, |r| r.0 - 1);
        keys.push((start, pose));
        if end > start {
            keys.push((end, pose));
        }
    }
    keys
}

/// An animation sampler (typed: a large export has hundreds of thousands).
#[derive(Debug, Serialize)]
struct Sampler {
    input: usize,
    output: usize,
    interpolation: &'static str,
}

#[derive(Debug, Serialize)]
struct Target {
    node: usize,
    path: &'static str,
}

#[derive(Debug, Serialize)]
struct Channel {
    sampler: usize,
    target: Target,
}

/// The glTF animation `dormant`.
#[derive(Debug, Serialize)]
pub(super) struct Animation {
    name: &'static str,
    samplers: Vec<Sampler>,
    channels: Vec<Channel>,
}

/// The samplers and channels of the animation, added node by node.
pub(super) struct AnimationBuilder {
    fps: f64,
    samplers: Vec<Sampler>,
    channels: Vec<Channel>,
}

impl AnimationBuilder {
    pub(super) fn new(fps: f64) -> Self {
        Self { fps, samplers: Vec::new(), channels: Vec::new() }
    }

    /// Translation and rotation channels (LINEAR) of `node` through `keys` (none without
    /// keys: a trajectory without frames).
    pub(super) fn pose(&mut self, node: usize, keys: &[(u32, Pose)], buffer: &mut BufferBuilder) {
        if keys.is_empty() {
            return;
        }
        let input = self.times(keys.iter().map(|k| k.0), buffer);
        let translations: Vec<f32> = keys.iter().flat_map(|(_, p)| p[..3].to_vec()).collect();
        let rotations: Vec<f32> = keys.iter().flat_map(|(_, p)| p[3..].to_vec()).collect();
        let translation = buffer.shared_floats(Kind::Vec3, &translations);
        let rotation = buffer.shared_floats(Kind::Vec4, &rotations);
        self.channel(node, "translation", input, translation, "LINEAR");
        self.channel(node, "rotation", input, rotation, "LINEAR");
    }

    /// The presence channel of `node`: scale 0 while absent, 1 while present (STEP).
    pub(super) fn presence(&mut self, node: usize, keys: &[(u32, bool)], buffer: &mut BufferBuilder) {
        if keys.is_empty() {
            return;
        }
        let input = self.times(keys.iter().map(|k| k.0), buffer);
        let scales: Vec<f32> =
            keys.iter().flat_map(|&(_, present)| [f32::from(u8::from(present)); 3]).collect();
        let output = buffer.shared_floats(Kind::Vec3, &scales);
        self.channel(node, "scale", input, output, "STEP");
    }

    fn times(&self, frames: impl Iterator<Item = u32>, buffer: &mut BufferBuilder) -> usize {
        let times: Vec<f32> = frames.map(|i| frame_time(i, self.fps)).collect();
        buffer.shared_floats(Kind::Scalar, &times)
    }

    fn channel(
        &mut self,
        node: usize,
        path: &'static str,
        input: usize,
        output: usize,
        interpolation: &'static str,
    ) {
        self.samplers.push(Sampler { input, output, interpolation });
        self.channels.push(Channel { sampler: self.samplers.len() - 1, target: Target { node, path } });
    }

    /// The animation, or `None` when it has no channel.
    pub(super) fn finish(self) -> Option<Animation> {
        (!self.channels.is_empty()).then_some(Animation {
            name: "dormant",
            samplers: self.samplers,
            channels: self.channels,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::{Pose, Track};

    fn at(x: f32) -> Option<Pose> {
        Some([x, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0])
    }

    #[test]
    fn a_resting_stretch_keeps_two_keys_and_absence_holds_the_nearest_pose() {
        let mut track = Track::default();
        let values = [None, None, at(1.0), at(2.0), at(2.0), at(2.0), at(2.0), at(3.0), None, None];
        for (i, v) in values.iter().enumerate() {
            track.push(i as u32, *v);
        }
        let keys: Vec<(u32, f32)> = track.pose_keys(10).iter().map(|(f, p)| (*f, p[0])).collect();
        assert_eq!(keys, vec![(0, 1.0), (2, 1.0), (3, 2.0), (6, 2.0), (7, 3.0), (9, 3.0)]);
        assert_eq!(track.presence_keys(), vec![(0, false), (2, true), (8, false)]);
    }

    #[test]
    fn a_gap_is_filled_from_both_sides() {
        let mut track = Track::default();
        for (i, v) in [at(1.0), None, None, None, at(5.0)].iter().enumerate() {
            track.push(i as u32, *v);
        }
        let keys: Vec<(u32, f32)> = track.pose_keys(5).iter().map(|(f, p)| (*f, p[0])).collect();
        assert_eq!(keys, vec![(0, 1.0), (2, 1.0), (3, 5.0), (4, 5.0)]);
    }
}
