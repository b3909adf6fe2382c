//! Primary rays: a pinhole camera, or a thin lens (depth of field) when the scene's camera has
//! an aperture.

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

use crate::geometry::Ray;
use crate::scene::Camera;

/// A camera generating primary rays for an image of `width x height` pixels: a pinhole, or a
/// thin lens focused at a plane when the scene camera has an aperture.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PinholeCamera {
    eye: Vec3,
    /// World-space vector from the eye to the image plane's top-left corner at distance 1.
    top_left: Vec3,
    /// World-space step per pixel to the right and down.
    right: Vec3,
    down: Vec3,
    forward: Vec3,
    /// Unit lens axes scaled by the aperture radius (zero for a pinhole).
    lens_u: Vec3,
    lens_v: Vec3,
    /// Distance of the plane in focus along `forward`.
    focus: f32,
}

/// Uniform point on the unit disc (Shirley-Chiu concentric mapping).
fn concentric_disc(u: Vec2) -> Vec2 {
    let p = 2.0 * u - Vec2::ONE;
    if p == Vec2::ZERO {
        return Vec2::ZERO;
    }
    let (r, theta) = if p.x.abs() > p.y.abs() {
        (p.x, PI / 4.0 * (p.y / p.x))
    } else {
        (p.y, PI / 2.0 - PI / 4.0 * (p.x / p.y))
    };
    r * Vec2::new(theta.cos(), theta.sin())
}

impl PinholeCamera {
    pub fn new(camera: &Camera, width: u32, height: u32) -> Self {
        let forward = (camera.target - camera.eye).normalize_or(Vec3::NEG_Z);
        let right = forward.cross(camera.up).normalize_or(Vec3::X);
        let up = right.cross(forward);
        let half_h = (camera.vfov_deg.to_radians() * 0.5).tan();
        let half_w = half_h * width as f32 / height as f32;
        let aperture = if camera.aperture_radius.is_finite() { camera.aperture_radius.max(0.0) } else { 0.0 };
        let focus =
            camera.focus_distance.unwrap_or_else(|| (camera.target - camera.eye).dot(forward)).max(1e-4);
        Self {
            eye: camera.eye,
            top_left: forward - half_w * right + half_h * up,
            right: right * (2.0 * half_w / width as f32),
            down: -up * (2.0 * half_h / height as f32),
            forward,
            lens_u: right * aperture,
            lens_v: up * aperture,
            focus: if focus.is_finite() { focus } else { 1.0 },
        }
    }

    /// Whether rays leave from a lens of non-zero size (so [`Self::ray_through_lens`] needs
    /// its lens sample).
    pub(crate) fn has_aperture(&self) -> bool {
        self.lens_u != Vec3::ZERO
    }

    /// The pinhole ray through image position `(x, y)` in pixels from the top-left corner
    /// (pixel centres are at `i + 0.5`), ignoring any aperture.
    pub fn ray(&self, x: f32, y: f32) -> Ray {
        let dir = (self.top_left + x * self.right + y * self.down).normalize();
        Ray::new(self.eye, dir)
    }

    /// The ray through image position `(x, y)` leaving the lens at the point `lens` (in
    /// `[0, 1)²`) picks; the pinhole ray when there is no aperture. Every ray through one
    /// image position meets the others on the plane in focus.
    pub(crate) fn ray_through_lens(&self, x: f32, y: f32, lens: Vec2) -> Ray {
        let pinhole = self.ray(x, y);
        if !self.has_aperture() {
            return pinhole;
        }
        let in_focus = self.eye + pinhole.dir * (self.focus / pinhole.dir.dot(self.forward));
        let d = concentric_disc(lens);
        let origin = self.eye + d.x * self.lens_u + d.y * self.lens_v;
        Ray::new(origin, (in_focus - origin).normalize())
    }

    /// One pinhole ray through each pixel centre of a `width x height` image of `camera`, row
    /// by row (cross-checks and probes; renders sample the pixel area instead).
    pub fn pixel_centre_rays(camera: &Camera, width: u32, height: u32) -> Vec<Ray> {
        let camera = PinholeCamera::new(camera, width, height);
        (0..height)
            .flat_map(|y| (0..width).map(move |x| (x, y)))
            .map(|(x, y)| camera.ray(x as f32 + 0.5, y as f32 + 0.5))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lens_rays_meet_on_the_focus_plane() {
        let camera = Camera {
            aperture_radius: 0.2,
            focus_distance: Some(5.0),
            ..Camera::pinhole(Vec3::ZERO, Vec3::new(0.0, 0.0, -10.0), Vec3::Y, 40.0)
        };
        let c = PinholeCamera::new(&camera, 64, 48);
        let at_focus = |r: Ray| r.at((-5.0 - r.origin.z) / r.dir.z);
        let reference = at_focus(c.ray(10.5, 30.5));
        for u in [Vec2::new(0.1, 0.9), Vec2::new(0.7, 0.3), Vec2::new(0.99, 0.01)] {
            let r = c.ray_through_lens(10.5, 30.5, u);
            assert!(r.origin.length() <= 0.2 + 1e-6 && r.origin != Vec3::ZERO);
            assert!((at_focus(r) - reference).length() < 1e-4);
        }
    }

    #[test]
    fn concentric_disc_stays_in_the_disc() {
        for i in 0..100 {
            let u = Vec2::new((i % 10) as f32 / 10.0, (i / 10) as f32 / 10.0);
            assert!(concentric_disc(u).length() <= 1.0 + 1e-6);
        }
    }
}
