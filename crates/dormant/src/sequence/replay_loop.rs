//! The one replay loop: every frame of a trajectory, in order, up to the last selected one.

use super::{FrameSelection, Sequence};
use crate::physics::trajectory::ReplayFrame;
use crate::residency::SceneManager;

/// What [`Sequence::replay`] calls with each selected frame and the scene managers.
pub(crate) type FrameVisitor<'v, E> = dyn FnMut(&ReplayFrame<'_>, &mut [SceneManager]) -> Result<(), E> + 'v;

impl Sequence {
    /// Replays the trajectory from its first frame (every island event must be seen) to the
    /// last frame `selection` can select: each frame's island events go to every manager in
    /// `managers` (none for callers that only describe frames), and each selected frame goes
    /// to `on_frame` with the managers.
    pub fn replay<E>(
        &self,
        selection: &FrameSelection,
        managers: &mut [SceneManager],
        on_frame: &mut FrameVisitor<'_, E>,
    ) -> Result<(), E> {
        let mut replay = self.trajectory.replay();
        while let Some(frame) = replay.next_frame() {
            if frame.index >= selection.end() {
                break;
            }
            for manager in managers.iter_mut() {
                manager.observe(frame.events);
                // A slice (`--frames A..B`, A > 0) counts island events from the frame a whole
                // run would have rendered last, so that its rows join into the whole run's
                // table; the events themselves still all reach the manager.
                if selection.skipped_on_grid(frame.index) {
                    manager.forget_event_counts();
                }
            }
            if selection.selects(frame.index) {
                on_frame(&frame, managers)?;
                // The managers were prepared for this frame: the next one changes from here.
                replay.restart_changes();
            }
        }
        Ok(())
    }
}
