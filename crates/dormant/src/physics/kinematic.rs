//! Key-framed paths for kinematic bodies: linear interpolation of position and heading.

use glam::{Quat, Vec3};

use super::body::BodyPose;
use crate::scene::file::KeyframeDef;

#[derive(Clone, Debug)]
pub(crate) struct KinematicPath {
    keys: Vec<KeyframeDef>,
    looped: bool,
}

impl KinematicPath {
    pub(crate) fn new(keys: &[KeyframeDef], looped: bool) -> Self {
        debug_assert!(!keys.is_empty());
        debug_assert!(keys.windows(2).all(|w| w[0].time < w[1].time));
        Self { keys: keys.to_vec(), looped }
    }

    /// The pose at `time` seconds: clamped to the first/last key, or wrapped when looped.
    pub(crate) fn pose_at(&self, time: f32) -> BodyPose {
        let first = self.keys[0];
        let last = self.keys[self.keys.len() - 1];
        let t = if self.looped && last.time > first.time {
            first.time + (time - first.time).rem_euclid(last.time - first.time)
        } else {
            time
        };
        let pose = |k: &KeyframeDef| (Vec3::from_array(k.position), k.yaw_degrees);
        let (position, yaw) = if t <= first.time {
            pose(&first)
        } else if t >= last.time {
            pose(&last)
        } else {
            let i = self.keys.partition_point(|k| k.time <= t);
            let (a, b) = (&self.keys[i - 1], &self.keys[i]);
            let f = (t - a.time) / (b.time - a.time);
            let (pa, ya) = pose(a);
            let (pb, yb) = pose(b);
            (pa.lerp(pb, f), ya + (yb - ya) * f)
        };
        BodyPose { translation: position, rotation: Quat::from_rotation_y(yaw.to_radians()) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(time: f32, x: f32) -> KeyframeDef {
        KeyframeDef { time, position: [x, 0.0, 0.0], yaw_degrees: 0.0 }
    }

    #[test]
    fn interpolates_and_loops() {
        let p = KinematicPath::new(&[key(0.0, 0.0), key(2.0, 4.0), key(4.0, 0.0)], true);
        assert_eq!(p.pose_at(1.0).translation.x, 2.0);
        assert_eq!(p.pose_at(5.0).translation.x, 2.0);
        let once = KinematicPath::new(&[key(0.0, 0.0), key(2.0, 4.0)], false);
        assert_eq!(once.pose_at(10.0).translation.x, 4.0);
    }
}
