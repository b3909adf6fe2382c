//! Camera rays: a pixel sample's ray, placed by the pixel filter, through the lens when the
//! camera has an aperture, and at the sample's time between the shutter's cameras when the
//! frame is motion blurred.

use glam::Vec2;

use crate::geometry::Ray;
use crate::render::integrator::dims;
use crate::render::{PinholeCamera, PixelSampler, RenderScene, RenderSettings};

/// The frame's camera: where it is at shutter open, and at close when the frame is motion
/// blurred (`None`: no blur; `Some(open)` for a camera that stays put over the shutter).
#[derive(Clone, Copy, Debug)]
pub(super) struct FrameCamera {
    open: PinholeCamera,
    close: Option<PinholeCamera>,
}

impl FrameCamera {
    /// `scene`'s camera (and its camera at shutter close) over a `width` x `height` image.
    pub(super) fn new(scene: &RenderScene, width: u32, height: u32) -> Self {
        FrameCamera {
            open: PinholeCamera::new(&scene.camera, width, height),
            close: scene.camera_close.as_ref().map(|c| PinholeCamera::new(c, width, height)),
        }
    }
}

/// Sample `i` of pixel `(x, y)`'s camera ray.
pub(super) fn camera_ray(
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
