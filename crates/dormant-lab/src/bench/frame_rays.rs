//! The rays of one rendered frame, recorded as the renderer traced them and traced again bare:
//! what the frame's tracing alone costs, so `bench render` can say how much of a frame goes
//! to shading, sampling and bookkeeping (the target: at least half the frame spent tracing).
//!
//! Recording wraps the frame's [`SceneQuery`] (a separate, untimed render); the bare trace
//! replays the same rays through the same queries (camera rays in their packets, bounce rays
//! as closest hits, shadow rays as occlusion tests) over rayon, with no shading in between.

use std::sync::Mutex;

use rayon::prelude::*;
use serde::Serialize;

use super::timed;
use dormant::accel::{Hit, SceneQuery};
use dormant::geometry::Ray;

/// Every ray one frame traced, by the query that traced it.
#[derive(Debug, Default)]
pub(crate) struct FrameRays {
    /// Camera-ray packets, as the renderer grouped them.
    pub camera_packets: Vec<Vec<Ray>>,
    /// Closest-hit queries of single rays (the path's bounces).
    pub closest: Vec<Ray>,
    /// Occlusion queries (shadow rays).
    pub any: Vec<Ray>,
}

impl FrameRays {
    pub fn camera_rays(&self) -> usize {
        self.camera_packets.iter().map(Vec::len).sum()
    }

    pub fn len(&self) -> usize {
        self.camera_rays() + self.closest.len() + self.any.len()
    }
}

/// A [`SceneQuery`] that answers through `inner` and keeps every ray it was asked about.
/// The lock per query is fine for recording; timings come from [`trace_bare`].
pub(crate) struct RecordingQuery<'a> {
    inner: &'a dyn SceneQuery,
    rays: Mutex<FrameRays>,
}

impl<'a> RecordingQuery<'a> {
    pub fn new(inner: &'a dyn SceneQuery) -> Self {
        Self { inner, rays: Mutex::new(FrameRays::default()) }
    }

    pub fn into_rays(self) -> FrameRays {
        self.rays.into_inner().unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    fn record(&self, f: impl FnOnce(&mut FrameRays)) {
        f(&mut self.rays.lock().unwrap_or_else(|poisoned| poisoned.into_inner()));
    }
}

impl SceneQuery for RecordingQuery<'_> {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.record(|r| r.closest.push(*ray));
        self.inner.intersect(ray)
    }

    fn intersect_p(&self, ray: &Ray) -> bool {
        self.record(|r| r.any.push(*ray));
        self.inner.intersect_p(ray)
    }

    fn intersect_packet(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        self.record(|r| r.camera_packets.push(rays.to_vec()));
        self.inner.intersect_packet(rays, hits);
    }

    fn intersect_p_packet(&self, rays: &[Ray], occluded: &mut [bool]) {
        // The renderer traces no shadow packets today; record them as single occlusion
        // queries if it ever does, so the bare trace still covers every ray.
        self.record(|r| r.any.extend_from_slice(rays));
        self.inner.intersect_p_packet(rays, occluded);
    }
}

/// The bare trace of one frame's rays.
#[derive(Clone, Debug, Serialize)]
pub struct BareFrameRays {
    pub camera_rays: usize,
    pub bounce_rays: usize,
    pub shadow_rays: usize,
    /// Best time of the three kinds traced one after another.
    pub ms: f64,
    pub mrays_per_s: f64,
}

/// Traces `rays` through `query` with nothing else to do; milliseconds.
pub(crate) fn trace_bare(query: &dyn SceneQuery, rays: &FrameRays) -> f64 {
    let (sum, ms) = timed(|| {
        let camera: f64 = rays
            .camera_packets
            .par_iter()
            .map(|packet| {
                let mut hits = [None; 16];
                packet
                    .chunks(16)
                    .map(|rays| {
                        let hits = &mut hits[..rays.len()];
                        query.intersect_packet(rays, hits);
                        hits.iter().map(|h| h.map_or(0.0, |h| h.t as f64)).sum::<f64>()
                    })
                    .sum::<f64>()
            })
            .sum();
        let bounce: f64 =
            rays.closest.par_iter().map(|r| query.intersect(r).map_or(0.0, |h| h.t as f64)).sum();
        let blocked = rays.any.par_iter().filter(|r| query.intersect_p(r)).count();
        camera + bounce + blocked as f64
    });
    std::hint::black_box(sum);
    ms
}

impl BareFrameRays {
    pub(crate) fn new(rays: &FrameRays, ms: f64) -> Self {
        Self {
            camera_rays: rays.camera_rays(),
            bounce_rays: rays.closest.len(),
            shadow_rays: rays.any.len(),
            ms,
            mrays_per_s: rays.len() as f64 / ms.max(1e-9) / 1e3,
        }
    }
}
