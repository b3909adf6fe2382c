//! One frame from camera to film: the public entry points ([`render_frame`],
//! [`render_with_aovs`]) and what they share with exact reuse: a [`FramePlan`] rendered in
//! 16x16 tiles spread over rayon ([`render_planned`]), and the tile loop bound to one frame
//! as reuse's [`PlanTracer`] ([`FrameTracer`]). Each pixel's samples depend only on (pixel,
//! frame, index), so the image is identical whatever the thread count or tile order.
//!
//! - `tile_loop.rs`: one tile, block by block (the plan's samples traced, the rest kept);
//! - `packet.rs`: a camera-ray block's pixels and the packet of their camera rays;
//! - `accumulator.rs`: a tile's sums per pixel, and its AOV passes' sums;
//! - `camera_rays.rs`: a pixel sample's camera ray (pixel filter, lens, shutter).

mod accumulator;
mod camera_rays;
mod packet;
mod tile_loop;

use std::time::Instant;

use rayon::prelude::*;

use camera_rays::FrameCamera;
use tile_loop::{Tile, TileRenderer};

use super::reuse::{traced_passes, FramePlan, PlanTracer, PlannedFrame};
use super::{
    Aov, AovIntegrator, AovPasses, Film, FrameContext, Integrator, RenderError, RenderScene, RenderSettings,
    RenderStats,
};
use crate::accel::SceneQuery;

/// Side of the square tiles rayon distributes.
const TILE: u32 = 16;

/// Pixel block whose camera rays (one sample each) are traced together as one packet
/// ([`SceneQuery::intersect_packet`]) before each pixel's integrator continues alone: 8 rays,
/// the AVX2 width. Embree traces 4x2 camera packets 1.3-3.4x as fast as single rays; whole
/// path-traced frames gain a few percent to 10%, camera rays being one in 4-5 of their rays:
/// docs/lab/rendering.md#2026-11-22-ray-packets-on-embree-rtcintersect4816-rtcoccluded4816
const BLOCK: (u32, u32) = (4, 2);
const BLOCK_PIXELS: usize = (BLOCK.0 * BLOCK.1) as usize;

/// Renders one frame with `integrator`, tiles spread over the current rayon pool. Each
/// pixel's samples depend only on (pixel, frame, index), so the image is identical whatever
/// the thread count or tile order.
pub fn render_frame(
    scene: &RenderScene,
    query: &dyn SceneQuery,
    integrator: &dyn Integrator,
    settings: &RenderSettings,
) -> Result<(Film, RenderStats), RenderError> {
    let out = render_planned(scene, query, integrator, settings, &FramePlan::default())?;
    let stats = out.stats();
    Ok((out.film, stats))
}

/// A frame's image with `integrator` and its `aovs` passes, in order. The passes see the
/// image's camera samples: with adaptive sampling, each pixel as many as the image gave it.
pub fn render_with_aovs(
    scene: &RenderScene,
    query: &dyn SceneQuery,
    integrator: &dyn Integrator,
    settings: &RenderSettings,
    aovs: &[Aov],
) -> Result<(Film, RenderStats, AovPasses), RenderError> {
    let traced = traced_passes(aovs);
    let plan = FramePlan { aovs: &traced, ..FramePlan::default() };
    Ok(render_planned(scene, query, integrator, settings, &plan)?.into_image(aovs))
}

/// Renders the blocks `plan` selects, tiles spread over the current rayon pool.
fn render_planned(
    scene: &RenderScene,
    query: &dyn SceneQuery,
    integrator: &dyn Integrator,
    settings: &RenderSettings,
    plan: &FramePlan,
) -> Result<PlannedFrame, RenderError> {
    settings.validate()?;
    let start = Instant::now();
    let (w, h) = (settings.width, settings.height);
    debug_assert!(plan.samples.is_none_or(|s| s.len() == (w * h) as usize));
    let renderer = TileRenderer {
        scene,
        camera: FrameCamera::new(scene, w, h),
        query,
        integrator: &*integrator.bind(FrameContext { scene, query }),
        settings,
        stopping: if plan.samples.is_some() { None } else { settings.adaptive.stopping(settings.spp) },
        plan,
    };
    let tiles_x = w.div_ceil(TILE);
    let tiles: Vec<(u32, u32)> =
        (0..tiles_x * h.div_ceil(TILE)).map(|t| ((t % tiles_x) * TILE, (t / tiles_x) * TILE)).collect();
    let rendered: Vec<(u32, u32, Tile)> =
        tiles.par_iter().map(|&(x0, y0)| (x0, y0, renderer.render(x0, y0))).collect();
    let mut out = PlannedFrame {
        film: Film::new(w, h),
        counts: vec![0; (w * h) as usize],
        horizons: vec![0; (w * h) as usize],
        aovs: plan.aovs.iter().map(|_| Film::new(w, h)).collect(),
        camera_horizons: if plan.keeps_camera_horizons() { vec![0; (w * h) as usize] } else { Vec::new() },
        samples: Vec::new(),
        rays: 0,
        neighbour_rays: 0,
        seconds: 0.0,
        horizon_queries: 0,
        horizon_seconds: 0.0,
    };
    for (x0, y0, tile) in rendered {
        tile.copy_into(&mut out, x0, y0);
    }
    out.seconds = start.elapsed().as_secs_f64();
    Ok(out)
}

/// The tile loop bound to one frame: its scene, geometry, integrator and settings. Exact
/// reuse has it trace its plans ([`PlanTracer`]).
pub(crate) struct FrameTracer<'a> {
    pub scene: &'a RenderScene<'a>,
    pub query: &'a dyn SceneQuery,
    pub integrator: &'a dyn Integrator,
    pub settings: &'a RenderSettings,
}

impl PlanTracer for FrameTracer<'_> {
    fn settings(&self) -> &RenderSettings {
        self.settings
    }

    fn trace(&self, plan: &FramePlan) -> Result<PlannedFrame, RenderError> {
        render_planned(self.scene, self.query, self.integrator, self.settings, plan)
    }

    fn trace_pass(&self, aov: Aov, plan: &FramePlan) -> Result<PlannedFrame, RenderError> {
        render_planned(self.scene, self.query, &AovIntegrator(aov), self.settings, plan)
    }
}
