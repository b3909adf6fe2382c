//! The path tracer (`--mode path`, the default): unidirectional paths on the
//! metallic-roughness BSDF with next-event estimation at every vertex.

use std::f32::consts::{FRAC_1_PI, PI};

use glam::Vec3;

use super::{dims, punctual_light, shadow_ray, FrameContext, FrameIntegrator, Integrator};
use crate::accel::Hit;
use crate::geometry::{offset_origin, Ray};
use crate::render::bsdf::{Bsdf, Frame};
use crate::render::{PixelSampler, RayLog, RenderScene, SurfaceHit};

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

/// A light sample's MIS weight over its pdf, `power_heuristic(a, b) / a`, as one quotient
/// `a / (a^2 + b^2)` (`a > 0`, the light sample's pdf; `b` the BSDF's).
fn power_heuristic_over_pdf(a: f32, b: f32) -> f32 {
    debug_assert!(a > 0.0, "light pdf {a}");
    a / (a * a + b * b)
}

/// The sun as an area light on the sky: a disc of `cos_max` around its direction with uniform
/// radiance `radiance`, sampled uniformly over its solid angle `1 / pdf`.
struct SunLight {
    /// Its direction, with a basis around it built once per frame.
    frame: Frame,
    cos_max: f32,
    radiance: Vec3,
    pdf: f32,
}

impl SunLight {
    fn new(scene: &RenderScene) -> Self {
        let cos_max = scene.sun.angular_radius_deg.max(0.01).to_radians().cos();
        let solid_angle = 2.0 * PI * (1.0 - cos_max);
        Self {
            frame: Frame::new(scene.sun.direction),
            cos_max,
            radiance: scene.sun.irradiance / solid_angle,
            pdf: 1.0 / solid_angle,
        }
    }

    fn contains(&self, d: Vec3) -> bool {
        d.dot(self.frame.n) >= self.cos_max
    }
}

/// A [`PathTracer`] bound to a frame, with the frame's sun as an area light.
struct PathTracerFrame<'a> {
    settings: PathTracer,
    frame: FrameContext<'a>,
    sun: SunLight,
}

/// One camera sample's path in flight: where its sample points come from, the light gathered
/// so far, the throughput up to the current vertex and how the current ray was sampled.
struct Path<'r, 'l> {
    sampler: &'r PixelSampler,
    index: u32,
    log: &'r mut RayLog<'l>,
    radiance: Vec3,
    beta: Vec3,
    /// The BSDF sample that made the current ray: its pdf and the shading normal it left from
    /// (for the sky's light pdf); `None` for the camera ray, which sees lights without MIS.
    came_from: Option<(f32, Vec3)>,
    clamp_indirect: f32,
}

impl Path<'_, '_> {
    /// Adds light `c` that reaches the camera through vertex `depth`. Direct light at the
    /// first vertex is never clamped; everything later is.
    fn add(&mut self, c: Vec3, depth: u32) {
        self.radiance += if depth == 0 { c } else { clamp_radiance(c, self.clamp_indirect) };
    }
}

/// A path vertex being shaded: the surface, the BSDF there seen from the direction back along
/// the path, the offset origin of rays leaving it, its depth (0 at the camera ray's hit) and
/// the shutter time of the path, which every ray leaving it keeps.
struct Vertex {
    s: SurfaceHit,
    bsdf: Bsdf,
    origin: Vec3,
    depth: u32,
    time: f32,
}

impl Vertex {
    fn new(s: SurfaceHit, ray: &Ray, depth: u32) -> Self {
        let wo = -ray.dir.normalize();
        let bsdf = Bsdf::new(&s.material, s.ns, wo);
        let origin = offset_origin(s.p, s.ng);
        Self { s, bsdf, origin, depth, time: ray.time }
    }

    /// First sampler dimension pair of this vertex's BSDF, sun and sky samples.
    fn dim(&self) -> u32 {
        dims::BOUNCE + 4 * self.depth
    }
}

impl FrameIntegrator for PathTracerFrame<'_> {
    fn li_from_hit(
        &self,
        camera_ray: &Ray,
        first: Option<Hit>,
        sampler: &PixelSampler,
        index: u32,
        log: &mut RayLog,
    ) -> Vec3 {
        let mut path = Path {
            sampler,
            index,
            log,
            radiance: Vec3::ZERO,
            beta: Vec3::ONE,
            came_from: None,
            clamp_indirect: self.settings.clamp_indirect,
        };
        let mut ray = *camera_ray;
        for depth in 0..self.settings.max_depth {
            let hit = if depth == 0 { first } else { self.frame.intersect(&ray, path.log) };
            let Some(hit) = hit else {
                // Light reached through a bounce from vertex depth-1.
                let c = path.beta * self.escaped(&ray, path.came_from);
                path.add(c, depth.saturating_sub(1));
                break;
            };
            let s = self.frame.scene.surface(&ray, &hit);
            if s.emission != Vec3::ZERO {
                // Emission seen directly, or reached through a bounce from vertex depth-1.
                let c = path.beta * s.emission * self.emission_weight(&ray, &s, path.came_from);
                path.add(c, depth.saturating_sub(1));
            }
            let vertex = Vertex::new(s, &ray, depth);
            self.punctual_lights(&vertex, &mut path);
            self.sun(&vertex, &mut path);
            self.sky(&vertex, &mut path);
            self.emitter(&vertex, &mut path);
            let Some(next) = continue_path(&vertex, &mut path) else { break };
            ray = next;
        }
        path.radiance
    }
}

impl PathTracerFrame<'_> {
    /// Radiance of the sky and the sun's disc along `ray`, which escaped the scene, weighted
    /// against light sampling at the vertex it left (`came_from`, see [`Path`]).
    fn escaped(&self, ray: &Ray, came_from: Option<(f32, Vec3)>) -> Vec3 {
        let d = ray.dir.normalize();
        let sky = self.frame.scene.sky.radiance(d);
        let sun_l = if self.sun.contains(d) { self.sun.radiance } else { Vec3::ZERO };
        match came_from {
            None => sky + sun_l,
            Some((p, n)) => {
                let w_sky = power_heuristic(p, n.dot(d).max(0.0) * FRAC_1_PI);
                sky * w_sky + sun_l * power_heuristic(p, self.sun.pdf)
            }
        }
    }

    /// MIS weight of emission at `s`, hit by `ray`: 1 when seen by the camera (or when no
    /// emitter is light-sampled), else against the emitter sampling that could have found it
    /// from the vertex the ray left.
    fn emission_weight(&self, ray: &Ray, s: &SurfaceHit, came_from: Option<(f32, Vec3)>) -> f32 {
        let emitters = &self.frame.scene.emitters;
        match came_from {
            Some((pdf_bsdf, _)) if !emitters.is_empty() => {
                let d = s.p - ray.origin;
                let cos = s.ng.dot(ray.dir.normalize()).abs();
                let pdf_light = emitters.pdf_area(s.material.emissive) * d.length_squared() / cos.max(1e-8);
                power_heuristic(pdf_bsdf, pdf_light)
            }
            _ => 1.0,
        }
    }

    /// Punctual lights: delta distributions, so light sampling alone.
    fn punctual_lights(&self, v: &Vertex, path: &mut Path) {
        for light in &self.frame.scene.lights {
            let Some((l, e, distance)) = punctual_light(light, v.s.p) else { continue };
            if v.bsdf.reflects(l)
                && v.s.ng.dot(l) > 0.0
                && self.frame.unoccluded(&shadow_ray(v.origin, l, distance).at_time(v.time), path.log)
            {
                path.add(path.beta * v.bsdf.eval(l) * e, v.depth);
            }
        }
    }

    /// The sun: a direction in its disc, MIS against BSDF sampling. Shadow rays stay single
    /// rays: as Embree packets of neighbouring pixels they paid on the monastery only in 4x4
    /// blocks, and packing them would mean shading a whole pixel block's first vertex before
    /// any of its shadow rays:
    /// docs/lab/rendering.md#2026-11-22-ray-packets-on-embree-rtcintersect4816-rtcoccluded4816
    ///
    /// Like every light sample here, the shadow ray goes first and the BSDF is evaluated only
    /// when it arrives (a blocked sample needs no BSDF value); [`Bsdf::reflects`] keeps the
    /// rays the BSDF would reject untraced, as testing its value for zero did.
    fn sun(&self, v: &Vertex, path: &mut Path) {
        let sun = &self.sun;
        let l = sun.frame.cone(sun.cos_max, path.sampler.get_2d(path.index, v.dim()));
        if v.bsdf.reflects(l)
            && v.s.ng.dot(l) > 0.0
            && self.frame.unoccluded(&Ray::new(v.origin, l).at_time(v.time), path.log)
        {
            let (f, pdf_bsdf) = v.bsdf.eval_pdf(l);
            let w_over_pdf = power_heuristic_over_pdf(sun.pdf, pdf_bsdf);
            path.add(path.beta * f * sun.radiance * w_over_pdf, v.depth);
        }
    }

    /// The sky: a direction cosine-weighted around the shading normal, MIS against BSDF
    /// sampling.
    fn sky(&self, v: &Vertex, path: &mut Path) {
        let d = v.bsdf.frame().cosine(path.sampler.get_2d(path.index, v.dim() + 1));
        let pdf_sky = v.s.ns.dot(d).max(0.0) * FRAC_1_PI;
        if pdf_sky > 0.0
            && v.bsdf.reflects(d)
            && v.s.ng.dot(d) > 0.0
            && self.frame.unoccluded(&Ray::new(v.origin, d).at_time(v.time), path.log)
        {
            let (f, pdf_bsdf) = v.bsdf.eval_pdf(d);
            let w_over_pdf = power_heuristic_over_pdf(pdf_sky, pdf_bsdf);
            path.add(path.beta * f * self.frame.scene.sky.radiance(d) * w_over_pdf, v.depth);
        }
    }

    /// Emissive triangles: one point on one of them, MIS against BSDF sampling.
    fn emitter(&self, v: &Vertex, path: &mut Path) {
        let scene = self.frame.scene;
        if scene.emitters.is_empty() {
            return;
        }
        let dim = dims::EMITTER + 2 * v.depth;
        let u_pick = path.sampler.get_2d(path.index, dim).x;
        let Some((e, le)) = scene.sample_emitter(u_pick, path.sampler.get_2d(path.index, dim + 1)) else {
            return;
        };
        let d = e.p - v.s.p;
        let dist2 = d.length_squared();
        let wi = d / dist2.sqrt();
        let cos_light = e.n.dot(wi).abs();
        if dist2 > 0.0 && cos_light > 0.0 && v.bsdf.reflects(wi) && v.s.ng.dot(wi) > 0.0 {
            let pdf_light = e.pdf_area * dist2 / cos_light;
            let shadow = Ray::segment(v.origin, wi, 0.0, dist2.sqrt() * (1.0 - 1e-3)).at_time(v.time);
            if self.frame.unoccluded(&shadow, path.log) {
                let (f, pdf_bsdf) = v.bsdf.eval_pdf(wi);
                let w_over_pdf = power_heuristic_over_pdf(pdf_light, pdf_bsdf);
                path.add(path.beta * f * le * w_over_pdf, v.depth);
            }
        }
    }
}

/// Continues the path by sampling the BSDF at `v` (Russian roulette from the fourth vertex
/// on): the next ray, or `None` where the path ends.
fn continue_path(v: &Vertex, path: &mut Path) -> Option<Ray> {
    let u = path.sampler.get_2d(path.index, v.dim() + 2);
    let u_lobe = path.sampler.get_2d(path.index, v.dim() + 3);
    let sample = v.bsdf.sample(u, u_lobe.x)?;
    if v.s.ng.dot(sample.wi) <= 0.0 {
        return None;
    }
    path.beta *= sample.weight;
    if v.depth >= 3 {
        let q = path.beta.max_element().min(0.95);
        if u_lobe.y >= q {
            return None;
        }
        path.beta *= 1.0 / q;
    }
    path.came_from = Some((sample.pdf, v.s.ns));
    Some(Ray::new(v.origin, sample.wi).at_time(v.time))
}
