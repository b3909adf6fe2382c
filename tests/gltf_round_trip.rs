//! A dormant simulation exported as animated glTF (`export --gltf`) and read back as the
//! scene (`render FILE.glb`) is the same sequence: every body present on the same frames at
//! the same pose, bit for bit, and the same images (issue 40's round trip).

mod common;

use std::path::Path;

use common::cli::{dormant, simulate_tiny, succeeds};
use dormant::physics::trajectory::Trajectory;
use dormant::physics::{simulate, BodyState, SimulateOptions};
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

fn export_tiny(dir: &Path) -> (Trajectory, std::path::PathBuf) {
    let traj = simulate_tiny(dir, &[]);
    let glb = dir.join("tiny.glb");
    succeeds(dormant().args(["--quiet", "export", "--trajectory"]).arg(&traj).arg("--gltf").arg(&glb));
    (Trajectory::read_unchecked(&traj).unwrap(), glb)
}

#[test]
fn an_exported_simulation_read_back_from_its_gltf_places_every_body_bit_for_bit() {
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
}

#[test]
fn an_exported_simulation_renders_the_same_images_from_its_gltf() {
    let dir = tempfile::TempDir::new().unwrap();
    let (_, glb) = export_tiny(dir.path());
    let render = |source: &[&std::ffi::OsStr], out: &Path| {
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
        ];
        succeeds(dormant().args(["--quiet", "render"]).args(source).args(args).arg("--out").arg(out));
    };
    let traj = dir.path().join("tiny.traj");
    render(&["--trajectory".as_ref(), traj.as_os_str()], &dir.path().join("a"));
    render(&[glb.as_os_str()], &dir.path().join("b"));
    for frame in [210, 280, 350, 420] {
        let name = format!("frame_{frame:04}.png");
        let (a, b) = (dir.path().join("a").join(&name), dir.path().join("b").join(&name));
        assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap(), "{name}");
    }
}
