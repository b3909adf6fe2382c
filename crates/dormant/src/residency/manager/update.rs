//! Stage 3, update: instances in the top level follow the awake bodies, and with a shutter
//! (motion blur) move over it.

use super::slots::{InstanceOwner, Placement};
use super::{FrameStats, SceneManager};
use crate::accel::AccelError;
use crate::geometry::InstanceMotion;
use crate::physics::trajectory::ReplayFrame;
use crate::physics::BodyId;

impl SceneManager {
    /// Instances follow the frame: added, moved or removed. Returns whether any changed.
    ///
    /// Only bodies that can need it are visited when the replay says which bodies changed
    /// since frame `previous` (the frame prepared before): those, the bodies integration or
    /// reactivation placed anew this frame, and the blurred ones. Visiting all 80,000 bodies
    /// of the demolition was a millisecond a frame, most of a later preview frame's update.
    pub(super) fn update(
        &mut self,
        frame: &ReplayFrame<'_>,
        previous: Option<u32>,
        stats: &mut FrameStats,
    ) -> Result<bool, AccelError> {
        let motions = frame.shutter_motions(self.options.shutter);
        let was_blurred = std::mem::take(&mut self.blurred);
        let changed = match previous.and_then(|p| frame.changed_after(p)) {
            Some(changed) => {
                let mut visit = std::mem::take(&mut self.visit);
                visit.clone_from(changed);
                visit.union_with(&self.touched);
                visit.extend(motions.iter().map(|(b, _)| *b).chain(was_blurred.iter().map(|&b| b as usize)));
                let changed = self.update_bodies(visit.iter(), frame, &motions, &was_blurred, stats);
                self.visit = visit;
                changed
            }
            None => self.update_bodies(0..self.bodies.len(), frame, &motions, &was_blurred, stats),
        };
        self.touched.make_empty();
        changed
    }

    /// Brings each of `bodies` (ascending, holding every body of `motions` and `was_blurred`)
    /// up to the frame; returns whether any instance changed.
    fn update_bodies(
        &mut self,
        bodies: impl Iterator<Item = usize>,
        frame: &ReplayFrame<'_>,
        motions: &[(usize, InstanceMotion)],
        was_blurred: &[u32],
        stats: &mut FrameStats,
    ) -> Result<bool, AccelError> {
        let mut changed = false;
        let mut motions = motions.iter().peekable();
        let mut was_blurred = was_blurred.iter().peekable();
        for b in bodies {
            let motion = motions.next_if(|(m, _)| *m == b).map(|(_, m)| *m);
            let blurred = was_blurred.next_if(|&&w| w as usize == b).is_some();
            changed |= self.update_body(b, frame, motion, blurred, stats)?;
            if motion.is_some() && matches!(self.bodies[b].placement, Placement::Instance { .. }) {
                self.blurred.push(b as u32);
            }
        }
        debug_assert!(motions.next().is_none() && was_blurred.next().is_none(), "every blurred body visited");
        Ok(changed)
    }

    /// Brings body `b`'s instance up to the frame (with `motion` over the shutter, or none
    /// after being `blurred` the frame before); returns whether it changed.
    fn update_body(
        &mut self,
        b: usize,
        frame: &ReplayFrame<'_>,
        motion: Option<InstanceMotion>,
        blurred: bool,
        stats: &mut FrameStats,
    ) -> Result<bool, AccelError> {
        let present = frame.is_present(b);
        let slot = &mut self.bodies[b];
        let (pose, prototype) = (frame.poses[b], slot.prototype);
        let owner = |resting| InstanceOwner::at(BodyId(b as u32), prototype, pose.to_affine(), resting);
        let mut changed = false;
        match slot.placement {
            Placement::Baked(island) if self.integrated.contains_key(&island) => {}
            // Reactivation turns a woken resting island's bodies back into instances, so
            // no map lookup is needed here (on the demolition's 80,000 bodies that lookup
            // per body and frame was most of this stage).
            Placement::Resting { island, .. } if present => {
                debug_assert!(self.resting.contains_key(&island), "resting body of a woken island");
            }
            Placement::Instance { id, pose: old } if present => {
                if old != pose {
                    self.accel.set_instance_transform(id, pose.to_affine())?;
                    self.instance_owner.set(id, Some(owner(false)));
                    slot.placement = Placement::Instance { id, pose };
                    stats.instances_moved += 1;
                    changed = true;
                }
                if motion.is_some() || blurred {
                    self.accel.set_instance_motion(id, motion)?;
                    changed = true;
                }
            }
            Placement::Instance { id, .. } | Placement::Resting { id, .. } => {
                self.accel.remove_instance(id)?;
                self.instance_owner.set(id, None);
                slot.placement = Placement::Absent;
                stats.instances_removed += 1;
                changed = true;
            }
            Placement::Absent | Placement::Baked(_) if present => {
                let id = self.accel.add_instance(self.prototype_ids[prototype as usize], pose.to_affine())?;
                if motion.is_some() {
                    self.accel.set_instance_motion(id, motion)?;
                }
                self.instance_owner.set(id, Some(owner(false)));
                slot.placement = Placement::Instance { id, pose };
                stats.instances_added += 1;
                changed = true;
            }
            Placement::Absent | Placement::Baked(_) => slot.placement = Placement::Absent,
        }
        Ok(changed)
    }
}
