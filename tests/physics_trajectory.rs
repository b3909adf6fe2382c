//! Trajectories: round trips, determinism across runs and thread counts, and rejection of
//! files from another scene, another format version, or damaged.

use std::path::Path;

use dormant::physics::{simulate, BodyState, SimulateOptions, Trajectory, TrajectoryError};

use dormant::scene::file::SceneFile;

fn tiny() -> SceneFile {
    SceneFile::load(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/tiny.toml")).unwrap()
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

/// FNV-1a 64, the trajectory checksum.
fn fnv1a64(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3))
}

#[test]
fn version_1_files_still_read_without_a_recorded_scene() {
    let t = Trajectory { scene: None, ..simulate(&tiny(), &short()).unwrap() };
    let mut bytes = t.to_bytes();
    // Version 1 is version 2 without the scene section (one 0 byte after the timestep).
    bytes.truncate(bytes.len() - 8);
    bytes[8..12].copy_from_slice(&1u32.to_le_bytes());
    assert_eq!(bytes.remove(24), 0);
    let checksum = fnv1a64(&bytes);
    bytes.extend_from_slice(&checksum.to_le_bytes());
    let back = Trajectory::from_bytes(&bytes, Path::new("v1.traj")).unwrap();
    assert_eq!(back, t);
}
