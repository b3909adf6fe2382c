//! Trace-penalty probes: the same rays traced just before and just after an integration, so
//! the cost model prices what the integrated form costs the trace on this scene and view
//! (baked rotated bodies are bounded more loosely than instances; a resting scene is a
//! second traversal per ray). Probe time counts in the integrate stage.

use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;

use crate::accel::SceneQuery;
use crate::geometry::{offset_origin, Ray};
use crate::residency::cost_model::CostModel;
use crate::residency::IntegrationForm;

/// Smallest share of the present bodies a baked batch must move for its probe to measure
/// more than timing noise.
const MIN_BAKED_SHARE: f64 = 0.05;
/// Probes per form and run: the penalty is a property of the scene and view, so a few
/// measurements suffice and later integrations pay nothing.
const MAX_PROBES: u32 = 4;
/// Timed repetitions of each probe (the best counts).
const REPEATS: usize = 3;

/// Rays a camera sample traces, for the trace estimate made before any frame was traced: the
/// shaded preview traces about 3 (the camera ray and two shadow rays), a path-traced sample
/// 5-10 (bounces and their shadow rays). 8 errs towards declining (camera rays alone made
/// path-traced frames look cheap), and the first measured frame corrects the estimate:
/// docs/lab/integration.md#2026-12-01-the-cost-models-priors-and-its-first-frame
const RAYS_PER_SAMPLE: f64 = 8.0;

/// A measurement started before an integration.
struct Pending {
    form: IntegrationForm,
    share: f64,
    before_ms: f64,
}

pub(super) struct Probe {
    /// Towards the sun: the probe's shadow rays, one per camera hit.
    sun: Vec3,
    camera: Vec<Ray>,
    shadow: Vec<Ray>,
    /// Camera samples of a rendered frame (pixels times samples per pixel).
    frame_samples: u64,
    pending: Option<Pending>,
    done: [u32; 2],
}

impl Probe {
    pub(crate) fn new(sun: Vec3) -> Self {
        Self { sun, camera: Vec::new(), shadow: Vec::new(), frame_samples: 0, pending: None, done: [0; 2] }
    }

    /// The probe's camera rays, and how many camera samples a rendered frame takes.
    pub(crate) fn set_rays(&mut self, camera: Vec<Ray>, frame_samples: u64) {
        self.camera = camera;
        self.frame_samples = frame_samples;
    }

    /// A frame's trace time estimated before any was measured: the probe's camera rays (closest
    /// hit) traced on `query`, scaled to the frame's camera samples times
    /// [`RAYS_PER_SAMPLE`]; `None` without rays.
    pub(crate) fn frame_trace_estimate(&self, query: &dyn SceneQuery) -> Option<f64> {
        if self.camera.is_empty() || self.frame_samples == 0 {
            return None;
        }
        let ms = (0..REPEATS)
            .map(|_| {
                let t = Instant::now();
                let hits = self.camera.par_iter().filter(|r| query.intersect(r).is_some()).count();
                std::hint::black_box(hits);
                t.elapsed().as_secs_f64() * 1e3
            })
            .fold(f64::INFINITY, f64::min);
        Some(ms * RAYS_PER_SAMPLE * self.frame_samples as f64 / self.camera.len() as f64)
    }

    /// Before integrating `moved` of `present` bodies in `form` (the resting scene empty or
    /// not): traces the probe on the committed scene if a measurement is due.
    pub(crate) fn start(
        &mut self,
        form: IntegrationForm,
        moved: usize,
        present: usize,
        resting_empty: bool,
        query: Option<&dyn SceneQuery>,
    ) {
        let (Some(query), false) = (query, self.camera.is_empty()) else { return };
        let share = moved as f64 / present.max(1) as f64;
        let due = self.done[form as usize] < MAX_PROBES
            && match form {
                IntegrationForm::Baked => share >= MIN_BAKED_SHARE,
                // What the second scene costs does not depend on how much it holds.
                IntegrationForm::Resting => resting_empty,
            };
        if !due {
            return;
        }
        self.shadow = self
            .camera
            .par_iter()
            .filter_map(|r| query.intersect(r).map(|h| Ray::new(offset_origin(r.at(h.t), h.ng), self.sun)))
            .collect();
        let share = if form == IntegrationForm::Resting { 1.0 } else { share };
        self.pending = Some(Pending { form, share, before_ms: self.time(query) });
    }

    /// After the integration was committed: traces the probe again and gives the cost model
    /// the ratio. Returns whether a probe ran.
    pub(crate) fn finish(&mut self, query: &dyn SceneQuery, cost: &mut CostModel) -> bool {
        let Some(p) = self.pending.take() else { return false };
        let after_ms = self.time(query);
        cost.record_probe(p.form, p.before_ms, after_ms, p.share);
        self.done[p.form as usize] += 1;
        true
    }

    /// Best of [`REPEATS`] traces of the probe's camera (closest hit) and shadow (any hit) rays.
    fn time(&self, query: &dyn SceneQuery) -> f64 {
        (0..REPEATS)
            .map(|_| {
                let t = Instant::now();
                let hits = self.camera.par_iter().filter(|r| query.intersect(r).is_some()).count();
                let blocked = self.shadow.par_iter().filter(|r| query.intersect_p(r)).count();
                std::hint::black_box((hits, blocked));
                t.elapsed().as_secs_f64() * 1e3
            })
            .fold(f64::INFINITY, f64::min)
    }
}
