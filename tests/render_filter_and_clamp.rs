//! `render --filter`, `--filter-width` and `--clamp-indirect`: a wider filter smooths the
//! image, clamping only ever takes light away (off, the image is the unclamped estimate),
//! both are recorded in a sequence's statistics and `--resume` refuses a run of another
//! filter (bad values: `tests/input_errors.rs`).

use crate::common;

use std::path::{Path, PathBuf};

use common::cli::{dormant, exits_with, read_stats, succeeds};
use common::images::pixels;
use common::scenes;

/// The built-in scene at 64x36, 32 spp, path traced, into `dir/name`, with `extra` flags;
/// returns the folder.
fn render_default(dir: &Path, name: &str, extra: &[&str]) -> PathBuf {
    let out = dir.join(name);
    succeeds(
        dormant()
            .args(["render", "--quiet", "--size", "64x36", "--spp", "32", "--exr", "--out"])
            .arg(&out)
            .args(extra),
    );
    out
}

/// Mean absolute difference of horizontally neighbouring pixels: how sharp an image is.
fn sharpness(image: &[[f32; 3]], width: usize) -> f64 {
    let rows = image.chunks(width);
    let diffs = rows.flat_map(|r| {
        r.windows(2).map(|w| (0..3).map(|c| f64::from((w[0][c] - w[1][c]).abs())).sum::<f64>())
    });
    let (sum, n) = diffs.fold((0.0, 0usize), |(s, n), d| (s + d, n + 1));
    sum / n as f64
}

#[test]
fn a_wider_filter_smooths_the_image() {
    let dir = tempfile::tempdir().unwrap();
    let sharp = render_default(dir.path(), "box", &["--filter", "box", "--filter-width", "1"]);
    let soft = render_default(dir.path(), "gauss", &["--filter", "gaussian", "--filter-width", "4"]);
    let bh = render_default(dir.path(), "bh", &["--filter", "blackman-harris"]);
    let [s, g, b] = [sharp, soft, bh].map(|d| sharpness(&pixels(&d.join("frame_0000.exr")), 64));
    assert!(g < 0.8 * s, "gaussian of width 4 ({g}) not smoother than a box of 1 ({s})");
    assert!(b < s && b > g, "blackman-harris 1.5 ({b}) not between them ({s}, {g})");
}

#[test]
fn clamping_only_takes_indirect_light_away() {
    let dir = tempfile::tempdir().unwrap();
    let off = pixels(&render_default(dir.path(), "off", &["--clamp-indirect", "0"]).join("frame_0000.exr"));
    let tight =
        pixels(&render_default(dir.path(), "tight", &["--clamp-indirect", "0.05"]).join("frame_0000.exr"));
    let default = pixels(&render_default(dir.path(), "default", &[]).join("frame_0000.exr"));
    // Same samples: per pixel and channel, each contribution is clamped or left alone.
    for ((o, t), d) in off.iter().zip(&tight).zip(&default) {
        for c in 0..3 {
            assert!(t[c] <= d[c] * (1.0 + 1e-6) && d[c] <= o[c] * (1.0 + 1e-6), "{t:?} {d:?} {o:?}");
        }
    }
    let mean = |img: &[[f32; 3]]| img.iter().map(|p| f64::from(p[0] + p[1] + p[2])).sum::<f64>();
    assert!(mean(&tight) < 0.99 * mean(&off), "a clamp of 0.05 took no light away");
}

#[test]
fn filter_and_clamp_are_recorded_and_resume_refuses_another_filter() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let run = |filter: &str| {
        let mut cmd = dormant();
        cmd.args(["--quiet", "render", "--size", "32x18", "--spp", "2", "--frames", "100..103", "--resume"])
            .args(["--filter", filter, "--clamp-indirect", "0", "--out"])
            .arg(&out)
            .arg(scenes::shipped("tiny"));
        cmd
    };
    succeeds(&mut run("blackman-harris"));
    let header = &read_stats(&out)["run"];
    assert_eq!(
        (&header["filter"], &header["filter_width"]),
        (&"blackman-harris".into(), &1.5.into()),
        "{header}"
    );
    assert_eq!(header["clamp_indirect"], 0.0, "{header}");
    let stderr = exits_with(&mut run("tent"), 2);
    assert!(stderr.contains("filter \"blackman-harris\" there, \"tent\" now"), "{stderr}");
}
