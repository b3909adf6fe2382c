use glam::Vec3;

use crate::geometry::Ray;
use crate::scene::Camera;

/// A pinhole camera generating primary rays for an image of `width x height` pixels.
#[derive(Clone, Copy, Debug)]
pub struct PinholeCamera {
    eye: Vec3,
    /// World-space vector from the eye to the image plane's top-left corner at distance 1.
    top_left: Vec3,
    /// World-space step per pixel to the right and down.
    right: Vec3,
    down: Vec3,
}

impl PinholeCamera {
    pub fn new(camera: &Camera, width: u32, height: u32) -> Self {
        let forward = (camera.target - camera.eye).normalize_or(Vec3::NEG_Z);
        let right = forward.cross(camera.up).normalize_or(Vec3::X);
        let up = right.cross(forward);
        let half_h = (camera.vfov_deg.to_radians() * 0.5).tan();
        let half_w = half_h * width as f32 / height as f32;
        Self {
            eye: camera.eye,
            top_left: forward - half_w * right + half_h * up,
            right: right * (2.0 * half_w / width as f32),
            down: -up * (2.0 * half_h / height as f32),
        }
    }

    /// The ray through image position `(x, y)` in pixels from the top-left corner
    /// (pixel centres are at `i + 0.5`).
    pub fn ray(&self, x: f32, y: f32) -> Ray {
        let dir = (self.top_left + x * self.right + y * self.down).normalize();
        Ray::new(self.eye, dir)
    }
}
