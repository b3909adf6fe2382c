//! Reading a trajectory of any readable version (see the module docs of [`super`] for the
//! layouts), checked as it is read. Every error about the contents names the file, the field
//! and the byte offset where that field starts; a count is checked against the bytes left
//! before anything is allocated for it.

use std::collections::BTreeMap;
use std::fmt;
use std::path::Path;

use glam::{Quat, Vec3};

use super::{FrameRecorder, RecordedScene, Trajectory, TrajectoryError, TrajectoryFrame, MAGIC};
use crate::physics::body::{BodyId, BodyInfo, BodyKind, BodyPose, BodyState};
use crate::physics::island::{IslandEvent, IslandId};
use crate::physics::options::SimulateOptions;
use crate::scene::file::fnv1a64;

/// Bytes of magic and version, before the checked contents start.
const HEADER_LEN: usize = MAGIC.len() + 4;
/// Bytes a pose takes (7 x f32), and a body id with a pose.
const POSE_LEN: usize = 28;
const BODY_POSE_LEN: usize = 4 + POSE_LEN;

pub(super) fn decode(bytes: &[u8], file: &Path) -> Result<Trajectory, TrajectoryError> {
    let (version, contents) = check_envelope(bytes, file)?;
    let mut r = Reader { bytes: contents, at: HEADER_LEN, file };
    let scene_hash = r.u64("scene_hash")?;
    let at = r.at;
    let timestep = r.f32("timestep")?;
    if !(timestep.is_finite() && timestep > 0.0) {
        return Err(r.corrupt(at, "timestep", format!("must be positive and finite, got {timestep}")));
    }
    let scene = if version == 1 { None } else { read_scene(&mut r)? };
    let prototypes = read_prototypes(&mut r)?;
    let bodies = read_bodies(&mut r, prototypes.len())?;
    let frames = read_frames(&mut r, version, bodies.len())?;
    if r.at != contents.len() {
        let extra = contents.len() - r.at;
        return Err(r.corrupt(r.at, "frames", format!("{extra} unexpected bytes after the last frame")));
    }
    Ok(Trajectory { scene_hash, timestep, scene, prototypes, bodies, frames })
}

/// Checks the magic, the version and the trailing checksum; returns the version and the
/// bytes before the checksum.
fn check_envelope<'a>(bytes: &'a [u8], file: &Path) -> Result<(u32, &'a [u8]), TrajectoryError> {
    let corrupt = |offset: usize, field: &str, message: String| TrajectoryError::Corrupt {
        file: file.to_path_buf(),
        offset,
        field: field.to_string(),
        message,
    };
    if bytes.len() < MAGIC.len() || &bytes[..MAGIC.len()] != MAGIC {
        return Err(TrajectoryError::NotATrajectory { file: file.to_path_buf() });
    }
    let version = bytes
        .get(MAGIC.len()..HEADER_LEN)
        .map(|b| u32::from_le_bytes(b.try_into().expect("4 bytes")))
        .ok_or_else(|| {
            corrupt(MAGIC.len(), "version", format!("truncated: the file ends at byte {}", bytes.len()))
        })?;
    if !(1..=Trajectory::FORMAT_VERSION).contains(&version) {
        return Err(TrajectoryError::Version {
            file: file.to_path_buf(),
            found: version,
            expected: Trajectory::FORMAT_VERSION,
        });
    }
    if bytes.len() < HEADER_LEN + 8 {
        let message = format!("truncated: the file ends at byte {}", bytes.len());
        return Err(corrupt(HEADER_LEN, "checksum", message));
    }
    let (contents, tail) = bytes.split_at(bytes.len() - 8);
    let stored = u64::from_le_bytes(tail.try_into().expect("8 bytes"));
    if fnv1a64(contents) != stored {
        let message = "does not match the contents (truncated or damaged file)".to_string();
        return Err(corrupt(contents.len(), "checksum", message));
    }
    Ok((version, contents))
}

/// The `scene` section (version 2 on): the recorded scene file, if any.
fn read_scene(r: &mut Reader<'_>) -> Result<Option<RecordedScene>, TrajectoryError> {
    let at = r.at;
    match r.u8("scene")? {
        0 => return Ok(None),
        1 => {}
        flag => return Err(r.corrupt(at, "scene", format!("bad presence flag {flag}"))),
    }
    let path = r.text("scene.path")?;
    let asset_dir = r.text("scene.asset_dir")?;
    let source = r.text("scene.source")?;
    let mut option = |field: &str| -> Result<Option<u32>, TrajectoryError> {
        let at = r.at;
        let (present, value) = (r.u8(field)?, r.u32(field)?);
        match present {
            0 => Ok(None),
            1 => Ok(Some(value)),
            flag => Err(r.corrupt(at, field, format!("bad presence flag {flag}"))),
        }
    };
    let options = SimulateOptions { count: option("scene.count")?, frames: option("scene.frames")? };
    Ok(Some(RecordedScene { path: path.into(), asset_dir: asset_dir.into(), source, options }))
}

/// The `prototypes` section: prototype names.
fn read_prototypes(r: &mut Reader<'_>) -> Result<Vec<String>, TrajectoryError> {
    let n = r.count("prototypes", 4)?;
    let mut prototypes = Vec::with_capacity(n);
    for i in 0..n {
        prototypes.push(r.text(format_args!("prototypes[{i}]"))?);
    }
    Ok(prototypes)
}

/// The `bodies` section, checked against the number of prototypes.
fn read_bodies(r: &mut Reader<'_>, prototype_count: usize) -> Result<Vec<BodyInfo>, TrajectoryError> {
    let n = r.count("bodies", 9)?;
    let mut bodies = Vec::with_capacity(n);
    for i in 0..n {
        let at = r.at;
        let prototype = r.u32(format_args!("bodies[{i}].prototype"))?;
        if prototype as usize >= prototype_count {
            let message = format!("prototype {prototype} out of range ({prototype_count} prototypes)");
            return Err(r.corrupt(at, format_args!("bodies[{i}].prototype"), message));
        }
        let at = r.at;
        let kind = match r.u8(format_args!("bodies[{i}].kind"))? {
            0 => BodyKind::Dynamic,
            1 => BodyKind::Kinematic,
            k => return Err(r.corrupt(at, format_args!("bodies[{i}].kind"), format!("unknown kind {k}"))),
        };
        let spawn_frame = r.u32(format_args!("bodies[{i}].spawn_frame"))?;
        bodies.push(BodyInfo { prototype, kind, spawn_frame });
    }
    Ok(bodies)
}

/// The `frames` section, as changes whatever the version, with the island event invariants
/// checked across frames.
fn read_frames(
    r: &mut Reader<'_>,
    version: u32,
    body_count: usize,
) -> Result<Vec<TrajectoryFrame>, TrajectoryError> {
    // Version 3 frames are changes; older ones hold every body's state and are recorded as
    // changes while they are read.
    let mut recorder = (version < 3).then(|| FrameRecorder::new(body_count));
    let min_frame_len = if recorder.is_some() { body_count + 8 } else { 12 };
    let n = r.count("frames", min_frame_len)?;
    let mut frames = Vec::with_capacity(n);
    let mut checker = EventChecker::new(body_count);
    for frame in 0..n {
        let field = |list| FrameField { frame, list, item: None };
        let mut changes = match &mut recorder {
            None => TrajectoryFrame {
                state_changes: read_state_changes(r, field("states"), body_count)?,
                pose_changes: read_poses(r, field("poses"), body_count)?,
                events: Vec::new(),
            },
            Some(recorder) => read_full_frame(r, frame, body_count, recorder)?,
        };
        changes.events = read_events(r, field("events"), body_count, &mut checker)?;
        frames.push(changes);
    }
    Ok(frames)
}

/// A version-1 or -2 frame's states (a byte for every body) and poses, as changes (its
/// events still to be read).
fn read_full_frame(
    r: &mut Reader<'_>,
    frame: usize,
    body_count: usize,
    recorder: &mut FrameRecorder,
) -> Result<TrajectoryFrame, TrajectoryError> {
    let field = FrameField { frame, list: "states", item: None };
    let at = r.at;
    for (i, &byte) in r.take(body_count, field)?.iter().enumerate() {
        let state =
            state_from_byte(byte).ok_or_else(|| r.corrupt(at + i, field.item(i), unknown_state(byte)))?;
        recorder.state(BodyId(i as u32), state);
    }
    for (body, pose) in read_poses(r, FrameField { list: "poses", ..field }, body_count)? {
        recorder.pose(body, pose);
    }
    Ok(recorder.finish(Vec::new()))
}

/// A version-3 frame's state changes: `(body, state)` pairs.
fn read_state_changes(
    r: &mut Reader<'_>,
    field: FrameField,
    body_count: usize,
) -> Result<Vec<(BodyId, BodyState)>, TrajectoryError> {
    let n = r.count(field, 5)?;
    let mut changes = Vec::with_capacity(n);
    for k in 0..n {
        let body = r.body(field.item(k), body_count)?;
        let at = r.at;
        let byte = r.u8(field.item(k))?;
        let state = state_from_byte(byte).ok_or_else(|| r.corrupt(at, field.item(k), unknown_state(byte)))?;
        changes.push((body, state));
    }
    Ok(changes)
}

/// A frame's list of `(body, pose)` pairs.
fn read_poses(
    r: &mut Reader<'_>,
    field: FrameField,
    body_count: usize,
) -> Result<Vec<(BodyId, BodyPose)>, TrajectoryError> {
    let n = r.count(field, BODY_POSE_LEN)?;
    let mut poses = Vec::with_capacity(n);
    for k in 0..n {
        poses.push((r.body(field.item(k), body_count)?, r.pose(field.item(k))?));
    }
    Ok(poses)
}

/// A frame's island events, fed to `checker` as they are read.
fn read_events(
    r: &mut Reader<'_>,
    field: FrameField,
    body_count: usize,
    checker: &mut EventChecker,
) -> Result<Vec<IslandEvent>, TrajectoryError> {
    let n = r.count(field, 9)?;
    let mut events = Vec::with_capacity(n);
    for k in 0..n {
        let (at, field) = (r.at, field.item(k));
        let (tag, island) = (r.u8(field)?, IslandId(r.u64(field)?));
        let event = match tag {
            0 => {
                let m = r.count(field, BODY_POSE_LEN)?;
                let mut bodies = Vec::with_capacity(m);
                let mut poses = Vec::with_capacity(m);
                for _ in 0..m {
                    bodies.push(r.body(field, body_count)?);
                    poses.push(r.pose(field)?);
                }
                IslandEvent::Slept { island, bodies, poses }
            }
            1 => IslandEvent::Woke { island },
            t => return Err(r.corrupt(at, field, format!("unknown event tag {t}"))),
        };
        checker.apply(&event).map_err(|m| r.corrupt(at, field, m))?;
        events.push(event);
    }
    Ok(events)
}

fn state_from_byte(byte: u8) -> Option<BodyState> {
    match byte {
        0 => Some(BodyState::Absent),
        1 => Some(BodyState::Awake),
        2 => Some(BodyState::Asleep),
        _ => None,
    }
}

fn unknown_state(byte: u8) -> String {
    format!("unknown state {byte}")
}

/// Names a list of a frame, or an item of it, in errors (`frames[3].poses[7]`); formatted
/// only when an error needs it.
#[derive(Clone, Copy)]
struct FrameField {
    frame: usize,
    list: &'static str,
    item: Option<usize>,
}

impl FrameField {
    fn item(self, item: usize) -> Self {
        Self { item: Some(item), ..self }
    }
}

impl fmt::Display for FrameField {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "frames[{}].{}", self.frame, self.list)?;
        match self.item {
            Some(item) => write!(f, "[{item}]"),
            None => Ok(()),
        }
    }
}

/// Checks the event-stream invariants incrementally.
struct EventChecker {
    live: BTreeMap<IslandId, Vec<BodyId>>,
    island_of: Vec<Option<IslandId>>,
    last_id: Option<IslandId>,
}

impl EventChecker {
    fn new(bodies: usize) -> Self {
        Self { live: BTreeMap::new(), island_of: vec![None; bodies], last_id: None }
    }

    fn apply(&mut self, e: &IslandEvent) -> Result<(), String> {
        match e {
            IslandEvent::Slept { island, bodies, .. } => {
                if self.last_id.is_some_and(|last| *island <= last) {
                    return Err(format!("island {} reuses or reorders an id", island.0));
                }
                if bodies.is_empty() {
                    return Err(format!("island {} has no bodies", island.0));
                }
                self.last_id = Some(*island);
                for b in bodies {
                    if let Some(other) = self.island_of[b.0 as usize] {
                        return Err(format!("body {} is in islands {} and {}", b.0, other.0, island.0));
                    }
                    self.island_of[b.0 as usize] = Some(*island);
                }
                self.live.insert(*island, bodies.clone());
            }
            IslandEvent::Woke { island } => {
                let bodies = self
                    .live
                    .remove(island)
                    .ok_or_else(|| format!("island {} woke without having slept", island.0))?;
                for b in bodies {
                    self.island_of[b.0 as usize] = None;
                }
            }
        }
        Ok(())
    }
}

/// A cursor over a trajectory's bytes (offsets count from the file's start) whose reads fail
/// with an error naming the file, the field and the offset.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
    file: &'a Path,
}

impl<'a> Reader<'a> {
    fn corrupt(
        &self,
        offset: usize,
        field: impl fmt::Display,
        message: impl Into<String>,
    ) -> TrajectoryError {
        TrajectoryError::Corrupt {
            file: self.file.to_path_buf(),
            offset,
            field: field.to_string(),
            message: message.into(),
        }
    }

    fn left(&self) -> usize {
        self.bytes.len() - self.at
    }

    fn take(&mut self, n: usize, field: impl fmt::Display) -> Result<&'a [u8], TrajectoryError> {
        if n > self.left() {
            let message = format!("truncated: needs {n} bytes, {} left", self.left());
            return Err(self.corrupt(self.at, field, message));
        }
        let bytes = &self.bytes[self.at..self.at + n];
        self.at += n;
        Ok(bytes)
    }

    fn array<const N: usize>(&mut self, field: impl fmt::Display) -> Result<[u8; N], TrajectoryError> {
        Ok(self.take(N, field)?.try_into().expect("N bytes"))
    }

    fn u8(&mut self, field: impl fmt::Display) -> Result<u8, TrajectoryError> {
        Ok(self.take(1, field)?[0])
    }

    fn u32(&mut self, field: impl fmt::Display) -> Result<u32, TrajectoryError> {
        self.array(field).map(u32::from_le_bytes)
    }

    fn u64(&mut self, field: impl fmt::Display) -> Result<u64, TrajectoryError> {
        self.array(field).map(u64::from_le_bytes)
    }

    fn f32(&mut self, field: impl fmt::Display) -> Result<f32, TrajectoryError> {
        self.array(field).map(f32::from_le_bytes)
    }

    /// A count of items that take at least `min_item_bytes` each: rejected when the rest of
    /// the file cannot hold them, so a damaged count cannot trigger a huge allocation.
    fn count(
        &mut self,
        field: impl fmt::Display + Copy,
        min_item_bytes: usize,
    ) -> Result<usize, TrajectoryError> {
        let at = self.at;
        let n = self.u32(field)? as usize;
        let need = n as u128 * min_item_bytes as u128;
        if need > self.left() as u128 {
            let message = format!("count {n} needs at least {need} bytes, {} left", self.left());
            return Err(self.corrupt(at, field, message));
        }
        Ok(n)
    }

    /// A length-prefixed UTF-8 string.
    fn text(&mut self, field: impl fmt::Display + Copy) -> Result<String, TrajectoryError> {
        let len = self.count(field, 1)?;
        let at = self.at;
        let raw = self.take(len, field)?;
        String::from_utf8(raw.to_vec()).map_err(|_| self.corrupt(at, field, "not UTF-8"))
    }

    fn body(
        &mut self,
        field: impl fmt::Display + Copy,
        body_count: usize,
    ) -> Result<BodyId, TrajectoryError> {
        let at = self.at;
        let id = self.u32(field)?;
        if id as usize >= body_count {
            return Err(self.corrupt(at, field, format!("body {id} out of range ({body_count} bodies)")));
        }
        Ok(BodyId(id))
    }

    fn pose(&mut self, field: impl fmt::Display + Copy) -> Result<BodyPose, TrajectoryError> {
        let at = self.at;
        let raw: [u8; POSE_LEN] = self.array(field)?;
        let v: [f32; 7] =
            std::array::from_fn(|i| f32::from_le_bytes(raw[4 * i..4 * i + 4].try_into().expect("4 bytes")));
        if let Some(bad) = v.iter().position(|x| !x.is_finite()) {
            return Err(self.corrupt(at + 4 * bad, field, format!("non-finite pose component {}", v[bad])));
        }
        Ok(BodyPose {
            translation: Vec3::new(v[0], v[1], v[2]),
            rotation: Quat::from_xyzw(v[3], v[4], v[5], v[6]),
        })
    }
}
