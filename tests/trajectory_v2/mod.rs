//! Trajectory format versions 1 and 2, written and replayed here independently of dormant's
//! reader, to check that old files read and replay as they did: `write` gives the bytes the
//! old writer gave (each frame: every body's state byte, and the poses of bodies awake at
//! its end or fallen asleep during it), `replay` rebuilds every frame the way the old
//! replay did.

use dormant::physics::{BodyKind, BodyPose, BodyState, IslandEvent};

use dormant::physics::trajectory::Trajectory;
use glam::{Quat, Vec3};

use crate::common::encoding::fnv1a64;

/// `t` in format `version` (1 or 2; version 1 has no scene section).
pub fn write(t: &Trajectory, version: u32) -> Vec<u8> {
    let mut w = b"DORMTRAJ".to_vec();
    let u32s = |w: &mut Vec<u8>, v: u32| w.extend_from_slice(&v.to_le_bytes());
    let text = |w: &mut Vec<u8>, s: &str| {
        w.extend_from_slice(&(s.len() as u32).to_le_bytes());
        w.extend_from_slice(s.as_bytes());
    };
    let pose = |w: &mut Vec<u8>, p: &BodyPose| {
        for v in p.translation.to_array().into_iter().chain(p.rotation.to_array()) {
            w.extend_from_slice(&v.to_le_bytes());
        }
    };
    u32s(&mut w, version);
    w.extend_from_slice(&t.scene_hash.to_le_bytes());
    w.extend_from_slice(&t.timestep.to_le_bytes());
    if version >= 2 {
        match &t.scene {
            None => w.push(0),
            Some(scene) => {
                w.push(1);
                text(&mut w, &scene.path.to_string_lossy());
                text(&mut w, &scene.asset_dir.to_string_lossy());
                text(&mut w, &scene.source);
                for v in [scene.options.count, scene.options.frames] {
                    w.push(u8::from(v.is_some()));
                    u32s(&mut w, v.unwrap_or(0));
                }
            }
        }
    }
    u32s(&mut w, t.prototypes.len() as u32);
    for name in &t.prototypes {
        text(&mut w, name);
    }
    u32s(&mut w, t.bodies.len() as u32);
    for b in &t.bodies {
        u32s(&mut w, b.prototype);
        w.push(u8::from(b.kind == BodyKind::Kinematic));
        u32s(&mut w, b.spawn_frame);
    }
    u32s(&mut w, t.frames.len() as u32);
    let mut previous = vec![BodyState::Absent; t.bodies.len()];
    let mut replay = t.replay();
    while let Some(f) = replay.next_frame() {
        w.extend(f.states.iter().map(|s| *s as u8));
        let stored: Vec<usize> = (0..f.states.len())
            .filter(|&b| {
                f.states[b] == BodyState::Awake
                    || (f.states[b] == BodyState::Asleep && previous[b] != BodyState::Asleep)
            })
            .collect();
        u32s(&mut w, stored.len() as u32);
        for b in stored {
            u32s(&mut w, b as u32);
            pose(&mut w, &f.poses[b]);
        }
        u32s(&mut w, f.events.len() as u32);
        for e in f.events {
            match e {
                IslandEvent::Slept { island, bodies, poses } => {
                    w.push(0);
                    w.extend_from_slice(&island.0.to_le_bytes());
                    u32s(&mut w, bodies.len() as u32);
                    for (b, p) in bodies.iter().zip(poses) {
                        u32s(&mut w, b.0);
                        pose(&mut w, p);
                    }
                }
                IslandEvent::Woke { island } => {
                    w.push(1);
                    w.extend_from_slice(&island.0.to_le_bytes());
                }
            }
        }
        previous.copy_from_slice(f.states);
    }
    let checksum = fnv1a64(&w);
    w.extend_from_slice(&checksum.to_le_bytes());
    w
}

/// One replayed frame: every body's state and pose (as bits, so -0.0 and 0.0 differ), and
/// the number of island events.
#[derive(Debug, PartialEq, Eq)]
pub struct Frame {
    pub states: Vec<u8>,
    pub poses: Vec<[u32; 7]>,
    pub events: usize,
}

impl Frame {
    pub fn of(states: &[BodyState], poses: &[BodyPose], events: usize) -> Self {
        Self {
            states: states.iter().map(|s| *s as u8).collect(),
            poses: poses.iter().map(bits).collect(),
            events,
        }
    }
}

pub fn bits(p: &BodyPose) -> [u32; 7] {
    let v: Vec<u32> =
        p.translation.to_array().into_iter().chain(p.rotation.to_array()).map(f32::to_bits).collect();
    v.try_into().unwrap()
}

/// Replays a valid version-1 or -2 file as the old replay did: each frame's states as
/// stored, and every body's last stored pose (the origin before its first).
pub fn replay(bytes: &[u8]) -> Vec<Frame> {
    let mut r = Cursor { bytes, at: 8 };
    let version = r.u32();
    assert!(version == 1 || version == 2, "version {version}");
    r.skip(12);
    if version == 2 && r.u8() == 1 {
        for _ in 0..3 {
            let n = r.u32();
            r.skip(n as usize);
        }
        r.skip(10);
    }
    for _ in 0..r.u32() {
        let n = r.u32();
        r.skip(n as usize);
    }
    let body_count = r.u32() as usize;
    r.skip(9 * body_count);
    let origin = BodyPose { translation: Vec3::ZERO, rotation: Quat::IDENTITY };
    let mut poses = vec![origin; body_count];
    let mut frames = Vec::new();
    for _ in 0..r.u32() {
        let states: Vec<BodyState> = r
            .skip(body_count)
            .iter()
            .map(|s| [BodyState::Absent, BodyState::Awake, BodyState::Asleep][*s as usize])
            .collect();
        for _ in 0..r.u32() {
            let body = r.u32() as usize;
            poses[body] = r.pose();
        }
        let events = r.u32() as usize;
        for _ in 0..events {
            if r.skip(9)[0] == 0 {
                let m = r.u32() as usize;
                r.skip(32 * m);
            }
        }
        frames.push(Frame::of(&states, &poses, events));
    }
    assert_eq!(r.at, bytes.len() - 8, "the whole file was read");
    frames
}

struct Cursor<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Cursor<'a> {
    fn skip(&mut self, n: usize) -> &'a [u8] {
        self.at += n;
        &self.bytes[self.at - n..self.at]
    }
    fn u8(&mut self) -> u8 {
        self.skip(1)[0]
    }
    fn u32(&mut self) -> u32 {
        u32::from_le_bytes(self.skip(4).try_into().unwrap())
    }
    fn pose(&mut self) -> BodyPose {
        let v: Vec<f32> = (0..7).map(|_| f32::from_le_bytes(self.skip(4).try_into().unwrap())).collect();
        BodyPose {
            translation: Vec3::new(v[0], v[1], v[2]),
            rotation: Quat::from_xyzw(v[3], v[4], v[5], v[6]),
        }
    }
}
