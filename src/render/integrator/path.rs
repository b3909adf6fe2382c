//! The path tracer (`--mode path`, the default): unidirectional paths on the
//! metallic-roughness BSDF with next-event estimation at every vertex.

use std::f32::consts::PI;

use glam::Vec3;

use super::{dims, punctual_light, shadow_ray, FrameContext, FrameIntegrator, Integrator};
use crate::accel::Hit;
use crate::geometry::{offset_origin, Ray};
use crate::render::bsdf::{sample_cone, sample_cosine, Bsdf};
use crate::render::{PixelSampler, RenderScene};

/// Unidirectional path tracing with next-event estimation of the sun, the sky and emissive
/// triangles, each combined with BSDF sampling by multiple importance sampling (power
/// heuristic), and of punctual lights (delta lights: light sampling only), on the
/// metallic-roughness BSDF, with Russian roulette after three bounces.
#[derive(Clone, Copy, Debug)]
pub struct PathTracer {
    pub max_depth: u32,
    /// Largest radiance one indirect contribution may add (like Cycles' "clamp indirect"):
    /// trades a little energy in caustics (sun off glossy metal onto diffuse surfaces) for
    /// no fireflies. `f32::INFINITY` keeps the estimator unbiased.
    pub clamp_indirect: f32,
}

impl Default for PathTracer {
    fn default() -> Self {
        Self { max_depth: 6, clamp_indirect: 4.0 }
    }
}

impl Integrator for PathTracer {
    fn bind<'a>(&'a self, frame: FrameContext<'a>) -> Box<dyn FrameIntegrator + 'a> {
        Box::new(PathTracerFrame { settings: *self, frame, sun: SunLight::new(frame.scene) })
    }
}

/// Scales `c` down so its largest component is at most `max`.
fn clamp_radiance(c: Vec3, max: f32) -> Vec3 {
    let m = c.max_element();
    if m > max {
        c * (max / m)
    } else {
        c
    }
}

fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 {
        a2 / (a2 + b2)
    } else {
        0.0
    }
}

/// The sun as an area light on the sky: a disc of `cos_max` around its direction with uniform
/// radiance `radiance`, sampled uniformly over its solid angle `1 / pdf`.
struct SunLight {
    dir: Vec3,
    cos_max: f32,
    radiance: Vec3,
    pdf: f32,
}

impl SunLight {
    fn new(scene: &RenderScene) -> Self {
        let cos_max = scene.sun.angular_radius_deg.max(0.01).to_radians().cos();
        let solid_angle = 2.0 * PI * (1.0 - cos_max);
        Self {
            dir: scene.sun.direction,
            cos_max,
            radiance: scene.sun.irradiance / solid_angle,
            pdf: 1.0 / solid_angle,
        }
    }

    fn contains(&self, d: Vec3) -> bool {
        d.dot(self.dir) >= self.cos_max
    }
}

/// A [`PathTracer`] bound to a frame, with the frame's sun as an area light.
struct PathTracerFrame<'a> {
    settings: PathTracer,
    frame: FrameContext<'a>,
    sun: SunLight,
}

impl FrameIntegrator for PathTracerFrame<'_> {
    fn li_from_hit(
        &self,
        camera_ray: &Ray,
        first: Option<Hit>,
        sampler: &PixelSampler,
        index: u32,
        rays: &mut u64,
    ) -> Vec3 {
        let FrameContext { scene, query } = self.frame;
        let sun = &self.sun;
        let mut ray = *camera_ray;
        let mut radiance = Vec3::ZERO;
        let mut beta = Vec3::ONE;
        let clamp = self.settings.clamp_indirect;
        // Direct light at the first vertex is never clamped; everything later is.
        let add = |radiance: &mut Vec3, c: Vec3, depth: u32| {
            *radiance += if depth == 0 { c } else { clamp_radiance(c, clamp) };
        };
        // The BSDF sample that made `ray`: its pdf and the shading normal it left from (for the
        // sky's light pdf); `None` for the camera ray, which sees lights without MIS.
        let mut came_from: Option<(f32, Vec3)> = None;
        for depth in 0..self.settings.max_depth {
            *rays += 1;
            let hit = if depth == 0 { first } else { query.intersect(&ray) };
            let Some(hit) = hit else {
                let d = ray.dir.normalize();
                let sky = scene.sky.radiance(d);
                let sun_l = if sun.contains(d) { sun.radiance } else { Vec3::ZERO };
                let c = beta
                    * match came_from {
                        None => sky + sun_l,
                        Some((p, n)) => {
                            let w_sky = power_heuristic(p, n.dot(d).max(0.0) / PI);
                            sky * w_sky + sun_l * power_heuristic(p, sun.pdf)
                        }
                    };
                // Light reached through a bounce from vertex depth-1.
                add(&mut radiance, c, depth.saturating_sub(1));
                break;
            };
            let s = scene.surface(&ray, &hit);
            if s.emission != Vec3::ZERO {
                // Emission seen directly, or reached through a bounce from vertex depth-1,
                // where emitter sampling could have found it too.
                let w = match came_from {
                    Some((pdf_bsdf, _)) if !scene.emitters.is_empty() => {
                        let d = s.p - ray.origin;
                        let cos = s.ng.dot(ray.dir.normalize()).abs();
                        let pdf_light =
                            scene.emitters.pdf_area(s.material.emissive) * d.length_squared() / cos.max(1e-8);
                        power_heuristic(pdf_bsdf, pdf_light)
                    }
                    _ => 1.0,
                };
                add(&mut radiance, beta * s.emission * w, depth.saturating_sub(1));
            }
            let wo = -ray.dir.normalize();
            let bsdf = Bsdf::new(&s.material, s.ns);
            let origin = offset_origin(s.p, s.ng);
            let dim = dims::BOUNCE + 4 * depth;

            // Punctual lights: delta distributions, so light sampling alone.
            for light in &scene.lights {
                let Some((l, e, distance)) = punctual_light(light, s.p) else { continue };
                let f = bsdf.eval(wo, l);
                if f != Vec3::ZERO && s.ng.dot(l) > 0.0 {
                    *rays += 1;
                    if !query.intersect_p(&shadow_ray(origin, l, distance)) {
                        add(&mut radiance, beta * f * e, depth);
                    }
                }
            }

            // Sun: sample its disc. Shadow rays stay single rays: in `dormant bench render`,
            // sun shadow rays of neighbouring pixels traced as Embree packets ran 0.9-1.1x as
            // fast as single rays on the monastery at 2x2-8x1 (1.2-1.5x at 4x4; 1.6-3.8x on
            // the small default scene), and packing them would mean shading a whole pixel
            // block's first vertex before any of its shadow rays (docs/performance.md, "Ray
            // packets").
            let l = sample_cone(sun.dir, sun.cos_max, sampler.get_2d(index, dim));
            let f = bsdf.eval(wo, l);
            if f != Vec3::ZERO && s.ng.dot(l) > 0.0 {
                *rays += 1;
                if !query.intersect_p(&Ray::new(origin, l)) {
                    let w = power_heuristic(sun.pdf, bsdf.pdf(wo, l));
                    add(&mut radiance, beta * f * sun.radiance * (w / sun.pdf), depth);
                }
            }
            // Sky: cosine-weighted around the shading normal.
            let d = sample_cosine(s.ns, sampler.get_2d(index, dim + 1));
            let pdf_sky = s.ns.dot(d).max(0.0) / PI;
            let f = bsdf.eval(wo, d);
            if f != Vec3::ZERO && pdf_sky > 0.0 && s.ng.dot(d) > 0.0 {
                *rays += 1;
                if !query.intersect_p(&Ray::new(origin, d)) {
                    let w = power_heuristic(pdf_sky, bsdf.pdf(wo, d));
                    add(&mut radiance, beta * f * scene.sky.radiance(d) * (w / pdf_sky), depth);
                }
            }

            // Emissive triangles: one point on one of them, MIS against BSDF sampling.
            if !scene.emitters.is_empty() {
                let dim = dims::EMITTER + 2 * depth;
                let u_pick = sampler.get_2d(index, dim).x;
                if let Some((e, le)) = scene.sample_emitter(u_pick, sampler.get_2d(index, dim + 1)) {
                    let d = e.p - s.p;
                    let dist2 = d.length_squared();
                    let wi = d / dist2.sqrt();
                    let cos_light = e.n.dot(wi).abs();
                    let f = bsdf.eval(wo, wi);
                    if dist2 > 0.0 && cos_light > 0.0 && f != Vec3::ZERO && s.ng.dot(wi) > 0.0 {
                        let pdf_light = e.pdf_area * dist2 / cos_light;
                        *rays += 1;
                        if !query.intersect_p(&Ray::segment(origin, wi, 0.0, dist2.sqrt() * (1.0 - 1e-3))) {
                            let w = power_heuristic(pdf_light, bsdf.pdf(wo, wi));
                            add(&mut radiance, beta * f * le * (w / pdf_light), depth);
                        }
                    }
                }
            }

            // Continue the path by sampling the BSDF.
            let u = sampler.get_2d(index, dim + 2);
            let u_lobe = sampler.get_2d(index, dim + 3);
            let Some(sample) = bsdf.sample(wo, u, u_lobe.x) else { break };
            if s.ng.dot(sample.wi) <= 0.0 {
                break;
            }
            beta *= sample.weight;
            if depth >= 3 {
                let q = beta.max_element().min(0.95);
                if u_lobe.y >= q {
                    break;
                }
                beta /= q;
            }
            came_from = Some((sample.pdf, s.ns));
            ray = Ray::new(origin, sample.wi);
        }
        radiance
    }
}
