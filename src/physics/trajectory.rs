//! Trajectories: a simulation's per-frame body states, poses and island events, in a
//! versioned binary file that carries the scene's hash. Rendering can replay one instead of
//! simulating.
//!
//! Format (little endian), version 2:
//! ```text
//! magic "DORMTRAJ" | version u32 | scene_hash u64 | timestep f32
//! scene:      u8 recorded [0, 1]; if 1: path, asset_dir, source (each u32 len, utf-8),
//!             count and frames overrides (each u8 present, u32 value)
//! prototypes: u32 n, then n x (u32 len, utf-8 name)
//! bodies:     u32 n, then n x (prototype u32, kind u8 [0 dynamic, 1 kinematic], spawn_frame u32)
//! frames:     u32 n, then per frame:
//!   states  body_count x u8 [0 absent, 1 awake, 2 asleep]
//!   poses   u32 n, n x (body u32, translation 3 x f32, rotation xyzw 4 x f32)
//!   events  u32 n, n x (tag u8 [0 slept, 1 woke], island u64,
//!                       slept only: u32 m, m x (body u32, translation, rotation))
//! checksum u64: FNV-1a 64 of every byte before it
//! ```
//! Version 1 is version 2 without the `scene` section; it still reads, with no recorded scene.
//! A frame stores the poses of bodies awake at its end and of bodies that fell asleep
//! during it; a sleeping body keeps its last stored pose.

use std::path::{Path, PathBuf};

use glam::{Quat, Vec3};

use super::body::{BodyId, BodyInfo, BodyKind, BodyPose, BodyState};
use super::island::{IslandEvent, IslandId};
use super::options::SimulateOptions;
use crate::scene::file::{fnv1a64, SceneError, SceneFile};

const MAGIC: &[u8; 8] = b"DORMTRAJ";

/// A trajectory file that cannot be written, read or trusted.
#[derive(Debug, thiserror::Error)]
pub enum TrajectoryError {
    #[error("{}: {source}", .file.display())]
    Io {
        file: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{}: not a dormant trajectory (bad magic)", .file.display())]
    NotATrajectory { file: PathBuf },
    #[error("{}: version: trajectory format version {found}, this build reads versions 1 to {expected}", .file.display())]
    Version { file: PathBuf, found: u32, expected: u32 },
    #[error("{}: scene_hash: trajectory was made from another scene (hash {found:016x}, expected {expected:016x})", .file.display())]
    SceneMismatch { file: PathBuf, found: u64, expected: u64 },
    #[error("{}: {field}: {message}", .file.display())]
    Corrupt { file: PathBuf, field: String, message: String },
}

/// The scene file a trajectory was simulated from, recorded in it so that the trajectory alone
/// can be rendered (`dormant render --trajectory FILE`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RecordedScene {
    /// Where the scene file was (names it in messages).
    pub path: PathBuf,
    /// The absolute directory its relative asset paths resolved against.
    pub asset_dir: PathBuf,
    /// The scene file's text.
    pub source: String,
    /// The overrides it was simulated with.
    pub options: SimulateOptions,
}

impl RecordedScene {
    /// Records `file` (as read, before `options` apply).
    pub fn new(file: &SceneFile, options: &SimulateOptions) -> Self {
        let absolute = |p: PathBuf| std::path::absolute(&p).unwrap_or(p);
        Self {
            path: file.path.clone(),
            asset_dir: absolute(file.asset_dir()),
            source: file.source().to_string(),
            options: options.clone(),
        }
    }

    /// The scene file again, its assets resolved where they were when it was simulated.
    pub fn scene_file(&self) -> Result<SceneFile, SceneError> {
        SceneFile::parse_with_assets(&self.path, self.source.as_str(), Some(&self.asset_dir))
    }
}

/// One simulated frame as a trajectory records it: every body's state at the frame's end,
/// the poses that must be stored (bodies awake at the end of the frame, and bodies that fell
/// asleep during it; a sleeping body keeps its last pose), and the island events.
#[derive(Clone, Debug, PartialEq)]
pub struct TrajectoryFrame {
    pub states: Vec<BodyState>,
    pub poses: Vec<(BodyId, BodyPose)>,
    pub events: Vec<IslandEvent>,
}

/// A recorded simulation.
#[derive(Clone, Debug, PartialEq)]
pub struct Trajectory {
    /// Hash of the scene (and overrides) that produced it.
    pub scene_hash: u64,
    /// Simulated seconds per frame.
    pub timestep: f32,
    /// The scene it was simulated from; `None` in version-1 files.
    pub scene: Option<RecordedScene>,
    /// Prototype names, indexed by [`BodyInfo::prototype`].
    pub prototypes: Vec<String>,
    pub bodies: Vec<BodyInfo>,
    pub frames: Vec<TrajectoryFrame>,
}

impl Trajectory {
    pub const FORMAT_VERSION: u32 = 2;

    /// Encodes the trajectory; identical trajectories give identical bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut w = Vec::new();
        w.extend_from_slice(MAGIC);
        put_u32(&mut w, Self::FORMAT_VERSION);
        w.extend_from_slice(&self.scene_hash.to_le_bytes());
        put_f32(&mut w, self.timestep);
        match &self.scene {
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
        put_u32(&mut w, self.prototypes.len() as u32);
        for name in &self.prototypes {
            put_u32(&mut w, name.len() as u32);
            w.extend_from_slice(name.as_bytes());
        }
        put_u32(&mut w, self.bodies.len() as u32);
        for b in &self.bodies {
            put_u32(&mut w, b.prototype);
            w.push(match b.kind {
                BodyKind::Dynamic => 0,
                BodyKind::Kinematic => 1,
            });
            put_u32(&mut w, b.spawn_frame);
        }
        put_u32(&mut w, self.frames.len() as u32);
        for f in &self.frames {
            debug_assert_eq!(f.states.len(), self.bodies.len());
            w.extend(f.states.iter().map(|s| *s as u8));
            put_u32(&mut w, f.poses.len() as u32);
            for (id, pose) in &f.poses {
                put_u32(&mut w, id.0);
                put_pose(&mut w, pose);
            }
            put_u32(&mut w, f.events.len() as u32);
            for e in &f.events {
                match e {
                    IslandEvent::Slept { island, bodies, poses } => {
                        w.push(0);
                        w.extend_from_slice(&island.0.to_le_bytes());
                        put_u32(&mut w, bodies.len() as u32);
                        for (b, p) in bodies.iter().zip(poses) {
                            put_u32(&mut w, b.0);
                            put_pose(&mut w, p);
                        }
                    }
                    IslandEvent::Woke { island } => {
                        w.push(1);
                        w.extend_from_slice(&island.0.to_le_bytes());
                    }
                }
            }
        }
        let checksum = fnv1a64(&w);
        w.extend_from_slice(&checksum.to_le_bytes());
        w
    }

    /// Decodes and checks a trajectory: format, checksum, ranges, and the island event
    /// invariants (no `Woke` without an earlier `Slept`, each body in at most one sleeping
    /// island). `file` names the source in errors.
    pub fn from_bytes(bytes: &[u8], file: &Path) -> Result<Self, TrajectoryError> {
        let (version, contents) = check_envelope(bytes, file)?;
        let mut r = Reader { bytes: contents, at: MAGIC.len() + 4, file };
        let scene_hash = r.u64("scene_hash")?;
        let timestep = r.f32("timestep")?;
        if !(timestep.is_finite() && timestep > 0.0) {
            return Err(r.corrupt("timestep", format!("must be positive and finite, got {timestep}")));
        }
        let scene = if version == 1 { None } else { read_scene(&mut r)? };
        let prototypes = read_prototypes(&mut r)?;
        let bodies = read_bodies(&mut r, prototypes.len())?;
        let frames = read_frames(&mut r, bodies.len())?;
        if r.at != contents.len() {
            let extra = contents.len() - r.at;
            return Err(r.corrupt("frames", format!("{extra} unexpected bytes after the last frame")));
        }
        Ok(Self { scene_hash, timestep, scene, prototypes, bodies, frames })
    }

    /// Writes the trajectory atomically: a temporary file in the same directory, then a
    /// rename, so readers never see a half-written file.
    pub fn write_atomic(&self, path: &Path) -> Result<(), TrajectoryError> {
        crate::atomic_file::write_atomic(path, &self.to_bytes())
            .map_err(|source| TrajectoryError::Io { file: path.to_path_buf(), source })
    }

    /// Reads a trajectory and checks that it was made from the scene with
    /// `expected_scene_hash` (see [`super::SimulateOptions::effective_scene`]).
    pub fn read(path: &Path, expected_scene_hash: u64) -> Result<Self, TrajectoryError> {
        let t = Self::read_unchecked(path)?;
        if t.scene_hash != expected_scene_hash {
            return Err(TrajectoryError::SceneMismatch {
                file: path.to_path_buf(),
                found: t.scene_hash,
                expected: expected_scene_hash,
            });
        }
        Ok(t)
    }

    /// Reads a trajectory without checking which scene made it.
    pub fn read_unchecked(path: &Path) -> Result<Self, TrajectoryError> {
        let bytes =
            std::fs::read(path).map_err(|source| TrajectoryError::Io { file: path.to_path_buf(), source })?;
        Self::from_bytes(&bytes, path)
    }

    /// Walks the frames with every body's current pose filled in.
    pub fn replay(&self) -> Replay<'_> {
        Replay {
            trajectory: self,
            next: 0,
            poses: vec![BodyPose { translation: Vec3::ZERO, rotation: Quat::IDENTITY }; self.bodies.len()],
        }
    }
}

/// A cursor over a trajectory's frames that keeps every body's latest pose.
pub struct Replay<'a> {
    trajectory: &'a Trajectory,
    next: usize,
    poses: Vec<BodyPose>,
}

/// One replayed frame. `poses[i]` is body `i`'s pose (meaningless while it is absent).
pub struct ReplayFrame<'a> {
    pub index: u32,
    pub states: &'a [BodyState],
    pub poses: &'a [BodyPose],
    pub events: &'a [IslandEvent],
}

impl ReplayFrame<'_> {
    /// Whether body `b` is in the world this frame: spawned, not removed, at a finite pose.
    /// The one place that decides which bodies a frame shows.
    pub fn is_present(&self, b: usize) -> bool {
        self.states[b] != BodyState::Absent && self.poses[b].translation.is_finite()
    }

    /// The bodies present this frame, ascending.
    pub fn present_bodies(&self) -> impl Iterator<Item = BodyId> + '_ {
        (0..self.states.len()).filter(|&b| self.is_present(b)).map(|b| BodyId(b as u32))
    }
}

impl Replay<'_> {
    pub fn next_frame(&mut self) -> Option<ReplayFrame<'_>> {
        let frame = self.trajectory.frames.get(self.next)?;
        for (id, pose) in &frame.poses {
            self.poses[id.0 as usize] = *pose;
        }
        self.next += 1;
        Some(ReplayFrame {
            index: (self.next - 1) as u32,
            states: &frame.states,
            poses: &self.poses,
            events: &frame.events,
        })
    }
}

/// Checks the magic, the version and the trailing checksum; returns the version and the
/// bytes before the checksum.
fn check_envelope<'a>(bytes: &'a [u8], file: &Path) -> Result<(u32, &'a [u8]), TrajectoryError> {
    let corrupt = |field: &str, message: &str| TrajectoryError::Corrupt {
        file: file.to_path_buf(),
        field: field.to_string(),
        message: message.to_string(),
    };
    if bytes.len() < MAGIC.len() || &bytes[..MAGIC.len()] != MAGIC {
        return Err(TrajectoryError::NotATrajectory { file: file.to_path_buf() });
    }
    let version = bytes
        .get(MAGIC.len()..MAGIC.len() + 4)
        .map(|b| u32::from_le_bytes(b.try_into().expect("4 bytes")))
        .ok_or_else(|| corrupt("version", "truncated"))?;
    if version != Trajectory::FORMAT_VERSION && version != 1 {
        return Err(TrajectoryError::Version {
            file: file.to_path_buf(),
            found: version,
            expected: Trajectory::FORMAT_VERSION,
        });
    }
    if bytes.len() < MAGIC.len() + 12 + 8 {
        return Err(corrupt("checksum", "truncated"));
    }
    let (contents, tail) = bytes.split_at(bytes.len() - 8);
    let stored = u64::from_le_bytes(tail.try_into().expect("8 bytes"));
    if fnv1a64(contents) != stored {
        return Err(corrupt("checksum", "does not match the contents (truncated or damaged file)"));
    }
    Ok((version, contents))
}

/// The `scene` section (version 2 on): the recorded scene file, if any.
fn read_scene(r: &mut Reader<'_>) -> Result<Option<RecordedScene>, TrajectoryError> {
    match r.u8("scene")? {
        0 => return Ok(None),
        1 => {}
        _ => return Err(r.corrupt("scene", "bad presence flag")),
    }
    let path = r.text("scene.path")?;
    let asset_dir = r.text("scene.asset_dir")?;
    let source = r.text("scene.source")?;
    let mut option = |field: &str| -> Result<Option<u32>, TrajectoryError> {
        let (present, value) = (r.u8(field)?, r.u32(field)?);
        match present {
            0 => Ok(None),
            1 => Ok(Some(value)),
            _ => Err(r.corrupt(field, "bad presence flag")),
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
        let len = r.count("prototypes", 1)?;
        let raw = r.take(len, "prototypes")?;
        let name = String::from_utf8(raw.to_vec())
            .map_err(|_| r.corrupt(&format!("prototypes[{i}]"), "not UTF-8"))?;
        prototypes.push(name);
    }
    Ok(prototypes)
}

/// The `bodies` section, checked against the number of prototypes.
fn read_bodies(r: &mut Reader<'_>, prototype_count: usize) -> Result<Vec<BodyInfo>, TrajectoryError> {
    let n = r.count("bodies", 9)?;
    let mut bodies = Vec::with_capacity(n);
    for i in 0..n {
        let (prototype, kind, spawn_frame) = (r.u32("bodies")?, r.u8("bodies")?, r.u32("bodies")?);
        if prototype as usize >= prototype_count {
            return Err(r.corrupt(&format!("bodies[{i}].prototype"), format!("{prototype} out of range")));
        }
        let kind = match kind {
            0 => BodyKind::Dynamic,
            1 => BodyKind::Kinematic,
            k => return Err(r.corrupt(&format!("bodies[{i}].kind"), format!("unknown kind {k}"))),
        };
        bodies.push(BodyInfo { prototype, kind, spawn_frame });
    }
    Ok(bodies)
}

/// The `frames` section: every frame's states, poses and events, with the event invariants
/// checked across frames.
fn read_frames(r: &mut Reader<'_>, body_count: usize) -> Result<Vec<TrajectoryFrame>, TrajectoryError> {
    let n = r.count("frames", body_count + 8)?;
    let mut frames = Vec::with_capacity(n);
    let mut checker = EventChecker::new(body_count);
    for fi in 0..n {
        let at = |f: &str| format!("frames[{fi}].{f}");
        let states = r
            .take(body_count, &at("states"))?
            .iter()
            .map(|&s| match s {
                0 => Ok(BodyState::Absent),
                1 => Ok(BodyState::Awake),
                2 => Ok(BodyState::Asleep),
                s => Err(s),
            })
            .collect::<Result<Vec<_>, _>>()
            .map_err(|s| r.corrupt(&at("states"), format!("unknown state {s}")))?;
        let np = r.count(&at("poses"), 32)?;
        let mut poses = Vec::with_capacity(np);
        for _ in 0..np {
            poses.push((r.body(&at("poses"), body_count)?, r.pose(&at("poses"))?));
        }
        let events = read_events(r, &at("events"), body_count, &mut checker)?;
        frames.push(TrajectoryFrame { states, poses, events });
    }
    Ok(frames)
}

/// One frame's island events, fed to `checker` as they are read.
fn read_events(
    r: &mut Reader<'_>,
    field: &str,
    body_count: usize,
    checker: &mut EventChecker,
) -> Result<Vec<IslandEvent>, TrajectoryError> {
    let n = r.count(field, 9)?;
    let mut events = Vec::with_capacity(n);
    for _ in 0..n {
        let (tag, island) = (r.u8(field)?, IslandId(r.u64(field)?));
        let event = match tag {
            0 => {
                let m = r.count(field, 32)?;
                let mut bodies = Vec::with_capacity(m);
                let mut poses = Vec::with_capacity(m);
                for _ in 0..m {
                    bodies.push(r.body(field, body_count)?);
                    poses.push(r.pose(field)?);
                }
                IslandEvent::Slept { island, bodies, poses }
            }
            1 => IslandEvent::Woke { island },
            t => return Err(r.corrupt(field, format!("unknown event tag {t}"))),
        };
        checker.apply(&event).map_err(|m| r.corrupt(field, m))?;
        events.push(event);
    }
    Ok(events)
}

/// Checks the event-stream invariants incrementally.
struct EventChecker {
    live: std::collections::BTreeMap<IslandId, Vec<BodyId>>,
    island_of: Vec<Option<IslandId>>,
    last_id: Option<IslandId>,
}

impl EventChecker {
    fn new(bodies: usize) -> Self {
        Self { live: Default::default(), island_of: vec![None; bodies], last_id: None }
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

/// A cursor over a trajectory's bytes whose reads fail with an error naming the file and
/// the field being read.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
    file: &'a Path,
}

impl<'a> Reader<'a> {
    fn corrupt(&self, field: &str, message: impl Into<String>) -> TrajectoryError {
        TrajectoryError::Corrupt {
            file: self.file.to_path_buf(),
            field: field.to_string(),
            message: message.into(),
        }
    }
    fn take(&mut self, n: usize, field: &str) -> Result<&'a [u8], TrajectoryError> {
        let bytes = self.bytes;
        let s = self.at.checked_add(n).and_then(|end| bytes.get(self.at..end));
        let s = s.ok_or_else(|| self.corrupt(field, "truncated"))?;
        self.at += n;
        Ok(s)
    }
    fn array<const N: usize>(&mut self, field: &str) -> Result<[u8; N], TrajectoryError> {
        Ok(self.take(N, field)?.try_into().expect("N bytes"))
    }
    fn u8(&mut self, field: &str) -> Result<u8, TrajectoryError> {
        Ok(self.take(1, field)?[0])
    }
    fn u32(&mut self, field: &str) -> Result<u32, TrajectoryError> {
        self.array(field).map(u32::from_le_bytes)
    }
    fn u64(&mut self, field: &str) -> Result<u64, TrajectoryError> {
        self.array(field).map(u64::from_le_bytes)
    }
    fn f32(&mut self, field: &str) -> Result<f32, TrajectoryError> {
        self.array(field).map(f32::from_le_bytes)
    }
    /// A count whose items take at least `min_item_bytes` each: rejects counts the rest of
    /// the file cannot hold (so a damaged count cannot trigger a huge allocation).
    fn count(&mut self, field: &str, min_item_bytes: usize) -> Result<usize, TrajectoryError> {
        let n = self.u32(field)? as usize;
        let fits =
            n.checked_mul(min_item_bytes.max(1)).is_some_and(|need| need <= self.bytes.len() - self.at);
        if fits {
            Ok(n)
        } else {
            Err(self.corrupt(field, "truncated"))
        }
    }
    /// A length-prefixed UTF-8 string.
    fn text(&mut self, field: &str) -> Result<String, TrajectoryError> {
        let len = self.count(field, 1)?;
        let raw = self.take(len, field)?;
        String::from_utf8(raw.to_vec()).map_err(|_| self.corrupt(field, "not UTF-8"))
    }
    fn body(&mut self, field: &str, body_count: usize) -> Result<BodyId, TrajectoryError> {
        let id = self.u32(field).map_err(|_| self.corrupt(field, "truncated or body out of range"))?;
        if (id as usize) < body_count {
            Ok(BodyId(id))
        } else {
            Err(self.corrupt(field, "truncated or body out of range"))
        }
    }
    fn pose(&mut self, field: &str) -> Result<BodyPose, TrajectoryError> {
        let mut v = [0f32; 7];
        for x in &mut v {
            *x = self.f32(field).map_err(|_| self.corrupt(field, "truncated or non-finite pose"))?;
        }
        if !v.iter().all(|x| x.is_finite()) {
            return Err(self.corrupt(field, "truncated or non-finite pose"));
        }
        Ok(BodyPose {
            translation: Vec3::new(v[0], v[1], v[2]),
            rotation: Quat::from_xyzw(v[3], v[4], v[5], v[6]),
        })
    }
}
