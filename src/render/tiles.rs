//! One frame from camera to film: camera rays per pixel sample (tent filter), 16x16 tiles
//! over rayon, camera rays of each pixel block traced as one packet, and the integrator bound
//! to the frame finishing each sample.

use std::time::Instant;

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::adaptive::{relative_variance, AdaptiveSampling, SppStats, Stopping};
use super::integrator::dims;
use super::{
    Film, FrameContext, FrameIntegrator, Integrator, PinholeCamera, PixelSampler, RenderError, RenderScene,
};
use crate::accel::SceneQuery;
use crate::geometry::Ray;
use crate::scene::limits::{image_size_problem, MAX_SAMPLES_PER_PIXEL};

/// Pixel offset distributed as a tent filter of radius one pixel per axis. Filter importance
/// sampling (as in pbrt-v4): each sample is weighted 1 and lands where the filter puts it, so
/// every pixel is computed alone (no splatting across tile borders) and the result is the
/// tent-filtered image.
fn tent_offset(u: Vec2) -> Vec2 {
    let tent = |u: f32| if u < 0.5 { (2.0 * u).sqrt() - 1.0 } else { 1.0 - (2.0 - 2.0 * u).sqrt() };
    Vec2::new(tent(u.x), tent(u.y))
}

/// Side of the square tiles rayon distributes.
const TILE: u32 = 16;

/// Pixel block whose camera rays (one sample each) are traced together as one packet
/// ([`SceneQuery::intersect_packet`]) before each pixel's integrator continues alone. In
/// `dormant bench render` (docs/performance.md) Embree traced 4x2 camera packets 1.3-1.6x
/// (monastery, 8,000 ducks) and 3.1-3.4x (default scene) as fast as single rays; whole
/// path-traced frames gained about 3% and 10%, as camera rays are one in 4-5 of their rays.
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
}

impl RenderSettings {
    pub(crate) fn validate(&self) -> Result<(), RenderError> {
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
    pub(crate) fn mrays_per_second(&self) -> f64 {
        self.rays as f64 / self.seconds.max(1e-9) / 1e6
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
fn camera_ray(camera: &FrameCamera, spp: u32, x: u32, y: u32, sampler: &PixelSampler, i: u32) -> Ray {
    // Tent reconstruction by filter importance sampling (see `tent_offset`); a single sample
    // goes through the pixel's centre.
    let jitter = if spp == 1 {
        Vec2::splat(0.5)
    } else {
        Vec2::splat(0.5) + tent_offset(sampler.get_2d(i, dims::PIXEL))
    };
    let (px, py) = (x as f32 + jitter.x, y as f32 + jitter.y);
    let lens = |c: &PinholeCamera| {
        if c.has_aperture() {
            c.ray_through_lens(px, py, sampler.get_2d(i, dims::LENS))
        } else {
            c.ray(px, py)
        }
    };
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

/// Renders one frame with `integrator`, tiles spread over the current rayon pool. Each
/// pixel's samples depend only on (pixel, frame, index), so the image is identical whatever
/// the thread count or tile order.
pub fn render_frame(
    scene: &RenderScene,
    query: &dyn SceneQuery,
    integrator: &dyn Integrator,
    settings: &RenderSettings,
) -> Result<(Film, RenderStats), RenderError> {
    render_frame_counted(scene, query, integrator, settings, None).map(|(film, stats, _)| (film, stats))
}

/// [`render_frame`], also returning the camera samples each pixel got (row-major). With
/// `samples` (one count per pixel, at most `spp`), pixel `p` gets exactly its first
/// `samples[p]` samples and adaptive sampling is not applied: the AOV passes of an adaptive
/// frame see the beauty pass's camera samples.
pub fn render_frame_counted(
    scene: &RenderScene,
    query: &dyn SceneQuery,
    integrator: &dyn Integrator,
    settings: &RenderSettings,
    samples: Option<&[u32]>,
) -> Result<(Film, RenderStats, Vec<u32>), RenderError> {
    settings.validate()?;
    let start = Instant::now();
    let (w, h) = (settings.width, settings.height);
    debug_assert!(samples.is_none_or(|s| s.len() == (w * h) as usize));
    let renderer = TileRenderer {
        camera: FrameCamera {
            open: PinholeCamera::new(&scene.camera, w, h),
            close: scene.camera_close.as_ref().map(|c| PinholeCamera::new(c, w, h)),
        },
        query,
        integrator: &*integrator.bind(FrameContext { scene, query }),
        settings,
        stopping: if samples.is_some() { None } else { settings.adaptive.stopping(settings.spp) },
        samples,
    };
    let tiles_x = w.div_ceil(TILE);
    let tiles: Vec<(u32, u32)> =
        (0..tiles_x * h.div_ceil(TILE)).map(|t| ((t % tiles_x) * TILE, (t / tiles_x) * TILE)).collect();
    let rendered: Vec<(u32, u32, Tile)> = match renderer.stopping {
        Some(stopping) => renderer.render_adaptive(&tiles, &stopping),
        None => tiles.par_iter().map(|&(x0, y0)| (x0, y0, renderer.render(x0, y0))).collect(),
    };
    let mut film = Film::new(w, h);
    let mut counts = vec![0; (w * h) as usize];
    let mut rays = 0;
    for (x0, y0, tile) in rendered {
        let tw = (x0 + TILE).min(w) - x0;
        for (i, (p, n)) in tile.pixels.into_iter().zip(tile.samples).enumerate() {
            let at = ((y0 + i as u32 / tw) * w + x0 + i as u32 % tw) as usize;
            film.pixels[at] = p;
            counts[at] = n;
        }
        rays += tile.rays;
    }
    let stats = RenderStats { rays, seconds: start.elapsed().as_secs_f64(), spp: SppStats::of(&counts) };
    Ok((film, stats, counts))
}

/// A rendered tile: its pixels row by row, the samples each got, and the rays traced.
struct Tile {
    pixels: Vec<Vec3>,
    samples: Vec<u32>,
    rays: u64,
}

/// A pixel of a camera-ray block: its coordinates, sampler, and the most samples it may get.
#[derive(Clone, Copy)]
struct Cell {
    x: u32,
    y: u32,
    sampler: PixelSampler,
    budget: u32,
}

/// What every tile of a frame is rendered with.
struct TileRenderer<'a> {
    camera: FrameCamera,
    /// Traces the camera-ray packets; the integrator traces the rest.
    query: &'a dyn SceneQuery,
    integrator: &'a dyn FrameIntegrator,
    settings: &'a RenderSettings,
    /// Adaptive sampling's rule, when on and no sample counts are fixed.
    stopping: Option<Stopping>,
    /// Fixed samples per pixel for the whole frame (row-major), instead of `spp`.
    samples: Option<&'a [u32]>,
}

impl TileRenderer<'_> {
    /// A tile's empty sums.
    fn accumulator(&self, x0: u32, y0: u32) -> Accumulator {
        let (w, h) = (self.settings.width, self.settings.height);
        let (x1, y1) = ((x0 + TILE).min(w), (y0 + TILE).min(h));
        let n = ((x1 - x0) * (y1 - y0)) as usize;
        Accumulator {
            x0,
            y0,
            tw: x1 - x0,
            th: y1 - y0,
            sums: vec![Vec3::ZERO; n],
            squares: if self.stopping.is_some() { vec![Vec3::ZERO; n] } else { Vec::new() },
            samples: vec![0; n],
            rays: 0,
        }
    }

    /// The tile whose top-left pixel is `(x0, y0)`, every pixel with its fixed budget.
    fn render(&self, x0: u32, y0: u32) -> Tile {
        let w = self.settings.width;
        let mut acc = self.accumulator(x0, y0);
        self.sample_tile(&mut acc, 0, |x, y| self.samples.map_or(self.settings.spp, |s| s[(y * w + x) as usize]));
        acc.into_tile()
    }

    /// Adaptive sampling in rounds over the whole frame: every pixel gets the minimum, then
    /// after each round of `check` samples the pixels still sampling are judged from the
    /// frame's sums (the same at any thread count or tile order).
    fn render_adaptive(&self, tiles: &[(u32, u32)], stopping: &Stopping) -> Vec<(u32, u32, Tile)> {
        let (w, h) = (self.settings.width as usize, self.settings.height as usize);
        let spp = self.settings.spp;
        let mut accs: Vec<Accumulator> = tiles.iter().map(|&(x0, y0)| self.accumulator(x0, y0)).collect();
        let mut active = vec![true; w * h];
        let mut variances = vec![0.0f32; w * h];
        let mut counts = vec![0u32; w * h];
        let mut lambda = None;
        let (mut from, mut to) = (0, stopping.min.min(spp));
        loop {
            accs.par_iter_mut().for_each(|acc| {
                self.sample_tile(acc, from, |x, y| if active[y as usize * w + x as usize] { to } else { 0 })
            });
            if to >= spp {
                break;
            }
            for acc in &accs {
                acc.variances(w, &mut variances, &mut counts);
            }
            if !stopping.judge(&variances, &counts, &mut active, spp, &mut lambda) {
                break;
            }
            (from, to) = (to, (to + stopping.check).min(spp));
        }
        tiles.iter().zip(accs).map(|(&(x0, y0), acc)| (x0, y0, acc.into_tile())).collect()
    }

    /// Samples `from..budget(x, y)` of every pixel of `acc`'s tile, block by block.
    fn sample_tile(&self, acc: &mut Accumulator, from: u32, budget: impl Fn(u32, u32) -> u32) {
        let (x0, y0) = (acc.x0, acc.y0);
        let (x1, y1) = (x0 + acc.tw, y0 + acc.th);
        for by in (y0..y1).step_by(BLOCK.1 as usize) {
            for bx in (x0..x1).step_by(BLOCK.0 as usize) {
                // A fixed array, not a Vec: one block per 8 pixels is on the hot path.
                let mut cells =
                    [Cell { x: 0, y: 0, sampler: PixelSampler::new(0, 0, 0), budget: 0 }; BLOCK_PIXELS];
                let mut n = 0;
                for y in by..(by + BLOCK.1).min(y1) {
                    for x in bx..(bx + BLOCK.0).min(x1) {
                        let budget = budget(x, y);
                        if budget > from {
                            cells[n] = Cell { x, y, sampler: PixelSampler::new(x, y, self.settings.seed), budget };
                            n += 1;
                        }
                    }
                }
                self.render_block(&cells[..n], from, acc);
            }
        }
    }

    /// Samples `from..` of the pixels of one block in index order, the camera rays of those
    /// still sampling traced as one packet per index, until each has its budget.
    fn render_block(&self, block: &[Cell], from: u32, acc: &mut Accumulator) {
        let spp = self.settings.spp;
        let mut camera_rays = [Ray::new(Vec3::ZERO, Vec3::Z); BLOCK_PIXELS];
        let mut hits = [None; BLOCK_PIXELS];
        // Which cell each packet slot samples.
        let mut slots = [0usize; BLOCK_PIXELS];
        let most = block.iter().map(|c| c.budget).max().unwrap_or(0);
        for i in from..most {
            let mut m = 0;
            for (c, cell) in block.iter().enumerate() {
                if i < cell.budget {
                    camera_rays[m] = camera_ray(&self.camera, spp, cell.x, cell.y, &cell.sampler, i);
                    slots[m] = c;
                    m += 1;
                }
            }
            self.query.intersect_packet(&camera_rays[..m], &mut hits[..m]);
            for ((ray, hit), &c) in camera_rays.iter().zip(hits).zip(&slots[..m]) {
                let cell = &block[c];
                let li = self.integrator.li_from_hit(ray, hit, &cell.sampler, i, &mut acc.rays);
                acc.add(cell, li);
            }
        }
    }
}

/// A tile's running sums per pixel, row by row. Per pixel, samples are summed in index order
/// whatever the blocking, so the image is the same as tracing pixel by pixel.
struct Accumulator {
    x0: u32,
    y0: u32,
    tw: u32,
    th: u32,
    sums: Vec<Vec3>,
    /// Sums of squared samples; only with adaptive sampling.
    squares: Vec<Vec3>,
    samples: Vec<u32>,
    rays: u64,
}

impl Accumulator {
    /// Adds sample `li` to `cell`'s pixel.
    fn add(&mut self, cell: &Cell, li: Vec3) {
        let at = ((cell.y - self.y0) * self.tw + (cell.x - self.x0)) as usize;
        self.sums[at] += li;
        self.samples[at] += 1;
        if !self.squares.is_empty() {
            self.squares[at] += li * li;
        }
    }

    /// Writes each pixel's per-sample relative variance into the frame's row-major `out`.
    fn variances(&self, w: usize, out: &mut [f32], counts: &mut [u32]) {
        for (i, ((&n, &sum), &squares)) in self.samples.iter().zip(&self.sums).zip(&self.squares).enumerate() {
            let (x, y) = (self.x0 as usize + i % self.tw as usize, self.y0 as usize + i / self.tw as usize);
            out[y * w + x] = relative_variance(n, sum, squares);
            counts[y * w + x] = n;
        }
    }

    fn into_tile(self) -> Tile {
        let pixels = self.sums.iter().zip(&self.samples).map(|(&sum, &k)| sum / k.max(1) as f32).collect();
        Tile { pixels, samples: self.samples, rays: self.rays }
    }
}
