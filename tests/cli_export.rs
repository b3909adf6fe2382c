//! `dormant export`: a trajectory's frames as JSON for another renderer
//! (scripts/compare-cycles.py): every selected frame, a pose per body id, the mesh sources.

use crate::common;

use common::cli::{dormant, read_json, succeeds};

/// `args` run from the repository root; panics unless they succeed.
fn run(args: &[&std::ffi::OsStr]) {
    succeeds(dormant().args(args).current_dir(env!("CARGO_MANIFEST_DIR")));
}

#[test]
fn export_writes_a_pose_per_body_for_every_selected_frame() {
    let dir = tempfile::TempDir::new().unwrap();
    let (traj, json) = (dir.path().join("tiny.traj"), dir.path().join("tiny.json"));
    run(&[
        "simulate".as_ref(),
        "scenes/tiny.toml".as_ref(),
        "--quiet".as_ref(),
        "--out".as_ref(),
        traj.as_ref(),
    ]);
    run(&[
        "export".as_ref(),
        "--trajectory".as_ref(),
        traj.as_ref(),
        "--frames".as_ref(),
        "30..40".as_ref(),
        "--quiet".as_ref(),
        "--out".as_ref(),
        json.as_ref(),
    ]);
    let e = read_json(&json);
    assert_eq!(e["format"], "dormant-export-1");
    assert_eq!(e["environment"]["builtin"], "ground");
    assert_eq!(e["prototypes"][0]["builtin"], "box");
    // tiny's prototypes are primitives without files: the colour dormant gives them is exported.
    assert!(e["prototypes"][0]["material"]["base_color"].is_array());
    let bodies = e["body_prototypes"].as_array().unwrap().len();
    let frames = e["frames"].as_array().unwrap();
    assert_eq!(
        frames.iter().map(|f| f["index"].as_u64().unwrap()).collect::<Vec<_>>(),
        (30..40).collect::<Vec<_>>()
    );
    let mut moved = false;
    for (f, next) in frames.iter().zip(frames.iter().skip(1)) {
        let poses = f["poses"].as_array().unwrap();
        assert_eq!(poses.len(), bodies);
        assert!(f["camera"]["vfov_deg"].as_f64().unwrap() > 0.0);
        for (p, q) in poses.iter().zip(next["poses"].as_array().unwrap()) {
            let Some(p) = p.as_array() else { continue };
            let v: Vec<f64> = p.iter().map(|x| x.as_f64().unwrap()).collect();
            let norm = v[3..].iter().map(|x| x * x).sum::<f64>().sqrt();
            assert!((norm - 1.0).abs() < 1e-3, "unit rotation quaternion, got {v:?}");
            moved |= q.as_array().is_some_and(|q| q[1] != p[1]);
        }
    }
    assert!(moved, "tiny's bodies fall in frames 30..40");
}
