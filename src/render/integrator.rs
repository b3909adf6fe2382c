use std::f32::consts::PI;

use glam::{Vec2, Vec3};

use super::{PixelSampler, RenderScene};
use crate::accel::SceneQuery;
use crate::geometry::Ray;

/// Computes the radiance arriving along a camera ray.
pub trait Integrator: Sync {
    /// Radiance along `ray` for sample `index` of `sampler`; adds the rays it traced to `rays`.
    fn li(
        &self,
        scene: &RenderScene,
        query: &dyn SceneQuery,
        ray: &Ray,
        sampler: &PixelSampler,
        index: u32,
        rays: &mut u64,
    ) -> Vec3;
}

/// Direct light only: the sun (a disc, so shadows are soft) and the sky, each through one
/// shadow ray per sample, on Lambertian surfaces. The preview mode beside the path tracer.
#[derive(Clone, Copy, Debug, Default)]
pub struct DirectLighting;

/// Dimension pairs of the pixel sampler, so each decision gets its own stratified points.
pub(crate) mod dims {
    pub const PIXEL: u32 = 0;
    pub const SUN: u32 = 1;
    pub const SKY: u32 = 2;
}

/// An orthonormal basis around unit `n` (Duff et al. 2017).
fn basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x), Vec3::new(b, sign + n.y * n.y * a, -n.y))
}

/// Uniform direction within the cone of half-angle `cos_max` around `axis`.
fn sample_cone(axis: Vec3, cos_max: f32, u: Vec2) -> Vec3 {
    let cos = 1.0 - u.x * (1.0 - cos_max);
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    let (t, b) = basis(axis);
    (t * (sin * phi.cos()) + b * (sin * phi.sin()) + axis * cos).normalize()
}

/// Cosine-weighted direction in the hemisphere around `n`.
fn sample_cosine(n: Vec3, u: Vec2) -> Vec3 {
    let r = u.x.sqrt();
    let phi = 2.0 * PI * u.y;
    let (t, b) = basis(n);
    (t * (r * phi.cos()) + b * (r * phi.sin()) + n * (1.0 - u.x).max(0.0).sqrt()).normalize()
}

/// Origin offset that keeps secondary rays off the surface they leave, scaled with the
/// magnitude of the position so it works far from the origin.
pub(crate) fn offset_origin(p: Vec3, ng: Vec3) -> Vec3 {
    let scale = 1e-4 * p.abs().max_element().max(1.0);
    p + ng * scale
}

impl Integrator for DirectLighting {
    fn li(
        &self,
        scene: &RenderScene,
        query: &dyn SceneQuery,
        ray: &Ray,
        sampler: &PixelSampler,
        index: u32,
        rays: &mut u64,
    ) -> Vec3 {
        *rays += 1;
        let Some(hit) = query.intersect(ray) else {
            return scene.sky.radiance(ray.dir.normalize());
        };
        let s = scene.surface(ray, &hit);
        let albedo = s.material.base_color;
        let origin = offset_origin(s.p, s.ng);
        let mut radiance = Vec3::ZERO;

        let sun = &scene.sun;
        let cos_max = sun.angular_radius_deg.to_radians().cos();
        let l = sample_cone(sun.direction, cos_max, sampler.get_2d(index, dims::SUN));
        let cos = s.ns.dot(l);
        if cos > 0.0 && s.ng.dot(l) > 0.0 {
            *rays += 1;
            if !query.intersect_p(&Ray::new(origin, l)) {
                radiance += albedo / PI * sun.irradiance * cos;
            }
        }

        let d = sample_cosine(s.ns, sampler.get_2d(index, dims::SKY));
        if s.ng.dot(d) > 0.0 {
            *rays += 1;
            if !query.intersect_p(&Ray::new(origin, d)) {
                // Lambert BRDF times cosine over the cosine-weighted pdf leaves the albedo.
                radiance += albedo * scene.sky.radiance(d);
            }
        }
        radiance
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_stay_in_their_domains() {
        let n = Vec3::new(0.3, -0.8, 0.52).normalize();
        for i in 0..64 {
            let u = Vec2::new((i % 8) as f32 / 8.0 + 0.01, (i / 8) as f32 / 8.0 + 0.01);
            assert!(sample_cosine(n, u).dot(n) >= 0.0);
            let c = sample_cone(n, 0.99, u);
            assert!(c.dot(n) >= 0.99 - 1e-4);
            assert!((c.length() - 1.0).abs() < 1e-4);
        }
    }
}
