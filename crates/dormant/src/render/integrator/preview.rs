//! The quick integrators beside the path tracer: direct light only (`--mode shaded`) and
//! ambient occlusion (`--mode ao`).

use std::f32::consts::PI;

use glam::Vec3;

use super::{dims, punctual_light, shadow_ray, FrameContext, FrameIntegrator, Integrator};
use crate::accel::Hit;
use crate::geometry::{offset_origin, Ray};
use crate::render::bsdf::{sample_cone, sample_cosine};
use crate::render::{PixelSampler, RayLog};

/// Direct light only: the sun (a disc, so shadows are soft), the sky and punctual lights,
/// each through one shadow ray per sample, on Lambertian surfaces, plus emission. The preview
/// mode beside the path tracer.
#[derive(Clone, Copy, Debug, Default)]
pub struct DirectLighting;

impl Integrator for DirectLighting {
    fn bind<'a>(&'a self, frame: FrameContext<'a>) -> Box<dyn FrameIntegrator + 'a> {
        let sun_cos_max = frame.scene.sun.angular_radius_deg.to_radians().cos();
        Box::new(DirectLightingFrame { frame, sun_cos_max })
    }
}

/// [`DirectLighting`] bound to a frame.
struct DirectLightingFrame<'a> {
    frame: FrameContext<'a>,
    /// Cosine of the sun's angular radius: the cone its shadow rays are drawn from.
    sun_cos_max: f32,
}

impl FrameIntegrator for DirectLightingFrame<'_> {
    fn li_from_hit(
        &self,
        ray: &Ray,
        first: Option<Hit>,
        sampler: &PixelSampler,
        index: u32,
        log: &mut RayLog,
    ) -> Vec3 {
        let FrameContext { scene, .. } = self.frame;
        let Some(hit) = first else {
            return scene.sky.radiance(ray.dir.normalize());
        };
        let s = scene.surface(ray, &hit);
        let albedo = s.material.base_color;
        let origin = offset_origin(s.p, s.ng);
        let mut radiance = s.emission;

        for light in &scene.lights {
            let Some((l, e, distance)) = punctual_light(light, s.p) else { continue };
            let cos = s.ns.dot(l);
            if cos > 0.0
                && s.ng.dot(l) > 0.0
                && self.frame.unoccluded(&shadow_ray(origin, l, distance).at_time(ray.time), log)
            {
                radiance += albedo / PI * e * cos;
            }
        }

        let sun = &scene.sun;
        let l = sample_cone(sun.direction, self.sun_cos_max, sampler.get_2d(index, dims::SUN));
        let cos = s.ns.dot(l);
        if cos > 0.0
            && s.ng.dot(l) > 0.0
            && self.frame.unoccluded(&Ray::new(origin, l).at_time(ray.time), log)
        {
            radiance += albedo / PI * sun.irradiance * cos;
        }

        let d = sample_cosine(s.ns, sampler.get_2d(index, dims::SKY));
        if s.ng.dot(d) > 0.0 && self.frame.unoccluded(&Ray::new(origin, d).at_time(ray.time), log) {
            // Lambert BRDF times cosine over the cosine-weighted pdf leaves the albedo.
            radiance += albedo * scene.sky.radiance(d);
        }
        radiance
    }
}

/// Ambient occlusion: the fraction of a cosine-weighted hemisphere that is open within
/// `radius`, shown as grey.
#[derive(Clone, Copy, Debug)]
pub struct AmbientOcclusion {
    pub radius: f32,
}

impl Integrator for AmbientOcclusion {
    fn bind<'a>(&'a self, frame: FrameContext<'a>) -> Box<dyn FrameIntegrator + 'a> {
        Box::new(AmbientOcclusionFrame { radius: self.radius, frame })
    }
}

/// [`AmbientOcclusion`] bound to a frame.
struct AmbientOcclusionFrame<'a> {
    radius: f32,
    frame: FrameContext<'a>,
}

impl FrameIntegrator for AmbientOcclusionFrame<'_> {
    fn li_from_hit(
        &self,
        ray: &Ray,
        first: Option<Hit>,
        sampler: &PixelSampler,
        index: u32,
        log: &mut RayLog,
    ) -> Vec3 {
        let Some(hit) = first else {
            return Vec3::ONE;
        };
        let s = self.frame.scene.surface(ray, &hit);
        let d = sample_cosine(s.ns, sampler.get_2d(index, dims::SKY));
        if s.ng.dot(d) <= 0.0 {
            return Vec3::ZERO;
        }
        let open = Ray::segment(offset_origin(s.p, s.ng), d, 0.0, self.radius).at_time(ray.time);
        let open = self.frame.unoccluded(&open, log);
        Vec3::splat(if open { 0.8 } else { 0.0 })
    }
}
