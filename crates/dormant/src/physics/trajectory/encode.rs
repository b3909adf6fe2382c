//! Writing a trajectory in the current format (see the module docs of
//! [`super`] for the layout).

use super::{Trajectory, TrajectoryFrame, MAGIC};
use crate::physics::body::{BodyKind, BodyPose};
use crate::physics::island::IslandEvent;
use crate::scene::file::fnv1a64;

/// The file's bytes, checksum included.
pub(super) fn encode(t: &Trajectory) -> Vec<u8> {
    let mut w = Vec::with_capacity(encoded_len_estimate(t));
    w.extend_from_slice(MAGIC);
    put_u32(&mut w, Trajectory::FORMAT_VERSION);
    w.extend_from_slice(&t.scene_hash.to_le_bytes());
    put_f32(&mut w, t.timestep);
    match &t.scene {
        None => w.push(0),
        Some(scene) => {
            w.push(1);
            put_str(&mut w, &scene.path.to_string_lossy());
            put_str(&mut w, &scene.asset_dir.to_string_lossy());
            put_str(&mut w, &scene.source);
            for v in [scene.options.count, scene.options.frames] {
                w.push(u8::from(v.is_some()));
                put_u32(&mut w, v.unwrap_or(0));
            }
        }
    }
    put_u32(&mut w, t.prototypes.len() as u32);
    for name in &t.prototypes {
        put_str(&mut w, name);
    }
    put_u32(&mut w, t.bodies.len() as u32);
    for b in &t.bodies {
        put_u32(&mut w, b.prototype);
        w.push(match b.kind {
            BodyKind::Dynamic => 0,
            BodyKind::Kinematic => 1,
        });
        put_u32(&mut w, b.spawn_frame);
    }
    put_u32(&mut w, t.frames.len() as u32);
    for f in &t.frames {
        put_frame(&mut w, f);
    }
    let checksum = fnv1a64(&w);
    w.extend_from_slice(&checksum.to_le_bytes());
    w
}

/// Bytes of the frames section, which dominates (the rest is reallocated if it is larger).
fn encoded_len_estimate(t: &Trajectory) -> usize {
    let frame = |f: &TrajectoryFrame| 12 + 5 * f.state_changes.len() + 32 * f.pose_changes.len();
    4096 + t.frames.iter().map(frame).sum::<usize>()
}

fn put_frame(w: &mut Vec<u8>, f: &TrajectoryFrame) {
    put_u32(w, f.state_changes.len() as u32);
    for &(body, state) in &f.state_changes {
        put_u32(w, body.0);
        w.push(state as u8);
    }
    put_u32(w, f.pose_changes.len() as u32);
    for (body, pose) in &f.pose_changes {
        put_u32(w, body.0);
        put_pose(w, pose);
    }
    put_u32(w, f.events.len() as u32);
    for e in &f.events {
        match e {
            IslandEvent::Slept { island, bodies, poses } => {
                w.push(0);
                w.extend_from_slice(&island.0.to_le_bytes());
                put_u32(w, bodies.len() as u32);
                for (b, p) in bodies.iter().zip(poses) {
                    put_u32(w, b.0);
                    put_pose(w, p);
                }
            }
            IslandEvent::Woke { island } => {
                w.push(1);
                w.extend_from_slice(&island.0.to_le_bytes());
            }
        }
    }
}

fn put_u32(w: &mut Vec<u8>, v: u32) {
    w.extend_from_slice(&v.to_le_bytes());
}

fn put_str(w: &mut Vec<u8>, s: &str) {
    put_u32(w, s.len() as u32);
    w.extend_from_slice(s.as_bytes());
}

fn put_f32(w: &mut Vec<u8>, v: f32) {
    w.extend_from_slice(&v.to_le_bytes());
}

fn put_pose(w: &mut Vec<u8>, p: &BodyPose) {
    for v in p.translation.to_array().into_iter().chain(p.rotation.to_array()) {
        put_f32(w, v);
    }
}
