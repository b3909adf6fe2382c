//! `dormant render SCENE` writes stats.json (checked against docs/stats-format.md's schema),
//! stats.csv (a header and one row per frame) and report.png.

use crate::common;

use common::cli::{dormant, read_stats, simulate_tiny, succeeds};
use serde_json::Value;

/// JSON types as the schema names them.
fn type_name(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "boolean",
        Value::Number(n) if n.is_u64() || n.is_i64() => "integer",
        Value::Number(_) => "number",
        Value::String(_) => "string",
        Value::Array(_) => "array",
        Value::Object(_) => "object",
    }
}

/// `expected` is `"a|b"`: any of the listed types; "number" also accepts integers.
fn check(path: &str, v: &Value, expected: &str) {
    let actual = type_name(v);
    let ok = expected.split('|').any(|t| t == actual || (t == "number" && actual == "integer"));
    assert!(ok, "{path}: expected {expected}, found {actual} ({v})");
}

/// Checks `object` has exactly the fields of `schema` (name, type) and no others.
fn check_object(path: &str, object: &Value, schema: &[(&str, &str)]) {
    let map = object.as_object().unwrap_or_else(|| panic!("{path}: not an object"));
    for (name, ty) in schema {
        let v = map.get(*name).unwrap_or_else(|| panic!("{path}.{name}: missing"));
        check(&format!("{path}.{name}"), v, ty);
    }
    for key in map.keys() {
        assert!(schema.iter().any(|(n, _)| n == key), "{path}.{key}: not in the documented schema");
    }
}

const RUN: &[(&str, &str)] = &[
    ("scene", "string"),
    ("backend", "string"),
    ("mode", "string"),
    ("integration", "string"),
    ("integrate_as", "string"),
    ("cache_enabled", "boolean"),
    ("lookahead", "boolean"),
    ("width", "integer"),
    ("height", "integer"),
    ("spp", "integer"),
    ("noise_threshold", "number"),
    ("min_spp", "integer|null"),
    ("physics", "string"),
    ("scene_hash", "string"),
    ("trajectory_frames", "integer"),
    ("frame_start", "integer"),
    ("frame_end", "integer"),
    ("frame_step", "integer"),
    ("max_depth", "integer|null"),
    ("clamp_indirect", "number"),
    ("filter", "string"),
    ("filter_width", "number"),
    ("seed", "string"),
    ("seed_offset", "integer"),
    ("reuse", "boolean"),
    ("reuse_mode", "string"),
    ("exposure", "number"),
    ("aovs", "array"),
    ("exr", "boolean"),
    ("denoise", "string|null"),
    ("keep_noisy", "boolean"),
    ("shutter", "number"),
    ("settings_from", "object"),
];

const FRAME: &[(&str, &str)] = &[
    ("frame", "integer"),
    ("physics_ms", "number|null"),
    ("update_ms", "number"),
    ("integrate_ms", "number"),
    ("reactivate_ms", "number"),
    ("commit_ms", "number"),
    ("trace_ms", "number"),
    ("frame_ms", "number"),
    ("rays", "integer"),
    ("mrays_per_second", "number"),
    ("spp_mean", "number"),
    ("spp_min", "integer"),
    ("spp_max", "integer"),
    ("committed", "boolean"),
    ("instances", "integer"),
    ("integrated_islands", "integer"),
    ("sleeping_islands", "integer"),
    ("baked_bodies", "integer"),
    ("resting_bodies", "integer"),
    ("rest_rebuilt", "boolean"),
    ("reused", "boolean"),
    ("islands_slept", "integer"),
    ("islands_woke", "integer"),
    ("islands_integrated", "integer"),
    ("islands_reactivated", "integer"),
    ("cache_full", "integer"),
    ("cache_partial", "integer"),
    ("cache_miss", "integer"),
    ("decisions", "array"),
    ("samples_traced", "integer"),
    ("samples_reused", "integer"),
    ("pixels_traced", "integer"),
    ("horizon_ms", "number"),
    ("neighbour_rays", "integer"),
    ("reuse_store_bytes", "integer"),
    ("full_frame", "string|null"),
    ("reuse_granularity", "string|null"),
];

const DECISION: &[(&str, &str)] = &[
    ("island", "integer"),
    ("bodies", "integer"),
    ("triangles", "integer"),
    ("age", "integer"),
    ("integrate", "boolean"),
    ("estimate", "object|null"),
];

const ESTIMATE: &[(&str, &str)] = &[
    ("build_ms", "number"),
    ("wake_ms", "number"),
    ("gain_ms_per_frame", "number"),
    ("expected_frames", "number"),
    ("exact", "boolean"),
];

const SUMMARY: &[(&str, &str)] = &[
    ("frames", "integer"),
    ("first_frame", "integer|null"),
    ("last_frame", "integer|null"),
    ("totals", "object"),
    ("median", "object"),
    ("cache", "object"),
    ("cost_model", "object"),
];

const TOTALS: &[(&str, &str)] = &[
    ("physics_ms", "number|null"),
    ("update_ms", "number"),
    ("integrate_ms", "number"),
    ("reactivate_ms", "number"),
    ("commit_ms", "number"),
    ("trace_ms", "number"),
    ("frame_ms", "number"),
    ("rays", "integer"),
    ("islands_slept", "integer"),
    ("islands_woke", "integer"),
    ("islands_integrated", "integer"),
    ("islands_reactivated", "integer"),
    ("rest_rebuilds", "integer"),
    ("reused_frames", "integer"),
    ("cache_full", "integer"),
    ("cache_partial", "integer"),
    ("cache_miss", "integer"),
    ("decisions_integrate", "integer"),
    ("decisions_decline", "integer"),
    ("samples_traced", "integer"),
    ("samples_reused", "integer"),
    ("horizon_ms", "number"),
    ("neighbour_rays", "integer"),
];

const MEDIAN: &[(&str, &str)] = &[
    ("physics_ms", "number|null"),
    ("update_ms", "number"),
    ("integrate_ms", "number"),
    ("reactivate_ms", "number"),
    ("commit_ms", "number"),
    ("trace_ms", "number"),
    ("frame_ms", "number"),
];

const CACHE: &[(&str, &str)] = &[
    ("requests", "integer"),
    ("full", "integer"),
    ("partial", "integer"),
    ("miss", "integer"),
    ("recorded", "integer"),
    ("evicted", "integer"),
    ("invalidated", "integer"),
    ("fraction_histogram", "array"),
    ("fraction_buckets", "array"),
    ("entries", "integer"),
    ("bytes", "integer"),
    ("peak_entries", "integer"),
    ("peak_bytes", "integer"),
    ("budget_entries", "integer"),
    ("budget_bytes", "integer"),
];

const COST_MODEL: &[(&str, &str)] = &[
    ("build_ms_intercept", "number"),
    ("build_ms_per_mtriangle", "number"),
    ("rest_ms_intercept", "number"),
    ("rest_ms_per_kinstance", "number"),
    ("commit_ms_per_instance", "number"),
    ("trace_ms_mean", "number"),
    ("penalty", "object"),
    ("sleep_samples", "integer"),
    ("shadow_islands", "integer"),
];

fn check_stats(stats: &Value, frames: std::ops::Range<u32>, physics: &str) {
    check_object(
        "",
        stats,
        &[
            ("format", "string"),
            ("version", "integer"),
            ("run", "object"),
            ("frames", "array"),
            ("summary", "object"),
        ],
    );
    assert_eq!(stats["format"], "dormant-stats");
    assert_eq!(stats["version"], 2);
    check_object("run", &stats["run"], RUN);
    assert_eq!(stats["run"]["physics"], physics);
    let records = stats["frames"].as_array().unwrap();
    assert_eq!(records.len(), frames.len());
    for (record, frame) in records.iter().zip(frames.clone()) {
        check_object("frames[]", record, FRAME);
        assert_eq!(record["frame"], frame);
        if physics == "trajectory" {
            assert!(record["physics_ms"].is_null());
        }
        for decision in record["decisions"].as_array().unwrap() {
            check_object("frames[].decisions[]", decision, DECISION);
            if !decision["estimate"].is_null() {
                check_object("frames[].decisions[].estimate", &decision["estimate"], ESTIMATE);
            }
        }
    }
    let summary = &stats["summary"];
    check_object("summary", summary, SUMMARY);
    assert_eq!(summary["frames"], frames.len());
    check_object("summary.totals", &summary["totals"], TOTALS);
    check_object("summary.median", &summary["median"], MEDIAN);
    check_object("summary.cache", &summary["cache"], CACHE);
    check_object("summary.cost_model", &summary["cost_model"], COST_MODEL);
    assert_eq!(summary["cache"]["fraction_histogram"].as_array().unwrap().len(), 12);
    assert_eq!(summary["cache"]["fraction_buckets"].as_array().unwrap().len(), 12);
}

fn check_csv(text: &str, frames: std::ops::Range<u32>) {
    let lines: Vec<&str> = text.lines().collect();
    let header: Vec<&str> = lines[0].split(',').collect();
    assert_eq!(header[0], "frame");
    for column in ["physics_ms", "trace_ms", "decisions_integrate", "decisions_decline", "cache_full"] {
        assert!(header.contains(&column), "stats.csv has no {column} column");
    }
    assert_eq!(lines.len() - 1, frames.len());
    for (line, frame) in lines[1..].iter().zip(frames) {
        let cells: Vec<&str> = line.split(',').collect();
        assert_eq!(cells.len(), header.len(), "{line}");
        assert_eq!(cells[0], frame.to_string());
    }
}

#[test]
fn render_writes_stats_csv_and_report_for_a_simulated_scene() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("tiny");
    succeeds(
        dormant()
            .args(["render", "scenes/tiny.toml", "--size", "64x36"])
            .args(["--spp", "1", "--frames", "0..60", "--quiet"])
            .arg("--out")
            .arg(&out)
            .current_dir(env!("CARGO_MANIFEST_DIR")),
    );
    let stats = read_stats(&out);
    check_stats(&stats, 0..60, "simulated");
    assert!(stats["frames"].as_array().unwrap().iter().all(|f| f["physics_ms"].is_number()));
    check_csv(&std::fs::read_to_string(out.join("stats.csv")).unwrap(), 0..60);
    let png = std::fs::metadata(out.join("report.png")).unwrap();
    assert!(png.len() > 0);
    let image = image::open(out.join("report.png")).unwrap();
    assert!(image.width() > 0 && image.height() > 0);
}

#[test]
fn replayed_frames_have_no_physics_time() {
    let dir = tempfile::tempdir().unwrap();
    let traj = simulate_tiny(dir.path(), &[]);
    let out = dir.path().join("slice");
    succeeds(
        dormant()
            .args(["render", "scenes/tiny.toml", "--size", "32x18"])
            .args(["--spp", "1", "--frames", "100..110", "--quiet"])
            .arg("--trajectory")
            .arg(&traj)
            .arg("--out")
            .arg(&out)
            .current_dir(env!("CARGO_MANIFEST_DIR")),
    );
    let stats = read_stats(&out);
    check_stats(&stats, 100..110, "trajectory");
    assert!(stats["summary"]["totals"]["physics_ms"].is_null());
    check_csv(&std::fs::read_to_string(out.join("stats.csv")).unwrap(), 100..110);
}

/// `frame,islands_slept,islands_woke` of every row of `dir`'s stats.csv.
fn island_event_columns(dir: &std::path::Path) -> Vec<String> {
    let text = std::fs::read_to_string(dir.join("stats.csv")).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let at = |name: &str| header.iter().position(|c| *c == name).unwrap();
    let columns = [at("frame"), at("islands_slept"), at("islands_woke")];
    text.lines()
        .skip(1)
        .map(|line| {
            let cells: Vec<&str> = line.split(',').collect();
            columns.map(|c| cells[c]).join(",")
        })
        .collect()
}

/// The README's job array joins the slices' stats.csv into one table: a slice's first row must
/// count the island events since the frame a whole run rendered before it, not since frame 0.
#[test]
fn slices_count_island_events_as_a_whole_run_does() {
    let dir = tempfile::tempdir().unwrap();
    let traj = simulate_tiny(dir.path(), &[]);
    let render = |frames: &str, out: &std::path::Path| {
        succeeds(
            dormant()
                .args(["render", "--quiet", "--size", "16x9", "--spp", "1"])
                .args(["--frame-step", "3", "--frames", frames])
                .arg("--trajectory")
                .arg(&traj)
                .arg("--out")
                .arg(out),
        );
        island_event_columns(out)
    };
    let whole = render("0..480", &dir.path().join("whole"));
    // 100 and 301 are off the step grid: the slices start at frames 102 and 303.
    let mut joined = Vec::new();
    for (i, frames) in ["0..100", "100..301", "301..480"].into_iter().enumerate() {
        joined.extend(render(frames, &dir.path().join(format!("part_{i}"))));
    }
    let events: u32 =
        whole.iter().map(|row| row.split(',').skip(1).map(|n| n.parse::<u32>().unwrap()).sum::<u32>()).sum();
    assert!(events > 0, "tiny's trajectory has island events");
    assert_eq!(joined, whole);
}

/// `--cache-entries` and `--cache-mib` bound the geometry cache, and stats.json reports the
/// budget and the peak it stayed within (the soak checks the same over 10,000 frames).
#[test]
fn cache_flags_set_the_budget_the_cache_keeps() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("cache");
    succeeds(
        dormant()
            .args(["render", "scenes/tiny.toml", "--size", "32x18", "--spp", "1", "--backend", "bvh"])
            .args(["--integration", "always", "--integrate-as", "baked", "--cache-entries", "1"])
            .args(["--cache-mib", "1", "--quiet", "--out"])
            .arg(&out)
            .current_dir(env!("CARGO_MANIFEST_DIR")),
    );
    let stats = read_stats(&out);
    let cache = &stats["summary"]["cache"];
    assert_eq!((cache["budget_entries"].as_u64(), cache["budget_bytes"].as_u64()), (Some(1), Some(1 << 20)));
    assert!(cache["recorded"].as_u64().unwrap() >= 2, "the run must record several scenes: {cache}");
    assert!(cache["evicted"].as_u64().unwrap() >= 1, "{cache}");
    assert_eq!(cache["peak_entries"].as_u64(), Some(1), "{cache}");
    assert!(cache["peak_bytes"].as_u64().unwrap() <= 1 << 20, "{cache}");
}

#[test]
fn built_in_single_frame_writes_no_stats() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("one");
    succeeds(dormant().args(["render", "--size", "16x9", "--spp", "1", "--quiet", "--out"]).arg(&out));
    assert!(out.join("frame_0000.png").is_file());
    assert!(!out.join("stats.json").exists());
}
