//! The accelerator interface on the Embree backend: id mapping, world-space normals of
//! instanced hits, staged changes, and bad input.
#![cfg(feature = "embree")]

use dormant::accel::{self, AccelError, Accelerator, Backend, HitObject, InstanceId};
use dormant::geometry::{primitives, Ray, TriangleMesh};
use glam::{Affine3A, Quat, Vec3};

fn embree() -> Box<dyn Accelerator> {
    accel::create(Backend::Embree, Some(2)).unwrap()
}

#[test]
fn static_and_instance_hits_map_to_their_ids() {
    let mut a = embree();
    let ground = a.add_static(&primitives::ground_plane(10.0, 0.0, 1)).unwrap();
    let cube = a.add_prototype(&primitives::cuboid(Vec3::splat(0.5))).unwrap();
    let _far = a.add_instance(cube, Affine3A::from_translation(Vec3::new(5.0, 0.5, 0.0))).unwrap();
    let near = a.add_instance(cube, Affine3A::from_translation(Vec3::new(0.0, 0.5, 0.0))).unwrap();
    a.commit().unwrap();
    let q = a.query().unwrap();
    let down = |x: f32| Ray::new(Vec3::new(x, 5.0, 0.0), Vec3::NEG_Y);
    let hit = q.intersect(&down(0.0)).unwrap();
    assert_eq!(hit.object, HitObject::Instance(near));
    assert!((hit.t - 4.0).abs() < 1e-5);
    assert!(hit.ng.abs_diff_eq(Vec3::Y, 1e-5), "{:?}", hit.ng);
    let hit = q.intersect(&down(2.5)).unwrap();
    assert_eq!(hit.object, HitObject::Static(ground));
    assert!((hit.t - 5.0).abs() < 1e-5);
}

#[test]
fn instanced_normals_are_in_world_space() {
    let mut a = embree();
    // A triangle facing +z in object space, rotated to face +x and stretched.
    let tri = TriangleMesh::new(
        vec![Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::new(0.0, 1.0, 0.0)],
        vec![[0, 1, 2]],
    );
    let p = a.add_prototype(&tri).unwrap();
    let xf = Affine3A::from_scale_rotation_translation(
        Vec3::new(3.0, 1.0, 1.0),
        Quat::from_rotation_y(std::f32::consts::FRAC_PI_2),
        Vec3::ZERO,
    );
    a.add_instance(p, xf).unwrap();
    a.commit().unwrap();
    let hit = a.query().unwrap().intersect(&Ray::new(Vec3::new(5.0, 0.0, 0.0), Vec3::NEG_X)).unwrap();
    assert!(hit.ng.abs_diff_eq(Vec3::X, 1e-5), "{:?}", hit.ng);
}

#[test]
fn staged_changes_block_queries_until_commit() {
    let mut a = embree();
    assert!(matches!(a.query(), Err(AccelError::NotCommitted)));
    a.commit().unwrap();
    assert!(a.query().unwrap().intersect(&Ray::new(Vec3::ZERO, Vec3::X)).is_none());
    let s = a.add_static(&primitives::cuboid(Vec3::ONE)).unwrap();
    assert!(matches!(a.query(), Err(AccelError::NotCommitted)));
    a.commit().unwrap();
    assert!(a.query().unwrap().intersect_p(&Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z)));
    a.remove_static(s).unwrap();
    a.commit().unwrap();
    assert!(!a.query().unwrap().intersect_p(&Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z)));
}

#[test]
fn moving_and_removing_instances() {
    let mut a = embree();
    let p = a.add_prototype(&primitives::cuboid(Vec3::splat(0.5))).unwrap();
    let i = a.add_instance(p, Affine3A::IDENTITY).unwrap();
    a.commit().unwrap();
    let ray = Ray::new(Vec3::new(3.0, 0.0, -5.0), Vec3::Z);
    assert!(!a.query().unwrap().intersect_p(&ray));
    a.set_instance_transform(i, Affine3A::from_translation(Vec3::new(3.0, 0.0, 0.0))).unwrap();
    a.commit().unwrap();
    assert!(a.query().unwrap().intersect_p(&ray));
    a.remove_instance(i).unwrap();
    a.commit().unwrap();
    assert!(!a.query().unwrap().intersect_p(&ray));
    assert!(matches!(a.remove_instance(i), Err(AccelError::UnknownId { .. })));
}

#[test]
fn bad_input_is_rejected_without_panicking() {
    let mut a = embree();
    let bad_index = TriangleMesh::new(vec![Vec3::ZERO], vec![[0, 1, 2]]);
    assert!(matches!(a.add_static(&bad_index), Err(AccelError::Mesh(_))));
    let p = a.add_prototype(&primitives::cuboid(Vec3::ONE)).unwrap();
    let nan = Affine3A::from_translation(Vec3::splat(f32::NAN));
    assert!(matches!(a.add_instance(p, nan), Err(AccelError::InvalidTransform { .. })));
    let singular = Affine3A::from_scale(Vec3::new(1.0, 0.0, 1.0));
    assert!(matches!(a.add_instance(p, singular), Err(AccelError::InvalidTransform { .. })));
    assert!(matches!(
        a.set_instance_transform(InstanceId(99), Affine3A::IDENTITY),
        Err(AccelError::UnknownId { .. })
    ));
    // NaN and zero-area triangles are counted and skipped, not fatal.
    let soup = TriangleMesh::new(
        vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::splat(f32::NAN), Vec3::ZERO, Vec3::ZERO],
        vec![[0, 1, 2], [3, 1, 2], [4, 5, 0]],
    );
    a.add_static(&soup).unwrap();
    let report = a.commit().unwrap();
    assert_eq!(report.skipped_triangles, 2);
    assert!(a.query().unwrap().intersect_p(&Ray::new(Vec3::new(0.2, 0.2, 1.0), Vec3::NEG_Z)));
}

#[test]
fn a_rejected_instance_does_not_use_up_a_free_id() {
    let mut a = embree();
    let p = a.add_prototype(&primitives::cuboid(Vec3::ONE)).unwrap();
    let first = a.add_instance(p, Affine3A::IDENTITY).unwrap();
    a.remove_instance(first).unwrap();
    let nan = Affine3A::from_translation(Vec3::splat(f32::NAN));
    assert!(matches!(a.add_instance(p, nan), Err(AccelError::InvalidTransform { .. })));
    assert_eq!(a.add_instance(p, Affine3A::IDENTITY).unwrap(), first, "the freed id is reused");
    assert_eq!(a.add_instance(p, Affine3A::IDENTITY).unwrap(), InstanceId(first.0 + 1));
}
