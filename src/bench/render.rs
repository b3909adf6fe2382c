//! `dormant bench render`: ray throughput per ray type and full path-traced frames, for every
//! compiled backend on one scene in one process.
//!
//! - **rays**: three ray sets made once from the scene's camera and traced by every backend:
//!   camera rays (one per pixel, closest hit), shadow rays (from each camera hit towards a
//!   point on the sun's disc, any hit) and bounce rays (cosine-distributed from each camera
//!   hit, closest hit); rayon over all cores, best of N runs;
//! - **frame**: a whole frame of the path tracer (as `dormant render`), best of N runs, as
//!   samples per second and the integrator's rays per second (all types together).

use glam::Vec2;
use rayon::prelude::*;
use serde::Serialize;

use super::timed;
use crate::accel::{self, Backend, SceneQuery};
use crate::crosscheck::camera_rays;
use crate::geometry::Ray;
use crate::render::{
    render_frame, sample_cone, sample_cosine, PathTracer, RenderError, RenderScene, RenderSettings,
};
use crate::rng::SplitMix64;
use crate::scene::SceneDescription;

pub struct RenderBenchOptions {
    /// Size of the rendered frame, and of the camera ray set (one ray per pixel).
    pub width: u32,
    pub height: u32,
    /// Samples per pixel of the rendered frame.
    pub spp: u32,
    /// Repetitions of each measurement (the best is kept).
    pub runs: u32,
    pub threads: Option<usize>,
}

impl Default for RenderBenchOptions {
    fn default() -> Self {
        Self { width: 640, height: 360, spp: 4, runs: 3, threads: None }
    }
}

/// One ray set traced by one backend.
#[derive(Clone, Debug, Serialize)]
pub struct RayTiming {
    pub rays: usize,
    pub ms: f64,
    pub mrays_per_s: f64,
}

impl RayTiming {
    fn new(rays: usize, ms: f64) -> Self {
        Self { rays, ms, mrays_per_s: rays as f64 / ms.max(1e-9) / 1e3 }
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct FrameTiming {
    pub ms: f64,
    /// Camera samples (pixels times spp) per second.
    pub samples_per_s: f64,
    /// Every ray the path tracer traced (camera, shadow and bounce), per second.
    pub mrays_per_s: f64,
    pub rays: u64,
}

#[derive(Clone, Debug, Serialize)]
pub struct BackendRenderTiming {
    pub backend: Backend,
    /// Loading the scene and committing it.
    pub build_ms: f64,
    pub camera: RayTiming,
    pub shadow: RayTiming,
    pub bounce: RayTiming,
    pub frame: FrameTiming,
}

/// BVH over Embree: ratios of throughput (Mrays/s or samples/s), so below 1 means the BVH is
/// slower. Absent (null) when Embree is not compiled in.
#[derive(Clone, Debug, Serialize)]
pub struct RenderRatios {
    pub bvh_over_embree_camera: Option<f64>,
    pub bvh_over_embree_shadow: Option<f64>,
    pub bvh_over_embree_bounce: Option<f64>,
    pub bvh_over_embree_frame_samples: Option<f64>,
}

#[derive(Clone, Debug, Serialize)]
pub struct RenderBenchReport {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub runs: u32,
    pub threads: usize,
    pub backends: Vec<BackendRenderTiming>,
    pub ratios: RenderRatios,
}

/// The three ray sets, made from the camera hits of the first backend.
struct RaySets {
    camera: Vec<Ray>,
    shadow: Vec<Ray>,
    bounce: Vec<Ray>,
}

impl RaySets {
    fn new(desc: &SceneDescription, query: &dyn SceneQuery, width: u32, height: u32) -> Self {
        let camera = camera_rays(desc, width, height);
        let hits: Vec<_> =
            camera.par_iter().map(|r| query.intersect(r).map(|h| (r.at(h.t), h.ng, r.dir))).collect();
        let mut rng = SplitMix64::new(11);
        let cos_max = desc.sun.angular_radius_deg.max(0.01).to_radians().cos();
        let (mut shadow, mut bounce) = (Vec::new(), Vec::new());
        for (p, ng, dir) in hits.into_iter().flatten() {
            let n = if ng.dot(dir) > 0.0 { -ng } else { ng };
            let l = sample_cone(desc.sun.direction, cos_max, Vec2::new(rng.unit(), rng.unit()));
            if n.dot(l) > 0.0 {
                shadow.push(Ray::spawn(p, n, l));
            }
            bounce.push(Ray::spawn(p, n, sample_cosine(n, Vec2::new(rng.unit(), rng.unit()))));
        }
        Self { camera, shadow, bounce }
    }
}

/// Best time in ms of `runs` runs of `f` (at least one).
fn best_of(runs: u32, mut f: impl FnMut() -> f64) -> f64 {
    (0..runs.max(1)).map(|_| f()).fold(f64::INFINITY, f64::min)
}

/// Closest hits of `rays` over rayon; the checksum keeps the work from being optimised away.
fn trace_closest(query: &dyn SceneQuery, rays: &[Ray]) -> f64 {
    let (sum, ms) =
        timed(|| rays.par_iter().map(|r| query.intersect(r).map_or(0.0, |h| h.t as f64)).sum::<f64>());
    std::hint::black_box(sum);
    ms
}

/// Occlusion tests of `rays` over rayon.
fn trace_any(query: &dyn SceneQuery, rays: &[Ray]) -> f64 {
    let (blocked, ms) = timed(|| rays.par_iter().filter(|r| query.intersect_p(r)).count());
    std::hint::black_box(blocked);
    ms
}

pub fn bench_render(
    desc: &SceneDescription,
    opts: &RenderBenchOptions,
) -> Result<RenderBenchReport, RenderError> {
    let settings = RenderSettings { width: opts.width, height: opts.height, spp: opts.spp, frame: 0 };
    settings.validate()?;
    let integrator = PathTracer::default();
    let mut sets: Option<RaySets> = None;
    let mut backends = Vec::new();
    for backend in Backend::compiled() {
        let mut accel = accel::create(backend, opts.threads)?;
        let (scene, build_ms) = timed(|| RenderScene::build(desc, accel.as_mut()));
        let scene = scene?;
        let query = accel.query()?;
        tracing::info!("bench render: {backend} built in {build_ms:.1} ms");
        let sets = sets.get_or_insert_with(|| RaySets::new(desc, query, opts.width, opts.height));
        let camera = best_of(opts.runs, || trace_closest(query, &sets.camera));
        let shadow = best_of(opts.runs, || trace_any(query, &sets.shadow));
        let bounce = best_of(opts.runs, || trace_closest(query, &sets.bounce));
        let mut rays = 0;
        let mut frame_err = None;
        let frame_ms = best_of(opts.runs, || match render_frame(&scene, query, &integrator, &settings) {
            Ok((_, stats)) => {
                rays = stats.rays;
                stats.seconds * 1e3
            }
            Err(e) => {
                frame_err = Some(e);
                f64::INFINITY
            }
        });
        if let Some(e) = frame_err {
            return Err(e);
        }
        let samples = opts.width as f64 * opts.height as f64 * opts.spp as f64;
        tracing::info!("bench render: {backend} frame in {frame_ms:.1} ms");
        backends.push(BackendRenderTiming {
            backend,
            build_ms,
            camera: RayTiming::new(sets.camera.len(), camera),
            shadow: RayTiming::new(sets.shadow.len(), shadow),
            bounce: RayTiming::new(sets.bounce.len(), bounce),
            frame: FrameTiming {
                ms: frame_ms,
                samples_per_s: samples / frame_ms.max(1e-9) * 1e3,
                mrays_per_s: rays as f64 / frame_ms.max(1e-9) / 1e3,
                rays,
            },
        });
    }
    let find = |b: Backend| backends.iter().find(|t| t.backend == b);
    let ratio = |f: fn(&BackendRenderTiming) -> f64| match (find(Backend::Bvh), find(Backend::Embree)) {
        (Some(bvh), Some(embree)) if f(embree) > 0.0 => Some(f(bvh) / f(embree)),
        _ => None,
    };
    let ratios = RenderRatios {
        bvh_over_embree_camera: ratio(|t| t.camera.mrays_per_s),
        bvh_over_embree_shadow: ratio(|t| t.shadow.mrays_per_s),
        bvh_over_embree_bounce: ratio(|t| t.bounce.mrays_per_s),
        bvh_over_embree_frame_samples: ratio(|t| t.frame.samples_per_s),
    };
    Ok(RenderBenchReport {
        scene: desc.name.clone(),
        width: opts.width,
        height: opts.height,
        spp: opts.spp,
        runs: opts.runs.max(1),
        threads: opts.threads.unwrap_or_else(rayon::current_num_threads),
        backends,
        ratios,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_compiled_backend_is_measured_on_the_same_rays() {
        let desc = crate::scene::default_scene();
        let opts = RenderBenchOptions { width: 24, height: 16, spp: 1, runs: 1, threads: None };
        let report = bench_render(&desc, &opts).unwrap();
        let measured: Vec<Backend> = report.backends.iter().map(|b| b.backend).collect();
        assert_eq!(measured, Backend::compiled());
        for b in &report.backends {
            assert_eq!(b.camera.rays, 24 * 16);
            assert_eq!(b.shadow.rays, report.backends[0].shadow.rays);
            assert_eq!(b.bounce.rays, report.backends[0].bounce.rays);
            assert!(b.frame.samples_per_s.is_finite() && b.frame.samples_per_s > 0.0);
        }
        assert_eq!(report.ratios.bvh_over_embree_frame_samples.is_some(), Backend::Embree.is_compiled());
    }

    #[test]
    fn invalid_size_is_an_error_not_a_panic() {
        let desc = crate::scene::default_scene();
        let opts = RenderBenchOptions { width: 0, ..RenderBenchOptions::default() };
        assert!(matches!(bench_render(&desc, &opts), Err(RenderError::InvalidSize { .. })));
    }
}
