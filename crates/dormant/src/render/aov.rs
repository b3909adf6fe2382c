//! Arbitrary output variables: per-pixel albedo (the textured base colour), shading normal
//! and depth at the first hit, rendered as integrators so they share tiles, sampling and the
//! film with the beauty pass; and the samples each pixel got.

use glam::Vec3;

use super::{
    render_frame_counted, Film, FrameContext, FrameIntegrator, Integrator, PixelSampler, RayLog, RenderError,
    RenderScene, RenderSettings, RenderStats, SurfaceKind,
};
use crate::accel::{Hit, SceneQuery};
use crate::geometry::Ray;

/// What an AOV pass records. Pixels whose camera ray escapes are 0.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Aov {
    /// Base colour with textures applied (linear RGB).
    Albedo,
    /// World-space shading normal facing the camera, components in [-1, 1].
    Normal,
    /// Distance from the camera to the first hit, in scene units (in all three channels).
    Depth,
    /// Debug view of integration: instanced bodies blue, baked (integrated) bodies orange, the
    /// environment grey, each shaded by the facing ratio so shapes stay readable.
    Baked,
    /// Camera samples the pixel got (the effective spp of adaptive sampling, `--spp`
    /// everywhere without it), in all three channels. Not an integrator's pass: it is the
    /// beauty pass's sample counts ([`render_with_aovs`]).
    Spp,
    /// Camera samples traced this frame: the pixel's samples where its block was traced, 0
    /// where exact temporal reuse took it from an earlier frame (every pixel's samples
    /// without reuse). Shows where the motion is.
    Traced,
}

impl Aov {
    pub fn name(self) -> &'static str {
        match self {
            Aov::Albedo => "albedo",
            Aov::Normal => "normal",
            Aov::Depth => "depth",
            Aov::Baked => "baked",
            Aov::Spp => "spp",
            Aov::Traced => "traced",
        }
    }

    /// Whether the pass is traced by its own integrator (not derived from sample counts).
    pub(crate) fn is_traced(self) -> bool {
        !matches!(self, Aov::Spp | Aov::Traced)
    }
}

/// AOV passes of a frame, each with what it records.
pub(crate) type AovPasses = Vec<(Aov, Film)>;

/// A frame's image with `integrator` and its `aovs` passes, in order. The passes see the
/// image's camera samples: with adaptive sampling, each pixel as many as the image gave it.
pub fn render_with_aovs(
    scene: &RenderScene,
    query: &dyn SceneQuery,
    integrator: &dyn Integrator,
    settings: &RenderSettings,
    aovs: &[Aov],
) -> Result<(Film, RenderStats, AovPasses), RenderError> {
    let (film, stats, samples) = render_frame_counted(scene, query, integrator, settings, None)?;
    let mut passes = Vec::with_capacity(aovs.len());
    for &aov in aovs {
        let pass = match aov {
            Aov::Spp | Aov::Traced => Film {
                width: film.width,
                height: film.height,
                pixels: samples.iter().map(|&n| Vec3::splat(n as f32)).collect(),
            },
            aov => render_frame_counted(scene, query, &AovIntegrator(aov), settings, Some(&samples))?.0,
        };
        passes.push((aov, pass));
    }
    Ok((film, stats, passes))
}

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
        let Some(hit) = first else {
            return Vec3::ZERO;
        };
        let s = self.scene.surface(ray, &hit);
        match self.aov {
            Aov::Albedo => s.material.base_color,
            Aov::Normal => s.ns,
            Aov::Depth => Vec3::splat((s.p - ray.origin).length()),
            Aov::Baked => {
                let colour = match s.kind {
                    SurfaceKind::Environment => Vec3::splat(0.5),
                    SurfaceKind::Instanced => Vec3::new(0.15, 0.35, 0.9),
                    SurfaceKind::Baked => Vec3::new(0.95, 0.55, 0.1),
                };
                colour * (0.35 + 0.65 * s.ns.dot(-ray.dir).abs())
            }
            // Filled from the sample counts by `render_with_aovs`, never traced.
            Aov::Spp | Aov::Traced => Vec3::ZERO,
        }
    }
}
