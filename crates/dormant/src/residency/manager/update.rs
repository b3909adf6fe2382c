//! Stage 3, update: instances in the top level follow the awake bodies, and with a shutter
//! (motion blur) move over it.

use super::slots::{InstanceOwner, Placement};
use super::{FrameStats, SceneManager};
use crate::accel::normal_matrix;
use crate::accel::AccelError;
use crate::physics::trajectory::ReplayFrame;
use crate::physics::BodyId;

impl SceneManager {
    /// Instances follow the frame: added, moved or removed. Returns whether any changed.
    pub(super) fn update(
        &mut self,
        frame: &ReplayFrame<'_>,
        stats: &mut FrameStats,
    ) -> Result<bool, AccelError> {
        let mut changed = false;
        let motions = frame.shutter_motions(self.options.shutter);
        let mut motions = motions.iter().peekable();
        let was_blurred = std::mem::take(&mut self.blurred);
        let mut was_blurred = was_blurred.iter().peekable();
        for (b, slot) in self.bodies.iter_mut().enumerate() {
            let motion = motions.next_if(|(m, _)| *m == b).map(|(_, m)| *m);
            let blurred = was_blurred.next_if(|&&w| w as usize == b).is_some();
            let present = frame.is_present(b);
            let (pose, prototype) = (frame.poses[b], slot.prototype);
            let owner = |resting| {
                let transform = pose.to_affine();
                InstanceOwner {
                    body: BodyId(b as u32),
                    prototype,
                    normal_matrix: normal_matrix(&transform),
                    transform,
                    resting,
                }
            };
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
                    let id =
                        self.accel.add_instance(self.prototype_ids[prototype as usize], pose.to_affine())?;
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
            if motion.is_some() && matches!(slot.placement, Placement::Instance { .. }) {
                self.blurred.push(b as u32);
            }
        }
        Ok(changed)
    }
}
