//! `dormant bench paper`: the quick preset end to end (paper.json against its documented
//! fields, paper.md's claims table, a non-empty figure), its input errors, and the scene files
//! it builds: the compiled-in atrium and the asset rain over the shared assets (skipped when
//! ../shared/assets is absent).

use crate::common;

use common::cli::{dormant, exits_with, read_json, succeeds};
use common::scenes;
use dormant::scene::file::spec::{ColliderKind, Shape};
use dormant::scene::file::SceneFile;

fn compiled_backends() -> Vec<&'static str> {
    if cfg!(feature = "embree") {
        vec!["embree", "bvh"]
    } else {
        vec!["bvh"]
    }
}

#[test]
fn quick_paper_run_writes_json_markdown_and_figure() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("paper");
    let also = dir.path().join("also.json");
    succeeds(
        dormant().args(["bench", "paper", "--quick", "--quiet", "--out"]).arg(&out).arg("--json").arg(&also),
    );
    let also = read_json(&also);

    let json = read_json(&out.join("paper.json"));
    assert_eq!(json, also, "--json writes the same report as paper.json");
    assert_eq!(json["format"], "dormant-paper");
    assert_eq!(json["version"], 1);
    assert_eq!(json["preset"], "quick");
    let atrium = &json["ratios"]["atrium"];
    for backend in compiled_backends() {
        let r = &atrium["integration"][backend];
        for key in [
            "settled_speedup",
            "run_speedup",
            "auto_over_best",
            "rebuild_over_insert",
            "partial_hit_90_99_fraction",
        ] {
            let v = r[key].as_f64().unwrap_or_else(|| panic!("{backend}.{key} missing in {r:#}"));
            assert!(v.is_finite() && v >= 0.0, "{backend}.{key} = {v}");
        }
        // Integration must pay for itself in build cost, whatever the frame-rate result.
        assert!(r["rebuild_over_insert"].as_f64().unwrap() > 1.0, "{r:#}");
    }
    for key in ["bvh_rebuild_over_insert", "bvh_insert_sah_over_rebuild"] {
        assert!(atrium["accel"][key].as_f64().unwrap() > 0.0, "{key}");
    }
    let workload = &json["workloads"][0];
    assert_eq!(workload["name"], "atrium");
    let runs = workload["runs"].as_array().unwrap();
    assert_eq!(runs.len(), compiled_backends().len());
    for run in runs {
        let configs = run["integration"]["runs"].as_array().unwrap();
        assert_eq!(
            configs.len(),
            8,
            "never; always and auto in each form; auto without lookahead; baked with the cache off"
        );
        let frames = run["integration"]["frames"].as_array().unwrap().len();
        assert!(frames >= 100, "{frames} frames rendered");
        for c in configs {
            assert_eq!(c["frame_ms"].as_array().unwrap().len(), frames);
        }
    }
    assert_eq!(json["claims"].as_array().unwrap().len(), 4 * compiled_backends().len());

    let md = std::fs::read_to_string(out.join("paper.md")).unwrap();
    assert!(md.contains("## The paper's claims against our measurements"), "{md}");
    assert!(md.contains("52% of requests at 90-99%"));
    assert!(md.contains("](figures/atrium.png)"));

    let figure = image::open(out.join("figures/atrium.png")).unwrap().to_rgb8();
    // One 480-pixel row per backend plus the row of stage costs and cache hits.
    let rows = compiled_backends().len() as u32 + 1;
    assert!(figure.width() >= 1000 && figure.height() >= 480 * rows, "{:?}", figure.dimensions());
    let distinct: std::collections::HashSet<[u8; 3]> = figure.pixels().map(|p| p.0).collect();
    assert!(distinct.len() > 20, "the figure is nearly blank: {} colours", distinct.len());
}

#[test]
fn paper_with_a_missing_environment_names_the_file_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("paper");
    let missing = dir.path().join("no-such-env.glb");
    let stderr = exits_with(
        dormant()
            .args(["bench", "paper", "--quick", "--quiet", "--backend", "bvh", "--env"])
            .arg(&missing)
            .arg("--object")
            .arg(&missing)
            .arg("--out")
            .arg(&out),
        2,
    );
    assert!(stderr.contains("no-such-env.glb") && stderr.contains("--env"), "{stderr}");
    assert!(!out.join("paper.json").exists());
}

#[test]
fn paper_env_without_object_is_a_usage_error() {
    let stderr = exits_with(dormant().args(["bench", "paper", "--out", "/tmp/unused", "--env", "x.glb"]), 2);
    assert!(stderr.contains("--object"));
}

#[test]
fn compiled_in_atrium_is_the_scene_file() {
    let on_disk = scenes::load("atrium");
    let built_in = SceneFile::atrium();
    assert_eq!(built_in.spec(), on_disk.spec());
    assert_eq!(built_in.source_hash(), on_disk.source_hash());
}

#[test]
fn asset_rain_scales_objects_to_the_environment_and_spawns_above_it() {
    let Some(dir) = common::shared_assets() else { return };
    let objects = [dir.join("duck.glb"), dir.join("soccerball.glb")];
    let file = SceneFile::asset_rain(&dir.join("monastery.glb"), &objects, 500, 300).unwrap();
    let d = file.spec();
    assert_eq!(d.scene.frames, 300);
    assert_eq!(d.spawners.len(), 2);
    assert_eq!(d.spawners.iter().map(|s| s.count).sum::<u32>(), 500);
    let env = dormant::scene::file::environment_mesh(&file).unwrap().bounds();
    let width = env.extent().x.max(env.extent().z);
    for (i, p) in d.prototypes.iter().enumerate() {
        assert!(matches!(p.shape, Shape::Gltf { collider: ColliderKind::ConvexHull, .. }), "{:?}", p.shape);
        let size = dormant::scene::file::prototype_mesh(&file, i).unwrap().bounds().extent().max_element();
        assert!((size / width - 1.0 / 150.0).abs() < 1e-4, "{}: {size} in {width}", p.name);
    }
    for spawner in &d.spawners {
        let region = spawner.region;
        assert!(region.min[1] > env.max.y, "spawns inside the environment");
        assert!(region.min[0] > env.min.x && region.max[0] < env.max.x);
        assert!(region.min[2] > env.min.z && region.max[2] < env.max.z);
    }
}

#[test]
fn paper_into_an_output_path_that_is_a_file_fails_before_benchmarking() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("not-a-dir");
    std::fs::write(&file, b"x").unwrap();
    let stderr =
        exits_with(dormant().args(["bench", "paper", "--quick", "--out"]).arg(file.join("paper")), 1);
    assert!(stderr.contains("cannot create output directory"), "{stderr}");
    // Not quiet, so a benchmark that had started would have logged its first phase.
    assert!(!stderr.contains("simulating"), "the benchmark ran before the output was checked: {stderr}");
}
