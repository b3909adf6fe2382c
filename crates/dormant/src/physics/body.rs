//! Identities and poses of simulated bodies, in glam types (the rest of dormant never sees
//! Rapier's types).

use crate::geometry::RigidTransform;
use glam::{Affine3A, Quat, Vec3};

/// A body's stable index in a simulation: kinematic bodies first, then spawned objects in
/// spawn order. Never reused.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize)]
pub struct BodyId(pub u32);

/// A rigid transform.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyPose {
    pub translation: Vec3,
    pub rotation: Quat,
}

impl BodyPose {
    pub fn to_affine(&self) -> Affine3A {
        self.rigid().to_affine()
    }

    /// The pose as a rigid transform (for motion blur's interpolation).
    pub(crate) fn rigid(&self) -> RigidTransform {
        RigidTransform { rotation: self.rotation, translation: self.translation }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BodyKind {
    /// Simulated; can fall asleep and join islands.
    Dynamic,
    /// Follows a key-framed path; never part of an island.
    Kinematic,
}

/// What a body is: its prototype (index into the scene's prototypes), kind and the frame
/// it enters the world.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BodyInfo {
    pub prototype: u32,
    pub kind: BodyKind,
    pub spawn_frame: u32,
}

/// A body's state at the end of a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum BodyState {
    /// Not spawned yet, or removed (fell below the kill plane).
    Absent = 0,
    Awake = 1,
    Asleep = 2,
}

pub(crate) fn to_rapier_vec(v: Vec3) -> rapier3d::math::Vector {
    rapier3d::math::Vector::from_array(v.to_array())
}

pub(crate) fn from_rapier_vec(v: rapier3d::math::Vector) -> Vec3 {
    Vec3::from_array(v.to_array())
}

pub(crate) fn to_rapier_pose(p: BodyPose) -> rapier3d::math::Pose {
    rapier3d::math::Pose::from_parts(
        to_rapier_vec(p.translation),
        rapier3d::math::Rotation::from_array(p.rotation.to_array()),
    )
}

pub(crate) fn from_rapier_pose(p: &rapier3d::math::Pose) -> BodyPose {
    BodyPose {
        translation: Vec3::from_array(p.translation.to_array()),
        rotation: Quat::from_array(p.rotation.to_array()),
    }
}
