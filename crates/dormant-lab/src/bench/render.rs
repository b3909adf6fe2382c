//! `dormant bench render`: ray throughput per ray type and full path-traced frames, for every
//! compiled backend on one scene in one process.
//!
//! - **rays**: three ray sets made once from the scene's camera and traced by every backend:
//!   camera rays (one per pixel, closest hit), shadow rays (from each camera hit towards a
//!   point on the sun's disc, any hit) and bounce rays (cosine-distributed from each camera
//!   hit, closest hit); rayon over all cores, best of N runs;
//! - **packets**: the camera and shadow rays regrouped by pixel tiles (2x2, 4x2, 8x1, 4x4),
//!   traced one by one and as packets ([`SceneQuery::intersect_packet`]) on the same rays in
//!   the same order, runs interleaved, with the packet-over-single ratio;
//! - **frame**: a whole frame of the path tracer (as `dormant render`, camera rays in packets),
//!   and the same frame through single rays only, runs interleaved, best of N runs each, as
//!   samples per second and the integrator's rays per second (all types together);
//! - **bare frame rays**: the frame's own rays, recorded in an untimed render and traced again
//!   with no shading in between ([`super::frame_rays`]); the frame's Mrays/s over theirs is
//!   the share of the frame spent tracing.

use glam::Vec2;
use rayon::prelude::*;
use serde::Serialize;

use super::frame_rays::{trace_bare, BareFrameRays, FrameRays, RecordingQuery};
use super::timed;
use crate::crosscheck::camera_rays;
use dormant::accel::{self, AccelError, Accelerator, Backend, SceneQuery};
use dormant::geometry::Ray;
use dormant::render::{
    render_frame, sample_cone, sample_cosine, PathTracer, RenderError, RenderScene, RenderSettings,
};
use dormant::rng::SplitMix64;
use dormant::scene::SceneDescription;

pub struct RenderBenchOptions {
    /// Size of the rendered frame, and of the camera ray set (one ray per pixel).
    pub width: u32,
    pub height: u32,
    /// Samples per pixel of the rendered frame.
    pub spp: u32,
    /// Repetitions of each measurement (the best is kept).
    pub runs: u32,
    pub threads: Option<usize>,
    /// Embree's scenes in robust mode (`RTC_SCENE_FLAG_ROBUST`: a watertight triangle test
    /// and conservative box tests, the guarantees the BVH always gives), for comparing like
    /// for like. Off: Embree as dormant renders with it.
    pub embree_robust: bool,
}

impl Default for RenderBenchOptions {
    fn default() -> Self {
        Self { width: 640, height: 360, spp: 4, runs: 3, threads: None, embree_robust: false }
    }
}

/// The accelerator `backend` is measured with: dormant's own configuration, or Embree's in
/// robust mode when asked.
fn accel_for(backend: Backend, opts: &RenderBenchOptions) -> Result<Box<dyn Accelerator>, AccelError> {
    #[cfg(feature = "embree")]
    if backend == Backend::Embree && opts.embree_robust {
        use dormant::accel::embree::EmbreeBuildParams;
        return super::embree_with(
            EmbreeBuildParams { robust: true, ..EmbreeBuildParams::DEFAULT },
            opts.threads,
        );
    }
    accel::create(backend, opts.threads)
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

impl FrameTiming {
    fn new(ms: f64, samples: f64, rays: u64) -> Self {
        Self {
            ms,
            samples_per_s: samples / ms.max(1e-9) * 1e3,
            mrays_per_s: rays as f64 / ms.max(1e-9) / 1e3,
            rays,
        }
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct BackendRenderTiming {
    pub backend: Backend,
    /// Loading the scene and committing it.
    pub build_ms: f64,
    pub camera: RayTiming,
    pub shadow: RayTiming,
    pub bounce: RayTiming,
    pub packets: PacketTimings,
    pub frame: FrameTiming,
    /// The same frame with every ray traced alone (packet queries fall back to the per-ray
    /// loop): what packets of camera rays gain on a whole frame.
    pub frame_single_rays: FrameTiming,
    /// The frame's rays traced again without the renderer (runs interleaved with the frames).
    pub bare_frame_rays: BareFrameRays,
    /// The frame's Mrays/s over the bare trace's of the same rays: the share of the frame
    /// spent tracing (the target: at least 0.5).
    pub frame_over_bare_rays: f64,
}

/// One ray set grouped by one pixel tile, traced ray by ray and as packets.
#[derive(Clone, Debug, Serialize)]
pub struct PacketTiming {
    /// Pixels per packet, columns x rows (shadow packets hold only the tile's pixels that
    /// have a shadow ray).
    pub tile: String,
    pub packets: usize,
    pub single: RayTiming,
    pub packet: RayTiming,
    /// Packet over single-ray throughput: above 1 means packets pay.
    pub packet_over_single: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct PacketTimings {
    pub camera: Vec<PacketTiming>,
    pub shadow: Vec<PacketTiming>,
}

/// BVH over Embree: ratios of throughput (Mrays/s or samples/s), so below 1 means the BVH is
/// slower. Absent (null) when Embree is not compiled in.
#[derive(Clone, Debug, Serialize)]
pub struct RenderRatios {
    pub bvh_over_embree_camera: Option<f64>,
    pub bvh_over_embree_shadow: Option<f64>,
    pub bvh_over_embree_bounce: Option<f64>,
    pub bvh_over_embree_frame_samples: Option<f64>,
    /// Embree's frame with camera-ray packets over the same frame in single rays.
    pub embree_frame_packets_over_single: Option<f64>,
    /// The same for the BVH (its own packets, `accel/bvh/flat/packet.rs`).
    pub bvh_frame_packets_over_single: Option<f64>,
}

#[derive(Clone, Debug, Serialize)]
pub struct RenderBenchReport {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub runs: u32,
    pub threads: usize,
    /// Whether Embree ran in robust mode ([`RenderBenchOptions::embree_robust`]).
    pub embree_robust: bool,
    pub backends: Vec<BackendRenderTiming>,
    pub ratios: RenderRatios,
}

/// The three ray sets, made from the camera hits of the first backend.
struct RaySets {
    width: u32,
    height: u32,
    /// Row-major, one per pixel.
    camera: Vec<Ray>,
    shadow: Vec<Ray>,
    /// The pixel (row-major index) each shadow ray belongs to.
    shadow_pixel: Vec<u32>,
    bounce: Vec<Ray>,
}

/// Pixel tiles (columns, rows) the packet measurement groups rays by.
const PACKET_TILES: [(u32, u32); 4] = [(2, 2), (4, 2), (8, 1), (4, 4)];

/// A ray set regrouped into packets of neighbouring pixels: packet `k` is
/// `rays[ranges[k].0..ranges[k].1]`.
struct Packets {
    rays: Vec<Ray>,
    ranges: Vec<(usize, usize)>,
}

impl Packets {
    /// Groups `rays` (with `pixel[i]` the row-major pixel of `rays[i]`) by `tile`-sized pixel
    /// tiles, tiles in row-major order, pixels row-major within a tile.
    fn by_tiles(
        rays: &[Ray],
        pixel: impl Fn(usize) -> u32,
        width: u32,
        height: u32,
        tile: (u32, u32),
    ) -> Self {
        let mut of_pixel = vec![None; (width * height) as usize];
        for i in 0..rays.len() {
            of_pixel[pixel(i) as usize] = Some(i);
        }
        let (mut out, mut ranges) = (Vec::with_capacity(rays.len()), Vec::new());
        for ty in (0..height).step_by(tile.1 as usize) {
            for tx in (0..width).step_by(tile.0 as usize) {
                let start = out.len();
                for y in ty..(ty + tile.1).min(height) {
                    for x in tx..(tx + tile.0).min(width) {
                        out.extend(of_pixel[(y * width + x) as usize].map(|i| rays[i]));
                    }
                }
                if out.len() > start {
                    ranges.push((start, out.len()));
                }
            }
        }
        Self { rays: out, ranges }
    }
}

impl RaySets {
    fn new(desc: &SceneDescription, query: &dyn SceneQuery, width: u32, height: u32) -> Self {
        let camera = camera_rays(desc, width, height);
        let hits: Vec<_> =
            camera.par_iter().map(|r| query.intersect(r).map(|h| (r.at(h.t), h.ng, r.dir))).collect();
        let mut rng = SplitMix64::new(11);
        let cos_max = desc.sun.angular_radius_deg.max(0.01).to_radians().cos();
        let (mut shadow, mut shadow_pixel, mut bounce) = (Vec::new(), Vec::new(), Vec::new());
        for (pixel, hit) in hits.into_iter().enumerate() {
            let Some((p, ng, dir)) = hit else { continue };
            let n = if ng.dot(dir) > 0.0 { -ng } else { ng };
            let l = sample_cone(desc.sun.direction, cos_max, Vec2::new(rng.unit(), rng.unit()));
            if n.dot(l) > 0.0 {
                shadow.push(Ray::spawn(p, n, l));
                shadow_pixel.push(pixel as u32);
            }
            bounce.push(Ray::spawn(p, n, sample_cosine(n, Vec2::new(rng.unit(), rng.unit()))));
        }
        Self { width, height, camera, shadow, shadow_pixel, bounce }
    }
}

/// Forwards the single-ray queries only, so packet queries take the trait's per-ray loop:
/// the renderer without packets, for the side-by-side frame timing.
struct SingleRays<'a>(&'a dyn SceneQuery);

impl SceneQuery for SingleRays<'_> {
    fn intersect(&self, ray: &Ray) -> Option<dormant::accel::Hit> {
        self.0.intersect(ray)
    }

    fn intersect_p(&self, ray: &Ray) -> bool {
        self.0.intersect_p(ray)
    }
}

/// Best time in ms of `runs` runs of `f` (at least one).
fn best_of(runs: u32, mut f: impl FnMut() -> f64) -> f64 {
    (0..runs.max(1)).map(|_| f()).fold(f64::INFINITY, f64::min)
}

/// A backend's frame with camera-ray packets over the same frame in single rays.
fn frame_packets_over_single(t: &BackendRenderTiming) -> f64 {
    t.frame.samples_per_s / t.frame_single_rays.samples_per_s.max(1e-12)
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

/// Closest hits (`closest`) or occlusion of every packet, ray by ray or as packets, over
/// rayon with one packet per work item either way.
fn trace_packets(query: &dyn SceneQuery, packets: &Packets, closest: bool, as_packets: bool) -> f64 {
    let (sum, ms) = timed(|| {
        packets
            .ranges
            .par_iter()
            .map(|&(a, b)| {
                let rays = &packets.rays[a..b];
                let (mut hits, mut occluded) = ([None; 16], [false; 16]);
                let mut sum = 0.0;
                for (rays, hits) in rays.chunks(16).zip(hits.chunks_mut(16)) {
                    let hits = &mut hits[..rays.len()];
                    let occluded = &mut occluded[..rays.len()];
                    match (closest, as_packets) {
                        (true, true) => query.intersect_packet(rays, hits),
                        (true, false) => hits.iter_mut().zip(rays).for_each(|(h, r)| *h = query.intersect(r)),
                        (false, true) => query.intersect_p_packet(rays, occluded),
                        (false, false) => {
                            occluded.iter_mut().zip(rays).for_each(|(o, r)| *o = query.intersect_p(r))
                        }
                    }
                    sum += hits.iter().map(|h| h.map_or(0.0, |h| h.t as f64)).sum::<f64>();
                    sum += occluded.iter().filter(|&&o| o).count() as f64;
                }
                sum
            })
            .sum::<f64>()
    });
    std::hint::black_box(sum);
    ms
}

/// Single rays against packets on every tile shape, runs interleaved so load changes hit both.
fn bench_packets(query: &dyn SceneQuery, sets: &RaySets, runs: u32) -> PacketTimings {
    let measure = |rays: &[Ray], pixel: &dyn Fn(usize) -> u32, closest: bool| {
        PACKET_TILES
            .iter()
            .map(|&tile| {
                let packets = Packets::by_tiles(rays, pixel, sets.width, sets.height, tile);
                let (mut single, mut packet) = (f64::INFINITY, f64::INFINITY);
                for _ in 0..runs.max(1) {
                    single = single.min(trace_packets(query, &packets, closest, false));
                    packet = packet.min(trace_packets(query, &packets, closest, true));
                }
                let (single, packet) =
                    (RayTiming::new(packets.rays.len(), single), RayTiming::new(packets.rays.len(), packet));
                PacketTiming {
                    tile: format!("{}x{}", tile.0, tile.1),
                    packets: packets.ranges.len(),
                    packet_over_single: packet.mrays_per_s / single.mrays_per_s.max(1e-12),
                    single,
                    packet,
                }
            })
            .collect()
    };
    PacketTimings {
        camera: measure(&sets.camera, &|i| i as u32, true),
        shadow: measure(&sets.shadow, &|i| sets.shadow_pixel[i], false),
    }
}

/// Best times of one path-traced frame: as the renderer traces it (camera rays in packets),
/// through single rays only, and its own rays traced bare.
struct FrameTimes {
    rays: u64,
    frame_ms: f64,
    single_ms: f64,
    bare_ms: f64,
    frame_rays: FrameRays,
}

/// Records the frame's rays once (untimed), then times the three forms, runs interleaved so
/// load changes hit all of them.
fn time_frames(
    scene: &RenderScene,
    query: &dyn SceneQuery,
    settings: &RenderSettings,
    runs: u32,
) -> Result<FrameTimes, RenderError> {
    let integrator = PathTracer::default();
    let recorder = RecordingQuery::new(query);
    render_frame(scene, &recorder, &integrator, settings)?;
    let frame_rays = recorder.into_rays();
    let (mut rays, mut frame_ms, mut single_ms, mut bare_ms) =
        (0, f64::INFINITY, f64::INFINITY, f64::INFINITY);
    for _ in 0..runs.max(1) {
        let (_, stats) = render_frame(scene, query, &integrator, settings)?;
        (rays, frame_ms) = (stats.rays, frame_ms.min(stats.seconds * 1e3));
        let (_, stats) = render_frame(scene, &SingleRays(query), &integrator, settings)?;
        single_ms = single_ms.min(stats.seconds * 1e3);
        bare_ms = bare_ms.min(trace_bare(query, &frame_rays));
    }
    debug_assert_eq!(frame_rays.len() as u64, rays, "the recorder saw every ray the frame counted");
    Ok(FrameTimes { rays, frame_ms, single_ms, bare_ms, frame_rays })
}

impl RenderRatios {
    /// The BVH against Embree, and each backend's packets against single rays, from their
    /// timings (`None` where a backend is missing).
    fn of(backends: &[BackendRenderTiming]) -> Self {
        let find = |b: Backend| backends.iter().find(|t| t.backend == b);
        let ratio = |f: fn(&BackendRenderTiming) -> f64| match (find(Backend::Bvh), find(Backend::Embree)) {
            (Some(bvh), Some(embree)) if f(embree) > 0.0 => Some(f(bvh) / f(embree)),
            _ => None,
        };
        RenderRatios {
            bvh_over_embree_camera: ratio(|t| t.camera.mrays_per_s),
            bvh_over_embree_shadow: ratio(|t| t.shadow.mrays_per_s),
            bvh_over_embree_bounce: ratio(|t| t.bounce.mrays_per_s),
            bvh_over_embree_frame_samples: ratio(|t| t.frame.samples_per_s),
            embree_frame_packets_over_single: find(Backend::Embree).map(frame_packets_over_single),
            bvh_frame_packets_over_single: find(Backend::Bvh).map(frame_packets_over_single),
        }
    }
}

pub fn bench_render(
    desc: &SceneDescription,
    opts: &RenderBenchOptions,
) -> Result<RenderBenchReport, RenderError> {
    let settings = RenderSettings::new(opts.width, opts.height, opts.spp);
    settings.validate()?;
    let mut sets: Option<RaySets> = None;
    let mut backends = Vec::new();
    for backend in Backend::compiled() {
        let mut accel = accel_for(backend, opts)?;
        let (scene, build_ms) = timed(|| RenderScene::build(desc, accel.as_mut()));
        let scene = scene?;
        let query = accel.query()?;
        tracing::info!("bench render: {backend} built in {build_ms:.1} ms");
        let sets = sets.get_or_insert_with(|| RaySets::new(desc, query, opts.width, opts.height));
        let camera = best_of(opts.runs, || trace_closest(query, &sets.camera));
        let shadow = best_of(opts.runs, || trace_any(query, &sets.shadow));
        let bounce = best_of(opts.runs, || trace_closest(query, &sets.bounce));
        let packets = bench_packets(query, sets, opts.runs);
        let frames = time_frames(&scene, query, &settings, opts.runs)?;
        let (rays, frame_ms, single_ms, bare_ms) =
            (frames.rays, frames.frame_ms, frames.single_ms, frames.bare_ms);
        let frame_rays = &frames.frame_rays;
        let samples = opts.width as f64 * opts.height as f64 * opts.spp as f64;
        tracing::info!(
            "bench render: {backend} frame in {frame_ms:.1} ms ({single_ms:.1} ms in single rays)"
        );
        backends.push(BackendRenderTiming {
            backend,
            build_ms,
            camera: RayTiming::new(sets.camera.len(), camera),
            shadow: RayTiming::new(sets.shadow.len(), shadow),
            bounce: RayTiming::new(sets.bounce.len(), bounce),
            packets,
            frame: FrameTiming::new(frame_ms, samples, rays),
            frame_single_rays: FrameTiming::new(single_ms, samples, rays),
            bare_frame_rays: BareFrameRays::new(frame_rays, bare_ms),
            frame_over_bare_rays: bare_ms / frame_ms.max(1e-9),
        });
    }
    let ratios = RenderRatios::of(&backends);
    Ok(RenderBenchReport {
        scene: desc.name.clone(),
        width: opts.width,
        height: opts.height,
        spp: opts.spp,
        runs: opts.runs.max(1),
        threads: opts.threads.unwrap_or_else(rayon::current_num_threads),
        embree_robust: opts.embree_robust && Backend::Embree.is_compiled(),
        backends,
        ratios,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_compiled_backend_is_measured_on_the_same_rays() {
        let desc = dormant::scene::default_scene();
        let opts =
            RenderBenchOptions { width: 24, height: 16, spp: 1, runs: 1, ..RenderBenchOptions::default() };
        let report = bench_render(&desc, &opts).unwrap();
        let measured: Vec<Backend> = report.backends.iter().map(|b| b.backend).collect();
        assert_eq!(measured, Backend::compiled());
        for b in &report.backends {
            assert_eq!(b.camera.rays, 24 * 16);
            assert_eq!(b.shadow.rays, report.backends[0].shadow.rays);
            assert_eq!(b.bounce.rays, report.backends[0].bounce.rays);
            assert!(b.frame.samples_per_s.is_finite() && b.frame.samples_per_s > 0.0);
            let tiles: Vec<&str> = b.packets.camera.iter().map(|p| p.tile.as_str()).collect();
            assert_eq!(tiles, ["2x2", "4x2", "8x1", "4x4"]);
            for (camera, shadow) in b.packets.camera.iter().zip(&b.packets.shadow) {
                assert_eq!(camera.packet.rays, 24 * 16);
                assert_eq!(shadow.single.rays, b.shadow.rays);
                assert!(camera.packet_over_single.is_finite() && camera.packet_over_single > 0.0);
            }
            assert_eq!(b.packets.camera[3].packets, 6 * 4);
        }
        assert_eq!(report.ratios.bvh_over_embree_frame_samples.is_some(), Backend::Embree.is_compiled());
    }

    #[test]
    fn invalid_size_is_an_error_not_a_panic() {
        let desc = dormant::scene::default_scene();
        let opts = RenderBenchOptions { width: 0, ..RenderBenchOptions::default() };
        assert!(matches!(bench_render(&desc, &opts), Err(RenderError::InvalidSize(_))));
    }
}
