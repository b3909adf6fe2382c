//! Which frames of a sequence are rendered.

/// A half-open range of frames, `A..B` on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameRange {
    pub start: u32,
    pub end: u32,
}

impl std::str::FromStr for FrameRange {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let (a, b) = s.split_once("..").ok_or_else(|| format!("'{s}': expected A..B, e.g. 0..120"))?;
        let parse =
            |v: &str| v.trim().parse::<u32>().map_err(|_| format!("'{s}': '{v}' is not a frame number"));
        let range = FrameRange { start: parse(a)?, end: parse(b)? };
        if range.start >= range.end {
            return Err(format!("'{s}': the range is empty (A must be less than B)"));
        }
        Ok(range)
    }
}

/// The frames a run renders, checked against its trajectory (made by
/// [`Sequence::select`](super::Sequence::select) and its siblings).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FrameSelection(Selected);

#[derive(Clone, Debug, PartialEq, Eq)]
enum Selected {
    /// Every `step`-th frame of `start..end`, counted from frame 0 so that split ranges line
    /// up.
    Stepped { start: u32, end: u32, step: u32 },
    /// These frames, ascending.
    List(Vec<u32>),
}

impl FrameSelection {
    pub(super) fn stepped(range: FrameRange, step: u32) -> Self {
        debug_assert!(step >= 1 && range.start <= range.end);
        Self(Selected::Stepped { start: range.start, end: range.end, step })
    }

    pub(super) fn list(mut frames: Vec<u32>) -> Self {
        frames.sort_unstable();
        frames.dedup();
        Self(Selected::List(frames))
    }

    /// Whether frame `index` is rendered.
    pub fn selects(&self, index: u32) -> bool {
        match &self.0 {
            Selected::Stepped { start, end, step } => (*start..*end).contains(&index) && index % step == 0,
            Selected::List(frames) => frames.binary_search(&index).is_ok(),
        }
    }

    /// Whether frame `index` comes before the first selected frame and a run of the same step
    /// from frame 0 would render it: a slice's first frame reports the island events since
    /// the last such frame, as that run would, not since frame 0.
    pub(crate) fn skipped_on_grid(&self, index: u32) -> bool {
        match &self.0 {
            Selected::Stepped { start, step, .. } => index < *start && index % step == 0,
            Selected::List(_) => false,
        }
    }

    /// The first frame that can be selected.
    pub fn start(&self) -> u32 {
        match &self.0 {
            Selected::Stepped { start, .. } => *start,
            Selected::List(frames) => frames.first().copied().unwrap_or(0),
        }
    }

    /// One past the last frame that can be selected: replay stops there.
    pub fn end(&self) -> u32 {
        match &self.0 {
            Selected::Stepped { end, .. } => *end,
            Selected::List(frames) => frames.last().map_or(0, |f| f + 1),
        }
    }

    /// The selected frames, ascending.
    pub fn frames(&self) -> Vec<u32> {
        match &self.0 {
            Selected::Stepped { start, end, .. } => (*start..*end).filter(|&f| self.selects(f)).collect(),
            Selected::List(frames) => frames.clone(),
        }
    }

    /// How many frames are selected.
    pub fn count(&self) -> u32 {
        match &self.0 {
            Selected::Stepped { start, end, step } => (*start..*end).filter(|f| f % step == 0).count() as u32,
            Selected::List(frames) => frames.len() as u32,
        }
    }

    /// The step between rendered frames (1 for a list).
    pub fn step(&self) -> u32 {
        match &self.0 {
            Selected::Stepped { step, .. } => *step,
            Selected::List(_) => 1,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_ranges_parse_and_reject() {
        assert_eq!("3..10".parse::<FrameRange>(), Ok(FrameRange { start: 3, end: 10 }));
        for bad in ["10..3", "5..5", "a..3", "3", "-1..4"] {
            assert!(bad.parse::<FrameRange>().is_err(), "{bad}");
        }
    }

    #[test]
    fn steps_count_from_frame_zero() {
        let s = FrameSelection::stepped(FrameRange { start: 5, end: 20 }, 4);
        assert_eq!(s.frames(), vec![8, 12, 16]);
        assert_eq!(s.count(), 3);
        assert_eq!((s.start(), s.end()), (5, 20));
        let l = FrameSelection::list(vec![9, 3, 3]);
        assert_eq!((l.frames(), l.count(), l.end()), (vec![3, 9], 2, 10));
        assert!(l.selects(9) && !l.selects(4));
        assert_eq!((0..9).filter(|&f| s.skipped_on_grid(f)).collect::<Vec<_>>(), vec![0, 4]);
        assert!(!l.skipped_on_grid(0));
    }
}
