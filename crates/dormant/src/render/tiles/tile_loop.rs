//! The tile loop: one 16x16 tile of a [`FramePlan`] rendered by [`TileRenderer`]. Its pixels go
//! in 4x2 blocks whose camera rays of one sample index are traced as one packet, each traced
//! sample then finished by the integrator bound to the frame, with the AOV passes shaded at
//! the camera hits; under exact reuse ([`Due::Samples`]) a sample that is not due keeps its
//! lane in the packets and is taken from the store instead.

use glam::Vec3;

use super::accumulator::{Accumulator, FirstHits};
use super::camera_rays::{camera_ray, FrameCamera};
use super::packet::{CameraPacket, Cell, Cells};
use super::{BLOCK, BLOCK_PIXELS, TILE};
use crate::accel::{Hit, SceneQuery};
use crate::geometry::Ray;
use crate::render::adaptive::Stopping;
use crate::render::aov::aov_at_hit;
use crate::render::reuse::{Due, FramePlan, PlannedFrame, StoredSamples, TracedSample};
use crate::render::{FrameIntegrator, PixelSampler, RayLog, RenderScene, RenderSettings};

/// A rendered tile: its pixels row by row, the samples each got and each one's horizon (0
/// without horizons), the rays traced, and what finding the horizons cost.
pub(super) struct Tile {
    pixels: Vec<Vec3>,
    samples: Vec<u32>,
    horizons: Vec<u32>,
    /// The plan's AOV passes, `aov_count` values per pixel, and their camera rays' horizons.
    aovs: Vec<Vec3>,
    aov_count: usize,
    camera_horizons: Vec<u32>,
    /// With [`Due::Samples`], the samples traced.
    traced: Vec<TracedSample>,
    rays: u64,
    neighbour_rays: u64,
    horizon_queries: u64,
    horizon_seconds: f64,
}

impl Tile {
    /// Copies this tile, whose top-left pixel is `(x0, y0)`, into `frame`.
    pub(super) fn copy_into(self, frame: &mut PlannedFrame, x0: u32, y0: u32) {
        let w = frame.film.width;
        let tw = (x0 + TILE).min(w) - x0;
        for (i, ((p, n), horizon)) in self.pixels.into_iter().zip(self.samples).zip(self.horizons).enumerate()
        {
            let at = ((y0 + i as u32 / tw) * w + x0 + i as u32 % tw) as usize;
            frame.film.pixels[at] = p;
            frame.counts[at] = n;
            frame.horizons[at] = horizon;
            for (k, film) in frame.aovs.iter_mut().enumerate() {
                film.pixels[at] = self.aovs[i * self.aov_count + k];
            }
            if let Some(&camera) = self.camera_horizons.get(i) {
                frame.camera_horizons[at] = camera;
            }
        }
        if !self.traced.is_empty() {
            frame.samples.push(self.traced);
        }
        frame.rays += self.rays;
        frame.neighbour_rays += self.neighbour_rays;
        frame.horizon_queries += self.horizon_queries;
        frame.horizon_seconds += self.horizon_seconds;
    }
}

/// What every tile of a frame is rendered with.
pub(super) struct TileRenderer<'a> {
    pub scene: &'a RenderScene<'a>,
    pub camera: FrameCamera,
    /// Traces the camera-ray packets; the integrator traces the rest.
    pub query: &'a dyn SceneQuery,
    pub integrator: &'a dyn FrameIntegrator,
    pub settings: &'a RenderSettings,
    /// Adaptive sampling's rule, when on and no sample counts are fixed.
    pub stopping: Option<Stopping>,
    /// Which blocks, with how many samples, and whether to find their horizons.
    pub plan: &'a FramePlan<'a>,
}

impl TileRenderer<'_> {
    /// The tile whose top-left pixel is `(x0, y0)`.
    pub(super) fn render(&self, x0: u32, y0: u32) -> Tile {
        let (w, h) = (self.settings.width, self.settings.height);
        let (x1, y1) = ((x0 + TILE).min(w), (y0 + TILE).min(h));
        let n = ((x1 - x0) * (y1 - y0)) as usize;
        let first_hits = FirstHits::new(self.plan.aovs.len(), n, self.plan.keeps_camera_horizons());
        let mut acc = Accumulator::new(x0, y0, (x1 - x0, y1 - y0), self.stopping.is_some(), first_hits);
        let mut tile = Tile {
            pixels: Vec::new(),
            samples: Vec::new(),
            horizons: vec![0; n],
            aovs: Vec::new(),
            aov_count: self.plan.aovs.len(),
            camera_horizons: Vec::new(),
            traced: Vec::new(),
            rays: 0,
            neighbour_rays: 0,
            horizon_queries: 0,
            horizon_seconds: 0.0,
        };
        for by in (y0..y1).step_by(BLOCK.1 as usize) {
            for bx in (x0..x1).step_by(BLOCK.0 as usize) {
                if !self.any_due(bx, by, x1, y1) {
                    continue;
                }
                let cells = self.cells(bx, by, x1, y1);
                let mut logs: [RayLog; BLOCK_PIXELS] = std::array::from_fn(|_| self.new_log());
                match self.plan.due {
                    Due::Samples { stored, .. } => {
                        self.render_block_samples(&cells, stored, &mut acc, &mut logs, &mut tile.traced)
                    }
                    _ => self.render_block(&cells, &mut acc, &mut logs),
                }
                for (cell, log) in cells.cells[..cells.len].iter().zip(&logs) {
                    tile.rays += log.rays;
                    tile.neighbour_rays += log.neighbour_rays;
                    let (queries, seconds) = log.query_cost();
                    tile.horizon_queries += u64::from(queries);
                    tile.horizon_seconds += seconds;
                    if let (true, Some(horizon)) = (cell.traced, log.horizon()) {
                        tile.horizons[acc.at(cell)] = horizon;
                    }
                }
            }
        }
        tile.pixels = acc.sums.iter().zip(&acc.samples).map(|(&sum, &k)| sum / k.max(1) as f32).collect();
        tile.samples = acc.samples;
        (tile.aovs, tile.camera_horizons) = acc.first_hits.finish();
        tile
    }

    /// A log for the rays of a pixel (or a sample), finding horizons when the plan asks.
    fn new_log(&self) -> RayLog<'_> {
        match self.plan.horizons {
            Some((index, ordinal, until)) => RayLog::with_horizon(index, self.scene, ordinal, until),
            None => RayLog::counting(),
        }
    }

    /// Whether sample `i` of `cell`'s pixel is traced.
    fn sample_due(&self, cell: &Cell, i: u32) -> bool {
        match self.plan.due {
            Due::Samples { stored, ordinal, .. } => {
                i >= stored.counts[cell.pixel as usize]
                    || stored.horizons[cell.pixel as usize * self.settings.spp as usize + i as usize]
                        <= ordinal
            }
            _ => cell.traced,
        }
    }

    /// Whether the block whose top-left pixel is `(bx, by)`, clipped to `(x1, y1)`, has a pixel
    /// to trace.
    fn any_due(&self, bx: u32, by: u32, x1: u32, y1: u32) -> bool {
        let due = match self.plan.due {
            Due::All => return true,
            Due::Pixels { due, .. } => due,
            Due::Samples { pixels, .. } => pixels,
        };
        let w = self.settings.width;
        (by..(by + BLOCK.1).min(y1)).any(|y| {
            let row = (y * w) as usize;
            due[row + bx as usize..row + (bx + BLOCK.0).min(x1) as usize].iter().any(|&d| d)
        })
    }

    /// The pixels of the block whose top-left pixel is `(bx, by)`, clipped to `(x1, y1)`:
    /// each with its sampler and sample budget. A fixed array, not a Vec: one block per 8
    /// pixels is on the hot path.
    fn cells(&self, bx: u32, by: u32, x1: u32, y1: u32) -> Cells {
        let w = self.settings.width;
        let mut cells = Cells {
            cells: [Cell {
                x: 0,
                y: 0,
                pixel: 0,
                sampler: PixelSampler::new(0, 0, 0),
                budget: 0,
                traced: false,
            }; BLOCK_PIXELS],
            len: 0,
        };
        for y in by..(by + BLOCK.1).min(y1) {
            for x in bx..(bx + BLOCK.0).min(x1) {
                let p = (y * w + x) as usize;
                let traced = match self.plan.due {
                    Due::All => true,
                    Due::Pixels { due, .. } => due[p],
                    Due::Samples { pixels, .. } => pixels[p],
                };
                // A pixel not traced keeps its lanes as when it was: its stored samples.
                let budget = match (self.plan.samples, self.plan.due) {
                    (Some(s), _) => s[p],
                    (None, Due::Pixels { stored, .. }) if !traced => stored[p],
                    (None, Due::Samples { stored, .. }) if !traced => stored.counts[p],
                    _ => self.settings.spp,
                };
                let sampler = PixelSampler::new(x, y, self.settings.seed);
                cells.cells[cells.len] = Cell { x, y, pixel: p as u32, sampler, budget, traced };
                cells.len += 1;
            }
        }
        cells
    }

    /// Samples the pixels of one block in index order, the camera rays of those still
    /// sampling traced as one packet per index, until each has its budget or has converged;
    /// each pixel's rays go into its log. A pixel not traced keeps its lane in the packets but
    /// its path is not continued.
    fn render_block(&self, cells: &Cells, acc: &mut Accumulator, logs: &mut [RayLog; BLOCK_PIXELS]) {
        let block = &cells.cells[..cells.len];
        let mut packet = CameraPacket::new();
        let mut done = [false; BLOCK_PIXELS];
        let most = block.iter().map(|c| c.budget).max().unwrap_or(0);
        for i in 0..most {
            if !packet.select(block, i, &done) {
                break;
            }
            // Camera rays are made only for packets with a pixel to trace.
            if !packet.slots().iter().any(|&c| block[c].traced) {
                continue;
            }
            self.trace_camera_packet(block, i, &mut packet);
            for (k, &c) in packet.slots().iter().enumerate() {
                let (cell, log, ray) = (&block[c], &mut logs[c], &packet.rays[k]);
                if cell.traced {
                    log.closest(ray, packet.hits[k].as_ref());
                    self.shade_aovs(acc, cell, ray, packet.hits[k].as_ref(), None);
                    let li = self.integrator.li_from_hit(ray, packet.hits[k], &cell.sampler, i, log);
                    done[c] = acc.add(cell, li, self.stopping.as_ref());
                } else {
                    log.count_neighbour();
                }
            }
        }
    }

    /// [`Self::render_block`] under [`Due::Samples`]: a sample is traced when due (recorded
    /// with its own horizon in `traced`) and otherwise taken from `stored`; either way it is
    /// added to its pixel, so adaptive sampling stops a pixel where a full frame does. Camera
    /// packets are traced only for an index with a due sample; a pixel with none keeps its
    /// lanes in them.
    fn render_block_samples(
        &self,
        cells: &Cells,
        stored: StoredSamples,
        acc: &mut Accumulator,
        logs: &mut [RayLog; BLOCK_PIXELS],
        traced: &mut Vec<TracedSample>,
    ) {
        let block = &cells.cells[..cells.len];
        let spp = self.settings.spp as usize;
        let mut packet = CameraPacket::new();
        let mut done = [false; BLOCK_PIXELS];
        let most = block.iter().map(|c| c.budget).max().unwrap_or(0);
        for i in 0..most {
            if !packet.select(block, i, &done) {
                break;
            }
            let any_due = packet.slots().iter().any(|&c| self.sample_due(&block[c], i));
            if any_due {
                self.trace_camera_packet(block, i, &mut packet);
            }
            for (k, &c) in packet.slots().iter().enumerate() {
                let cell = &block[c];
                let due = any_due && self.sample_due(cell, i);
                if any_due && !due {
                    logs[c].count_neighbour();
                }
                if !cell.traced {
                    continue;
                }
                let li = match due {
                    true => {
                        let (ray, hit) = (&packet.rays[k], packet.hits[k]);
                        let (sample, camera) = self.trace_sample(cell, i, ray, hit, &mut logs[c]);
                        self.shade_aovs(acc, cell, ray, hit.as_ref(), camera);
                        traced.push(sample);
                        sample.li
                    }
                    false => stored.values[cell.pixel as usize * spp + i as usize],
                };
                done[c] = acc.add(cell, li, self.stopping.as_ref());
            }
        }
    }

    /// The camera rays of `packet`'s lanes for sample `i`, traced as one packet.
    fn trace_camera_packet(&self, block: &[Cell], i: u32, packet: &mut CameraPacket) {
        for k in 0..packet.len {
            let cell = &block[packet.slots[k]];
            packet.rays[k] = camera_ray(&self.camera, self.settings, cell.x, cell.y, &cell.sampler, i);
        }
        self.query.intersect_packet(&packet.rays[..packet.len], &mut packet.hits[..packet.len]);
    }

    /// Continues sample `i` of `cell`'s pixel from its camera `ray` and `hit`; its rays
    /// count into the pixel's `log`. Returns the sample with its own horizon, and the horizon
    /// of its camera ray alone (when horizons are found).
    fn trace_sample(
        &self,
        cell: &Cell,
        i: u32,
        ray: &Ray,
        hit: Option<Hit>,
        log: &mut RayLog,
    ) -> (TracedSample, Option<u32>) {
        let mut sample_log = self.new_log();
        sample_log.closest(ray, hit.as_ref());
        let camera = sample_log.horizon();
        let li = self.integrator.li_from_hit(ray, hit, &cell.sampler, i, &mut sample_log);
        let horizon = sample_log.horizon().unwrap_or(0);
        log.absorb(&sample_log);
        (TracedSample { pixel: cell.pixel, index: i, li, horizon }, camera)
    }

    /// Adds the plan's AOV passes at the camera `ray`'s `hit` to `cell`'s pixel, and the
    /// ray's own horizon (`camera`) to the pixel's passes' horizon.
    #[inline]
    fn shade_aovs(
        &self,
        acc: &mut Accumulator,
        cell: &Cell,
        ray: &Ray,
        hit: Option<&Hit>,
        camera: Option<u32>,
    ) {
        if self.plan.aovs.is_empty() {
            return;
        }
        let values = self.plan.aovs.iter().map(|&aov| aov_at_hit(aov, self.scene, ray, hit));
        let at = acc.at(cell);
        acc.first_hits.add(at, values, camera);
    }
}
