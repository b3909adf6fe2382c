//! The [`ReuseStore`]: the last traced value of every sample (or pixel) of a run's frames, the
//! AOV passes, and each one's horizon; and one frame rendered through it
//! ([`ReuseStore::render_frame`]), which traces only what is due and takes the rest from the
//! store.
//!
//! The store keeps every sample when the budget allows (a pixel whose path changed in one
//! sample of sixteen retraces one; with adaptive sampling, `spp` slots per pixel, of which a
//! pixel fills as many as it takes); otherwise one value per pixel, retraced whole
//! ([`ReuseGranularity`]). Adaptive sampling then decides on reused and retraced samples
//! alike, in index order, as a full frame decides on traced ones.

use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::plan::{Due, FramePlan, PlanTracer, PlannedFrame, StoredSamples};
use crate::accel::bvh::ChangeIndex;
use crate::render::{Aov, AovPasses, Film, RenderError, RenderSettings, RenderStats, SppStats};

/// What the store keeps of every pixel: a sample count and a horizon (4 bytes each) and one RGB
/// value (12 bytes) for the image and for each AOV pass that is traced.
const PIXEL_BYTES: usize = 4 + 4 + 12;
/// And of every sample, when it keeps samples: a value and a horizon.
const SAMPLE_BYTES: usize = 12 + 4;

/// What the store keeps, and so the unit a frame retraces.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ReuseGranularity {
    /// Every sample's value and horizon: only the samples whose horizon has come are traced.
    #[default]
    Sample,
    /// A value and a horizon per pixel: a pixel with any sample's horizon come is traced whole.
    Pixel,
}

impl ReuseGranularity {
    pub(crate) fn name(self) -> &'static str {
        match self {
            ReuseGranularity::Sample => "sample",
            ReuseGranularity::Pixel => "pixel",
        }
    }
}

/// The last traced values of a sequence's frames and their horizons.
#[derive(Clone, Debug, Default)]
pub(crate) struct ReuseStore {
    /// What the stored values were rendered with; a frame of other settings starts afresh.
    settings: Option<(RenderSettings, Vec<Aov>)>,
    granularity: ReuseGranularity,
    /// Per pixel: the value, the sample count, and the ordinal of the first frame that must
    /// trace it (or one of its samples) again.
    image: Vec<Vec3>,
    counts: Vec<u32>,
    horizons: Vec<u32>,
    /// Per traced AOV pass (not `spp` or `traced`, which come from the counts), its pixels;
    /// and per pixel the passes' own horizon. A pass sees only its samples' camera rays
    /// (first hits), so it changes only where those meet a change or the pixel's sample count
    /// changes, not wherever a path does (docs/lab/reuse.md, 2026-12-06).
    passes: Vec<(Aov, Vec<Vec3>)>,
    pass_horizons: Vec<u32>,
    /// With [`ReuseGranularity::Sample`], per sample (`spp` per pixel, pixel by pixel): its
    /// radiance and horizon.
    samples: Vec<Vec3>,
    sample_horizons: Vec<u32>,
}

/// One frame's use of the store: the change index, this frame's ordinal, the latest horizon
/// worth finding, whether the frame must be traced in full, and the memory the store may use.
#[derive(Clone, Copy)]
pub(crate) struct FrameReuse<'a> {
    pub index: &'a ChangeIndex,
    pub ordinal: u32,
    /// Horizons end here at the latest: the next frame traced in full, or the run's end.
    pub until: u32,
    /// Trace everything (and refill the store): the first frame, or one where something every
    /// sample sees changed (the camera, a light, the scene's representation).
    pub full: bool,
    /// Bytes the store may hold: with room for every sample it keeps samples.
    pub budget: usize,
}

/// What reuse did in a frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct ReuseStats {
    pub granularity: ReuseGranularity,
    /// Camera samples traced and taken from the store.
    pub samples_traced: u64,
    pub samples_reused: u64,
    /// Pixels with a sample traced, of all pixels.
    pub pixels_traced: u64,
    pub pixels: u64,
    /// Horizon queries (one per traced ray segment that could still bring its horizon nearer)
    /// and their time, estimated from a sample of them.
    pub horizon_queries: u64,
    pub horizon_ms: f64,
    /// Of the frame's rays, the camera rays traced only because a due sample shared their
    /// packet (a full frame traces them as its packets have them).
    pub neighbour_rays: u64,
    /// Bytes the store holds.
    pub store_bytes: u64,
}

impl ReuseStats {
    /// A frame rendered without the store: every sample of `film` traced.
    pub(crate) fn traced_in_full(film: &Film, stats: &RenderStats) -> Self {
        let pixels = u64::from(film.width) * u64::from(film.height);
        ReuseStats {
            samples_traced: stats.camera_samples(film.width, film.height),
            pixels_traced: pixels,
            pixels,
            ..ReuseStats::default()
        }
    }
}

impl ReuseStore {
    /// The bytes a store of `width` x `height` pixels with `aovs` needs: one value per pixel
    /// and pass (the least the store works with).
    pub(crate) fn bytes_for(width: u32, height: u32, aovs: &[Aov]) -> usize {
        let traced_passes = aovs.iter().filter(|a| a.is_traced()).count();
        // The passes' values, and their horizon when there are any.
        let passes = 12 * traced_passes + if traced_passes > 0 { 4 } else { 0 };
        width as usize * height as usize * (PIXEL_BYTES + passes)
    }

    /// The bytes a store that keeps every one of `spp` samples per pixel needs.
    pub(crate) fn sample_bytes_for(width: u32, height: u32, spp: u32, aovs: &[Aov]) -> usize {
        Self::bytes_for(width, height, aovs) + width as usize * height as usize * spp as usize * SAMPLE_BYTES
    }

    /// Bytes the store holds now.
    pub(crate) fn memory_bytes(&self) -> usize {
        let pixels = self.image.len() * (12 + 4 + 4);
        let passes: usize = self.passes.iter().map(|(_, p)| p.len() * 12).sum();
        pixels + passes + self.pass_horizons.len() * 4 + self.samples.len() * SAMPLE_BYTES
    }

    /// Whether the store holds nothing yet.
    pub(crate) fn is_empty(&self) -> bool {
        self.settings.is_none()
    }

    /// Whether the store holds a frame rendered with `settings` and `aovs`.
    fn fits(&self, settings: &RenderSettings, aovs: &[Aov]) -> bool {
        self.settings.as_ref().is_some_and(|(s, a)| s == settings && a == aovs)
    }

    /// An empty store for frames of `settings` and `aovs` in `budget` bytes, every value due
    /// at `ordinal`.
    fn fresh(settings: &RenderSettings, aovs: &[Aov], budget: usize, ordinal: u32) -> Self {
        let (w, h, spp) = (settings.width, settings.height, settings.spp);
        let pixels = w as usize * h as usize;
        let passes: Vec<(Aov, Vec<Vec3>)> =
            aovs.iter().filter(|a| a.is_traced()).map(|&a| (a, vec![Vec3::ZERO; pixels])).collect();
        let keep_samples = Self::sample_bytes_for(w, h, spp, aovs) <= budget;
        let samples = if keep_samples { pixels * spp as usize } else { 0 };
        ReuseStore {
            settings: Some((*settings, aovs.to_vec())),
            granularity: if keep_samples { ReuseGranularity::Sample } else { ReuseGranularity::Pixel },
            image: vec![Vec3::ZERO; pixels],
            counts: vec![0; pixels],
            horizons: vec![ordinal; pixels],
            pass_horizons: if passes.is_empty() { Vec::new() } else { vec![ordinal; pixels] },
            passes,
            samples: vec![Vec3::ZERO; samples],
            sample_horizons: vec![ordinal; samples],
        }
    }

    /// What a frame at `ordinal` traces of the image: the samples (or pixels) `due`.
    fn beauty_due<'a>(&'a self, due: &'a [bool], ordinal: u32) -> Due<'a> {
        match self.granularity {
            ReuseGranularity::Sample => Due::Samples {
                stored: StoredSamples {
                    values: &self.samples,
                    horizons: &self.sample_horizons,
                    counts: &self.counts,
                },
                pixels: due,
                ordinal,
            },
            ReuseGranularity::Pixel => Due::Pixels { due, stored: &self.counts },
        }
    }

    /// Pixels a frame at `ordinal` must trace (wholly or in part): those whose horizon has come.
    fn due(&self, ordinal: u32) -> Vec<bool> {
        self.horizons.iter().map(|&h| h <= ordinal).collect()
    }
}

impl ReuseStore {
    /// A frame's image and its `aovs` passes through `tracer`, tracing only what `reuse` and
    /// the store say must be traced and taking the rest from the store, which is brought up to
    /// date. The same bits as a full render of the frame (see `render/reuse/mod.rs`); the
    /// statistics count only what was traced, but for the samples per pixel, which are the
    /// whole frame's.
    pub fn render_frame(
        &mut self,
        tracer: &dyn PlanTracer,
        aovs: &[Aov],
        reuse: FrameReuse,
    ) -> Result<(Film, RenderStats, AovPasses, ReuseStats), RenderError> {
        let settings = tracer.settings();
        if reuse.full || !self.fits(settings, aovs) {
            *self = ReuseStore::fresh(settings, aovs, reuse.budget, reuse.ordinal);
        }
        let due = self.due(reuse.ordinal);
        let plan = FramePlan {
            samples: None,
            due: self.beauty_due(&due, reuse.ordinal),
            horizons: Some((reuse.index, reuse.ordinal, reuse.until)),
            aovs: &self.first_hit_passes(),
        };
        let beauty = tracer.trace(&plan)?;
        let counts_before = (!self.passes.is_empty()).then(|| self.counts.clone());
        let traced = match self.granularity {
            ReuseGranularity::Sample => self.merge_samples(&beauty, &due, settings.spp),
            ReuseGranularity::Pixel => self.merge_pixels(&beauty, &due),
        };
        let mut seconds = beauty.seconds;
        if let Some(before) = counts_before {
            let shaded = self.merge_first_hit_passes(&beauty, &traced);
            seconds += self.render_passes(tracer, reuse, &before, &shaded)?;
        }
        let (film, passes) = self.frame(aovs, &traced, settings);
        let stats = RenderStats { rays: beauty.rays, seconds, spp: SppStats::of(&self.counts) };
        Ok((film, stats, passes, self.stats(&beauty, &traced)))
    }

    /// What reuse did in a frame that traced `beauty`, `traced` samples per pixel.
    fn stats(&self, beauty: &PlannedFrame, traced: &[u32]) -> ReuseStats {
        let total: u64 = self.counts.iter().map(|&n| u64::from(n)).sum();
        let samples_traced: u64 = traced.iter().map(|&n| u64::from(n)).sum();
        ReuseStats {
            granularity: self.granularity,
            samples_traced,
            samples_reused: total - samples_traced,
            pixels_traced: traced.iter().filter(|&&n| n > 0).count() as u64,
            pixels: traced.len() as u64,
            horizon_queries: beauty.horizon_queries,
            horizon_ms: beauty.horizon_seconds * 1e3,
            neighbour_rays: beauty.neighbour_rays,
            store_bytes: self.memory_bytes() as u64,
        }
    }
}

/// Copies the values of the pixels `due` from `from` into `to`.
fn copy_due<T: Copy>(to: &mut [T], from: &[T], due: &[bool]) {
    for ((to, from), &due) in to.iter_mut().zip(from).zip(due) {
        if due {
            *to = *from;
        }
    }
}

impl ReuseStore {
    /// The AOV passes the beauty pass shades at its camera hits: every traced pass when the
    /// store keeps samples, whose per-sample logs give each camera ray's own horizon (a
    /// pixel's log, kept per pixel, mixes it with the paths'); none otherwise.
    fn first_hit_passes(&self) -> Vec<Aov> {
        match self.granularity {
            ReuseGranularity::Sample => self.passes.iter().map(|(aov, _)| *aov).collect(),
            ReuseGranularity::Pixel => Vec::new(),
        }
    }

    /// Takes the passes of the pixels whose every sample `beauty` traced (`traced` per pixel)
    /// from its first-hit passes, with their camera horizons: the values and horizons a pass
    /// of their own would give. Returns which pixels it took (all of them in a full frame).
    fn merge_first_hit_passes(&mut self, beauty: &PlannedFrame, traced: &[u32]) -> Vec<bool> {
        if beauty.aovs.is_empty() {
            return vec![false; traced.len()];
        }
        let shaded: Vec<bool> = traced.iter().zip(&self.counts).map(|(&t, &n)| t > 0 && t == n).collect();
        for ((_, pass), film) in self.passes.iter_mut().zip(&beauty.aovs) {
            copy_due(pass, &film.pixels, &shaded);
        }
        copy_due(&mut self.pass_horizons, &beauty.camera_horizons, &shaded);
        shaded
    }

    /// Traces the AOV passes of the pixels not `shaded` by the beauty pass whose passes'
    /// horizon has come or whose sample count differs from `counts_before` (the beauty
    /// pass's, before this frame); returns the seconds taken.
    fn render_passes(
        &mut self,
        tracer: &dyn PlanTracer,
        reuse: FrameReuse,
        counts_before: &[u32],
        shaded: &[bool],
    ) -> Result<f64, RenderError> {
        let due: Vec<bool> = (self.pass_horizons.iter().zip(&self.counts).zip(counts_before).zip(shaded))
            .map(|(((&h, &now), &before), &shaded)| !shaded && (h <= reuse.ordinal || now != before))
            .collect();
        if !due.contains(&true) {
            return Ok(0.0);
        }
        // One trace of the due camera rays shades every pass: the first as the frame's
        // integrator (its camera rays give the horizons), the others at the same hits.
        let rest: Vec<Aov> = self.passes[1..].iter().map(|(aov, _)| *aov).collect();
        let plan = FramePlan {
            samples: Some(&self.counts),
            due: Due::Pixels { due: &due, stored: &self.counts },
            horizons: Some((reuse.index, reuse.ordinal, reuse.until)),
            aovs: &rest,
        };
        let traced = tracer.trace_pass(self.passes[0].0, &plan)?;
        copy_due(&mut self.passes[0].1, &traced.film.pixels, &due);
        for ((_, stored), film) in self.passes[1..].iter_mut().zip(&traced.aovs) {
            copy_due(stored, &film.pixels, &due);
        }
        copy_due(&mut self.pass_horizons, &traced.horizons, &due);
        Ok(traced.seconds)
    }

    /// Copies the traced pixels of `beauty` (image, counts, horizons) in; returns the camera
    /// samples traced per pixel.
    fn merge_pixels(&mut self, beauty: &PlannedFrame, due: &[bool]) -> Vec<u32> {
        copy_due(&mut self.image, &beauty.film.pixels, due);
        let mut traced = vec![0; due.len()];
        for (p, _) in due.iter().enumerate().filter(|(_, d)| **d) {
            self.counts[p] = beauty.counts[p];
            self.horizons[p] = beauty.horizons[p];
            traced[p] = beauty.counts[p];
        }
        traced
    }

    /// Copies the traced samples of `beauty` in and its pixels `due` (those with a traced
    /// sample): each the sum of its samples in index order over their count, as a full frame
    /// computes it, and its horizon the nearest of those samples'. Returns the samples traced
    /// per pixel.
    fn merge_samples(&mut self, beauty: &PlannedFrame, due: &[bool], spp: u32) -> Vec<u32> {
        let n = spp as usize;
        let mut traced = vec![0; due.len()];
        for s in beauty.samples.iter().flatten() {
            let at = s.pixel as usize * n + s.index as usize;
            self.samples[at] = s.li;
            self.sample_horizons[at] = s.horizon;
            traced[s.pixel as usize] += 1;
        }
        for (p, _) in due.iter().enumerate().filter(|(_, d)| **d) {
            let count = beauty.counts[p];
            self.image[p] = beauty.film.pixels[p];
            self.counts[p] = count;
            let samples = &self.sample_horizons[p * n..p * n + count as usize];
            self.horizons[p] = samples.iter().copied().min().unwrap_or(0);
        }
        traced
    }

    /// The stored frame as images: the beauty image and `aovs` in order (`spp` from the
    /// counts, `traced` from the samples traced per pixel this frame).
    fn frame(&self, aovs: &[Aov], traced: &[u32], settings: &RenderSettings) -> (Film, AovPasses) {
        let (w, h) = (settings.width, settings.height);
        let film = |pixels: Vec<Vec3>| Film { width: w, height: h, pixels };
        let passes = aovs
            .iter()
            .map(|&aov| {
                let film = match aov {
                    Aov::Spp => Film::from_counts(w, h, &self.counts),
                    Aov::Traced => Film::from_counts(w, h, traced),
                    aov => film(
                        self.passes
                            .iter()
                            .find(|(a, _)| *a == aov)
                            .map(|(_, p)| p.clone())
                            .unwrap_or_default(),
                    ),
                };
                (aov, film)
            })
            .collect();
        (film(self.image.clone()), passes)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::reuse::decision::DEFAULT_REUSE_BYTES;

    #[test]
    fn the_default_budget_holds_a_4k_frame_per_pixel_and_hd_per_sample() {
        let every = [Aov::Albedo, Aov::Normal, Aov::Depth, Aov::Baked, Aov::Spp, Aov::Traced];
        assert!(ReuseStore::bytes_for(3840, 2160, &every) <= DEFAULT_REUSE_BYTES);
        assert!(ReuseStore::sample_bytes_for(1920, 1080, 16, &[]) <= DEFAULT_REUSE_BYTES);
        assert!(ReuseStore::sample_bytes_for(960, 540, 64, &[]) <= DEFAULT_REUSE_BYTES);
    }
}
