//! Adaptive sampling (`render --noise-threshold`) end to end on the built-in scene: flat
//! regions stop early and edges and noisy regions get more samples (the `spp` AOV), the image
//! matches uniform sampling against a high-spp reference within a stated tolerance while
//! spending fewer samples, it is identical at one and two threads, the statistics report the
//! effective spp, and a scene file's `[render] noise_threshold` turns it on.

use crate::common;

use std::path::{Path, PathBuf};

use common::cli::{dormant, read_stats, succeeds};
use common::images::{pixels, relative_mse};
use common::scenes;

/// Renders the default scene at 160x90 into `out` with `extra` flags, writing EXRs; returns
/// the `--json` report.
fn render(out: &Path, extra: &[&str]) -> serde_json::Value {
    let output = succeeds(
        dormant().args(["--json", "-", "render", "--size", "160x90", "--exr", "--out"]).arg(out).args(extra),
    );
    serde_json::from_slice(&output.stdout).unwrap()
}

fn mean(values: impl Iterator<Item = f64>) -> f64 {
    let (sum, n) = values.fold((0.0, 0), |(s, n), v| (s + v, n + 1));
    sum / n.max(1) as f64
}

fn frame(dir: &Path, name: &str) -> PathBuf {
    dir.join(format!("frame_0000{name}.exr"))
}

#[test]
fn adaptive_sampling_stops_early_on_flat_regions_and_samples_edges() {
    let dir = tempfile::tempdir().unwrap();
    let report = render(dir.path(), &["--spp", "64", "--noise-threshold", "0.07", "--aov", "spp,albedo"]);
    let spp: Vec<f64> = pixels(&frame(dir.path(), ".spp")).iter().map(|p| f64::from(p[0])).collect();
    let albedo = pixels(&frame(dir.path(), ".albedo"));
    let (w, h) = (160usize, 90usize);
    // Edges: a neighbour's albedo differs (silhouettes, checker squares, grout lines); flat:
    // the 3x3 neighbourhood has one albedo.
    let step = |a: [f32; 3], b: [f32; 3]| (0..3).map(|c| (a[c] - b[c]).abs()).fold(0.0f32, f32::max);
    let (mut flat, mut edges) = (Vec::new(), Vec::new());
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let most = (0..9)
                .map(|k| step(albedo[y * w + x], albedo[(y + k / 3 - 1) * w + x + k % 3 - 1]))
                .fold(0.0f32, f32::max);
            if most == 0.0 {
                flat.push(spp[y * w + x]);
            } else if most > 0.1 {
                edges.push(spp[y * w + x]);
            }
        }
    }
    let (flat, edges) = (mean(flat.into_iter()), mean(edges.into_iter()));
    // The sky (top rows) is the flattest of all: constant radiance, done at the minimum (8).
    let sky = mean(spp[..5 * w].iter().copied());
    eprintln!("mean spp: flat {flat:.1}, edges {edges:.1}, sky {sky:.1}");
    assert!(flat < 0.7 * edges, "flat regions {flat:.1} spp, edges {edges:.1}");
    assert_eq!(sky, 8.0);
    // The statistics and the AOV agree.
    let stats = &report["frames"][0];
    assert!((stats["spp_mean"].as_f64().unwrap() - mean(spp.iter().copied())).abs() < 1e-6);
    assert_eq!(stats["spp_min"], 8);
    assert_eq!(stats["spp_max"], 64);
}

#[test]
fn adaptive_sampling_matches_uniform_sampling_against_a_reference() {
    let dir = tempfile::tempdir().unwrap();
    let [reference, uniform, adaptive] = ["reference", "uniform", "adaptive"].map(|d| dir.path().join(d));
    render(&reference, &["--spp", "256"]);
    render(&uniform, &["--spp", "64"]);
    let report = render(&adaptive, &["--spp", "64", "--noise-threshold", "0.065"]);
    let reference = pixels(&frame(&reference, ""));
    let (u, a) = (pixels(&frame(&uniform, "")), pixels(&frame(&adaptive, "")));
    let (u_error, a_error) = (relative_mse(&u, &reference), relative_mse(&a, &reference));
    let spp = report["frames"][0]["spp_mean"].as_f64().unwrap();
    let brightness = |img: &[[f32; 3]]| mean(img.iter().map(|p| f64::from(p[0] + p[1] + p[2])));
    let bias = brightness(&a) / brightness(&reference) - 1.0;
    eprintln!("relMSE uniform 64 spp {u_error:.6}, adaptive {a_error:.6} at {spp:.1} spp; bias {bias:+.4}");
    // Tolerance: within 1.5x the error of uniform sampling at the same most samples, with at
    // most three quarters of its samples, and no visible bias (mean within 1%).
    assert!(a_error < 1.5 * u_error, "adaptive {a_error} against uniform {u_error}");
    assert!(spp < 48.0, "{spp} spp");
    assert!(bias.abs() < 0.01, "{bias}");
}

#[test]
fn adaptive_sampling_is_identical_at_one_and_two_threads() {
    let dir = tempfile::tempdir().unwrap();
    let outputs: Vec<PathBuf> = ["1", "2"]
        .iter()
        .map(|threads| {
            let out = dir.path().join(threads);
            succeeds(
                dormant()
                    .args(["--quiet", "--threads", threads, "render", "--size", "96x54", "--spp", "32"])
                    .args(["--noise-threshold", "0.1", "--aov", "spp", "--exr", "--out"])
                    .arg(&out),
            );
            out
        })
        .collect();
    for name in ["frame_0000.exr", "frame_0000.png", "frame_0000.spp.exr"] {
        let (a, b) =
            (std::fs::read(outputs[0].join(name)).unwrap(), std::fs::read(outputs[1].join(name)).unwrap());
        assert!(a == b, "{name} differs between 1 and 2 threads");
    }
    // Adaptive: not every pixel has the same count.
    let spp = pixels(&outputs[0].join("frame_0000.spp.exr"));
    assert!(spp.iter().any(|p| p[0] < 32.0) && spp.iter().any(|p| p[0] == 32.0));
}

#[test]
fn scene_file_noise_threshold_turns_adaptive_sampling_on_and_stats_record_it() {
    let dir = tempfile::tempdir().unwrap();
    let source = std::fs::read_to_string(scenes::shipped("tiny")).unwrap();
    assert!(source.contains("[render]"), "tiny.toml has a [render] table");
    let scene = dir.path().join("tiny.toml");
    std::fs::write(&scene, source.replace("[render]", "[render]\nnoise_threshold = 0.2\nmin_spp = 4"))
        .unwrap();
    let out = dir.path().join("out");
    succeeds(
        dormant()
            .args(["--quiet", "render", "--frames", "0..1", "--size", "32x18", "--spp", "16", "--out"])
            .arg(&out)
            .arg(&scene),
    );
    let stats = read_stats(&out);
    assert_eq!(stats["run"]["noise_threshold"], 0.2);
    assert_eq!(stats["run"]["min_spp"], 4);
    let frame = &stats["frames"][0];
    let mean = frame["spp_mean"].as_f64().unwrap();
    assert!(mean < 16.0 && frame["spp_min"].as_u64().unwrap() >= 4, "{frame}");
    assert_eq!(frame["spp_max"], 16);
    let csv = std::fs::read_to_string(out.join("stats.csv")).unwrap();
    assert!(csv.lines().next().unwrap().contains(",spp_mean,spp_min,spp_max,"));
}
