//! Packet queries (`intersect_packet`, `intersect_p_packet`) equal the single-ray queries on
//! every compiled backend; on Embree also the wrapper's 4/8/16-wide packets with partially
//! valid masks and instanced geometry.

use dormant::accel::{self, Accelerator, Backend, Hit};
use dormant::geometry::{InstanceMotion, Ray, RigidTransform};
use dormant::scene::default_scene;
use dormant_lab::crosscheck::{camera_rays, surface_rays};
use glam::{Quat, Vec3};
use proptest::prelude::*;

fn loaded(backend: Backend) -> Box<dyn Accelerator> {
    let mut a = accel::create(backend, Some(2)).unwrap();
    accel::load_scene(&default_scene(), a.as_mut()).unwrap();
    a.commit().unwrap();
    a
}

/// Same distance (within 1e-5 relative) and the same object and triangle, unless two
/// surfaces tie at that distance (a body resting on the floor: its bottom face and the floor
/// coincide), where traversal order picks one and packets may pick the other.
fn assert_same_hit(packet: Option<Hit>, single: Option<Hit>, ray: &Ray) {
    match (packet, single) {
        (None, None) => {}
        (Some(p), Some(s)) => {
            assert!((p.t - s.t).abs() <= 1e-5 * s.t.max(1.0), "t {} vs {} for {ray:?}", p.t, s.t);
            if (p.object, p.prim) != (s.object, s.prim) {
                assert!(p.ng.dot(s.ng).abs() > 1.0 - 1e-4, "ties are coplanar: {p:?} vs {s:?}");
                return;
            }
            assert!((p.u - s.u).abs() < 1e-4 && (p.v - s.v).abs() < 1e-4, "uv for {ray:?}");
            assert!(p.ng.abs_diff_eq(s.ng, 1e-4), "ng {} vs {} for {ray:?}", p.ng, s.ng);
        }
        (p, s) => panic!("packet {p:?} vs single {s:?} for {ray:?}"),
    }
}

/// Traces `rays` in groups of `group` rays (the last may be shorter) both ways and compares.
fn check_groups(a: &dyn Accelerator, rays: &[Ray], group: usize) {
    let q = a.query().unwrap();
    let mut hits = vec![None; rays.len()];
    let mut occluded = vec![false; rays.len()];
    for ((r, h), o) in rays.chunks(group).zip(hits.chunks_mut(group)).zip(occluded.chunks_mut(group)) {
        q.intersect_packet(r, h);
        q.intersect_p_packet(r, o);
    }
    for ((ray, hit), occ) in rays.iter().zip(hits).zip(occluded) {
        assert_same_hit(hit, q.intersect(ray), ray);
        assert_eq!(occ, q.intersect_p(ray), "occlusion of {ray:?}");
    }
}

/// Camera rays (coherent, with instanced and static hits and misses) and surface rays
/// (incoherent, some with finite `t_max`).
fn test_rays() -> Vec<Ray> {
    let desc = default_scene();
    let mut rays = camera_rays(&desc, 24, 16);
    let mut surface = surface_rays(&desc, 300, 5);
    for (i, r) in surface.iter_mut().enumerate() {
        if i % 3 == 0 {
            r.t_max = 0.5 + i as f32 * 0.01;
        }
    }
    rays.extend(surface);
    rays
}

#[test]
fn packets_equal_single_rays_on_every_backend_and_width() {
    let rays = test_rays();
    for backend in Backend::compiled() {
        let a = loaded(backend);
        for group in [1, 3, 4, 5, 8, 13, 16, 17, 40] {
            check_groups(a.as_ref(), &rays, group);
        }
    }
}

#[test]
fn instanced_hits_come_back_from_packets() {
    let rays = camera_rays(&default_scene(), 24, 16);
    for backend in Backend::compiled() {
        let a = loaded(backend);
        let q = a.query().unwrap();
        let mut hits = vec![None; rays.len()];
        for (r, h) in rays.chunks(8).zip(hits.chunks_mut(8)) {
            q.intersect_packet(r, h);
        }
        let instanced = hits.iter().flatten().filter(|h| matches!(h.object, accel::HitObject::Instance(_)));
        assert!(instanced.count() > 10, "{backend}: the default scene's bodies are in view");
    }
}

/// Moving instances (motion blur): the lanes of one packet, each at its own time, see every
/// instance where it is at that time, as single rays do.
#[test]
fn moving_instances_in_packets_hit_like_single_rays() {
    let desc = default_scene();
    let mut rays = camera_rays(&desc, 24, 16);
    for (i, r) in rays.iter_mut().enumerate() {
        r.time = (i * 37 % 101) as f32 / 100.0;
    }
    for backend in Backend::compiled() {
        let mut a = accel::create(backend, Some(2)).unwrap();
        let loaded = accel::load_scene(&desc, a.as_mut()).unwrap();
        for (id, body) in loaded.instances.iter().zip(&desc.bodies) {
            let (_, rotation, translation) = body.transform.to_scale_rotation_translation();
            let open = RigidTransform { rotation, translation };
            let close = RigidTransform {
                rotation: Quat::from_rotation_y(0.3) * rotation,
                translation: translation + Vec3::new(0.3, 0.1, 0.0),
            };
            a.set_instance_motion(*id, Some(InstanceMotion { open, close })).unwrap();
        }
        a.commit().unwrap();
        for group in [8, 5] {
            check_groups(a.as_ref(), &rays, group);
        }
    }
}

/// Lanes with an empty or NaN interval (`t_min > t_max`) miss and are never blocked, and do
/// not disturb the valid lanes of their packet.
#[test]
fn lanes_with_empty_intervals_miss_inside_a_packet() {
    let desc = default_scene();
    let mut rays = camera_rays(&desc, 4, 2);
    rays[1].t_min = 2.0;
    rays[1].t_max = 1.0;
    rays[4].t_max = f32::NAN;
    rays[6].t_min = f32::NAN;
    for backend in Backend::compiled() {
        let a = loaded(backend);
        let q = a.query().unwrap();
        let mut hits = [None; 8];
        let mut occluded = [true; 8];
        q.intersect_packet(&rays, &mut hits);
        q.intersect_p_packet(&rays, &mut occluded);
        for i in [1, 4, 6] {
            assert_eq!(hits[i], None, "{backend}: lane {i}");
            assert!(!occluded[i], "{backend}: lane {i}");
        }
        for i in [0, 2, 3, 5, 7] {
            assert_same_hit(hits[i], q.intersect(&rays[i]), &rays[i]);
            assert_eq!(occluded[i], q.intersect_p(&rays[i]), "{backend}: lane {i}");
        }
        assert!(hits.iter().flatten().count() >= 4, "{backend}: the camera sees the scene");
    }
}

#[test]
#[should_panic(expected = "one hit slot per ray")]
fn mismatched_lengths_panic() {
    let a = loaded(Backend::Bvh);
    let rays = test_rays();
    a.query().unwrap().intersect_packet(&rays[..4], &mut [None; 3]);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]
    #[test]
    fn random_groups_match(start in 0usize..600, len in 1usize..40) {
        let rays = test_rays();
        let rays = &rays[start.min(rays.len() - 1)..(start + len).min(rays.len())];
        for backend in Backend::compiled() {
            check_groups(loaded(backend).as_ref(), rays, rays.len());
        }
    }
}

#[cfg(feature = "embree")]
mod embree_wrapper {
    use std::sync::Arc;

    use dormant::geometry::Ray;
    use dormant_embree::{
        BuildQuality, Coherence, Device, EmbreeHit, FrozenScene, InstanceGeometry, Scene, SceneFlags,
        TriangleGeometry,
    };
    use glam::{Affine3A, Vec3};

    fn prototype(d: &Device) -> Arc<FrozenScene> {
        let mut s = Scene::new(d, SceneFlags::default(), BuildQuality::Medium).unwrap();
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(0.0, 0.0, 1.0)];
        s.attach(TriangleGeometry::new(d, &p, &[[0, 1, 2], [0, 1, 3]]).unwrap()).unwrap();
        s.freeze().unwrap()
    }

    /// A triangle at the origin plus three instances of a two-triangle prototype along x.
    fn scene(d: &Device) -> Scene {
        let proto = prototype(d);
        let mut top = Scene::new(d, SceneFlags::default(), BuildQuality::Medium).unwrap();
        top.attach_by_id(TriangleGeometry::new(d, &[Vec3::ZERO, Vec3::X, Vec3::Y], &[[0, 1, 2]]).unwrap(), 0)
            .unwrap();
        for i in 1..4u32 {
            let xf = Affine3A::from_translation(Vec3::new(10.0 * i as f32, 0.0, 0.0));
            top.attach_by_id(InstanceGeometry::new(d, &proto, &xf).unwrap(), i).unwrap();
        }
        top.commit().unwrap();
        top
    }

    /// Lane `i`: a ray down -z at x = 10 * (i % 5) + 0.25 (the triangle, instances 1-3 or
    /// nothing), every third one too short to reach.
    fn lane(i: usize) -> Ray {
        let x = 10.0 * (i % 5) as f32 + 0.25;
        let t_max = if i % 3 == 2 { 0.5 } else { f32::INFINITY };
        Ray::segment(Vec3::new(x, 0.25, 3.0), Vec3::NEG_Z, 0.0, t_max)
    }

    fn single(s: &Scene, r: &Ray) -> (Option<EmbreeHit>, bool) {
        let v = s.view().unwrap();
        let (o, d) = (r.origin.to_array(), r.dir.to_array());
        (
            v.intersect1_at(o, d, r.t_min, r.t_max, Ray::FRAME_TIME),
            v.occluded1_at(o, d, r.t_min, r.t_max, Ray::FRAME_TIME),
        )
    }

    fn check<const N: usize>(
        s: &Scene,
        rays: &[Option<Ray>; N],
        hits: [Option<EmbreeHit>; N],
        occluded: [bool; N],
    ) {
        for i in 0..N {
            let Some(r) = rays[i] else {
                assert!(hits[i].is_none() && !occluded[i], "inactive lane {i} reported something");
                continue;
            };
            let (hit, occ) = single(s, &r);
            assert_eq!(occluded[i], occ, "lane {i}");
            match (hits[i], hit) {
                (Some(p), Some(h)) => {
                    assert_eq!(
                        (p.inst_id, p.geom_id, p.prim_id),
                        (h.inst_id, h.geom_id, h.prim_id),
                        "lane {i}"
                    );
                    assert!((p.t - h.t).abs() < 1e-5 && (p.u - h.u).abs() < 1e-5, "lane {i}");
                }
                (p, h) => assert_eq!(p.is_some(), h.is_some(), "lane {i}: {p:?} vs {h:?}"),
            }
        }
    }

    #[test]
    fn wrapper_packets_with_partial_masks_and_instances() {
        let d = Device::new(Some(2)).unwrap();
        let s = scene(&d);
        let v = s.view().unwrap();
        let mut seen_instances = 0;
        // Every mask pattern of the first lanes in turn: full, every other lane, a single lane.
        for pattern in [0usize, 1, 2] {
            let active = |i: usize| match pattern {
                0 => true,
                1 => i % 2 == 1,
                _ => i == 5,
            };
            for c in [Coherence::Incoherent, Coherence::Coherent] {
                let r4: [Option<Ray>; 4] = std::array::from_fn(|i| active(i).then(|| lane(i)));
                check(&s, &r4, v.intersect4(&r4, c), v.occluded4(&r4, c));
                let r8: [Option<Ray>; 8] = std::array::from_fn(|i| active(i).then(|| lane(i)));
                check(&s, &r8, v.intersect8(&r8, c), v.occluded8(&r8, c));
                let r16: [Option<Ray>; 16] = std::array::from_fn(|i| active(i).then(|| lane(i)));
                let hits = v.intersect16(&r16, c);
                seen_instances += hits.iter().flatten().filter(|h| h.inst_id.is_some()).count();
                check(&s, &r16, hits, v.occluded16(&r16, c));
            }
        }
        assert!(seen_instances > 0);
        // An all-inactive packet is allowed and reports nothing.
        assert_eq!(v.intersect8(&[None::<Ray>; 8], Coherence::Coherent), [None; 8]);
        assert_eq!(v.occluded16(&[None::<Ray>; 16], Coherence::Incoherent), [false; 16]);
    }
}
