//! One frame from camera to film: camera rays per pixel sample (tent filter), 16x16 tiles
//! over rayon, camera rays of each pixel block traced as one packet, and the integrator bound
//! to the frame finishing each sample.

use std::time::Instant;

use glam::{Vec2, Vec3};
use rayon::prelude::*;

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
    pub spp: u32,
    /// Seeds the pixel sampler: a sequence passes the frame number so consecutive frames
    /// decorrelate, or one value for every frame (`--seed fixed`).
    pub seed: u32,
}

impl RenderSettings {
    pub(crate) fn validate(&self) -> Result<(), RenderError> {
        if let Some(problem) = image_size_problem(self.width, self.height) {
            return Err(RenderError::InvalidSize(problem));
        }
        if !(1..=MAX_SAMPLES_PER_PIXEL).contains(&self.spp) {
            return Err(RenderError::InvalidSpp);
        }
        Ok(())
    }
}

#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct RenderStats {
    pub rays: u64,
    pub seconds: f64,
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
    settings.validate()?;
    let start = Instant::now();
    let (w, h) = (settings.width, settings.height);
    let renderer = TileRenderer {
        camera: FrameCamera {
            open: PinholeCamera::new(&scene.camera, w, h),
            close: scene.camera_close.as_ref().map(|c| PinholeCamera::new(c, w, h)),
        },
        query,
        integrator: &*integrator.bind(FrameContext { scene, query }),
        settings,
    };
    let tiles_x = w.div_ceil(TILE);
    let tiles: Vec<(u32, u32)> =
        (0..tiles_x * h.div_ceil(TILE)).map(|t| ((t % tiles_x) * TILE, (t / tiles_x) * TILE)).collect();
    let rendered: Vec<(u32, u32, Vec<Vec3>, u64)> = tiles
        .par_iter()
        .map(|&(x0, y0)| {
            let (pixels, rays) = renderer.render(x0, y0);
            (x0, y0, pixels, rays)
        })
        .collect();
    let mut film = Film::new(w, h);
    let mut rays = 0;
    for (x0, y0, pixels, tile_rays) in rendered {
        let tw = (x0 + TILE).min(w) - x0;
        for (i, p) in pixels.into_iter().enumerate() {
            let (x, y) = (x0 + i as u32 % tw, y0 + i as u32 / tw);
            film.pixels[(y * w + x) as usize] = p;
        }
        rays += tile_rays;
    }
    Ok((film, RenderStats { rays, seconds: start.elapsed().as_secs_f64() }))
}

/// What every tile of a frame is rendered with.
struct TileRenderer<'a> {
    camera: FrameCamera,
    /// Traces the camera-ray packets; the integrator traces the rest.
    query: &'a dyn SceneQuery,
    integrator: &'a dyn FrameIntegrator,
    settings: &'a RenderSettings,
}

impl TileRenderer<'_> {
    /// The pixels of the tile whose top-left pixel is `(x0, y0)`, row by row, and the rays
    /// traced for them.
    fn render(&self, x0: u32, y0: u32) -> (Vec<Vec3>, u64) {
        let (w, h, spp) = (self.settings.width, self.settings.height, self.settings.spp);
        let (x1, y1) = ((x0 + TILE).min(w), (y0 + TILE).min(h));
        let tw = x1 - x0;
        let mut rays = 0u64;
        // Per pixel, samples are summed in index order whatever the blocking, so the image is
        // the same as tracing pixel by pixel.
        let mut sums = vec![Vec3::ZERO; (tw * (y1 - y0)) as usize];
        for by in (y0..y1).step_by(BLOCK.1 as usize) {
            for bx in (x0..x1).step_by(BLOCK.0 as usize) {
                // A fixed array, not a Vec: one block per 8 pixels is on the hot path.
                let mut cells = [(0, 0, PixelSampler::new(0, 0, 0)); BLOCK_PIXELS];
                let mut n = 0;
                for y in by..(by + BLOCK.1).min(y1) {
                    for x in bx..(bx + BLOCK.0).min(x1) {
                        cells[n] = (x, y, PixelSampler::new(x, y, self.settings.seed));
                        n += 1;
                    }
                }
                let block = &cells[..n];
                let mut camera_rays = [Ray::new(Vec3::ZERO, Vec3::Z); BLOCK_PIXELS];
                let mut hits = [None; BLOCK_PIXELS];
                for i in 0..spp {
                    for (ray, (x, y, sampler)) in camera_rays.iter_mut().zip(block) {
                        *ray = camera_ray(&self.camera, spp, *x, *y, sampler, i);
                    }
                    self.query.intersect_packet(&camera_rays[..n], &mut hits[..n]);
                    for ((ray, hit), (x, y, sampler)) in camera_rays.iter().zip(hits).zip(block) {
                        sums[((y - y0) * tw + (x - x0)) as usize] +=
                            self.integrator.li_from_hit(ray, hit, sampler, i, &mut rays);
                    }
                }
            }
        }
        let pixels = sums.into_iter().map(|sum| sum / spp as f32).collect();
        (pixels, rays)
    }
}
