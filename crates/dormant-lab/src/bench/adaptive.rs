//! `dormant bench adaptive`: error against samples of uniform and adaptive sampling (and,
//! with the denoiser, of denoised frames) on one view. A reference at many samples per pixel is
//! rendered with another sampler seed than the frames measured, so its samples are
//! independent of theirs; each frame's error is its relative MSE against it
//! ([`relative_mse`]). The samples at which adaptive sampling reaches each uniform frame's
//! error are interpolated (log-log) between the thresholds measured.

use std::path::PathBuf;

use serde::Serialize;

use dormant::accel::{self, Backend};
use dormant::render::denoise::Denoiser;
use dormant::render::{
    render_frame, render_with_aovs, AdaptiveSampling, Aov, Film, PathTracer, RenderError, RenderScene,
    RenderSettings, RenderStats,
};
use dormant::scene::SceneDescription;

/// What `bench adaptive` measures.
pub struct AdaptiveBenchOptions {
    pub backend: Backend,
    pub width: u32,
    pub height: u32,
    pub max_depth: u32,
    /// Samples per pixel of the reference.
    pub reference_spp: u32,
    /// Read the reference from this EXR when it exists (and matches the size), else render
    /// it and write it there.
    pub reference: Option<PathBuf>,
    /// Uniform frames' samples per pixel.
    pub uniform_spp: Vec<u32>,
    /// Adaptive frames' noise thresholds, each with at most `adaptive_spp` samples.
    pub thresholds: Vec<f32>,
    pub adaptive_spp: u32,
    /// Adaptive sampling's minimum; `None`: the default for `adaptive_spp`.
    pub min_spp: Option<u32>,
    /// Also denoise every frame (OIDN, albedo and normal guides from the frame's samples).
    pub denoiser: Option<Denoiser>,
}

/// One measured frame.
#[derive(Clone, Debug, Serialize)]
pub struct AdaptiveRow {
    /// `uniform` or `adaptive`.
    pub sampling: &'static str,
    /// Samples per pixel (the most, for adaptive frames).
    pub spp: u32,
    /// 0 for uniform frames.
    pub noise_threshold: f32,
    pub spp_mean: f64,
    pub spp_min: u32,
    pub spp_max: u32,
    pub relative_mse: f64,
    /// With the denoiser: the denoised frame's relative MSE.
    pub denoised_relative_mse: Option<f64>,
    /// Tracing the frame (the AOV guides not included).
    pub trace_seconds: f64,
}

/// A uniform frame against adaptive sampling at its error.
#[derive(Clone, Debug, Serialize)]
pub struct EqualError {
    pub uniform_spp: u32,
    pub relative_mse: f64,
    /// Interpolated threshold and mean samples per pixel at which adaptive sampling has
    /// this error; `None` outside the thresholds measured.
    pub adaptive_threshold: Option<f64>,
    pub adaptive_spp_mean: Option<f64>,
    /// `uniform_spp / adaptive_spp_mean`.
    pub sample_ratio: Option<f64>,
}

#[derive(Clone, Debug, Serialize)]
pub struct AdaptiveBenchReport {
    pub scene: String,
    pub backend: Backend,
    pub width: u32,
    pub height: u32,
    pub reference_spp: u32,
    pub reference_seconds: Option<f64>,
    pub min_spp: u32,
    /// The relative MSE's dark floor: `(x - ref)^2 / (ref^2 + floor^2)`.
    pub floor: f32,
    /// `--denoise`: `oidn`, or `oidn-prefilter` with `--denoise-prefilter`; `null` without.
    pub denoise: Option<&'static str>,
    pub rows: Vec<AdaptiveRow>,
    pub equal_error: Vec<EqualError>,
}

/// Relative MSE of `image` against `reference`: the mean over pixels and RGB channels of
/// `(x - ref)^2 / (ref^2 + 0.01)` (the metric of docs/performance.md#denoising-render---denoise);
/// non-finite pixels count as black.
pub fn relative_mse(image: &Film, reference: &Film) -> f64 {
    debug_assert_eq!(image.pixels.len(), reference.pixels.len());
    let floor = f64::from(dormant::render::AdaptiveSampling::DARK_FLOOR).powi(2);
    let sum: f64 = image
        .pixels
        .iter()
        .zip(&reference.pixels)
        .flat_map(|(p, q)| (0..3).map(move |c| (p[c], q[c])))
        .map(|(x, r)| {
            let (x, r) = (if x.is_finite() { f64::from(x) } else { 0.0 }, f64::from(r));
            (x - r).powi(2) / (r * r + floor)
        })
        .sum();
    sum / (3 * image.pixels.len().max(1)) as f64
}

/// Reads an EXR written by `render --exr` as a film.
fn read_exr(path: &std::path::Path) -> Option<Film> {
    let img = image::open(path).ok()?.to_rgb32f();
    let pixels = img.pixels().map(|p| glam::Vec3::from_array(p.0)).collect();
    Some(Film { width: img.width(), height: img.height(), pixels })
}

/// The reference image: read from `opts.reference` when it holds one of the right size, else
/// rendered by `render` (and written there).
fn reference_film(
    opts: &AdaptiveBenchOptions,
    render: impl FnOnce() -> Result<(Film, RenderStats), RenderError>,
    log: &mut dyn FnMut(&str),
) -> Result<(Film, Option<f64>), RenderError> {
    let cached = opts
        .reference
        .as_deref()
        .and_then(read_exr)
        .filter(|f| (f.width, f.height) == (opts.width, opts.height));
    if let Some(film) = cached {
        return Ok((film, None));
    }
    log(&format!("reference, {} spp", opts.reference_spp));
    let (film, stats) = render()?;
    if let Some(path) = &opts.reference {
        dormant::render::write_exr_atomic(&film, path)?;
    }
    Ok((film, Some(stats.seconds)))
}

pub fn bench_adaptive(
    desc: &SceneDescription,
    opts: &AdaptiveBenchOptions,
    threads: Option<usize>,
    log: &mut dyn FnMut(&str),
) -> Result<AdaptiveBenchReport, RenderError> {
    let mut accel = accel::create(opts.backend, threads)?;
    let scene = RenderScene::build(desc, accel.as_mut())?;
    let query = accel.query()?;
    let integrator = PathTracer { max_depth: opts.max_depth, ..PathTracer::default() };
    let base = RenderSettings::new(opts.width, opts.height, 1);
    let settings = |spp, seed, adaptive| RenderSettings { spp, seed, adaptive, ..base };
    let reference =
        || render_frame(&scene, query, &integrator, &settings(opts.reference_spp, 1, AdaptiveSampling::OFF));
    let (reference, reference_seconds) = reference_film(opts, reference, log)?;
    let guides: &[Aov] = if opts.denoiser.is_some() { &dormant::render::denoise::GUIDE_AOVS } else { &[] };
    let uniform = opts.uniform_spp.iter().map(|&spp| (spp, AdaptiveSampling::OFF));
    let adaptive = opts
        .thresholds
        .iter()
        .map(|&t| (opts.adaptive_spp, AdaptiveSampling { noise_threshold: t, min_spp: opts.min_spp }));
    let mut rows = Vec::new();
    for (spp, sampling) in uniform.chain(adaptive) {
        log(&format!("spp {spp}, threshold {}", sampling.noise_threshold));
        let (film, stats, aovs) =
            render_with_aovs(&scene, query, &integrator, &settings(spp, 0, sampling), guides)?;
        let denoised_relative_mse = match &opts.denoiser {
            None => None,
            Some(d) => {
                let (denoised, _) = d
                    .denoise(&film, &aovs[0].1, &aovs[1].1)
                    .map_err(|e| RenderError::Scene { scene: desc.name.clone(), what: e.to_string() })?;
                Some(relative_mse(&denoised, &reference))
            }
        };
        rows.push(AdaptiveRow {
            sampling: if sampling.is_on() { "adaptive" } else { "uniform" },
            spp,
            noise_threshold: sampling.noise_threshold,
            spp_mean: stats.spp.mean,
            spp_min: stats.spp.min,
            spp_max: stats.spp.max,
            relative_mse: relative_mse(&film, &reference),
            denoised_relative_mse,
            trace_seconds: stats.seconds,
        });
    }
    let equal_error = equal_error(&rows);
    Ok(AdaptiveBenchReport {
        scene: desc.name.clone(),
        backend: opts.backend,
        width: opts.width,
        height: opts.height,
        reference_spp: opts.reference_spp,
        reference_seconds,
        min_spp: AdaptiveSampling { noise_threshold: 1.0, min_spp: opts.min_spp }.min_spp(opts.adaptive_spp),
        floor: dormant::render::AdaptiveSampling::DARK_FLOOR,
        denoise: opts.denoiser.as_ref().map(Denoiser::label),
        rows,
        equal_error,
    })
}

/// For each uniform row, the adaptive threshold and mean samples at the same error,
/// interpolated log-log between the two adaptive rows around it.
fn equal_error(rows: &[AdaptiveRow]) -> Vec<EqualError> {
    let mut adaptive: Vec<&AdaptiveRow> = rows.iter().filter(|r| r.sampling == "adaptive").collect();
    adaptive.sort_by(|a, b| a.relative_mse.total_cmp(&b.relative_mse));
    rows.iter()
        .filter(|r| r.sampling == "uniform")
        .map(|u| {
            let bracket = adaptive
                .windows(2)
                .find(|w| w[0].relative_mse <= u.relative_mse && u.relative_mse <= w[1].relative_mse);
            let (threshold, spp) = match bracket {
                Some([lo, hi]) => {
                    let t = if hi.relative_mse > lo.relative_mse {
                        (u.relative_mse.ln() - lo.relative_mse.ln())
                            / (hi.relative_mse.ln() - lo.relative_mse.ln())
                    } else {
                        0.0
                    };
                    let lerp = |a: f64, b: f64| (a.ln() + t * (b.ln() - a.ln())).exp();
                    (
                        Some(lerp(f64::from(lo.noise_threshold), f64::from(hi.noise_threshold))),
                        Some(lerp(lo.spp_mean, hi.spp_mean)),
                    )
                }
                _ => (None, None),
            };
            EqualError {
                uniform_spp: u.spp,
                relative_mse: u.relative_mse,
                adaptive_threshold: threshold,
                adaptive_spp_mean: spp,
                sample_ratio: spp.map(|s| f64::from(u.spp) / s),
            }
        })
        .collect()
}
