//! Motion blur (`--shutter`, `render.shutter`): a body moving at constant velocity renders a
//! streak as long as the shutter says, a resting body stays sharp, Embree and the BVH blur
//! alike, and `dormant verify` finds no mismatch between them with rays at random times.
//!
//! The scene (tests/data/motion.toml): a dark slider crossing the view at 0.4 units a frame
//! and a blue crate at rest (in other rows and columns of the image), under an overhead sun
//! against a constant sky.

use crate::common;

use common::cli::dormant;
use common::scenes;
use dormant::accel::Backend;
use dormant::physics::SimulateOptions;
use dormant::render::{DirectLighting, Film};
use dormant::residency::{IntegrationPolicy, ManagerOptions};
use dormant::scene::file::SceneFile;
use dormant::sequence::{FrameRange, FrameRenderer, ReuseMode, Sequence, SequenceError, SequenceSource};
use glam::Vec3;

const SIZE: (u32, u32) = (320, 180);
const SPP: u32 = 64;

fn motion_scene() -> Sequence {
    let source = SequenceSource::scene(
        SceneFile::load(scenes::data("motion")).unwrap(),
        SimulateOptions::default(),
        None,
    );
    Sequence::load(source, &mut |_| {}).unwrap()
}

/// Frames `first..first + count` of `sequence` rendered with direct light at `shutter`.
fn render(sequence: &Sequence, backend: Backend, shutter: f32, first: u32, count: u32) -> Vec<Film> {
    let frames = sequence.select(Some(FrameRange { start: first, end: first + count }), Some(1)).unwrap();
    let integrator = DirectLighting;
    let renderer = FrameRenderer {
        reuse: ReuseMode::Off,
        shutter,
        ..FrameRenderer::new(&integrator, SIZE.0, SIZE.1, SPP)
    };
    let options = ManagerOptions { policy: IntegrationPolicy::Never, shutter, ..ManagerOptions::default() };
    let mut manager = sequence.manager(backend, Some(2), options).unwrap();
    let mut films = Vec::new();
    sequence
        .render(&frames, &mut manager, &renderer, &[], &mut |f, _, _| {
            films.push(f.film.clone());
            Ok::<(), SequenceError>(())
        })
        .unwrap();
    films
}

fn luminance(p: Vec3) -> f32 {
    p.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

/// The slider's coverage along row `y` of `film`: 0 on the lit ground, 1 on the slider
/// (`dark`, its luminance in a sharp frame).
fn coverage(film: &Film, y: u32, ground: f32, dark: f32) -> Vec<f32> {
    (0..film.width)
        .map(|x| {
            ((ground - luminance(film.pixels[(y * film.width + x) as usize])) / (ground - dark))
                .clamp(0.0, 1.0)
        })
        .collect()
}

/// Whether `p` is the slider's (dark grey, unlike the blue crate).
fn is_slider(p: Vec3, ground: f32) -> bool {
    luminance(p) < 0.3 * ground && (p.z - p.x).abs() < 0.02
}

/// The rows through the middle of the slider in a sharp frame: those where it covers pixels,
/// trimmed by a quarter at either end (away from its top and bottom edges).
fn slider_rows(sharp: &Film, ground: f32) -> Vec<u32> {
    let rows: Vec<u32> = (0..sharp.height)
        .filter(|&y| {
            (0..sharp.width).any(|x| is_slider(sharp.pixels[(y * sharp.width + x) as usize], ground))
        })
        .collect();
    let (lo, hi) = (rows[0], rows[rows.len() - 1]);
    let q = (hi - lo) / 4;
    ((lo + q)..=(hi - q)).collect()
}

/// How far the slider travels during the shutter in `film`, in pixels, from its coverage
/// profiles along `rows` against those of the `sharp` frame. Sweeping a profile uniformly
/// over `d` pixels convolves it with a box `d` wide, which adds `d² / 12` to its variance
/// (whatever the box's width, the pixel filter or thresholds), so `d = sqrt(12 (var_blurred -
/// var_sharp))`, with the variances summed over the rows.
fn streak(film: &Film, sharp: &Film, rows: &[u32], ground: f32, dark: f32) -> f32 {
    let variance = |f: &Film| {
        let mut v = 0.0;
        for &y in rows {
            let c = coverage(f, y, ground, dark);
            let w: f32 = c.iter().sum();
            let mean = c.iter().enumerate().map(|(x, c)| x as f32 * c).sum::<f32>() / w;
            v += c.iter().enumerate().map(|(x, c)| (x as f32 - mean).powi(2) * c).sum::<f32>() / w;
        }
        v / rows.len() as f32
    };
    (12.0 * (variance(film) - variance(sharp))).max(0.0).sqrt()
}

/// Coverage-weighted mean column of the slider over `rows`.
fn centroid(film: &Film, rows: &[u32], ground: f32, dark: f32) -> f32 {
    let (mut sum, mut weight) = (0.0, 0.0);
    for &y in rows {
        for (x, c) in coverage(film, y, ground, dark).into_iter().enumerate() {
            sum += x as f32 * c;
            weight += c;
        }
    }
    sum / weight
}

/// Root mean square difference of linear radiance over the pixels of `region` (x0, y0, x1,
/// y1; all of it when `None`).
fn rmse(a: &Film, b: &Film, region: Option<(u32, u32, u32, u32)>) -> f64 {
    let (x0, y0, x1, y1) = region.unwrap_or((0, 0, a.width, a.height));
    let mut se = 0.0f64;
    for y in y0..y1 {
        for x in x0..x1 {
            let i = (y * a.width + x) as usize;
            se += f64::from((a.pixels[i] - b.pixels[i]).length_squared()) / 3.0;
        }
    }
    (se / f64::from((x1 - x0) * (y1 - y0))).sqrt()
}

#[test]
fn constant_velocity_body_streaks_by_the_shutter() {
    let sequence = motion_scene();
    for backend in Backend::compiled() {
        // Frames 44 and 46 sharp give the slider's travel per frame in pixels.
        let sharp = render(&sequence, backend, 0.0, 44, 3);
        let ground = luminance(sharp[1].pixels[(5 * SIZE.0 + 5) as usize]);
        let rows = slider_rows(&sharp[1], ground);
        let dark = rows
            .iter()
            .flat_map(|&y| (0..SIZE.0).map(move |x| (x, y)))
            .map(|(x, y)| luminance(sharp[1].pixels[(y * SIZE.0 + x) as usize]))
            .fold(f32::INFINITY, f32::min);
        let per_frame =
            (centroid(&sharp[2], &rows, ground, dark) - centroid(&sharp[0], &rows, ground, dark)) / 2.0;
        assert!(per_frame > 8.0, "{backend}: the slider moves {per_frame} px a frame");
        for shutter in [0.5f32, 1.0] {
            let blurred = &render(&sequence, backend, shutter, 45, 1)[0];
            let measured = streak(blurred, &sharp[1], &rows, ground, dark);
            let expected = shutter * per_frame;
            eprintln!("{backend}: shutter {shutter}: streak {measured:.2} px, expected {expected:.2} px");
            assert!(
                (measured - expected).abs() <= (0.15 * expected).max(1.5),
                "{backend}: shutter {shutter}: streak {measured} px, expected {expected} px"
            );
            // The blur keeps the slider's place: the streak is centred on the frame's pose.
            let shift = centroid(blurred, &rows, ground, dark) - centroid(&sharp[1], &rows, ground, dark);
            assert!(
                shift.abs() < 1.0,
                "{backend}: shutter {shutter}: the streak is off centre by {shift} px"
            );
        }
    }
}

#[test]
fn resting_body_stays_sharp_while_the_moving_one_blurs() {
    let sequence = motion_scene();
    for backend in Backend::compiled() {
        let sharp = &render(&sequence, backend, 0.0, 45, 1)[0];
        let blurred = &render(&sequence, backend, 1.0, 45, 1)[0];
        // Bounding boxes (pixels) of the blue crate and of the dark slider in the sharp frame.
        let bounds = |pick: &dyn Fn(Vec3) -> bool| {
            let (mut x0, mut y0, mut x1, mut y1) = (u32::MAX, u32::MAX, 0, 0);
            for y in 0..SIZE.1 {
                for x in 0..SIZE.0 {
                    if pick(sharp.pixels[(y * SIZE.0 + x) as usize]) {
                        (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x + 1), y1.max(y + 1));
                    }
                }
            }
            assert!(x0 < x1, "{backend}: object not found");
            (x0.saturating_sub(2), y0.saturating_sub(2), (x1 + 2).min(SIZE.0), (y1 + 2).min(SIZE.1))
        };
        let crate_box = bounds(&|p: Vec3| p.z > 2.0 * p.x && p.z > 0.05);
        let ground = luminance(sharp.pixels[(5 * SIZE.0 + 5) as usize]);
        let slider_box = bounds(&|p: Vec3| is_slider(p, ground));
        let (at_rest, moving) =
            (rmse(sharp, blurred, Some(crate_box)), rmse(sharp, blurred, Some(slider_box)));
        eprintln!("{backend}: RMSE blur on/off: resting crate {at_rest:.2e}, slider {moving:.2e}");
        // Rays meet the crate at every time alike (the camera samples are the same, only their
        // time is new), so its pixels change only where a light ray meets the slider.
        assert!(at_rest < 1e-3, "{backend}: the resting crate changed by RMSE {at_rest}");
        assert!(moving > 100.0 * at_rest.max(1e-5), "{backend}: the slider did not blur (RMSE {moving})");
    }
}

#[test]
fn embree_and_bvh_blur_alike() {
    if !Backend::Embree.is_compiled() {
        eprintln!("skipped: Embree is not compiled in");
        return;
    }
    let sequence = motion_scene();
    let embree = &render(&sequence, Backend::Embree, 1.0, 45, 1)[0];
    let bvh = &render(&sequence, Backend::Bvh, 1.0, 45, 1)[0];
    // The same samples at the same times through both backends: they may differ only where a
    // hit moved by float rounding (a sample at the slider's edge landing on the other side).
    // Measured: RMSE 0 (identical images).
    let e = rmse(embree, bvh, None);
    eprintln!("Embree against the BVH, shutter 1: RMSE {e:.2e}");
    assert!(e < 2e-3, "Embree and the BVH blur differently: RMSE {e}");
}

#[test]
fn verify_with_shutter_reports_no_mismatches() {
    if !Backend::Embree.is_compiled() {
        eprintln!("skipped: Embree is not compiled in");
        return;
    }
    let out = dormant()
        .args(["--threads", "2", "verify"])
        .arg(scenes::data("motion"))
        .args(["--shutter", "1", "--check-frames", "5", "--surface-rays", "20000", "--json"])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}{}", String::from_utf8_lossy(&out.stderr));
    let report: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(report["shutter"], 1.0);
    assert_eq!(report["mismatches"], 0, "{report}");
    assert!(report["hits"].as_u64().unwrap() > 100_000, "{report}");
}
