//! What a long run needs from every compiled backend: instance ids of removed instances are
//! given out again, so the tables indexed by them (the backend's and the scene manager's
//! owners) stay as large as the most instances alive at once, not the number ever added. The
//! BVH gave every instance a new id until the soak (docs/performance.md#soak-make-soak) showed its
//! tables growing with every island that woke.

use dormant::accel::{self, Backend, InstanceId};
use dormant::geometry::primitives;
use glam::{Affine3A, Vec3};

#[test]
fn removed_instance_ids_are_given_out_again() {
    for backend in Backend::compiled() {
        let mut accel = accel::create(backend, Some(1)).unwrap();
        let proto = accel.add_prototype(&primitives::cuboid(Vec3::splat(0.5))).unwrap();
        let at = |i: usize| Affine3A::from_translation(Vec3::new(i as f32 % 7.0, 0.0, 0.0));
        let mut live: Vec<InstanceId> = (0..3).map(|i| accel.add_instance(proto, at(i)).unwrap()).collect();
        accel.commit().unwrap();
        let mut highest = 0;
        for round in 0..2_000 {
            // Wake and rest as an island does: one leaves the scene (or rests), one comes back.
            let gone = live.remove(round % live.len());
            if round % 3 == 0 {
                accel.set_instance_resting(gone, true).unwrap();
                accel.commit().unwrap();
            }
            accel.remove_instance(gone).unwrap();
            let id = accel.add_instance(proto, at(round)).unwrap();
            highest = highest.max(id.0);
            live.push(id);
            accel.commit().unwrap();
        }
        assert!(highest < 4, "{backend}: instance id {highest} after 2,000 removals with 3 alive");
        assert!(accel.query().is_ok());
    }
}
