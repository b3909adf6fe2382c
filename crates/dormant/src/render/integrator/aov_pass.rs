//! [`AovIntegrator`]: one AOV pass as the integrator, shading only camera-ray hits. A frame's
//! passes are normally shaded at the beauty pass's camera hits as it traces them; exact reuse
//! traces a pass on its own where only the passes changed, over the same tiles, sampling and
//! film, so both give the same bits.

use glam::Vec3;

use super::{FrameContext, FrameIntegrator, Integrator, RayLog};
use crate::accel::Hit;
use crate::geometry::Ray;
use crate::render::aov::aov_at_hit;
use crate::render::{Aov, PixelSampler, RenderScene};

/// An [`Integrator`] that returns one AOV at the camera ray's first hit.
#[derive(Clone, Copy, Debug)]
pub struct AovIntegrator(pub Aov);

impl Integrator for AovIntegrator {
    fn bind<'a>(&'a self, frame: FrameContext<'a>) -> Box<dyn FrameIntegrator + 'a> {
        Box::new(AovFrame { aov: self.0, scene: frame.scene })
    }
}

/// [`AovIntegrator`] bound to a frame: it only shades camera-ray hits, so it needs no query.
struct AovFrame<'a> {
    aov: Aov,
    scene: &'a RenderScene<'a>,
}

impl FrameIntegrator for AovFrame<'_> {
    fn li_from_hit(
        &self,
        ray: &Ray,
        first: Option<Hit>,
        _sampler: &PixelSampler,
        _index: u32,
        _log: &mut RayLog,
    ) -> Vec3 {
        aov_at_hit(self.aov, self.scene, ray, first.as_ref())
    }
}
