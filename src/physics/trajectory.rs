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
use super::simulate::SimulateOptions;
use super::simulation::FrameRecord;
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
            path: file.path().to_path_buf(),
            asset_dir: absolute(file.asset_dir().to_path_buf()),
            source: file.source().to_string(),
            options: options.clone(),
        }
    }

    /// The scene file again, its assets resolved where they were when it was simulated.
    pub fn scene_file(&self) -> Result<SceneFile, SceneError> {
        SceneFile::parse_with_assets(&self.path, self.source.as_str(), Some(&self.asset_dir))
    }
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
    pub frames: Vec<FrameRecord>,
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
        let corrupt = |field: &str, message: String| TrajectoryError::Corrupt {
            file: file.to_path_buf(),
            field: field.to_string(),
            message,
        };
        if bytes.len() < MAGIC.len() || &bytes[..MAGIC.len()] != MAGIC {
            return Err(TrajectoryError::NotATrajectory { file: file.to_path_buf() });
        }
        let mut r = Reader { bytes, at: MAGIC.len() };
        let version = r.u32().ok_or_else(|| corrupt("version", "truncated".into()))?;
        if version != Self::FORMAT_VERSION && version != 1 {
            return Err(TrajectoryError::Version {
                file: file.to_path_buf(),
                found: version,
                expected: Self::FORMAT_VERSION,
            });
        }
        if bytes.len() < MAGIC.len() + 12 + 8 {
            return Err(corrupt("checksum", "truncated".into()));
        }
        let (body_bytes, tail) = bytes.split_at(bytes.len() - 8);
        let stored = u64::from_le_bytes(tail.try_into().expect("8 bytes"));
        if fnv1a64(body_bytes) != stored {
            return Err(corrupt(
                "checksum",
                "does not match the contents (truncated or damaged file)".into(),
            ));
        }
        let mut r = Reader { bytes: body_bytes, at: r.at };
        let truncated = |field: &str| corrupt(field, "truncated".into());
        let scene_hash = r.u64().ok_or_else(|| truncated("scene_hash"))?;
        let timestep = r.f32().ok_or_else(|| truncated("timestep"))?;
        if !(timestep.is_finite() && timestep > 0.0) {
            return Err(corrupt("timestep", format!("must be positive and finite, got {timestep}")));
        }
        let scene = match version {
            1 => None,
            _ => match r.u8() {
                Some(0) => None,
                Some(1) => {
                    let mut text = |field: &str| -> Result<String, TrajectoryError> {
                        let len = r.count(1).ok_or_else(|| truncated(field))?;
                        let raw = r.take(len).ok_or_else(|| truncated(field))?;
                        String::from_utf8(raw.to_vec()).map_err(|_| corrupt(field, "not UTF-8".into()))
                    };
                    let (path, asset_dir, source) =
                        (text("scene.path")?, text("scene.asset_dir")?, text("scene.source")?);
                    let mut option = |field: &str| match (r.u8(), r.u32()) {
                        (Some(0), Some(_)) => Ok(None),
                        (Some(1), Some(v)) => Ok(Some(v)),
                        (Some(_), Some(_)) => Err(corrupt(field, "bad presence flag".into())),
                        _ => Err(truncated(field)),
                    };
                    let options =
                        SimulateOptions { count: option("scene.count")?, frames: option("scene.frames")? };
                    Some(RecordedScene { path: path.into(), asset_dir: asset_dir.into(), source, options })
                }
                Some(_) => return Err(corrupt("scene", "bad presence flag".into())),
                None => return Err(truncated("scene")),
            },
        };
        let n = r.count(4).ok_or_else(|| truncated("prototypes"))?;
        let mut prototypes = Vec::with_capacity(n);
        for i in 0..n {
            let len = r.count(1).ok_or_else(|| truncated("prototypes"))?;
            let raw = r.take(len).ok_or_else(|| truncated("prototypes"))?;
            prototypes.push(
                String::from_utf8(raw.to_vec())
                    .map_err(|_| corrupt(&format!("prototypes[{i}]"), "not UTF-8".into()))?,
            );
        }
        let n = r.count(9).ok_or_else(|| truncated("bodies"))?;
        let mut bodies = Vec::with_capacity(n);
        for i in 0..n {
            let (prototype, kind, spawn_frame) = (r.u32(), r.u8(), r.u32());
            let (Some(prototype), Some(kind), Some(spawn_frame)) = (prototype, kind, spawn_frame) else {
                return Err(truncated("bodies"));
            };
            if prototype as usize >= prototypes.len() {
                return Err(corrupt(&format!("bodies[{i}].prototype"), format!("{prototype} out of range")));
            }
            let kind = match kind {
                0 => BodyKind::Dynamic,
                1 => BodyKind::Kinematic,
                k => return Err(corrupt(&format!("bodies[{i}].kind"), format!("unknown kind {k}"))),
            };
            bodies.push(BodyInfo { prototype, kind, spawn_frame });
        }
        let body_count = bodies.len();
        let n = r.count(body_count + 8).ok_or_else(|| truncated("frames"))?;
        let mut frames = Vec::with_capacity(n);
        let mut checker = EventChecker::new(body_count);
        for fi in 0..n {
            let at = |f: &str| format!("frames[{fi}].{f}");
            let raw = r.take(body_count).ok_or_else(|| truncated(&at("states")))?;
            let states = raw
                .iter()
                .map(|&s| match s {
                    0 => Ok(BodyState::Absent),
                    1 => Ok(BodyState::Awake),
                    2 => Ok(BodyState::Asleep),
                    s => Err(corrupt(&at("states"), format!("unknown state {s}"))),
                })
                .collect::<Result<Vec<_>, _>>()?;
            let np = r.count(32).ok_or_else(|| truncated(&at("poses")))?;
            let mut poses = Vec::with_capacity(np);
            for _ in 0..np {
                let id = r
                    .body(body_count)
                    .ok_or_else(|| corrupt(&at("poses"), "truncated or body out of range".into()))?;
                let pose =
                    r.pose().ok_or_else(|| corrupt(&at("poses"), "truncated or non-finite pose".into()))?;
                poses.push((id, pose));
            }
            let ne = r.count(9).ok_or_else(|| truncated(&at("events")))?;
            let mut events = Vec::with_capacity(ne);
            for _ in 0..ne {
                let (tag, island) = (r.u8(), r.u64());
                let (Some(tag), Some(island)) = (tag, island) else {
                    return Err(truncated(&at("events")));
                };
                let island = IslandId(island);
                let event = match tag {
                    0 => {
                        let m = r.count(32).ok_or_else(|| truncated(&at("events")))?;
                        let mut ids = Vec::with_capacity(m);
                        let mut ps = Vec::with_capacity(m);
                        for _ in 0..m {
                            let id = r.body(body_count).ok_or_else(|| {
                                corrupt(&at("events"), "truncated or body out of range".into())
                            })?;
                            let pose = r.pose().ok_or_else(|| {
                                corrupt(&at("events"), "truncated or non-finite pose".into())
                            })?;
                            ids.push(id);
                            ps.push(pose);
                        }
                        IslandEvent::Slept { island, bodies: ids, poses: ps }
                    }
                    1 => IslandEvent::Woke { island },
                    t => return Err(corrupt(&at("events"), format!("unknown event tag {t}"))),
                };
                checker.apply(&event).map_err(|m| corrupt(&at("events"), m))?;
                events.push(event);
            }
            frames.push(FrameRecord { states, poses, events });
        }
        if r.at != body_bytes.len() {
            return Err(corrupt(
                "frames",
                format!("{} unexpected bytes after the last frame", body_bytes.len() - r.at),
            ));
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

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take(&mut self, n: usize) -> Option<&[u8]> {
        let end = self.at.checked_add(n)?;
        let s = self.bytes.get(self.at..end)?;
        self.at = end;
        Some(s)
    }
    fn u8(&mut self) -> Option<u8> {
        self.take(1).map(|b| b[0])
    }
    fn u32(&mut self) -> Option<u32> {
        self.take(4).map(|b| u32::from_le_bytes(b.try_into().expect("4 bytes")))
    }
    fn u64(&mut self) -> Option<u64> {
        self.take(8).map(|b| u64::from_le_bytes(b.try_into().expect("8 bytes")))
    }
    fn f32(&mut self) -> Option<f32> {
        self.take(4).map(|b| f32::from_le_bytes(b.try_into().expect("4 bytes")))
    }
    /// A count whose items take at least `min_item_bytes` each: rejects counts the rest of
    /// the file cannot hold (so a damaged count cannot trigger a huge allocation).
    fn count(&mut self, min_item_bytes: usize) -> Option<usize> {
        let n = self.u32()? as usize;
        (n.checked_mul(min_item_bytes.max(1))? <= self.bytes.len() - self.at).then_some(n)
    }
    fn body(&mut self, body_count: usize) -> Option<BodyId> {
        let id = self.u32()?;
        ((id as usize) < body_count).then_some(BodyId(id))
    }
    fn pose(&mut self) -> Option<BodyPose> {
        let mut v = [0f32; 7];
        for x in &mut v {
            *x = self.f32()?;
        }
        v.iter().all(|x| x.is_finite()).then(|| BodyPose {
            translation: Vec3::new(v[0], v[1], v[2]),
            rotation: Quat::from_xyzw(v[3], v[4], v[5], v[6]),
        })
    }
}
