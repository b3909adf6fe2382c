//! The trajectory of an `[animation]` scene: what `simulate` records, made from the glTF
//! file's motion instead of Rapier. A body is present where its scale is not zero. It rests
//! from a frame where its pose holds, for at least `min_rest_frames` frames, within
//! `rest_tolerance` (no point of its bounds farther than that from where the rest began),
//! and holds the rest's first pose until it next moves. Bodies whose rests begin and end at
//! the same frames form one island, so the residency engine sees the file's rest exactly as
//! it sees a simulation's sleep, wake frames included. A file that records its simulation's
//! islands (dormant's own export) gets those instead (`given_islands`).

use std::collections::BTreeMap;
use std::time::Instant;

use rayon::prelude::*;

use super::body::{BodyId, BodyInfo, BodyKind, BodyPose, BodyState};
use super::given_islands::given_islands;
use super::island::{IslandEvent, IslandId};
use super::observed::SimulatedFrame;
use super::trajectory::{pose_bits, FrameRecorder, RecordedScene, Trajectory, TrajectoryFrame};
use super::PhysicsError;
use crate::scene::file::SceneFile;
use crate::scene::AnimatedScene;

/// One body's frames: its displayed state and pose wherever either changes, and its rests
/// (first frame, frame it moves again or leaves, or the frame count).
struct BodyTrack {
    changes: Vec<(u32, BodyState, BodyPose)>,
    rests: Vec<(u32, u32)>,
    spawn: u32,
}

/// Records the animation of `scene` (read from `file`, overrides applied) as a trajectory.
pub(crate) fn animated_trajectory(
    file: &SceneFile,
    scene: &AnimatedScene,
    recorded: RecordedScene,
    on_frame: &mut dyn FnMut(SimulatedFrame),
) -> Result<Trajectory, PhysicsError> {
    let start = Instant::now();
    let given = match &scene.gltf.extras.simulation {
        Some(simulation) => Some(
            given_islands(simulation, scene.roles.bodies.len(), scene.frames)
                .map_err(|m| file.error("animation.gltf", format!("asset.extras.dormant.simulation: {m}")))?,
        ),
        None => None,
    };
    let tracks: Vec<BodyTrack> = (0..scene.roles.bodies.len())
        .into_par_iter()
        .map(|b| track(file, scene, b, given.as_ref().map(|g| g.rests[b].as_slice())))
        .collect::<Result<_, _>>()?;
    let groups = match &given {
        Some(g) => g.groups.clone(),
        None => groups_resting_together(&tracks),
    };
    let frames = record_frames(scene.frames, &tracks, groups);
    let ms = start.elapsed().as_secs_f64() * 1e3 / scene.frames.max(1) as f64;
    for index in 0..scene.frames {
        on_frame(SimulatedFrame { index, frames: scene.frames, step_ms: ms });
    }
    let bodies = scene
        .roles
        .bodies
        .iter()
        .zip(&tracks)
        .enumerate()
        .map(|(i, (b, t))| {
            let kinematic = given.as_ref().is_some_and(|g| g.kinematic[i]);
            let kind = if kinematic { BodyKind::Kinematic } else { BodyKind::Dynamic };
            BodyInfo { prototype: b.prototype, kind, spawn_frame: t.spawn }
        })
        .collect();
    Ok(Trajectory {
        scene_hash: file.source_hash(),
        timestep: scene.timestep(),
        scene: Some(recorded),
        prototypes: scene.prototype_names(),
        bodies,
        frames,
    })
}

/// Body `b`'s poses sampled at every frame, its rests found (or `given`) and its displayed
/// frames kept where they change.
fn track(
    file: &SceneFile,
    scene: &AnimatedScene,
    b: usize,
    given: Option<&[(u32, u32)]>,
) -> Result<BodyTrack, PhysicsError> {
    let body = scene.roles.bodies[b];
    let expected = scene.roles.prototypes[body.prototype as usize].scale;
    let mut poses = Vec::with_capacity(scene.frames as usize);
    for i in 0..scene.frames {
        let (translation, rotation, scale) = scene.gltf.trs_at(body.node, scene.time(i));
        let pose = BodyPose { translation, rotation };
        if !(translation.is_finite() && rotation.is_finite() && scale.is_finite()) {
            let message =
                format!("nodes[{}]: its world transform at frame {i} is degenerate (not finite)", body.node);
            return Err(file.error("animation.gltf", message).into());
        }
        let present = scale.x != 0.0 && scale.y != 0.0 && scale.z != 0.0;
        if present && (scale - expected).abs().max_element() > 1e-3 * expected.abs().max_element() {
            let message = format!(
                "its scale changes over time (frame {i}: {:?}, first seen {:?}); only a scale of 0 (absent) may change",
                scale.to_array(),
                expected.to_array()
            );
            return Err(file.error("animation.gltf", format!("nodes[{}]: {message}", body.node)).into());
        }
        poses.push(present.then_some(pose));
    }
    let rests = match given {
        Some(rests) => rests.to_vec(),
        None => find_rests(&poses, scene.rest_tolerance, body.radius, scene.min_rest_frames),
    };
    if let Some(&(start, _)) =
        rests.iter().find(|r| r.0 as usize >= poses.len() || poses[r.0 as usize].is_none())
    {
        let message = format!("nodes[{}]: rests from frame {start}, where it is absent", body.node);
        return Err(file.error("animation.gltf", message).into());
    }
    Ok(displayed(&poses, rests))
}

/// The rests of a body with `poses` (None: absent) whose points lie within `radius` of its
/// origin, each as (first frame, end frame).
fn find_rests(poses: &[Option<BodyPose>], tolerance: f32, radius: f32, min_frames: u32) -> Vec<(u32, u32)> {
    let mut rests = Vec::new();
    let mut f = 0;
    while f < poses.len() {
        let Some(first) = poses[f] else {
            f += 1;
            continue;
        };
        let mut end = f + 1;
        while end < poses.len() && poses[end].is_some_and(|p| within(&first, &p, tolerance, radius)) {
            end += 1;
        }
        if end - f >= min_frames as usize {
            rests.push((f as u32, end as u32));
            f = end;
        } else {
            f += 1;
        }
    }
    rests
}

/// Whether no point within `radius` of the body's origin moves farther than `tolerance`
/// between poses `a` and `b` (bit-identical poses always are).
fn within(a: &BodyPose, b: &BodyPose, tolerance: f32, radius: f32) -> bool {
    if a.translation == b.translation && a.rotation == b.rotation {
        return true;
    }
    // The rotation angle from the chord between the quaternions (q and -q are one rotation):
    // exact for small angles, where `angle_between`'s arccosine rounds them to 0.
    let (p, q) = (glam::Vec4::from(a.rotation), glam::Vec4::from(b.rotation));
    let chord = (p - q).length().min((p + q).length());
    let angle = 4.0 * (chord / 2.0).min(1.0).asin();
    a.translation.distance(b.translation) + angle * radius <= tolerance
}

/// The states and poses a body shows: its own where it moves, its rest's first pose where it
/// rests; kept where they change.
fn displayed(poses: &[Option<BodyPose>], rests: Vec<(u32, u32)>) -> BodyTrack {
    let mut changes: Vec<(u32, BodyState, BodyPose)> = Vec::new();
    let mut rest = rests.iter().peekable();
    let mut last: Option<(BodyState, [u32; 7])> = None;
    for (i, pose) in poses.iter().enumerate() {
        let i = i as u32;
        while rest.peek().is_some_and(|r| r.1 <= i) {
            rest.next();
        }
        let resting = rest.peek().filter(|r| r.0 <= i);
        let (state, pose) = match (pose, resting) {
            (None, _) => (
                BodyState::Absent,
                BodyPose { translation: glam::Vec3::ZERO, rotation: glam::Quat::IDENTITY },
            ),
            (Some(_), Some(r)) => (BodyState::Asleep, poses[r.0 as usize].expect("a rest starts present")),
            (Some(p), None) => (BodyState::Awake, *p),
        };
        let key = (state, pose_bits(&pose));
        if last != Some(key) {
            last = Some(key);
            changes.push((i, state, pose));
        }
    }
    let spawn = poses.iter().position(Option::is_some).unwrap_or(0) as u32;
    BodyTrack { changes, rests, spawn }
}

/// The groups of bodies whose rests begin and end at the same frames, by first frame.
fn groups_resting_together(tracks: &[BodyTrack]) -> Vec<((u32, u32), Vec<BodyId>)> {
    let mut groups: BTreeMap<(u32, u32), Vec<BodyId>> = BTreeMap::new();
    for (b, track) in tracks.iter().enumerate() {
        for &rest in &track.rests {
            groups.entry(rest).or_default().push(BodyId(b as u32));
        }
    }
    groups.into_iter().collect()
}

/// The frames as a trajectory records them: each body's changes, and an island per group
/// (`Woke` before `Slept` within a frame; ids in the groups' order).
fn record_frames(
    frame_count: u32,
    tracks: &[BodyTrack],
    groups: Vec<((u32, u32), Vec<BodyId>)>,
) -> Vec<TrajectoryFrame> {
    let mut by_frame: Vec<Vec<(BodyId, BodyState, BodyPose)>> = vec![Vec::new(); frame_count as usize];
    for (b, track) in tracks.iter().enumerate() {
        for &(f, state, pose) in &track.changes {
            by_frame[f as usize].push((BodyId(b as u32), state, pose));
        }
    }
    let mut slept: Vec<Vec<IslandEvent>> = vec![Vec::new(); frame_count as usize];
    let mut woke: Vec<Vec<IslandEvent>> = vec![Vec::new(); frame_count as usize];
    for (id, ((start, end), bodies)) in groups.into_iter().enumerate() {
        let island = IslandId(id as u64);
        let poses = bodies.iter().map(|b| rest_pose(&tracks[b.0 as usize], start)).collect();
        slept[start as usize].push(IslandEvent::Slept { island, bodies, poses });
        if end < frame_count {
            woke[end as usize].push(IslandEvent::Woke { island });
        }
    }
    let mut recorder = FrameRecorder::new(tracks.len());
    let mut frames = Vec::with_capacity(frame_count as usize);
    for f in 0..frame_count as usize {
        for &(body, state, pose) in &by_frame[f] {
            recorder.state(body, state);
            if state != BodyState::Absent {
                recorder.pose(body, pose);
            }
        }
        let mut events = std::mem::take(&mut woke[f]);
        events.append(&mut slept[f]);
        frames.push(recorder.finish(events));
    }
    frames
}

/// The pose a body shows from frame `start`, where one of its rests begins.
fn rest_pose(track: &BodyTrack, start: u32) -> BodyPose {
    let at = track.changes.partition_point(|c| c.0 <= start);
    track.changes[at - 1].2
}
