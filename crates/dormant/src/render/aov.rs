//! Arbitrary output variables: per-pixel albedo (the textured base colour), shading normal
//! and depth at the first hit, and the samples each pixel got. A frame's passes are shaded at
//! the beauty pass's camera hits as it traces them (no second trace of the camera rays); a
//! pass alone, as exact reuse retraces where only the passes changed, is an integrator
//! ([`AovIntegrator`](super::AovIntegrator), `integrator/aov_pass.rs`) over the same tiles,
//! sampling and film, so both give the same bits ([`render_with_aovs`](super::render_with_aovs)
//! renders a frame's image with its passes).

use glam::Vec3;

use super::{Film, RenderScene, SurfaceKind};
use crate::accel::Hit;
use crate::geometry::Ray;
use crate::names::{named_enum, Named};

named_enum! {
    /// What an AOV pass records. Pixels whose camera ray escapes are 0.
    #[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
    #[serde(rename_all = "lowercase")]
    pub enum Aov {
        /// Base colour with textures applied (linear RGB).
        Albedo = "albedo",
        /// World-space shading normal facing the camera, components in [-1, 1].
        Normal = "normal",
        /// Distance from the camera to the first hit, in scene units (in all three channels).
        Depth = "depth",
        /// Debug view of integration: instanced bodies blue, baked (integrated) bodies orange, the
        /// environment grey, each shaded by the facing ratio so shapes stay readable.
        Baked = "baked",
        /// Camera samples the pixel got (the effective spp of adaptive sampling, `--spp`
        /// everywhere without it), in all three channels.
        ///
        /// Not an integrator's pass: it is the beauty pass's sample counts
        /// ([`render_with_aovs`](super::render_with_aovs)).
        Spp = "spp",
        /// Camera samples traced this frame: the pixel's samples where its block was traced, 0
        /// where exact temporal reuse took it from an earlier frame (every pixel's samples
        /// without reuse). Shows where the motion is.
        Traced = "traced",
    }
}

impl Aov {
    /// The pass's name ([`Named::name`], callable without the trait): `frame_NNNN.<name>.png`.
    pub fn name(self) -> &'static str {
        Named::name(self)
    }

    /// Whether the pass is traced by its own integrator (not derived from sample counts).
    pub(crate) fn is_traced(self) -> bool {
        !matches!(self, Aov::Spp | Aov::Traced)
    }
}

/// AOV passes of a frame, each with what it records.
pub(crate) type AovPasses = Vec<(Aov, Film)>;

/// What `aov` records of camera ray `ray`'s first hit `first` (0 where it escapes).
pub(crate) fn aov_at_hit(aov: Aov, scene: &RenderScene, ray: &Ray, first: Option<&Hit>) -> Vec3 {
    let Some(hit) = first else {
        return Vec3::ZERO;
    };
    let s = scene.surface(ray, hit);
    match aov {
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
        // Filled from the sample counts, never traced.
        Aov::Spp | Aov::Traced => Vec3::ZERO,
    }
}
