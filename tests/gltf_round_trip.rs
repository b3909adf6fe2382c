//! A dormant simulation exported as animated glTF (`export --gltf`) and read back as the
//! scene (`render FILE.glb`) is the same sequence: every body present on the same frames at
//! the same pose, bit for bit, and the same images (issue 40's round trip).

use crate::common;

use std::path::Path;

use common::cli::{dormant, simulate_tiny, succeeds};
use dormant::physics::trajectory::Trajectory;
use dormant::physics::{simulate, BodyState, IslandEvent, SimulateOptions};
use dormant::scene::file::SceneFile;

/// Every frame's presence and pose of every body, poses as bits.
fn frames_of(t: &Trajectory) -> Vec<Vec<Option<[u32; 7]>>> {
    let mut out = Vec::new();
    let mut replay = t.replay();
    while let Some(frame) = replay.next_frame() {
        let bodies = (0..frame.states.len()).map(|b| {
            (frame.states[b] != BodyState::Absent).then(|| {
                let (p, q) = (frame.poses[b].translation, frame.poses[b].rotation);
                [p.x, p.y, p.z, q.x, q.y, q.z, q.w].map(f32::to_bits)
            })
        });
        out.push(bodies.collect());
    }
    out
}

/// Every frame's island events with ids numbered in the order islands first appear (the
/// recorded ids need not be the same, only which events they tie together).
fn events_of(t: &Trajectory) -> Vec<Vec<(bool, usize, Vec<u32>)>> {
    let mut order = std::collections::HashMap::new();
    let mut number = |id| {
        let next = order.len();
        *order.entry(id).or_insert(next)
    };
    let event = |e: &IslandEvent, number: &mut dyn FnMut(u64) -> usize| match e {
        IslandEvent::Slept { island, bodies, .. } => {
            (true, number(island.0), bodies.iter().map(|b| b.0).collect())
        }
        IslandEvent::Woke { island } => (false, number(island.0), Vec::new()),
    };
    t.frames.iter().map(|f| f.events.iter().map(|e| event(e, &mut number)).collect()).collect()
}

fn export_tiny(dir: &Path) -> (Trajectory, std::path::PathBuf) {
    let traj = simulate_tiny(dir, &[]);
    let glb = dir.join("tiny.glb");
    succeeds(dormant().args(["--quiet", "export", "--trajectory"]).arg(&traj).arg("--gltf").arg(&glb));
    (Trajectory::read_unchecked(&traj).unwrap(), glb)
}

#[test]
fn an_exported_simulation_read_back_from_its_gltf_places_every_body_bit_for_bit_with_its_islands() {
    let dir = tempfile::TempDir::new().unwrap();
    let (original, glb) = export_tiny(dir.path());
    let file = SceneFile::load(&glb).unwrap();
    let read_back = simulate(&file, &SimulateOptions::default()).unwrap();
    assert_eq!(read_back.timestep.to_bits(), original.timestep.to_bits());
    assert_eq!(read_back.bodies.len(), original.bodies.len());
    let (a, b) = (frames_of(&original), frames_of(&read_back));
    assert_eq!(a.len(), b.len());
    for (f, (a, b)) in a.iter().zip(&b).enumerate() {
        assert_eq!(a, b, "frame {f}");
    }
    // The file carries the simulation's islands and kinds: the same rests, bodies and events.
    assert_eq!(read_back.bodies, original.bodies);
    assert_eq!(events_of(&read_back), events_of(&original));
}

/// The backends this build can render with.
fn backends() -> Vec<&'static str> {
    let mut backends = vec!["bvh"];
    if cfg!(feature = "embree") {
        backends.push("embree");
    }
    backends
}

/// The same images, and the same bits in every pass a render writes as EXR (radiance and the
/// shading normal, whose last bits the 8-bit PNGs hide), on both backends.
#[test]
fn an_exported_simulation_renders_the_same_bits_from_its_gltf_on_both_backends() {
    let dir = tempfile::TempDir::new().unwrap();
    let (_, glb) = export_tiny(dir.path());
    let render = |source: &[&std::ffi::OsStr], backend: &str, out: &Path| {
        let args = [
            "--frames",
            "200..480",
            "--frame-step",
            "70",
            "--size",
            "96x54",
            "--spp",
            "2",
            "--integration",
            "always",
            "--exr",
            "--aov",
            "albedo,normal,depth",
            "--backend",
            backend,
        ];
        succeeds(dormant().args(["--quiet", "render"]).args(source).args(args).arg("--out").arg(out));
    };
    let traj = dir.path().join("tiny.traj");
    for backend in backends() {
        let (a, b) = (dir.path().join(format!("{backend}-a")), dir.path().join(format!("{backend}-b")));
        render(&["--trajectory".as_ref(), traj.as_os_str()], backend, &a);
        render(&[glb.as_os_str()], backend, &b);
        for frame in [210, 280, 350, 420] {
            for pass in ["png", "exr", "albedo.exr", "normal.exr", "depth.exr"] {
                let name = format!("frame_{frame:04}.{pass}");
                let same = std::fs::read(a.join(&name)).unwrap() == std::fs::read(b.join(&name)).unwrap();
                assert!(same, "{backend}: {name} differs between the trajectory and its glTF");
            }
        }
    }
}

fn with_json(glb: &[u8], edit: impl FnOnce(&mut serde_json::Value)) -> Vec<u8> {
    let length = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    let mut json: serde_json::Value = serde_json::from_slice(&glb[20..20 + length]).unwrap();
    edit(&mut json);
    let mut text = serde_json::to_vec(&json).unwrap();
    text.resize(text.len().next_multiple_of(4), b' ');
    let rest = &glb[20 + length..];
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend(((20 + text.len() + rest.len()) as u32).to_le_bytes());
    out.extend((text.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(text);
    out.extend(rest);
    out
}

#[test]
fn recorded_islands_that_cannot_be_are_an_input_error() {
    let dir = tempfile::TempDir::new().unwrap();
    let (_, glb) = export_tiny(dir.path());
    let bytes = std::fs::read(&glb).unwrap();
    let broken = dir.path().join("broken.glb");
    for (island, expected) in [
        (serde_json::json!([0, null, [99999]]), "bodies must be distinct ids below 21"),
        (serde_json::json!([5, 3, [1]]), "frames 5..3 are not within"),
    ] {
        let edited = with_json(&bytes, |j| {
            j["asset"]["extras"]["dormant"]["simulation"]["islands"].as_array_mut().unwrap().push(island)
        });
        std::fs::write(&broken, edited).unwrap();
        let stderr = common::cli::exits_with(
            dormant().args(["--quiet", "simulate"]).arg(&broken).arg("--out").arg(dir.path().join("t.traj")),
            2,
        );
        assert!(
            stderr.contains("broken.glb") && stderr.contains("simulation") && stderr.contains(expected),
            "{stderr}"
        );
    }
}
