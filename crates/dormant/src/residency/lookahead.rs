//! What an offline render knows of its future: the frames it will render, and when each
//! sleeping island wakes. The trajectory is simulated (or read) before the first frame, so the
//! cost model can use each island's true remaining sleep instead of an estimate.

use std::collections::HashMap;

use crate::physics::{IslandEvent, IslandId};

/// The run's rendered frames and every island's wake frame.
#[derive(Clone, Debug, Default)]
pub struct Lookahead {
    /// Frame index of the `Woke` event ending each island that wakes within the trajectory.
    wakes: HashMap<IslandId, u32>,
    /// Frames the run renders, ascending.
    rendered: Vec<u32>,
}

impl Lookahead {
    /// From every frame's island events (`(frame index, event)` in order) and the frames
    /// the run renders.
    pub(crate) fn new<'a>(
        events: impl IntoIterator<Item = (u32, &'a IslandEvent)>,
        mut rendered: Vec<u32>,
    ) -> Self {
        rendered.sort_unstable();
        rendered.dedup();
        let wakes = events
            .into_iter()
            .filter_map(|(frame, e)| match e {
                IslandEvent::Woke { island } => Some((*island, frame)),
                IslandEvent::Slept { .. } => None,
            })
            .collect();
        Self { wakes, rendered }
    }

    /// The frame at which `island` wakes, if it does within the trajectory.
    pub(crate) fn wake_frame(&self, island: IslandId) -> Option<u32> {
        self.wakes.get(&island).copied()
    }

    /// Rendered frames from `now` (inclusive) before `island` wakes: the frames integrating it
    /// now would serve.
    pub(crate) fn remaining_sleep(&self, island: IslandId, now: u32) -> u32 {
        self.rendered_in(now, self.wake_frame(island).unwrap_or(u32::MAX))
    }

    /// Rendered frames from `now` (inclusive) to the end of the run.
    pub(crate) fn frames_left(&self, now: u32) -> u32 {
        self.rendered_in(now, u32::MAX)
    }

    /// Rendered frames in `from..to`.
    pub(crate) fn rendered_in(&self, from: u32, to: u32) -> u32 {
        if to <= from {
            return 0;
        }
        let a = self.rendered.partition_point(|&f| f < from);
        let b = self.rendered.partition_point(|&f| f < to);
        (b - a) as u32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn remaining_sleep_counts_rendered_frames_until_the_wake() {
        let woke = IslandEvent::Woke { island: IslandId(7) };
        let l = Lookahead::new([(30, &woke)], (0..100).step_by(10).collect());
        assert_eq!(l.wake_frame(IslandId(7)), Some(30));
        // Integrated at frame 10, it serves frames 10 and 20; at 30 it is awake again.
        assert_eq!(l.remaining_sleep(IslandId(7), 10), 2);
        assert_eq!(l.remaining_sleep(IslandId(7), 11), 1);
        // An island that never wakes sleeps to the end of the run.
        assert_eq!(l.remaining_sleep(IslandId(8), 55), 4);
        assert_eq!(l.frames_left(90), 1);
        // A wake after the last rendered frame: asleep for every frame left.
        let late = IslandEvent::Woke { island: IslandId(9) };
        let l = Lookahead::new([(95, &late)], (0..100).step_by(10).collect());
        assert_eq!(l.remaining_sleep(IslandId(9), 50), 5);
    }
}
