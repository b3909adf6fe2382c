//! Trajectories: round trips, determinism across runs and thread counts, older format
//! versions (a version-2 file from the old writer, and version-1 and -2 bytes written here)
//! replaying to the same frames, and rejection of files from another scene, another format
//! version, or damaged, with errors that name the offset.

use crate::common;
use crate::trajectory_v2;

use std::path::Path;
use std::sync::OnceLock;

use common::encoding::fnv1a64;
use common::scenes;
use dormant::physics::trajectory::{Trajectory, TrajectoryError};
use dormant::physics::{simulate, BodyState, SimulateOptions};
use dormant::scene::file::SceneFile;
use proptest::prelude::*;

fn tiny() -> SceneFile {
    scenes::load("tiny")
}

fn short() -> SimulateOptions {
    SimulateOptions { count: None, frames: Some(240) }
}

#[test]
fn a_trajectory_round_trips_through_a_file() {
    let file = tiny();
    let options = short();
    let t = simulate(&file, &options).unwrap();
    assert_eq!(t.frames.len(), 240);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("tiny.traj");
    t.write_atomic(&path).unwrap();
    let hash = options.effective_scene(&file).unwrap().source_hash();
    let back = Trajectory::read(&path, hash).unwrap();
    assert_eq!(back, t);
    // No temporary file is left behind.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

#[test]
fn replay_fills_in_the_poses_of_sleeping_bodies() {
    let t = simulate(&tiny(), &short()).unwrap();
    let mut replay = t.replay();
    let mut last = None;
    while let Some(frame) = replay.next_frame() {
        for (i, s) in frame.states.iter().enumerate() {
            if *s != BodyState::Absent {
                assert!(frame.poses[i].translation.is_finite());
                assert!((frame.poses[i].rotation.length() - 1.0).abs() < 1e-3);
            }
        }
        last = Some(frame.index);
    }
    assert_eq!(last, Some(239));
}

#[test]
fn the_same_scene_gives_identical_bytes_across_runs_and_thread_counts() {
    let file = tiny();
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| simulate(&file, &short()).unwrap().to_bytes())
    };
    let one = run(1);
    assert_eq!(one, run(1));
    assert_eq!(one, run(2));
    assert_eq!(one, run(4));
}

#[test]
fn count_and_frame_overrides_change_the_scene_hash() {
    let file = tiny();
    let base = SimulateOptions::default().effective_scene(&file).unwrap().source_hash();
    let counted = SimulateOptions { count: Some(6), frames: None };
    let scene = counted.effective_scene(&file).unwrap();
    assert_ne!(scene.source_hash(), base);
    assert_eq!(scene.spec().spawners.iter().map(|s| s.count).sum::<u32>(), 6);
    assert_ne!(short().effective_scene(&file).unwrap().source_hash(), base);
    assert!(SimulateOptions { count: Some(0), frames: None }.effective_scene(&file).is_err());
}

#[test]
fn a_trajectory_from_another_scene_is_rejected() {
    let t = simulate(&tiny(), &short()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("t.traj");
    t.write_atomic(&path).unwrap();
    let err = Trajectory::read(&path, t.scene_hash ^ 1).unwrap_err();
    assert!(matches!(err, TrajectoryError::SceneMismatch { .. }), "{err}");
    assert!(err.to_string().contains("scene_hash"), "{err}");
    assert!(err.to_string().contains("t.traj"), "{err}");
}

#[test]
fn another_format_version_is_rejected() {
    let t = simulate(&tiny(), &short()).unwrap();
    let mut bytes = t.to_bytes();
    bytes[8..12].copy_from_slice(&99u32.to_le_bytes());
    let err = Trajectory::from_bytes(&bytes, Path::new("old.traj")).unwrap_err();
    assert!(matches!(err, TrajectoryError::Version { found: 99, .. }), "{err}");
    assert!(err.to_string().contains("old.traj"));
}

#[test]
fn damaged_or_foreign_files_are_errors_not_panics() {
    let t = simulate(&tiny(), &short()).unwrap();
    let bytes = t.to_bytes();
    let name = Path::new("x.traj");
    for cut in [0, 4, 12, 30, bytes.len() / 2, bytes.len() - 1] {
        assert!(Trajectory::from_bytes(&bytes[..cut], name).is_err(), "cut at {cut}");
    }
    let mut flipped = bytes.clone();
    let mid = flipped.len() / 2;
    flipped[mid] ^= 0x40;
    let err = Trajectory::from_bytes(&flipped, name).unwrap_err();
    assert!(matches!(err, TrajectoryError::Corrupt { .. }), "{err}");
    let err = Trajectory::from_bytes(b"{\"not\": \"a trajectory\"}", name).unwrap_err();
    assert!(matches!(err, TrajectoryError::NotATrajectory { .. }), "{err}");
    let err = Trajectory::read_unchecked(Path::new("/nonexistent/dir/x.traj")).unwrap_err();
    assert!(matches!(err, TrajectoryError::Io { .. }), "{err}");
}

#[test]
fn a_trajectory_records_the_scene_it_was_simulated_from() {
    let file = tiny();
    let options = SimulateOptions { count: Some(8), frames: Some(60) };
    let t = simulate(&file, &options).unwrap();
    let back = Trajectory::from_bytes(&t.to_bytes(), Path::new("t.traj")).unwrap();
    let recorded = back.scene.as_ref().expect("recorded scene");
    assert_eq!(recorded.options, options);
    assert!(recorded.asset_dir.is_absolute());
    let again = recorded.scene_file().unwrap();
    assert_eq!(again.spec(), file.spec());
    assert_eq!(options.effective_scene(&again).unwrap().source_hash(), t.scene_hash);
}

#[test]
fn version_1_files_still_read_without_a_recorded_scene() {
    let t = Trajectory { scene: None, ..simulate(&tiny(), &short()).unwrap() };
    let bytes = trajectory_v2::write(&t, 1);
    let back = Trajectory::from_bytes(&bytes, Path::new("v1.traj")).unwrap();
    assert_eq!(back, t);
    assert_eq!(replayed(&back), trajectory_v2::replay(&bytes));
}

/// Every frame of `t` as its replay gives it.
fn replayed(t: &Trajectory) -> Vec<trajectory_v2::Frame> {
    let mut replay = t.replay();
    let mut frames = Vec::new();
    while let Some(f) = replay.next_frame() {
        frames.push(trajectory_v2::Frame::of(f.states, f.poses, f.events.len()));
    }
    frames
}

/// `tests/data/tiny-v2.traj`: written by dormant before format version 3
/// (`dormant simulate scenes/tiny.toml --count 6 --frames 300`).
fn old_v2_file() -> &'static [u8] {
    static BYTES: OnceLock<Vec<u8>> = OnceLock::new();
    BYTES.get_or_init(|| std::fs::read(common::repo("tests/data/tiny-v2.traj")).unwrap())
}

#[test]
fn a_version_2_file_from_the_old_writer_replays_to_the_same_frames() {
    let bytes = old_v2_file();
    let t = Trajectory::from_bytes(bytes, Path::new("tiny-v2.traj")).unwrap();
    assert_eq!(t.frames.len(), 300);
    assert!(t.scene.is_some());
    let expected = trajectory_v2::replay(bytes);
    assert_eq!(replayed(&t), expected);
    // Nothing the file held is lost: written as version 2 again, it is the same bytes.
    assert_eq!(trajectory_v2::write(&t, 2), bytes);
    // As version 3 it is smaller, reads back equal and replays the same.
    let v3 = t.to_bytes();
    assert!(v3.len() < bytes.len(), "{} bytes, version 2 {}", v3.len(), bytes.len());
    let back = Trajectory::from_bytes(&v3, Path::new("tiny-v3.traj")).unwrap();
    assert_eq!(back, t);
    assert_eq!(replayed(&back), expected);
}

#[test]
fn version_2_bytes_read_as_the_simulation_recorded_them() {
    let t = simulate(&tiny(), &short()).unwrap();
    let v2 = trajectory_v2::write(&t, 2);
    assert_eq!(Trajectory::from_bytes(&v2, Path::new("v2.traj")).unwrap(), t);
    assert_eq!(replayed(&t), trajectory_v2::replay(&v2));
    assert!(t.to_bytes().len() < v2.len());
}

/// A version-3 file from `contents` (everything after the version), checksum appended.
fn v3_file(contents: &[u8]) -> Vec<u8> {
    let mut bytes = b"DORMTRAJ".to_vec();
    bytes.extend_from_slice(&3u32.to_le_bytes());
    bytes.extend_from_slice(contents);
    let checksum = fnv1a64(&bytes);
    bytes.extend_from_slice(&checksum.to_le_bytes());
    bytes
}

/// Header (scene hash, timestep 1/60, no recorded scene) and one prototype "box", then
/// `bodies` dynamic bodies and `rest`.
fn header_then(bodies: u32, rest: &[u8]) -> Vec<u8> {
    let mut c = 7u64.to_le_bytes().to_vec();
    c.extend_from_slice(&(1.0f32 / 60.0).to_le_bytes());
    c.push(0);
    c.extend_from_slice(&1u32.to_le_bytes());
    c.extend_from_slice(&3u32.to_le_bytes());
    c.extend_from_slice(b"box");
    c.extend_from_slice(&bodies.to_le_bytes());
    for _ in 0..bodies {
        c.extend_from_slice(&[0, 0, 0, 0, 0, 0, 0, 0, 0]);
    }
    c.extend_from_slice(rest);
    v3_file(&c)
}

fn u32s(values: &[u32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

fn corrupt(bytes: &[u8]) -> (String, usize, String) {
    match Trajectory::from_bytes(bytes, Path::new("c.traj")).unwrap_err() {
        TrajectoryError::Corrupt { field, offset, message, .. } => (field, offset, message),
        e => panic!("not Corrupt: {e}"),
    }
}

#[test]
fn huge_declared_counts_are_errors_before_anything_is_allocated() {
    // Offsets: magic 8, version 4, hash 8, timestep 4, scene flag 1 = 25; the prototype list
    // takes 4 + 4 + 3, so the body count is at 36 and, with no bodies, the frame count at 40.
    let (field, offset, message) = corrupt(&header_then(0, &u32s(&[u32::MAX])));
    assert_eq!((field.as_str(), offset), ("frames", 40), "{message}");
    assert!(message.contains("count 4294967295"), "{message}");
    let (field, offset, _) = corrupt(&header_then(0, &u32s(&[1, 0, u32::MAX, 0])));
    assert_eq!((field.as_str(), offset), ("frames[0].poses", 48));
    let (field, offset, _) = corrupt(&header_then(0, &u32s(&[1, u32::MAX, 0, 0])));
    assert_eq!((field.as_str(), offset), ("frames[0].states", 44));
    let mut bodies = 7u64.to_le_bytes().to_vec();
    bodies.extend_from_slice(&1.0f32.to_le_bytes());
    bodies.push(0);
    bodies.extend_from_slice(&u32s(&[u32::MAX]));
    let (field, offset, _) = corrupt(&v3_file(&bodies));
    assert_eq!((field.as_str(), offset), ("prototypes", 25));
}

#[test]
fn errors_name_the_file_the_field_and_the_byte_offset() {
    // One body; frame 0: body 0 awake, then a pose for body 5 (out of range).
    let mut frame = u32s(&[1, 1, 0]);
    frame.push(1);
    frame.extend_from_slice(&u32s(&[1, 5]));
    frame.extend_from_slice(&[0; 28]);
    frame.extend_from_slice(&u32s(&[0]));
    let bytes = header_then(1, &frame);
    let err = Trajectory::from_bytes(&bytes, Path::new("c.traj")).unwrap_err();
    assert_eq!(
        err.to_string(),
        "c.traj: frames[0].poses[0] at byte 66: body 5 out of range (1 bodies)",
        "bodies from 40, 9 bytes each; frame count at 49, states at 53, poses at 62"
    );
    // The same pose for body 0, with a NaN y.
    frame[17..21].copy_from_slice(&0u32.to_le_bytes());
    frame[25..29].copy_from_slice(&f32::NAN.to_le_bytes());
    let (field, offset, message) = corrupt(&header_then(1, &frame));
    assert_eq!((field.as_str(), offset), ("frames[0].poses[0]", 74), "{message}");
    assert!(message.contains("non-finite"), "{message}");
    // A state byte that is no state.
    frame[12] = 7;
    let (field, offset, message) = corrupt(&header_then(1, &frame));
    assert_eq!((field.as_str(), offset, message.as_str()), ("frames[0].states[0]", 61, "unknown state 7"));
}

/// The old writer's file and its version-3 encoding.
fn valid_files() -> [&'static [u8]; 2] {
    static V3: OnceLock<Vec<u8>> = OnceLock::new();
    let v3 = V3.get_or_init(|| Trajectory::from_bytes(old_v2_file(), Path::new("v2")).unwrap().to_bytes());
    [old_v2_file(), v3]
}

/// Reads damaged bytes: a trajectory that replays (a flipped bit may leave a valid file) or
/// an error that names the file and a byte offset. A panic fails the property.
fn read_damaged(bytes: &[u8]) -> Result<(), TestCaseError> {
    match Trajectory::from_bytes(bytes, Path::new("fuzz.traj")) {
        Ok(t) => {
            replayed(&t);
            Ok(())
        }
        Err(e) => {
            let text = e.to_string();
            prop_assert!(text.starts_with("fuzz.traj: "), "{text}");
            let offset = text.split(" at byte ").nth(1).and_then(|rest| rest.split(':').next());
            prop_assert!(offset.is_some_and(|o| o.parse::<usize>().is_ok()), "{text}");
            Ok(())
        }
    }
}

/// `bytes` with the checksum recomputed over everything before it, so the damage reaches
/// the section readers instead of stopping at the checksum.
fn with_checksum(mut bytes: Vec<u8>) -> Vec<u8> {
    if bytes.len() >= 8 {
        bytes.truncate(bytes.len() - 8);
    }
    let checksum = fnv1a64(&bytes);
    bytes.extend_from_slice(&checksum.to_le_bytes());
    bytes
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn truncated_files_give_errors_naming_an_offset(which in 0usize..2, cut in 0.0f64..1.0, rechecksum: bool) {
        let bytes = valid_files()[which];
        let cut = &bytes[..(cut * bytes.len() as f64) as usize];
        let damaged = if rechecksum { with_checksum(cut.to_vec()) } else { cut.to_vec() };
        prop_assert!(Trajectory::from_bytes(&damaged, Path::new("fuzz.traj")).is_err());
        read_damaged(&damaged)?;
    }

    #[test]
    fn flipped_bytes_give_errors_naming_an_offset(
        which in 0usize..2,
        flips in proptest::collection::vec((0.0f64..1.0, 1u8..=255), 1..4),
        rechecksum: bool,
    ) {
        let mut damaged = valid_files()[which].to_vec();
        for (at, mask) in flips {
            let at = (at * damaged.len() as f64) as usize;
            damaged[at] ^= mask;
        }
        let damaged = if rechecksum { with_checksum(damaged) } else { damaged };
        read_damaged(&damaged)?;
    }
}
