//! Exact temporal reuse: a frame traces only the pixel blocks whose horizon has come, and takes
//! every other block's pixels from the [`ReuseStore`], which holds the last traced value of
//! every pixel (image, sample count, AOV passes) and each block's horizon.
//!
//! Why it is exact: a block is traced as a full frame traces it (the same camera-ray packets,
//! samples in the same order, adaptive sampling deciding from the pixel's own samples), and
//! its horizon is the earliest later frame whose changes ([`ChangeIndex`]) any of its rays'
//! segments meets. Until then every segment sees the same geometry, so with the camera, lights
//! and seed unchanged every sample computes the same bits, and the stored pixel is the pixel a
//! full render would compute. Whether a frame may reuse at all (camera, lights, seed, the
//! scene's representation) is its caller's to decide ([`FrameReuse::full`]).

use glam::Vec3;
use serde::Serialize;

use super::aov::{AovIntegrator, AovPasses};
use super::tiles::{block_grid, block_index, render_planned, FramePlan, PlannedFrame};
use super::{Aov, Film, Integrator, RenderError, RenderScene, RenderSettings, RenderStats, SppStats};
use crate::accel::bvh::ChangeIndex;
use crate::accel::SceneQuery;

/// What the store keeps of every pixel: a sample count (4 bytes) and one RGB value (12 bytes)
/// for the image and for each AOV pass that is traced.
const PIXEL_BYTES: usize = 4 + 12;

/// The last traced value of every pixel of a sequence's frames, and each pixel block's horizon.
#[derive(Clone, Debug, Default)]
pub struct ReuseStore {
    /// What the stored pixels were rendered with; a frame of other settings starts afresh.
    settings: Option<(RenderSettings, Vec<Aov>)>,
    image: Vec<Vec3>,
    counts: Vec<u32>,
    /// Per traced AOV pass (not `spp` or `traced`, which come from the counts), its pixels.
    passes: Vec<(Aov, Vec<Vec3>)>,
    /// Per block, the ordinal of the first frame that must trace it again.
    horizons: Vec<u32>,
}

/// One frame's use of the store: the change index, this frame's ordinal, the run's number of
/// rendered frames, and whether the frame must be traced in full.
#[derive(Clone, Copy)]
pub struct FrameReuse<'a> {
    pub index: &'a ChangeIndex,
    pub ordinal: u32,
    pub frames: u32,
    /// Trace every block (and refill the store): the first frame, or one where something
    /// every sample sees changed (the camera, a light, the scene's representation).
    pub full: bool,
}

/// What reuse did in a frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct ReuseStats {
    /// Camera samples traced and taken from the store.
    pub samples_traced: u64,
    pub samples_reused: u64,
    /// Pixel blocks traced, of all blocks.
    pub blocks_traced: u64,
    pub blocks: u64,
    /// Horizon queries (one per traced ray segment that could still lower its block's
    /// horizon) and their time, estimated from a sample of them.
    pub horizon_queries: u64,
    pub horizon_ms: f64,
    /// Bytes the store holds.
    pub store_bytes: u64,
}

impl ReuseStore {
    /// The bytes a store of `width` x `height` pixels with `aovs` needs.
    pub fn bytes_for(width: u32, height: u32, aovs: &[Aov]) -> usize {
        let traced_passes = aovs.iter().filter(|a| a.is_traced()).count();
        let (bw, bh) = block_grid(width, height);
        width as usize * height as usize * (PIXEL_BYTES + 12 * traced_passes) + (bw * bh) as usize * 4
    }

    /// Bytes the store holds now.
    pub fn memory_bytes(&self) -> usize {
        let pixels = self.image.len() * 12 + self.counts.len() * 4;
        let passes: usize = self.passes.iter().map(|(_, p)| p.len() * 12).sum();
        pixels + passes + self.horizons.len() * 4
    }

    /// Whether the store holds a frame rendered with `settings` and `aovs`.
    fn fits(&self, settings: &RenderSettings, aovs: &[Aov]) -> bool {
        self.settings.as_ref().is_some_and(|(s, a)| s == settings && a == aovs)
    }

    /// Blocks a frame at `ordinal` must trace: those whose horizon has come.
    fn due(&self, ordinal: u32) -> Vec<bool> {
        self.horizons.iter().map(|&h| h <= ordinal).collect()
    }
}

/// A frame's image with `integrator` and its `aovs` passes, tracing only the blocks `reuse`
/// and the store say must be traced, and the rest taken from `store`, which is brought up to
/// date. The same bits as [`super::render_with_aovs`] (see the module docs); the statistics
/// count only what was traced, but for the samples per pixel, which are the whole frame's.
pub fn render_reusing(
    scene: &RenderScene,
    query: &dyn SceneQuery,
    integrator: &dyn Integrator,
    settings: &RenderSettings,
    aovs: &[Aov],
    reuse: FrameReuse,
    store: &mut ReuseStore,
) -> Result<(Film, RenderStats, AovPasses, ReuseStats), RenderError> {
    let full = reuse.full || !store.fits(settings, aovs);
    let due = (!full).then(|| store.due(reuse.ordinal));
    let plan = FramePlan {
        samples: None,
        blocks: due.as_deref(),
        horizons: Some((reuse.index, reuse.ordinal, reuse.frames)),
    };
    let beauty = render_planned(scene, query, integrator, settings, &plan)?;
    if full {
        *store = ReuseStore {
            settings: Some((*settings, aovs.to_vec())),
            image: vec![Vec3::ZERO; beauty.counts.len()],
            counts: vec![0; beauty.counts.len()],
            passes: aovs
                .iter()
                .filter(|a| a.is_traced())
                .map(|&a| (a, vec![Vec3::ZERO; beauty.counts.len()]))
                .collect(),
            horizons: beauty.horizons.clone(),
        };
    }
    let traced = due.unwrap_or_else(|| vec![true; beauty.horizons.len()]);
    let merged = merge(store, &beauty, &traced, settings.width);
    let mut seconds = beauty.seconds;
    for i in 0..store.passes.len() {
        let aov = store.passes[i].0;
        let plan = FramePlan { samples: Some(&store.counts), blocks: Some(&traced), horizons: None };
        let pass = render_planned(scene, query, &AovIntegrator(aov), settings, &plan)?;
        seconds += pass.seconds;
        copy_blocks(&mut store.passes[i].1, &pass.film.pixels, &traced, settings.width);
    }
    let (film, passes) = store.frame(aovs, &traced, settings);
    let stats = RenderStats { rays: beauty.rays, seconds, spp: SppStats::of(&store.counts) };
    let reuse_stats = ReuseStats {
        samples_traced: merged.0,
        samples_reused: merged.1,
        blocks_traced: traced.iter().filter(|t| **t).count() as u64,
        blocks: traced.len() as u64,
        horizon_queries: beauty.horizon_queries,
        horizon_ms: beauty.horizon_seconds * 1e3,
        store_bytes: store.memory_bytes() as u64,
    };
    Ok((film, stats, passes, reuse_stats))
}

/// Copies the traced blocks of `beauty` (image, counts, horizons) into `store`; returns the
/// camera samples traced and reused.
fn merge(store: &mut ReuseStore, beauty: &PlannedFrame, traced: &[bool], width: u32) -> (u64, u64) {
    copy_blocks(&mut store.image, &beauty.film.pixels, traced, width);
    let (mut samples_traced, mut samples_reused) = (0u64, 0u64);
    for (i, (&count, stored)) in beauty.counts.iter().zip(store.counts.iter_mut()).enumerate() {
        let (x, y) = (i as u32 % width, i as u32 / width);
        if traced[block_index(width, x, y)] {
            *stored = count;
            samples_traced += u64::from(count);
        } else {
            samples_reused += u64::from(*stored);
        }
    }
    for (b, &horizon) in beauty.horizons.iter().enumerate() {
        if traced[b] {
            store.horizons[b] = horizon;
        }
    }
    (samples_traced, samples_reused)
}

/// Copies the pixels of the traced blocks from `from` into `to` (both row-major, `width` wide).
fn copy_blocks(to: &mut [Vec3], from: &[Vec3], traced: &[bool], width: u32) {
    for (i, (to, from)) in to.iter_mut().zip(from).enumerate() {
        if traced[block_index(width, i as u32 % width, i as u32 / width)] {
            *to = *from;
        }
    }
}

impl ReuseStore {
    /// The stored frame as images: the beauty image and `aovs` in order (`spp` and `traced`
    /// from the counts and the blocks `traced` this frame).
    fn frame(&self, aovs: &[Aov], traced: &[bool], settings: &RenderSettings) -> (Film, AovPasses) {
        let (w, h) = (settings.width, settings.height);
        let film = |pixels: Vec<Vec3>| Film { width: w, height: h, pixels };
        let passes = aovs
            .iter()
            .map(|&aov| {
                let pixels = match aov {
                    Aov::Spp => self.counts.iter().map(|&n| Vec3::splat(n as f32)).collect(),
                    Aov::Traced => self
                        .counts
                        .iter()
                        .enumerate()
                        .map(|(i, &n)| {
                            let block = block_index(w, i as u32 % w, i as u32 / w);
                            Vec3::splat(if traced[block] { n as f32 } else { 0.0 })
                        })
                        .collect(),
                    aov => self
                        .passes
                        .iter()
                        .find(|(a, _)| *a == aov)
                        .map(|(_, p)| p.clone())
                        .unwrap_or_default(),
                };
                (aov, film(pixels))
            })
            .collect();
        (film(self.image.clone()), passes)
    }
}
