//! The safe Embree wrapper against the real library: hits, instancing, attach/detach,
//! recommit, errors and the committed-scene rule.
#![cfg(feature = "embree")]

use std::sync::Arc;

use dormant::accel::embree::shutter_poses;
use dormant::geometry::{InstanceMotion, Ray, RigidTransform};
use dormant_embree::{
    BuildQuality, Device, EmbreeError, Geometry, InstanceArrayGeometry, InstanceGeometry, Scene, SceneFlags,
    TriangleGeometry, Version,
};
use glam::{Affine3A, Quat, Vec3};

fn device() -> Device {
    Device::new(Some(2)).expect("Embree device")
}

fn unit_triangle(device: &Device) -> TriangleGeometry {
    let p = [Vec3::ZERO, Vec3::X, Vec3::Y];
    TriangleGeometry::new(device, &p, &[[0, 1, 2]]).unwrap()
}

fn scene(device: &Device) -> Scene {
    Scene::new(device, SceneFlags::default(), BuildQuality::Medium).unwrap()
}

#[test]
fn library_version_is_4x_and_not_older_than_headers() {
    let d = device();
    assert_eq!(d.library_version().major, 4);
    assert_eq!(Version::header().major, 4);
    assert!(d.library_version() >= Version::header());
}

#[test]
fn known_triangle_hit_has_expected_t_u_v_and_prim() {
    let d = device();
    let mut s = scene(&d);
    // Two triangles, so the hit's primID must be 1.
    let p = [
        Vec3::ZERO,
        Vec3::X,
        Vec3::Y,
        Vec3::new(5.0, 0.0, 0.0),
        Vec3::new(6.0, 0.0, 0.0),
        Vec3::new(5.0, 1.0, 0.0),
    ];
    s.attach(TriangleGeometry::new(&d, &p, &[[0, 1, 2], [3, 4, 5]]).unwrap()).unwrap();
    s.commit().unwrap();
    let hit = s
        .view()
        .unwrap()
        .intersect1_at([5.2, 0.3, -3.0], [0.0, 0.0, 1.0], 0.0, f32::INFINITY, Ray::FRAME_TIME)
        .unwrap();
    assert_eq!((hit.geom_id, hit.prim_id, hit.inst_id), (0, 1, None));
    assert!((hit.t - 3.0).abs() < 1e-6);
    assert!((hit.u - 0.2).abs() < 1e-5 && (hit.v - 0.3).abs() < 1e-5, "u={} v={}", hit.u, hit.v);
    // Ng = (p1-p0) x (p2-p0) = +z.
    assert!(hit.ng[2] > 0.0);
    assert!(s.view().unwrap().occluded1_at([5.2, 0.3, -3.0], [0.0, 0.0, 1.0], 0.0, 10.0, Ray::FRAME_TIME));
    assert!(!s.view().unwrap().occluded1_at([5.2, 0.3, -3.0], [0.0, 0.0, 1.0], 0.0, 2.9, Ray::FRAME_TIME));
    assert!(s
        .view()
        .unwrap()
        .intersect1_at([5.2, 0.3, -3.0], [0.0, 0.0, -1.0], 0.0, f32::INFINITY, Ray::FRAME_TIME)
        .is_none());
}

#[test]
fn instanced_hit_reports_instance_id() {
    let d = device();
    let mut proto = scene(&d);
    proto.attach(unit_triangle(&d)).unwrap();
    let proto = proto.freeze().unwrap();
    let mut top = scene(&d);
    let xf = Affine3A::from_translation(Vec3::new(10.0, 0.0, 0.0));
    top.attach_by_id(InstanceGeometry::new(&d, &proto, &Affine3A::IDENTITY).unwrap(), 3).unwrap();
    top.attach_by_id(InstanceGeometry::new(&d, &proto, &xf).unwrap(), 7).unwrap();
    top.commit().unwrap();
    let hit = top
        .view()
        .unwrap()
        .intersect1_at([10.25, 0.25, 1.0], [0.0, 0.0, -1.0], 0.0, f32::INFINITY, Ray::FRAME_TIME)
        .unwrap();
    assert_eq!((hit.inst_id, hit.geom_id, hit.prim_id), (Some(7), 0, 0));
    assert!((hit.t - 1.0).abs() < 1e-6);
}

#[test]
fn changes_need_a_commit_before_rays() {
    let d = device();
    let mut s = scene(&d);
    assert!(s.view().is_none(), "a new scene is not committed");
    s.attach(unit_triangle(&d)).unwrap();
    assert!(s.view().is_none());
    s.commit().unwrap();
    assert!(s.view().is_some());
}

#[test]
fn detach_reattach_and_recommit() {
    let d = device();
    let mut s =
        Scene::new(&d, SceneFlags { dynamic: true, ..Default::default() }, BuildQuality::Low).unwrap();
    let id = s.attach(unit_triangle(&d)).unwrap();
    s.commit().unwrap();
    let ray = ([0.25, 0.25, 1.0], [0.0, 0.0, -1.0]);
    assert!(s.view().unwrap().intersect1_at(ray.0, ray.1, 0.0, f32::INFINITY, Ray::FRAME_TIME).is_some());

    let geometry = s.detach(id).unwrap();
    assert!(s.view().is_none());
    s.commit().unwrap();
    assert!(s.view().unwrap().intersect1_at(ray.0, ray.1, 0.0, f32::INFINITY, Ray::FRAME_TIME).is_none());

    s.attach_by_id(geometry, 42).unwrap();
    s.commit().unwrap();
    let hit = s.view().unwrap().intersect1_at(ray.0, ray.1, 0.0, f32::INFINITY, Ray::FRAME_TIME).unwrap();
    assert_eq!(hit.geom_id, 42);
}

#[test]
fn one_geometry_in_two_scenes() {
    let d = device();
    let g = unit_triangle(&d);
    let (mut a, mut b) = (scene(&d), scene(&d));
    a.attach(g.clone()).unwrap();
    b.attach(g).unwrap();
    a.commit().unwrap();
    b.commit().unwrap();
    for s in [&a, &b] {
        assert!(s.view().unwrap().occluded1_at(
            [0.25, 0.25, 1.0],
            [0.0, 0.0, -1.0],
            0.0,
            2.0,
            Ray::FRAME_TIME
        ));
    }
}

#[test]
fn shared_buffers_are_traced() {
    let d = device();
    let vertices: Arc<[[f32; 4]]> =
        Arc::from(vec![[0.0, 0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]]);
    let indices: Arc<[[u32; 3]]> = Arc::from(vec![[0u32, 1, 2]]);
    let g = TriangleGeometry::new_shared(&d, vertices, indices).unwrap();
    let mut s = scene(&d);
    s.attach(g).unwrap();
    s.commit().unwrap();
    let hit = s
        .view()
        .unwrap()
        .intersect1_at([0.5, 0.25, -2.0], [0.0, 0.0, 1.0], 0.0, f32::INFINITY, Ray::FRAME_TIME)
        .unwrap();
    assert!((hit.t - 2.0).abs() < 1e-6);
}

#[test]
fn invalid_call_is_a_rust_error() {
    let d = device();
    let mut s = scene(&d);
    // Embree itself rejects the unknown geometry id; the wrapper surfaces its message.
    match s.detach(12345) {
        Err(EmbreeError::Api { code, message }) => {
            assert!(code.starts_with("RTC_ERROR_"), "{code}");
            assert!(!message.is_empty());
        }
        Err(other) => panic!("expected an Embree API error, got {other}"),
        Ok(_) => panic!("detaching an unknown id succeeded"),
    }
    // The device stays usable after an error.
    s.attach(unit_triangle(&d)).unwrap();
    s.commit().unwrap();
}

#[test]
fn bad_device_config_is_a_rust_error() {
    assert!(Device::with_config("threads=not_a_number").is_err());
}

#[test]
fn owned_child_scene_changes_reach_the_parent() {
    let d = device();
    let child =
        Scene::new(&d, SceneFlags { dynamic: true, ..Default::default() }, BuildQuality::Medium).unwrap();
    let mut top = scene(&d);
    top.attach_by_id(InstanceGeometry::owning(&d, child, &Affine3A::IDENTITY).unwrap(), 0).unwrap();
    top.commit().unwrap();
    let ray = ([0.25, 0.25, 1.0], [0.0, 0.0, -1.0]);
    assert!(top.view().unwrap().intersect1_at(ray.0, ray.1, 0.0, f32::INFINITY, Ray::FRAME_TIME).is_none());

    let inst = top.instance_mut(0).unwrap();
    inst.child_mut().unwrap().attach_by_id(unit_triangle(&d), 5).unwrap();
    assert!(top.view().is_none(), "changing the child stages a change in the parent");
    top.commit().unwrap();
    let hit = top.view().unwrap().intersect1_at(ray.0, ray.1, 0.0, f32::INFINITY, Ray::FRAME_TIME).unwrap();
    assert_eq!((hit.inst_id, hit.geom_id), (Some(0), 5));
}

#[test]
fn instance_transform_updates_and_rejects_nan() {
    let d = device();
    let mut proto = scene(&d);
    proto.attach(unit_triangle(&d)).unwrap();
    let proto = proto.freeze().unwrap();
    let mut top = scene(&d);
    top.attach_by_id(InstanceGeometry::new(&d, &proto, &Affine3A::IDENTITY).unwrap(), 0).unwrap();
    top.commit().unwrap();
    let moved = Affine3A::from_rotation_translation(Quat::from_rotation_z(0.3), Vec3::new(0.0, 0.0, -4.0));
    top.instance_mut(0).unwrap().set_transform(&moved).unwrap();
    top.commit().unwrap();
    let hit = top
        .view()
        .unwrap()
        .intersect1_at([0.1, 0.3, 1.0], [0.0, 0.0, -1.0], 0.0, f32::INFINITY, Ray::FRAME_TIME)
        .unwrap();
    assert!((hit.t - 5.0).abs() < 1e-5);
    let nan = Affine3A::from_translation(Vec3::new(f32::NAN, 0.0, 0.0));
    assert_eq!(top.instance_mut(0).unwrap().set_transform(&nan), Err(EmbreeError::NonFiniteTransform));
    assert!(matches!(top.geometry(0), Some(Geometry::Instance(_))));
}

/// A square at z = 1 in object space, so a wrong scale of the instance moves it.
fn raised_square(device: &Device) -> Arc<dormant_embree::FrozenScene> {
    let p = [
        Vec3::new(-2.0, -2.0, 1.0),
        Vec3::new(2.0, -2.0, 1.0),
        Vec3::new(2.0, 2.0, 1.0),
        Vec3::new(-2.0, 2.0, 1.0),
    ];
    let mut proto = scene(device);
    proto.attach(TriangleGeometry::new(device, &p, &[[0, 1, 2], [0, 2, 3]]).unwrap()).unwrap();
    proto.freeze().unwrap()
}

/// Where a ray from `org` straight down (-z) meets the raised square placed by `motion` at
/// `time`, from dormant's own interpolation ([`InstanceMotion::at`]).
fn expected_t(motion: &InstanceMotion, time: f32, org: Vec3) -> f32 {
    let xf = motion.at(time).to_affine();
    let (n, p) = (xf.transform_vector3(Vec3::Z), xf.transform_point3(Vec3::Z));
    n.dot(p - org) / n.dot(Vec3::NEG_Z)
}

/// The raised square instanced alone with `motion`, traced straight down from `org` at five
/// shutter times: each time with the hit distance Embree reports and the one
/// [`expected_t`] gives.
fn traced_over_the_shutter(
    d: &Device,
    proto: &Arc<dormant_embree::FrozenScene>,
    motion: &InstanceMotion,
    org: Vec3,
) -> Vec<(f32, f32, f32)> {
    let mut top = scene(d);
    top.attach_by_id(InstanceGeometry::new(d, proto, &Affine3A::IDENTITY).unwrap(), 0).unwrap();
    let instance = top.instance_mut(0).unwrap();
    let poses = shutter_poses(motion, instance.child_radius());
    instance.set_motion(&poses).unwrap();
    top.commit().unwrap();
    let view = top.view().unwrap();
    [0.0, 0.25, 0.5, 0.75, 1.0]
        .into_iter()
        .map(|time| {
            let hit = view.intersect1_at(org.to_array(), [0.0, 0.0, -1.0], 0.0, f32::INFINITY, time).unwrap();
            (time, hit.t, expected_t(motion, time, org))
        })
        .collect()
}

#[test]
fn moving_instance_is_where_its_motion_puts_it_at_every_shutter_time() {
    let d = device();
    let proto = raised_square(&d);
    let open =
        RigidTransform { rotation: Quat::from_rotation_x(0.1), translation: Vec3::new(0.0, 0.0, -2.0) };
    // A pure translation and turns of 2e-4 and 1.9e-3 rad are lerped as matrices, a turn of 0.4
    // rad is slerped as quaternions: lerping it would put the square 0.02 off halfway.
    for angle in [0.0, 2e-4, 1.9e-3, 0.4] {
        let close = RigidTransform {
            rotation: Quat::from_rotation_x(0.1 + angle),
            translation: Vec3::new(0.5, 0.0, -4.0),
        };
        let motion = InstanceMotion { open, close };
        for (time, t, want) in traced_over_the_shutter(&d, &proto, &motion, Vec3::new(0.3, 0.2, 5.0)) {
            assert!((t - want).abs() < 1e-4, "angle {angle}, time {time}: t {t} against {want}");
        }
    }
}

#[test]
fn far_instance_turning_past_the_fixed_angle_stays_within_the_crosscheck_allowance() {
    // 1,000 units out, the raised square (points within 3 of its origin) may turn by up to
    // 2e-3 * sqrt(1000 / 3) = 0.037 rad as lerped matrices: halfway through a 0.03 turn they
    // put it up to 0.03^2 / 8 * 3 = 3.4e-4 off the slerp, within 8 unit roundoffs of 1,000.
    let d = device();
    let proto = raised_square(&d);
    let far = Vec3::new(1000.0, 0.0, -2.0);
    let motion = InstanceMotion {
        open: RigidTransform { rotation: Quat::from_rotation_x(0.1), translation: far },
        close: RigidTransform {
            rotation: Quat::from_rotation_x(0.13),
            translation: far + Vec3::new(0.5, 0.0, -2.0),
        },
    };
    let org = Vec3::new(1000.3, 0.2, 5.0);
    // The crosscheck's allowance for Embree's transform: 16 unit roundoffs of the ray origin's
    // and the translation's magnitudes (docs/crosscheck.md), along a ray nearly normal to the
    // square.
    let allowance = 16.0 * f32::EPSILON / 2.0 * (org.abs().max_element() + far.abs().max_element());
    for (time, t, want) in traced_over_the_shutter(&d, &proto, &motion, org) {
        assert!((t - want).abs() <= allowance, "time {time}: t {t} against {want} (allowance {allowance})");
    }
}

#[test]
fn instance_array_places_each_entry_and_skips_holes() {
    let d = device();
    let proto = raised_square(&d);
    let at = |x: f32| RigidTransform { rotation: Quat::IDENTITY, translation: Vec3::new(x, 0.0, -2.0) };
    let xs = [0.0, 10.0, 20.0];
    let down = |view: &dormant_embree::SceneView, x: f32, time: f32| {
        view.intersect1_at([x, 0.5, 5.0], [0.0, 0.0, -1.0], 0.0, f32::INFINITY, time)
    };
    let mut still = scene(&d);
    let mut array = InstanceArrayGeometry::new(&d, std::slice::from_ref(&proto), false).unwrap();
    let entries: Vec<_> =
        xs.iter().enumerate().map(|(i, &x)| ((i != 1).then_some(0), at(x).to_affine())).collect();
    array.set_still(&entries).unwrap();
    still.attach_by_id(array, 4).unwrap();
    still.commit().unwrap();
    let view = still.view().unwrap();
    for (i, &x) in xs.iter().enumerate() {
        let hit = down(&view, x, 0.5);
        assert_eq!(hit.map(|h| h.inst_id), (i != 1).then_some(Some(4)), "entry {i}");
        assert!(hit.is_none_or(|h| (h.t - 6.0).abs() < 1e-5));
    }
    for angle in [0.0, 0.4] {
        let mut moving = scene(&d);
        let mut array = InstanceArrayGeometry::new(&d, std::slice::from_ref(&proto), true).unwrap();
        let motion = |x: f32| InstanceMotion {
            open: at(x),
            close: RigidTransform {
                rotation: Quat::from_rotation_x(angle),
                translation: Vec3::new(x, 0.0, -4.0),
            },
        };
        let entries: Vec<_> =
            xs.iter().map(|&x| (Some(0), shutter_poses(&motion(x), proto.radius()))).collect();
        array.set_moving(&entries).unwrap();
        moving.attach_by_id(array, 0).unwrap();
        moving.commit().unwrap();
        let view = moving.view().unwrap();
        for time in [0.0, 0.5, 1.0] {
            let hit = down(&view, 10.0, time).unwrap();
            let want = expected_t(&motion(10.0), time, Vec3::new(10.0, 0.5, 5.0));
            assert!((hit.t - want).abs() < 1e-4, "angle {angle}, time {time}: t {} against {want}", hit.t);
        }
    }
}
