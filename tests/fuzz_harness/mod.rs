//! What each fuzz target does with its input, shared by the cargo-fuzz targets (`fuzz/`,
//! which include this file by path) and the regression tests (`tests/fuzz_regressions.rs`,
//! which replay the inputs the fuzzer found). Each function returns `Ok` when the input was
//! accepted and `Err(message)` when it was rejected cleanly; a panic, a hang or an unbounded
//! allocation is the bug the fuzzer looks for. Inputs are taken from memory: nothing is read
//! from disk but what an input names itself (and a scene's relative assets resolve into a
//! directory that does not exist).

// Each user (a fuzz target, the tests) calls only some of these.
#![allow(dead_code)]

use std::path::Path;

use dormant::physics::trajectory::Trajectory;
use dormant::render::ImageSize;
use dormant::scene::file::SceneFile;
use dormant::scene::gltf::{inspect_animated_slice, load_gltf_slice};
use dormant::scene::SceneAssets;
use dormant::sequence::stats::{RunInfo, StatsFile};
use dormant::sequence::FrameRange;

// Base64 and the trajectory checksum, shared with the tests' helpers; by path, so that the
// fuzz targets, which include this file by path, find it too (in the test suite the file is
// thus loaded twice, here and as `common::encoding`).
#[allow(clippy::duplicate_mod)]
#[path = "../common/encoding.rs"]
mod encoding;

pub use encoding::base64;

/// Where fuzzed scene files pretend to live: relative asset paths resolve under it, and it
/// does not exist.
pub const SCENE_PATH: &str = "/nonexistent/dormant-fuzz/scene.toml";

/// A scene file's text as `dormant render SCENE` takes it before simulating: parsed and
/// validated, its environment and prototypes loaded, and the scene (without bodies)
/// described at its first and last frame.
pub fn scene_toml(data: &[u8]) -> Result<(), String> {
    let text = std::str::from_utf8(data).map_err(|e| format!("not UTF-8: {e}"))?;
    let file = SceneFile::parse(SCENE_PATH, text).map_err(|e| e.to_string())?;
    let assets = SceneAssets::load(&file).map_err(|e| e.to_string())?;
    let scene = &file.spec().scene;
    let end = scene.frames as f32 * file.spec().physics.timestep;
    for time in [0.0, end] {
        assets.describe(time);
    }
    Ok(())
}

/// The bytes of a `.glb` (or any glTF) imported from memory with materials and textures,
/// then read as an animation (an `[animation]` scene's file) and sampled at 16 frames.
pub fn gltf_glb(data: &[u8]) -> Result<(), String> {
    let name = Path::new("fuzz.glb");
    let mesh = load_gltf_slice(data, name).map(|_| ()).map_err(|e| e.to_string());
    let animation = inspect_animated_slice(data, name, 24.0, 16).map(|_| ()).map_err(|e| e.to_string());
    mesh.and(animation)
}

/// Where [`gltf_json`] puts its binary buffer: every occurrence in the JSON is replaced by a
/// `data:` URI holding the bytes after the first NUL.
pub const BIN_PLACEHOLDER: &str = "@BIN@";

/// A `.gltf` JSON document with one binary buffer: the bytes before the first NUL are the
/// JSON, the bytes after it the buffer, which the JSON references as
/// `"uri": "@BIN@"` ([`BIN_PLACEHOLDER`], replaced by a base64 `data:` URI). Imported, then
/// read as an animation and sampled, as [`gltf_glb`] does.
pub fn gltf_json(data: &[u8]) -> Result<(), String> {
    let (json, bin) = match data.iter().position(|&b| b == 0) {
        Some(i) => (&data[..i], &data[i + 1..]),
        None => (data, &[][..]),
    };
    let uri = format!("data:application/octet-stream;base64,{}", base64(bin));
    let text = String::from_utf8_lossy(json).replace(BIN_PLACEHOLDER, &uri);
    let name = Path::new("fuzz.gltf");
    let mesh = load_gltf_slice(text.as_bytes(), name).map(|_| ()).map_err(|e| e.to_string());
    let animation =
        inspect_animated_slice(text.as_bytes(), name, 24.0, 16).map(|_| ()).map_err(|e| e.to_string());
    mesh.and(animation)
}

/// A trajectory file's bytes, read as they are and then with their trailing checksum made
/// right (so that mutations reach past it), as `dormant render --trajectory` reads them: the
/// frames replayed, island statistics taken, the recorded scene parsed and its hash checked.
/// A trajectory that reads must write back to bytes that read to the same trajectory.
pub fn trajectory(data: &[u8]) -> Result<(), String> {
    let name = Path::new("fuzz.traj");
    let _ = Trajectory::from_bytes(data, name);
    let t = Trajectory::from_bytes(&with_checksum(data), name).map_err(|e| e.to_string())?;
    let mut replay = t.replay();
    while let Some(frame) = replay.next_frame() {
        frame.present_bodies().count();
    }
    t.states_at_end();
    t.island_stats();
    let again = Trajectory::from_bytes(&t.to_bytes(), name).expect("a written trajectory reads back");
    assert_eq!(again, t, "a trajectory reads back as it was written");
    let recorded = t.scene.as_ref().ok_or("no recorded scene")?;
    let file = recorded.scene_file().map_err(|e| e.to_string())?;
    let effective = recorded.options.effective_scene(&file).map_err(|e| e.to_string())?;
    if effective.source_hash() != t.scene_hash {
        return Err("the recorded scene's hash differs".into());
    }
    Ok(())
}

/// `data` with its last 8 bytes replaced by the FNV-1a 64 checksum of the bytes before them
/// (unchanged when shorter than a trajectory's header and checksum).
pub fn with_checksum(data: &[u8]) -> Vec<u8> {
    let mut bytes = data.to_vec();
    if bytes.len() >= 20 {
        let end = bytes.len() - 8;
        let hash = encoding::fnv1a64(&bytes[..end]);
        bytes[end..].copy_from_slice(&hash.to_le_bytes());
    }
    bytes
}

/// A command-line value as `--frames A..B` and `--size WxH` parse it; what parses must hold
/// what the parsers promise and print back to itself.
pub fn cli_values(data: &[u8]) -> Result<(), String> {
    let text = std::str::from_utf8(data).map_err(|e| format!("not UTF-8: {e}"))?;
    let frames = text.parse::<FrameRange>();
    if let Ok(r) = frames {
        assert!(r.start < r.end, "{text:?} parsed to an empty range {r:?}");
        assert_eq!(format!("{}..{}", r.start, r.end).parse::<FrameRange>(), Ok(r));
    }
    let size = text.parse::<ImageSize>();
    if let Ok(s) = size {
        assert!((1..=16384).contains(&s.width) && (1..=16384).contains(&s.height), "{text:?}: {s:?}");
        assert_eq!(format!("{}x{}", s.width, s.height).parse::<ImageSize>(), Ok(s));
    }
    match (frames, size) {
        (Err(a), Err(b)) => Err(format!("{a}; {b}")),
        _ => Ok(()),
    }
}

/// Where fuzzed statistics pretend to be read from (the path errors name).
pub const STATS_PATH: &str = "/nonexistent/dormant-fuzz/stats.json";

/// The run header that [`stats_json`] also checks every input against: a real run's
/// (`tests/data/stats-tiny.json`, the stats.json of a 4-frame render of `scenes/tiny.toml`).
const REAL_RUN_STATS: &str = include_str!("../data/stats-tiny.json");

/// A stats.json as `render --resume` reads it, checked against the run header it holds itself
/// (so that mutations reach the frame records) and against a real run's (so that the fields
/// that differ are named). Records that read must write back to JSON that reads to the same.
pub fn stats_json(data: &[u8]) -> Result<(), String> {
    let path = Path::new(STATS_PATH);
    let header = |bytes: &[u8]| -> Option<RunInfo> {
        let value: serde_json::Value = serde_json::from_slice(bytes).ok()?;
        serde_json::from_value(value.get("run")?.clone()).ok()
    };
    let real = header(REAL_RUN_STATS.as_bytes()).expect("the real run's header reads");
    let against_real = StatsFile::kept_records(path, data, &real).map_err(|e| e.to_string());
    let Some(own) = header(data) else {
        return against_real.map(|_| ());
    };
    let records = StatsFile::kept_records(path, data, &own).map_err(|e| e.to_string())?;
    let written = serde_json::to_vec(&records).expect("frame records write");
    let again: Vec<dormant::sequence::stats::FrameRecord> =
        serde_json::from_slice(&written).expect("written frame records read back");
    assert_eq!(again, records, "frame records read back as they were written");
    Ok(())
}
