//! Integrators: the interface ([`Integrator`] bound to one frame's [`FrameContext`] as a
//! [`FrameIntegrator`]), the sampler dimensions they draw from, what they share about
//! punctual lights and shadow rays, and the [`RayLog`] every ray they trace is recorded in
//! (`ray_log.rs`). The integrators themselves: path tracing in `path.rs`, the direct-light
//! preview and ambient occlusion in `preview.rs`, one AOV pass in `aov_pass.rs` (what the
//! passes record is `render/aov.rs`).

pub(super) mod aov_pass;
pub(super) mod path;
pub(super) mod preview;
pub(super) mod ray_log;

use glam::Vec3;

use super::{PixelSampler, RenderScene};
use crate::accel::{Hit, Occluder, SceneQuery};
use crate::geometry::Ray;
use crate::scene::Light;
use ray_log::RayLog;

/// What an integrator sees of one frame: the shading data, camera and lights
/// ([`RenderScene`]) and the committed geometry to trace rays against.
#[derive(Clone, Copy)]
pub struct FrameContext<'a> {
    pub scene: &'a RenderScene<'a>,
    pub query: &'a dyn SceneQuery,
}

impl FrameContext<'_> {
    /// The closest hit along `ray`, recorded in `log`.
    fn intersect(&self, ray: &Ray, log: &mut RayLog) -> Option<Hit> {
        let hit = self.query.intersect(ray);
        log.closest(ray, hit.as_ref());
        hit
    }

    /// Whether nothing blocks `ray` (a shadow ray: any hit counts), recorded in `log` with
    /// its blocker when the log finds horizons.
    fn unoccluded(&self, ray: &Ray, log: &mut RayLog) -> bool {
        let blocker = if log.finds_horizon() {
            self.query.occluder(ray)
        } else {
            self.query.intersect_p(ray).then_some(Occluder::Unknown)
        };
        log.any(ray, blocker);
        blocker.is_none()
    }
}

/// An integrator's settings. Object-safe, so the command line picks one at run time
/// (`Box<dyn Integrator>`); rendering a frame first binds it to the frame's scene.
pub trait Integrator: Sync {
    /// This integrator bound to `frame` (as pbrt-v4 binds scene and lights at construction),
    /// with whatever stays fixed over the frame computed once.
    fn bind<'a>(&'a self, frame: FrameContext<'a>) -> Box<dyn FrameIntegrator + 'a>;
}

/// An integrator bound to one frame: computes the radiance arriving along camera rays.
pub trait FrameIntegrator: Sync {
    /// Radiance along camera ray `ray` whose closest hit `first` the caller traced (as
    /// `query.intersect(ray)`, possibly in a packet with neighbouring pixels) and recorded in
    /// `log`, for sample `index` of `sampler`; records every further ray it traces in `log`.
    fn li_from_hit(
        &self,
        ray: &Ray,
        first: Option<Hit>,
        sampler: &PixelSampler,
        index: u32,
        log: &mut RayLog,
    ) -> Vec3;
}

/// Dimension pairs of the pixel sampler, so each decision gets its own stratified points.
pub(crate) mod dims {
    pub(crate) const PIXEL: u32 = 0;
    pub(crate) const SUN: u32 = 1;
    pub(crate) const SKY: u32 = 2;
    /// Path vertices use `BOUNCE + 4 * depth + k`, `k` in 0..4.
    pub(crate) const BOUNCE: u32 = 3;
    /// Emitter sampling at path vertex `depth` uses `EMITTER + 2 * depth + k`, `k` in 0..2
    /// (past every `BOUNCE` pair of the longest path, 64 bounces).
    pub(crate) const EMITTER: u32 = BOUNCE + 4 * 64;
    /// The point on the camera's lens (depth of field).
    pub(crate) const LENS: u32 = EMITTER + 2 * 64;
    /// The camera sample's time in the shutter (motion blur; one dimension, `get_1d`).
    pub(crate) const TIME: u32 = LENS + 1;
}

/// Light from a punctual light reaching point `p`: the unit direction towards the light, the
/// irradiance it gives a surface facing it, and the distance to it (infinite for directional
/// lights). `None` when `p` is outside a spot's cone or on a point light.
fn punctual_light(light: &Light, p: Vec3) -> Option<(Vec3, Vec3, f32)> {
    let towards = |position: Vec3| {
        let d = position - p;
        let r2 = d.length_squared();
        (r2 > 0.0 && r2.is_finite()).then(|| (d / r2.sqrt(), r2))
    };
    match *light {
        Light::Point { position, intensity } => {
            let (wi, r2) = towards(position)?;
            Some((wi, intensity / r2, r2.sqrt()))
        }
        Light::Spot { position, direction, intensity, cos_inner, cos_outer } => {
            let (wi, r2) = towards(position)?;
            let cos = (-wi).dot(direction);
            if cos <= cos_outer {
                return None;
            }
            // glTF's recommended smooth falloff between the cones.
            let t = if cos_inner > cos_outer {
                ((cos - cos_outer) / (cos_inner - cos_outer)).min(1.0)
            } else {
                1.0
            };
            Some((wi, intensity * (t * t) / r2, r2.sqrt()))
        }
        Light::Directional { direction, irradiance } => Some((-direction, irradiance, f32::INFINITY)),
    }
}

/// A shadow ray from `origin` towards a light `distance` away in unit direction `wi`.
fn shadow_ray(origin: Vec3, wi: Vec3, distance: f32) -> Ray {
    Ray::segment(origin, wi, 0.0, if distance.is_finite() { distance * (1.0 - 1e-4) } else { f32::INFINITY })
}
