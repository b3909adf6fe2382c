//! Island statistics of a trajectory: how many islands formed, their sizes, how long they
//! slept, and how much of the world ended asleep.

use std::collections::BTreeMap;

use super::body::{BodyKind, BodyState};
use super::island::{IslandEvent, IslandId};
use super::trajectory::Trajectory;

#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct IslandStats {
    pub frames: u32,
    /// Islands that fell asleep over the whole run.
    pub islands_formed: u64,
    pub islands_woken: u64,
    /// Islands asleep after the last frame.
    pub islands_asleep_at_end: u64,
    pub(crate) size_min: u64,
    pub size_max: u64,
    pub size_mean: f64,
    pub(crate) size_median: u64,
    /// Sizes of the islands asleep at the end, largest first.
    pub(crate) sizes_at_end: Vec<u64>,
    /// Mean frames an island slept before waking (islands that woke).
    pub(crate) mean_sleep_frames_woken: f64,
    /// Mean frames asleep over all islands, those still asleep counted to the last frame.
    pub mean_sleep_frames_all: f64,
    pub(crate) mean_sleep_seconds_all: f64,
    pub dynamic_bodies_at_end: u64,
    pub asleep_bodies_at_end: u64,
    pub asleep_fraction_at_end: f64,
}

impl Trajectory {
    pub fn island_stats(&self) -> IslandStats {
        let mut started: BTreeMap<IslandId, (u32, u64)> = BTreeMap::new();
        let mut sizes = Vec::new();
        let mut woken_durations = Vec::new();
        for (f, frame) in self.frames.iter().enumerate() {
            for e in &frame.events {
                match e {
                    IslandEvent::Slept { island, bodies, .. } => {
                        started.insert(*island, (f as u32, bodies.len() as u64));
                        sizes.push(bodies.len() as u64);
                    }
                    IslandEvent::Woke { island } => {
                        if let Some((start, _)) = started.remove(island) {
                            woken_durations.push((f as u32 - start) as f64);
                        }
                    }
                }
            }
        }
        let end = self.frames.len() as u32;
        let open: Vec<f64> = started.values().map(|(s, _)| (end - s) as f64).collect();
        let mut sizes_at_end: Vec<u64> = started.values().map(|(_, n)| *n).collect();
        sizes_at_end.sort_unstable_by(|a, b| b.cmp(a));
        let mean = |v: &[f64]| if v.is_empty() { 0.0 } else { v.iter().sum::<f64>() / v.len() as f64 };
        let all: Vec<f64> = woken_durations.iter().chain(&open).copied().collect();
        let mut sorted = sizes.clone();
        sorted.sort_unstable();
        let (mut dynamic, mut asleep) = (0u64, 0u64);
        for (state, body) in self.states_at_end().into_iter().zip(&self.bodies) {
            if body.kind == BodyKind::Dynamic && state != BodyState::Absent {
                dynamic += 1;
                asleep += u64::from(state == BodyState::Asleep);
            }
        }
        IslandStats {
            frames: end,
            islands_formed: sizes.len() as u64,
            islands_woken: woken_durations.len() as u64,
            islands_asleep_at_end: started.len() as u64,
            size_min: sorted.first().copied().unwrap_or(0),
            size_max: sorted.last().copied().unwrap_or(0),
            size_mean: mean(&sizes.iter().map(|&s| s as f64).collect::<Vec<_>>()),
            size_median: sorted.get(sorted.len() / 2).copied().unwrap_or(0),
            sizes_at_end,
            mean_sleep_frames_woken: mean(&woken_durations),
            mean_sleep_frames_all: mean(&all),
            mean_sleep_seconds_all: mean(&all) * self.timestep as f64,
            dynamic_bodies_at_end: dynamic,
            asleep_bodies_at_end: asleep,
            asleep_fraction_at_end: if dynamic == 0 { 0.0 } else { asleep as f64 / dynamic as f64 },
        }
    }
}
