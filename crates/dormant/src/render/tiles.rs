//! One frame from camera to film: camera rays per pixel sample (placed by the pixel filter), 16x16 tiles over
//! rayon, camera rays of each pixel block traced as one packet, the integrator bound to the
//! frame finishing each sample, and the AOV passes shaded at the camera hits.

use std::time::Instant;

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::adaptive::{AdaptiveSampling, SppStats, Stopping};
use super::aov::{aov_at_hit, AovPasses};
use super::integrator::dims;
use super::{
    Aov, Film, FrameContext, FrameIntegrator, Integrator, PinholeCamera, PixelFilter, PixelSampler, RayLog,
    RenderError, RenderScene,
};
use crate::accel::bvh::ChangeIndex;
use crate::accel::{Hit, SceneQuery};
use crate::geometry::Ray;
use crate::scene::limits::{image_size_problem, MAX_SAMPLES_PER_PIXEL};

/// Side of the square tiles rayon distributes.
const TILE: u32 = 16;

/// Pixel block whose camera rays (one sample each) are traced together as one packet
/// ([`SceneQuery::intersect_packet`]) before each pixel's integrator continues alone: 8 rays,
/// the AVX2 width. Embree traces 4x2 camera packets 1.3-3.4x as fast as single rays; whole
/// path-traced frames gain a few percent to 10%, camera rays being one in 4-5 of their rays:
/// docs/lab/rendering.md#2026-11-22-ray-packets-on-embree-rtcintersect4816-rtcoccluded4816
const BLOCK: (u32, u32) = (4, 2);
const BLOCK_PIXELS: usize = (BLOCK.0 * BLOCK.1) as usize;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    /// Samples per pixel; with adaptive sampling, the most a pixel gets.
    pub spp: u32,
    /// Seeds the pixel sampler: a sequence passes the frame number so consecutive frames
    /// decorrelate, or one value for every frame (`--seed fixed`).
    pub seed: u32,
    /// When a pixel may stop before `spp` samples (off: never).
    pub adaptive: AdaptiveSampling,
    /// Where a pixel's samples land around its centre (filter importance sampling).
    pub filter: PixelFilter,
}

impl RenderSettings {
    /// `width` x `height` at `spp` samples per pixel, seed 0, no adaptive sampling, the
    /// default tent filter.
    pub fn new(width: u32, height: u32, spp: u32) -> Self {
        Self { width, height, spp, seed: 0, adaptive: AdaptiveSampling::OFF, filter: PixelFilter::default() }
    }

    /// Checks the size, the samples per pixel and adaptive sampling.
    pub fn validate(&self) -> Result<(), RenderError> {
        if let Some(problem) = image_size_problem(self.width, self.height) {
            return Err(RenderError::InvalidSize(problem));
        }
        if !(1..=MAX_SAMPLES_PER_PIXEL).contains(&self.spp) {
            return Err(RenderError::InvalidSpp);
        }
        self.adaptive.validate(self.spp)
    }
}

#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct RenderStats {
    pub rays: u64,
    pub seconds: f64,
    /// Camera samples per pixel: mean, least and most.
    #[serde(flatten)]
    pub spp: SppStats,
}

impl RenderStats {
    pub fn mrays_per_second(&self) -> f64 {
        self.rays as f64 / self.seconds.max(1e-9) / 1e6
    }

    /// The camera samples of a `width` x `height` image at these samples per pixel.
    pub(crate) fn camera_samples(&self, width: u32, height: u32) -> u64 {
        (self.spp.mean * f64::from(width) * f64::from(height)).round() as u64
    }
}

/// The frame's camera: where it is at shutter open, and at close when the frame is motion
/// blurred (`None`: no blur; `Some(open)` for a camera that stays put over the shutter).
#[derive(Clone, Copy, Debug)]
struct FrameCamera {
    open: PinholeCamera,
    close: Option<PinholeCamera>,
}

/// Sample `i` of pixel `(x, y)`'s camera ray.
fn camera_ray(
    camera: &FrameCamera,
    settings: &RenderSettings,
    x: u32,
    y: u32,
    sampler: &PixelSampler,
    i: u32,
) -> Ray {
    // Filter importance sampling (`PixelFilter`); a single sample goes through the pixel's
    // centre.
    let jitter = if settings.spp == 1 {
        Vec2::splat(0.5)
    } else {
        Vec2::splat(0.5) + settings.filter.sample_offset(sampler.get_2d(i, dims::PIXEL))
    };
    let (px, py) = (x as f32 + jitter.x, y as f32 + jitter.y);
    let lens = |c: &PinholeCamera| through_lens(c, px, py, sampler, i);
    let open = lens(&camera.open);
    let Some(close) = &camera.close else { return open };
    // Motion blur: the sample's time in the shutter; a moving camera's ray is the one between
    // its open and close rays (linear in origin, normalised linear in direction, as its key
    // frames are linear in position and target).
    let time = sampler.get_1d(i, dims::TIME);
    if *close == camera.open {
        return open.at_time(time);
    }
    let close = lens(close);
    let dir = open.dir.lerp(close.dir, time).normalize_or(open.dir);
    Ray::new(open.origin.lerp(close.origin, time), dir).at_time(time)
}

/// Sample `i`'s ray from `camera` through film point `(px, py)`. Kept inline: as a closure the
/// compiler at times called it out of line
/// (docs/lab/reuse.md#2026-12-06-evening-the-previews-update-visits-only-the-bodies-that-changed).
#[inline(always)]
fn through_lens(camera: &PinholeCamera, px: f32, py: f32, sampler: &PixelSampler, i: u32) -> Ray {
    if camera.has_aperture() {
        camera.ray_through_lens(px, py, sampler.get_2d(i, dims::LENS))
    } else {
        camera.ray(px, py)
    }
}

/// Renders one frame with `integrator`, tiles spread over the current rayon pool. Each
/// pixel's samples depend only on (pixel, frame, index), so the image is identical whatever
/// the thread count or tile order.
pub fn render_frame(
    scene: &RenderScene,
    query: &dyn SceneQuery,
    integrator: &dyn Integrator,
    settings: &RenderSettings,
) -> Result<(Film, RenderStats), RenderError> {
    let out = render_planned(scene, query, integrator, settings, &FramePlan::default())?;
    let stats = out.stats();
    Ok((out.film, stats))
}

/// A frame's image with `integrator` and its `aovs` passes, in order. The passes see the
/// image's camera samples: with adaptive sampling, each pixel as many as the image gave it.
pub fn render_with_aovs(
    scene: &RenderScene,
    query: &dyn SceneQuery,
    integrator: &dyn Integrator,
    settings: &RenderSettings,
    aovs: &[Aov],
) -> Result<(Film, RenderStats, AovPasses), RenderError> {
    let traced: Vec<Aov> = aovs.iter().copied().filter(|a| a.is_traced()).collect();
    let plan = FramePlan { aovs: &traced, ..FramePlan::default() };
    let out = render_planned(scene, query, integrator, settings, &plan)?;
    let stats = out.stats();
    let mut shaded = traced.iter().copied().zip(out.aovs);
    let passes = aovs
        .iter()
        .map(|&aov| match aov {
            Aov::Spp | Aov::Traced => (aov, Film::from_counts(settings.width, settings.height, &out.counts)),
            _ => shaded.next().expect("one film per traced pass, in order"),
        })
        .collect();
    Ok((out.film, stats, passes))
}

/// Which of a frame's pixels (or samples) to render, and how. For exact temporal reuse a
/// sample must be traced exactly as a full frame traces it: its camera ray goes in the same
/// packet, with the same neighbours, as in a full frame, so a block with a sample to trace
/// traces that sample's camera packet and continues only the paths of the samples it traces.
#[derive(Clone, Copy, Default)]
pub(crate) struct FramePlan<'a> {
    /// Fixed samples per pixel (row-major) instead of `spp` and adaptive sampling.
    pub samples: Option<&'a [u32]>,
    /// Which samples to trace.
    pub due: Due<'a>,
    /// Find each traced pixel's (or sample's) horizon against this index: the frame's ordinal
    /// and the horizon of what meets no change (the run's number of rendered frames).
    pub horizons: Option<(&'a ChangeIndex, u32, u32)>,
    /// AOV passes shaded at the traced samples' camera hits as they are traced, each pixel
    /// averaged over its traced samples ([`PlannedFrame::aovs`]): a pixel whose every sample
    /// is traced gets the value an [`AovIntegrator`](super::AovIntegrator) pass would give.
    pub aovs: &'a [Aov],
}

impl FramePlan<'_> {
    /// Whether the frame keeps its AOV passes' camera horizons ([`PlannedFrame::camera_horizons`]).
    fn keeps_camera_horizons(&self) -> bool {
        !self.aovs.is_empty() && self.horizons.is_some() && matches!(self.due, Due::Samples { .. })
    }
}

/// Which samples a frame traces (row-major pixels).
#[derive(Clone, Copy, Default)]
pub(crate) enum Due<'a> {
    /// Every sample of every pixel.
    #[default]
    All,
    /// Every sample of the pixels marked; the other pixels take their lanes in the camera
    /// packets from their `stored` sample counts. They come back black with no samples.
    Pixels { due: &'a [bool], stored: &'a [u32] },
    /// The samples whose horizon has come by `ordinal` and those never traced (`pixels`:
    /// whether a pixel has any); the others are taken from `stored`. Traced samples come
    /// back one by one ([`PlannedFrame::samples`]); the pixels with any, as values and counts.
    Samples { stored: StoredSamples<'a>, pixels: &'a [bool], ordinal: u32 },
}

/// The samples kept from earlier frames: `spp` slots per pixel, pixel by pixel.
#[derive(Clone, Copy)]
pub(crate) struct StoredSamples<'a> {
    /// Each slot's radiance and horizon.
    pub values: &'a [Vec3],
    pub horizons: &'a [u32],
    /// Per pixel, how many of its slots hold samples: all but where adaptive sampling stopped
    /// the pixel early.
    pub counts: &'a [u32],
}

/// A planned frame: the traced pixels' values and sample counts and horizons (row-major; zero
/// elsewhere), or with [`Due::Samples`] the traced samples; the rays traced, and what the
/// horizon queries cost.
pub(crate) struct PlannedFrame {
    pub film: Film,
    pub counts: Vec<u32>,
    pub horizons: Vec<u32>,
    /// The plan's AOV passes, in order, over the traced samples.
    pub aovs: Vec<Film>,
    /// With AOV passes, horizons and [`Due::Samples`]: per pixel, the horizon of its traced
    /// samples' camera rays alone (what the passes see).
    pub camera_horizons: Vec<u32>,
    /// With [`Due::Samples`], the traced samples tile by tile: kept apart, since a full
    /// frame's (8.3 M at 960x540, 16 spp) would be copied into ever larger buffers to join.
    pub samples: Vec<Vec<TracedSample>>,
    pub rays: u64,
    pub seconds: f64,
    pub horizon_queries: u64,
    pub horizon_seconds: f64,
}

/// One sample traced under [`Due::Samples`]: its pixel (row-major), index, radiance and
/// horizon.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TracedSample {
    pub pixel: u32,
    pub index: u32,
    pub li: Vec3,
    pub horizon: u32,
}

/// Renders the blocks `plan` selects, tiles spread over the current rayon pool.
pub(crate) fn render_planned(
    scene: &RenderScene,
    query: &dyn SceneQuery,
    integrator: &dyn Integrator,
    settings: &RenderSettings,
    plan: &FramePlan,
) -> Result<PlannedFrame, RenderError> {
    settings.validate()?;
    let start = Instant::now();
    let (w, h) = (settings.width, settings.height);
    debug_assert!(plan.samples.is_none_or(|s| s.len() == (w * h) as usize));
    let renderer = TileRenderer {
        scene,
        camera: FrameCamera {
            open: PinholeCamera::new(&scene.camera, w, h),
            close: scene.camera_close.as_ref().map(|c| PinholeCamera::new(c, w, h)),
        },
        query,
        integrator: &*integrator.bind(FrameContext { scene, query }),
        settings,
        stopping: if plan.samples.is_some() { None } else { settings.adaptive.stopping(settings.spp) },
        plan,
    };
    let tiles_x = w.div_ceil(TILE);
    let tiles: Vec<(u32, u32)> =
        (0..tiles_x * h.div_ceil(TILE)).map(|t| ((t % tiles_x) * TILE, (t / tiles_x) * TILE)).collect();
    let rendered: Vec<(u32, u32, Tile)> =
        tiles.par_iter().map(|&(x0, y0)| (x0, y0, renderer.render(x0, y0))).collect();
    let mut out = PlannedFrame {
        film: Film::new(w, h),
        counts: vec![0; (w * h) as usize],
        horizons: vec![0; (w * h) as usize],
        aovs: plan.aovs.iter().map(|_| Film::new(w, h)).collect(),
        camera_horizons: if plan.keeps_camera_horizons() { vec![0; (w * h) as usize] } else { Vec::new() },
        samples: Vec::new(),
        rays: 0,
        seconds: 0.0,
        horizon_queries: 0,
        horizon_seconds: 0.0,
    };
    for (x0, y0, tile) in rendered {
        out.add_tile(x0, y0, tile);
    }
    out.seconds = start.elapsed().as_secs_f64();
    Ok(out)
}

impl PlannedFrame {
    /// The frame's rays, time and samples per pixel.
    pub(crate) fn stats(&self) -> RenderStats {
        RenderStats { rays: self.rays, seconds: self.seconds, spp: SppStats::of(&self.counts) }
    }

    /// Copies a rendered tile whose top-left pixel is `(x0, y0)` into the frame.
    fn add_tile(&mut self, x0: u32, y0: u32, tile: Tile) {
        let w = self.film.width;
        let tw = (x0 + TILE).min(w) - x0;
        for (i, ((p, n), horizon)) in tile.pixels.into_iter().zip(tile.samples).zip(tile.horizons).enumerate()
        {
            let at = ((y0 + i as u32 / tw) * w + x0 + i as u32 % tw) as usize;
            self.film.pixels[at] = p;
            self.counts[at] = n;
            self.horizons[at] = horizon;
            for (k, film) in self.aovs.iter_mut().enumerate() {
                film.pixels[at] = tile.aovs[i * tile.aov_count + k];
            }
            if let Some(&camera) = tile.camera_horizons.get(i) {
                self.camera_horizons[at] = camera;
            }
        }
        if !tile.traced.is_empty() {
            self.samples.push(tile.traced);
        }
        self.rays += tile.rays;
        self.horizon_queries += tile.horizon_queries;
        self.horizon_seconds += tile.horizon_seconds;
    }
}

/// A rendered tile: its pixels row by row, the samples each got and each one's horizon (0
/// without horizons), the rays traced, and what finding the horizons cost.
struct Tile {
    pixels: Vec<Vec3>,
    samples: Vec<u32>,
    horizons: Vec<u32>,
    /// The plan's AOV passes, `aov_count` values per pixel, and their camera rays' horizons.
    aovs: Vec<Vec3>,
    aov_count: usize,
    camera_horizons: Vec<u32>,
    /// With [`Due::Samples`], the samples traced.
    traced: Vec<TracedSample>,
    rays: u64,
    horizon_queries: u64,
    horizon_seconds: f64,
}

/// The pixels of one camera-ray block (at most [`BLOCK_PIXELS`]).
struct Cells {
    cells: [Cell; BLOCK_PIXELS],
    len: usize,
}

/// A pixel of a camera-ray block: its coordinates, sampler, the most samples it may get, and
/// whether its paths are traced (a pixel reused from earlier frames only takes its place in
/// the camera packets, for each of its samples up to its stored count).
#[derive(Clone, Copy)]
struct Cell {
    x: u32,
    y: u32,
    /// Row-major index of the pixel in the image.
    pixel: u32,
    sampler: PixelSampler,
    budget: u32,
    traced: bool,
}

/// What every tile of a frame is rendered with.
struct TileRenderer<'a> {
    scene: &'a RenderScene<'a>,
    camera: FrameCamera,
    /// Traces the camera-ray packets; the integrator traces the rest.
    query: &'a dyn SceneQuery,
    integrator: &'a dyn FrameIntegrator,
    settings: &'a RenderSettings,
    /// Adaptive sampling's rule, when on and no sample counts are fixed.
    stopping: Option<Stopping>,
    /// Which blocks, with how many samples, and whether to find their horizons.
    plan: &'a FramePlan<'a>,
}

impl TileRenderer<'_> {
    /// The tile whose top-left pixel is `(x0, y0)`.
    fn render(&self, x0: u32, y0: u32) -> Tile {
        let (w, h) = (self.settings.width, self.settings.height);
        let (x1, y1) = ((x0 + TILE).min(w), (y0 + TILE).min(h));
        let n = ((x1 - x0) * (y1 - y0)) as usize;
        let mut acc = Accumulator {
            x0,
            y0,
            tw: x1 - x0,
            sums: vec![Vec3::ZERO; n],
            squares: if self.stopping.is_some() { vec![Vec3::ZERO; n] } else { Vec::new() },
            samples: vec![0; n],
            first_hits: FirstHits::new(self.plan.aovs.len(), n, self.plan.keeps_camera_horizons()),
        };
        let mut tile = Tile {
            pixels: Vec::new(),
            samples: Vec::new(),
            horizons: vec![0; n],
            aovs: Vec::new(),
            aov_count: self.plan.aovs.len(),
            camera_horizons: Vec::new(),
            traced: Vec::new(),
            rays: 0,
            horizon_queries: 0,
            horizon_seconds: 0.0,
        };
        for by in (y0..y1).step_by(BLOCK.1 as usize) {
            for bx in (x0..x1).step_by(BLOCK.0 as usize) {
                if !self.any_due(bx, by, x1, y1) {
                    continue;
                }
                let cells = self.cells(bx, by, x1, y1);
                let mut logs: [RayLog; BLOCK_PIXELS] = std::array::from_fn(|_| self.new_log());
                match self.plan.due {
                    Due::Samples { stored, .. } => {
                        self.render_block_samples(&cells, stored, &mut acc, &mut logs, &mut tile.traced)
                    }
                    _ => self.render_block(&cells, &mut acc, &mut logs),
                }
                for (cell, log) in cells.cells[..cells.len].iter().zip(&logs) {
                    tile.rays += log.rays;
                    let (queries, seconds) = log.query_cost();
                    tile.horizon_queries += u64::from(queries);
                    tile.horizon_seconds += seconds;
                    if let (true, Some(horizon)) = (cell.traced, log.horizon()) {
                        tile.horizons[acc.at(cell)] = horizon;
                    }
                }
            }
        }
        tile.pixels = acc.sums.iter().zip(&acc.samples).map(|(&sum, &k)| sum / k.max(1) as f32).collect();
        tile.samples = acc.samples;
        (tile.aovs, tile.camera_horizons) = acc.first_hits.finish();
        tile
    }

    /// A log for the rays of a pixel (or a sample), finding horizons when the plan asks.
    fn new_log(&self) -> RayLog<'_> {
        match self.plan.horizons {
            Some((index, ordinal, until)) => RayLog::with_horizon(index, self.scene, ordinal, until),
            None => RayLog::counting(),
        }
    }

    /// Whether sample `i` of `cell`'s pixel is traced.
    fn sample_due(&self, cell: &Cell, i: u32) -> bool {
        match self.plan.due {
            Due::Samples { stored, ordinal, .. } => {
                i >= stored.counts[cell.pixel as usize]
                    || stored.horizons[cell.pixel as usize * self.settings.spp as usize + i as usize]
                        <= ordinal
            }
            _ => cell.traced,
        }
    }

    /// Whether the block whose top-left pixel is `(bx, by)`, clipped to `(x1, y1)`, has a pixel
    /// to trace.
    fn any_due(&self, bx: u32, by: u32, x1: u32, y1: u32) -> bool {
        let due = match self.plan.due {
            Due::All => return true,
            Due::Pixels { due, .. } => due,
            Due::Samples { pixels, .. } => pixels,
        };
        let w = self.settings.width;
        (by..(by + BLOCK.1).min(y1)).any(|y| {
            let row = (y * w) as usize;
            due[row + bx as usize..row + (bx + BLOCK.0).min(x1) as usize].iter().any(|&d| d)
        })
    }

    /// The pixels of the block whose top-left pixel is `(bx, by)`, clipped to `(x1, y1)`:
    /// each with its sampler and sample budget. A fixed array, not a Vec: one block per 8
    /// pixels is on the hot path.
    fn cells(&self, bx: u32, by: u32, x1: u32, y1: u32) -> Cells {
        let w = self.settings.width;
        let mut cells = Cells {
            cells: [Cell {
                x: 0,
                y: 0,
                pixel: 0,
                sampler: PixelSampler::new(0, 0, 0),
                budget: 0,
                traced: false,
            }; BLOCK_PIXELS],
            len: 0,
        };
        for y in by..(by + BLOCK.1).min(y1) {
            for x in bx..(bx + BLOCK.0).min(x1) {
                let p = (y * w + x) as usize;
                let traced = match self.plan.due {
                    Due::All => true,
                    Due::Pixels { due, .. } => due[p],
                    Due::Samples { pixels, .. } => pixels[p],
                };
                // A pixel not traced keeps its lanes as when it was: its stored samples.
                let budget = match (self.plan.samples, self.plan.due) {
                    (Some(s), _) => s[p],
                    (None, Due::Pixels { stored, .. }) if !traced => stored[p],
                    (None, Due::Samples { stored, .. }) if !traced => stored.counts[p],
                    _ => self.settings.spp,
                };
                let sampler = PixelSampler::new(x, y, self.settings.seed);
                cells.cells[cells.len] = Cell { x, y, pixel: p as u32, sampler, budget, traced };
                cells.len += 1;
            }
        }
        cells
    }

    /// Samples the pixels of one block in index order, the camera rays of those still
    /// sampling traced as one packet per index, until each has its budget or has converged;
    /// each pixel's rays go into its log. A pixel not traced keeps its lane in the packets but
    /// its path is not continued.
    fn render_block(&self, cells: &Cells, acc: &mut Accumulator, logs: &mut [RayLog; BLOCK_PIXELS]) {
        let block = &cells.cells[..cells.len];
        let mut packet = CameraPacket::new();
        let mut done = [false; BLOCK_PIXELS];
        let most = block.iter().map(|c| c.budget).max().unwrap_or(0);
        for i in 0..most {
            if !packet.select(block, i, &done) {
                break;
            }
            // Camera rays are made only for packets with a pixel to trace.
            if !packet.slots().iter().any(|&c| block[c].traced) {
                continue;
            }
            self.trace_camera_packet(block, i, &mut packet);
            for (k, &c) in packet.slots().iter().enumerate() {
                let (cell, log, ray) = (&block[c], &mut logs[c], &packet.rays[k]);
                if cell.traced {
                    log.closest(ray, packet.hits[k].as_ref());
                    self.shade_aovs(acc, cell, ray, packet.hits[k].as_ref(), None);
                    let li = self.integrator.li_from_hit(ray, packet.hits[k], &cell.sampler, i, log);
                    done[c] = acc.add(cell, li, self.stopping.as_ref());
                } else {
                    log.count_untraced();
                }
            }
        }
    }

    /// [`Self::render_block`] under [`Due::Samples`]: a sample is traced when due (recorded
    /// with its own horizon in `traced`) and otherwise taken from `stored`; either way it is
    /// added to its pixel, so adaptive sampling stops a pixel where a full frame does. Camera
    /// packets are traced only for an index with a due sample; a pixel with none keeps its
    /// lanes in them.
    fn render_block_samples(
        &self,
        cells: &Cells,
        stored: StoredSamples,
        acc: &mut Accumulator,
        logs: &mut [RayLog; BLOCK_PIXELS],
        traced: &mut Vec<TracedSample>,
    ) {
        let block = &cells.cells[..cells.len];
        let spp = self.settings.spp as usize;
        let mut packet = CameraPacket::new();
        let mut done = [false; BLOCK_PIXELS];
        let most = block.iter().map(|c| c.budget).max().unwrap_or(0);
        for i in 0..most {
            if !packet.select(block, i, &done) {
                break;
            }
            let any_due = packet.slots().iter().any(|&c| self.sample_due(&block[c], i));
            if any_due {
                self.trace_camera_packet(block, i, &mut packet);
            }
            for (k, &c) in packet.slots().iter().enumerate() {
                let cell = &block[c];
                let due = any_due && self.sample_due(cell, i);
                if any_due && !due {
                    logs[c].count_untraced();
                }
                if !cell.traced {
                    continue;
                }
                let li = match due {
                    true => {
                        let (ray, hit) = (&packet.rays[k], packet.hits[k]);
                        let (sample, camera) = self.trace_sample(cell, i, ray, hit, &mut logs[c]);
                        self.shade_aovs(acc, cell, ray, hit.as_ref(), camera);
                        traced.push(sample);
                        sample.li
                    }
                    false => stored.values[cell.pixel as usize * spp + i as usize],
                };
                done[c] = acc.add(cell, li, self.stopping.as_ref());
            }
        }
    }

    /// The camera rays of `packet`'s lanes for sample `i`, traced as one packet.
    fn trace_camera_packet(&self, block: &[Cell], i: u32, packet: &mut CameraPacket) {
        for k in 0..packet.len {
            let cell = &block[packet.slots[k]];
            packet.rays[k] = camera_ray(&self.camera, self.settings, cell.x, cell.y, &cell.sampler, i);
        }
        self.query.intersect_packet(&packet.rays[..packet.len], &mut packet.hits[..packet.len]);
    }

    /// Continues sample `i` of `cell`'s pixel from its camera `ray` and `hit`; its rays
    /// count into the pixel's `log`. Returns the sample with its own horizon, and the horizon
    /// of its camera ray alone (when horizons are found).
    fn trace_sample(
        &self,
        cell: &Cell,
        i: u32,
        ray: &Ray,
        hit: Option<Hit>,
        log: &mut RayLog,
    ) -> (TracedSample, Option<u32>) {
        let mut sample_log = self.new_log();
        sample_log.closest(ray, hit.as_ref());
        let camera = sample_log.horizon();
        let li = self.integrator.li_from_hit(ray, hit, &cell.sampler, i, &mut sample_log);
        let horizon = sample_log.horizon().unwrap_or(0);
        log.absorb(&sample_log);
        (TracedSample { pixel: cell.pixel, index: i, li, horizon }, camera)
    }

    /// Adds the plan's AOV passes at the camera `ray`'s `hit` to `cell`'s pixel, and the
    /// ray's own horizon (`camera`) to the pixel's passes' horizon.
    #[inline]
    fn shade_aovs(
        &self,
        acc: &mut Accumulator,
        cell: &Cell,
        ray: &Ray,
        hit: Option<&Hit>,
        camera: Option<u32>,
    ) {
        if self.plan.aovs.is_empty() {
            return;
        }
        let values = self.plan.aovs.iter().map(|&aov| aov_at_hit(aov, self.scene, ray, hit));
        let at = acc.at(cell);
        acc.first_hits.add(at, values, camera);
    }
}

/// One camera packet of a block: which cells sample at the current index (`slots`, the first
/// `len`), their rays and hits.
struct CameraPacket {
    slots: [usize; BLOCK_PIXELS],
    len: usize,
    rays: [Ray; BLOCK_PIXELS],
    hits: [Option<Hit>; BLOCK_PIXELS],
}

impl CameraPacket {
    fn new() -> Self {
        Self {
            slots: [0; BLOCK_PIXELS],
            len: 0,
            rays: [Ray::new(Vec3::ZERO, Vec3::Z); BLOCK_PIXELS],
            hits: [None; BLOCK_PIXELS],
        }
    }

    /// Takes the cells of `block` that still sample at index `i` (within their budget, not
    /// converged); whether there is any.
    fn select(&mut self, block: &[Cell], i: u32, done: &[bool; BLOCK_PIXELS]) -> bool {
        self.len = 0;
        for (c, cell) in block.iter().enumerate() {
            if i < cell.budget && !done[c] {
                self.slots[self.len] = c;
                self.len += 1;
            }
        }
        self.len > 0
    }

    fn slots(&self) -> &[usize] {
        &self.slots[..self.len]
    }
}

/// A tile's running sums per pixel, row by row. Per pixel, samples are summed in index order
/// whatever the blocking, so the image is the same as tracing pixel by pixel.
struct Accumulator {
    x0: u32,
    y0: u32,
    tw: u32,
    sums: Vec<Vec3>,
    /// Sums of squared samples; only with adaptive sampling.
    squares: Vec<Vec3>,
    samples: Vec<u32>,
    first_hits: FirstHits,
}

/// A tile's AOV passes shaded at traced samples' camera hits: per pixel, `passes` running
/// sums in index order, the samples added, and the least horizon of their camera rays.
struct FirstHits {
    passes: usize,
    sums: Vec<Vec3>,
    samples: Vec<u32>,
    camera_horizons: Vec<u32>,
}

impl FirstHits {
    /// Room for `passes` passes of `pixels` pixels (nothing without passes), and their camera
    /// horizons when `horizons`.
    fn new(passes: usize, pixels: usize, horizons: bool) -> Self {
        let pixels = if passes == 0 { 0 } else { pixels };
        FirstHits {
            passes,
            sums: vec![Vec3::ZERO; passes * pixels],
            samples: vec![0; pixels],
            camera_horizons: if horizons { vec![u32::MAX; pixels] } else { Vec::new() },
        }
    }

    /// Adds one sample's pass `values` to pixel `at`, with its camera ray's horizon.
    fn add(&mut self, at: usize, values: impl Iterator<Item = Vec3>, camera: Option<u32>) {
        for (sum, value) in self.sums[at * self.passes..(at + 1) * self.passes].iter_mut().zip(values) {
            *sum += value;
        }
        self.samples[at] += 1;
        if let (Some(camera), Some(least)) = (camera, self.camera_horizons.get_mut(at)) {
            *least = (*least).min(camera);
        }
    }

    /// The passes' pixel values (the sums over their samples, as the image's pixels are
    /// computed) and camera horizons.
    fn finish(self) -> (Vec<Vec3>, Vec<u32>) {
        if self.passes == 0 {
            return (Vec::new(), Vec::new());
        }
        let values = self
            .sums
            .chunks_exact(self.passes)
            .zip(&self.samples)
            .flat_map(|(sums, &k)| sums.iter().map(move |&sum| sum / k.max(1) as f32))
            .collect();
        (values, self.camera_horizons)
    }
}

impl Accumulator {
    /// The index of `cell`'s pixel in the tile.
    fn at(&self, cell: &Cell) -> usize {
        ((cell.y - self.y0) * self.tw + (cell.x - self.x0)) as usize
    }

    /// Adds sample `li` to `cell`'s pixel; whether the pixel has converged.
    fn add(&mut self, cell: &Cell, li: Vec3, stopping: Option<&Stopping>) -> bool {
        let at = self.at(cell);
        self.sums[at] += li;
        self.samples[at] += 1;
        let Some(stopping) = stopping else {
            return false;
        };
        self.squares[at] += li * li;
        stopping.converged(self.samples[at], self.sums[at], self.squares[at])
    }
}
