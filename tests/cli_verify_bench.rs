//! `dormant verify`, `dormant bench accel` and `dormant bench render` end to end, on the built-in scene and (when
//! ../shared/assets exists) on the monastery with ducks.
#![cfg(feature = "embree")]

use crate::common;

use common::cli::{dormant, exits_with, read_json, succeeds};
use common::scenes;

#[test]
fn verify_default_scene_has_no_mismatches() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("verify.json");
    succeeds(
        dormant()
            .args([
                "verify",
                "--size",
                "160x90",
                "--surface-rays",
                "20000",
                "--shadow-rays",
                "5000",
                "--json",
            ])
            .arg(&json),
    );
    let report = read_json(&json);
    for key in [
        "rays",
        "mismatches",
        "ties",
        "closest",
        "occlusion",
        "bound",
        "max_t_err_over_bound",
        "max_t_rel_err",
    ] {
        assert!(report.get(key).is_some(), "missing {key}");
    }
    assert_eq!(report["rays"], 160 * 90 + 20000 + 5000);
    assert_eq!(report["mismatches"], 0);
    for query in ["closest", "occlusion"] {
        let counts = &report[query];
        let total: u64 = ["agree", "tie", "mismatch"].iter().map(|k| counts[k].as_u64().unwrap()).sum();
        assert_eq!(total, 160 * 90 + 20000 + 5000, "{query}: {counts}");
    }
    // Every hit either backend reported lies within the derived bound of its f64 `t`.
    assert!(report["max_t_err_over_bound"].as_f64().unwrap() <= 1.0);
    assert!(report["max_t_rel_err"].as_f64().unwrap() <= 1e-4);
}

/// `dormant verify` on `scenes/NAME.toml` with `args`: its JSON report, after checking that
/// it succeeded.
fn verify_scene_file(name: &str, args: &[&str]) -> serde_json::Value {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("verify.json");
    let scene = scenes::shipped(name);
    let status = dormant().arg("verify").args(args).arg("--json").arg(&json).arg(&scene).status().unwrap();
    let report = read_json(&json);
    assert!(status.success(), "{report:#}");
    report
}

#[test]
fn verify_simulated_frames_of_a_scene_file_has_no_mismatches() {
    let report =
        verify_scene_file("tiny", &["--size", "96x54", "--surface-rays", "20000", "--check-frames", "3"]);
    assert_eq!(report["frames"].as_array().unwrap().len(), 3);
    assert_eq!(report["mismatches"], 0);
}

#[test]
fn verify_monastery_with_ducks_has_no_mismatches() {
    let Some(assets) = common::shared_assets() else { return };
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("verify.json");
    let status = dormant()
        .args(["verify", "--count", "300", "--size", "160x90", "--surface-rays", "20000", "--env"])
        .arg(assets.join("monastery.glb"))
        .arg("--object")
        .arg(assets.join("duck.glb"))
        .arg("--json")
        .arg(&json)
        .status()
        .unwrap();
    let report = read_json(&json);
    assert!(status.success(), "{report:#}");
    assert_eq!(report["mismatches"], 0);
}

/// The teddy bear (scanned, near-coincident triangles), ducks and soccer balls piled 40 units
/// from the origin: f32 instance transforms and ray origins far out (docs/crosscheck.md).
#[test]
fn verify_assets_far_from_the_origin_has_no_mismatches() {
    if common::shared_assets().is_none() {
        return;
    }
    let report = verify_scene_file(
        "far-assets",
        &["--size", "160x90", "--surface-rays", "20000", "--check-frames", "2"],
    );
    assert_eq!(report["mismatches"], 0);
    assert!(report["max_t_err_over_bound"].as_f64().unwrap() <= 1.0);
}

#[test]
fn bench_accel_reports_its_ratios() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("accel.json");
    succeeds(dormant().args(["bench", "accel", "--size", "64x36", "--runs", "1", "--json"]).arg(&json));
    let report = read_json(&json);
    // The SIMD path that ran (DORMANT_SIMD, else the fastest this CPU runs).
    assert!(["portable", "avx2", "avx512"].contains(&report["simd_path"].as_str().unwrap()), "{report:#}");
    for key in [
        "bvh_over_embree_trace",
        "bvh_over_embree_build",
        // Against Embree in robust mode: the BVH's own guarantees (docs/performance.md).
        "bvh_over_embree_robust_trace",
        "bvh_over_embree_robust_build",
        "bvh_rebuild_over_insert",
        "bvh_insert_sah_over_rebuild",
        "bvh_resting_trace_over_instanced",
        "bvh_baked_trace_over_instanced",
    ] {
        assert!(
            report["ratios"][key].as_f64().is_some_and(f64::is_finite),
            "ratio {key}: {:#}",
            report["ratios"]
        );
    }
    // The forms section: one per compiled backend, the last island awake, the rest resting.
    let forms = report["forms"].as_array().unwrap();
    assert_eq!(forms.len(), if cfg!(feature = "embree") { 2 } else { 1 });
    for f in forms {
        let (resting, awake) =
            (f["resting_instances"].as_u64().unwrap(), f["awake_instances"].as_u64().unwrap());
        assert!(resting > 0 && awake > 0 && resting > awake, "{f:#}");
        assert!(f["resting_rebuild_ms"].as_f64().is_some_and(|ms| ms > 0.0), "{f:#}");
    }
}

#[test]
fn bench_integration_reports_the_five_ratios_and_every_configuration() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("integration.json");
    succeeds(
        dormant()
            .args(["--quiet", "bench", "integration"])
            .arg(scenes::shipped("tiny"))
            .args(["--backend", "bvh", "--size", "16x9", "--frames", "0..120", "--frame-step", "6", "--json"])
            .arg(&json),
    );
    let report = read_json(&json);
    for key in ["run_speedup", "auto_over_best", "rebuild_over_insert", "partial_hit_90_99_fraction"] {
        assert!(report["ratios"][key].as_f64().is_some_and(f64::is_finite), "{key}: {:#}", report["ratios"]);
    }
    // No frame of tiny's first two seconds has 90% of its bodies asleep: no settled ratio.
    assert!(report["ratios_by_form"]["baked"]["rebuild_over_insert"].as_f64().is_some_and(f64::is_finite));
    assert_eq!(report["settled_frames"], 0);
    assert!(report["ratios"]["settled_speedup"].is_null(), "{:#}", report["ratios"]);
    let runs = report["runs"].as_array().unwrap();
    let configs: Vec<&str> = runs.iter().map(|r| r["name"].as_str().unwrap()).collect();
    // never; always and auto in each form (the default first); auto without lookahead.
    assert_eq!(
        configs,
        ["never", "always resting", "auto resting", "always baked", "auto baked", "auto resting, online"],
    );
    assert!(runs.iter().all(|r| r["frame_ms"].as_array().unwrap().len() == 20));
}

#[test]
fn bench_regimes_reports_reuse_integration_and_both_per_cell() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("regimes");
    succeeds(
        dormant()
            .args(["--quiet", "bench", "regimes"])
            .arg(scenes::shipped("demolition"))
            .args(["--quick", "--budgets", "preview320", "--backend", "bvh", "--out"])
            .arg(&out),
    );
    let report = read_json(&out.join("regimes.json"));
    let cells = report["cells"].as_array().unwrap();
    assert_eq!(cells.len(), 2, "two body counts, one budget, one backend");
    for cell in cells {
        let reuse = &cell["reuse"];
        for key in ["reuse_speedup", "integration_speedup", "both_speedup", "bound"] {
            assert!(reuse[key].as_f64().is_some_and(|v| v.is_finite() && v > 0.0), "{key}: {reuse:#}");
        }
        assert_eq!(reuse["identical"], true, "reuse changed an image: {reuse:#}");
    }
    let table = std::fs::read_to_string(out.join("regimes.md")).unwrap();
    assert!(table.contains("| reuse | integration | both | traced share (bound) |"), "{table}");
    assert!(out.join("regimes-reuse.png").is_file());
}

#[test]
fn bench_render_reports_both_backends_and_ratios_per_ray_type() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("render.json");
    succeeds(
        dormant()
            .args(["bench", "render", "--size", "48x27", "--spp", "1", "--runs", "1", "--json"])
            .arg(&json),
    );
    let report = read_json(&json);
    let backends = report["backends"].as_array().unwrap();
    let names: Vec<&str> = backends.iter().map(|b| b["backend"].as_str().unwrap()).collect();
    assert_eq!(names, ["embree", "bvh"]);
    for b in backends {
        assert_eq!(b["camera"]["rays"], 48 * 27);
        for kind in ["camera", "shadow", "bounce"] {
            assert!(b[kind]["rays"].as_u64().unwrap() > 0, "{kind}: {b:#}");
            assert!(b[kind]["mrays_per_s"].as_f64().is_some_and(|r| r.is_finite() && r > 0.0), "{b:#}");
        }
        assert!(b["frame"]["samples_per_s"].as_f64().is_some_and(|s| s.is_finite() && s > 0.0));
        assert!(b["frame"]["rays"].as_u64().unwrap() >= 48 * 27);
    }
    // Both backends traced the same ray sets.
    for kind in ["shadow", "bounce"] {
        assert_eq!(backends[0][kind]["rays"], backends[1][kind]["rays"]);
    }
    for key in [
        "bvh_over_embree_camera",
        "bvh_over_embree_shadow",
        "bvh_over_embree_bounce",
        "bvh_over_embree_frame_samples",
        "embree_frame_packets_over_single",
        "bvh_frame_packets_over_single",
    ] {
        assert!(report["ratios"][key].as_f64().is_some_and(f64::is_finite), "ratio {key}");
    }
}

#[test]
fn bench_render_embree_robust_is_recorded_with_the_same_camera_rays() {
    let dir = tempfile::tempdir().unwrap();
    let run = |robust: bool| {
        let json = dir.path().join(format!("render-{robust}.json"));
        let mut cmd = dormant();
        cmd.args(["bench", "render", "--size", "32x18", "--spp", "1", "--runs", "1", "--json"]).arg(&json);
        if robust {
            cmd.arg("--embree-robust");
        }
        succeeds(&mut cmd);
        read_json(&json)
    };
    let (plain, robust) = (run(false), run(true));
    assert_eq!(plain["embree_robust"], false);
    assert_eq!(robust["embree_robust"], true);
    // The same camera rays (the shadow and bounce sets come from Embree's camera hits, which
    // robust mode may move at edges).
    assert_eq!(plain["backends"][0]["camera"]["rays"], robust["backends"][0]["camera"]["rays"]);
    assert!(robust["ratios"]["bvh_over_embree_camera"].as_f64().is_some_and(f64::is_finite));
}

#[test]
fn missing_asset_is_an_input_error() {
    let stderr = exits_with(
        dormant().args(["verify", "--env", "/nonexistent/env.glb", "--object", "/nonexistent/duck.glb"]),
        2,
    );
    assert!(stderr.contains("/nonexistent/env.glb"), "{stderr}");
}

#[test]
fn bench_runs_of_zero_are_a_usage_error_naming_the_flag() {
    for bench in ["accel", "render"] {
        let stderr = exits_with(dormant().args(["bench", bench, "--runs", "0"]), 2);
        assert!(stderr.contains("--runs"), "{bench}: {stderr}");
    }
}

#[test]
fn bench_integration_takes_the_old_range_spelling_and_names_the_flag_in_errors() {
    let scene = scenes::shipped("tiny");
    for flag in ["--frames", "--range"] {
        let stderr = exits_with(
            dormant().args(["--quiet", "bench", "integration"]).arg(&scene).args([
                "--backend",
                "bvh",
                "--frame-count",
                "30",
                flag,
                "0..40",
            ]),
            2,
        );
        assert!(stderr.contains("--frames 0..40: the trajectory has 30 frames"), "{flag}: {stderr}");
    }
}
