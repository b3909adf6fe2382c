//! Frames of a sequence as plain scene descriptions.

use super::Sequence;
use crate::physics::trajectory::ReplayFrame;
use crate::scene::{Body, SceneDescription};

impl Sequence {
    /// The bodies present in `frame`, each at its pose.
    pub(crate) fn bodies_at(&self, frame: &ReplayFrame<'_>) -> Vec<Body> {
        frame
            .present_bodies()
            .map(|b| Body {
                prototype: self.trajectory.bodies[b.0 as usize].prototype,
                transform: frame.poses[b.0 as usize].to_affine(),
            })
            .collect()
    }

    /// `frame` as a render description: the environment as the only static mesh, every
    /// present body (awake or asleep) an instance of its prototype at its pose, and the
    /// camera where its keyframes put it. The reference integrated scenes are checked
    /// against.
    pub fn describe_frame(&self, frame: &ReplayFrame<'_>) -> SceneDescription {
        SceneDescription { bodies: self.bodies_at(frame), ..self.assets.describe(self.time_of(frame.index)) }
    }
}
