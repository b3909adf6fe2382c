//! The cross-check's verdicts on answers traced by the real backends, judged against the f64
//! re-intersection of the triangles hit (docs/crosscheck.md):
//! - identical answers agree, for random triangles, instance transforms and rays far from the
//!   origin (a property test: each backend's f32 `t` is within the derived bound);
//! - near-coincident triangles 1e-4 apart in an instance 40 units out, hit by a ray leaving a
//!   point 38 units out, one backend on each triangle: a tie, not a mismatch (the case that
//!   tolerance rules once reported as a mismatch);
//! - a backend answering a farther triangle, no hit, or no occlusion where a triangle surely
//!   blocks: a mismatch naming the wrong side and why.
//!
//! The constructed cases trace with Embree and the BVH, so they need the `embree` feature.

use dormant::accel::{self, Backend, Hit};
use dormant::accel::{HitTriangle, MeshRef};
use dormant::geometry::{Ray, TriangleMesh};
use dormant::physics::BodyId;
use dormant_lab::crosscheck::{judge, AgreeReason, Answer, TriangleKey, Verdict};
use glam::{Affine3A, Quat, Vec3};
use proptest::prelude::*;

/// A one-triangle mesh as an instance placed by `xf` (or world-space static geometry when
/// `xf` is `None`), traced with `backend`: the answer with its triangle.
fn traced(backend: Backend, tri: [Vec3; 3], xf: Option<Affine3A>, key: u32, ray: &Ray) -> Answer {
    let mut a = accel::create(backend, Some(1)).unwrap();
    let mesh = TriangleMesh::new(tri.to_vec(), vec![[0, 1, 2]]);
    match xf {
        Some(xf) => {
            let p = a.add_prototype(&mesh).unwrap();
            a.add_instance(p, xf).unwrap();
        }
        None => {
            a.add_static(&mesh).unwrap();
        }
    }
    a.commit().unwrap();
    let q = a.query().unwrap();
    let hit: Option<Hit> = q.intersect(ray);
    let mesh_ref = if xf.is_some() { MeshRef::Prototype(0) } else { MeshRef::Static(0) };
    let triangle = (
        TriangleKey { mesh: mesh_ref, prim: key, body: xf.map(|_| BodyId(0)) },
        HitTriangle { vertices: tri, transform: xf },
    );
    Answer { hit, triangle: hit.map(|_| triangle), occluded: q.intersect_p(ray) }
}

fn unit(v: Vec3) -> Vec3 {
    v.normalize_or_zero()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    #[test]
    fn identical_answers_agree_within_the_derived_bound(
        centre in prop::array::uniform3(-60.0f32..60.0),
        size in 0.005f32..2.0,
        corners in prop::array::uniform9(-1.0f32..1.0),
        angles in prop::array::uniform3(-3.1f32..3.1),
        instanced in any::<bool>(),
        bary in (0.02f32..0.96, 0.02f32..0.96),
        from in prop::array::uniform3(-1.0f32..1.0),
        distance in 0.05f32..20.0,
    ) {
        let centre = Vec3::from(centre);
        let c = corners;
        let local = [Vec3::new(c[0], c[1], c[2]), Vec3::new(c[3], c[4], c[5]), Vec3::new(c[6], c[7], c[8])]
            .map(|v| v * size);
        prop_assume!((local[1] - local[0]).cross(local[2] - local[0]).length() > 1e-3 * size * size);
        let rot = Quat::from_euler(glam::EulerRot::XYZ, angles[0], angles[1], angles[2]);
        let (tri, xf) = if instanced {
            (local, Some(Affine3A::from_rotation_translation(rot, centre)))
        } else {
            (local.map(|v| rot * v + centre), None)
        };
        let world = local.map(|v| rot * v + centre);
        let (u, v) = if bary.0 + bary.1 > 0.98 { (1.0 - bary.0, 1.0 - bary.1) } else { bary };
        let target = world[0] + u * (world[1] - world[0]) + v * (world[2] - world[0]);
        let dir = unit(Vec3::from(from));
        prop_assume!(dir != Vec3::ZERO);
        let ray = Ray::new(target - dir * distance, dir);
        for backend in Backend::compiled() {
            let answer = traced(backend, tri, xf, 0, &ray);
            let v = judge(&ray, &answer, &answer);
            prop_assert!(
                matches!(v.closest, Verdict::Agree(AgreeReason::Identical)),
                "{backend}: {v:?} for {answer:?}"
            );
            prop_assert!(matches!(v.occlusion, Verdict::Agree(_)), "{backend}: {v:?}");
            if let (Some(h), Some(e)) = (answer.hit, v.exact[0]) {
                prop_assert!(e.t_error_over_bound(h.t) <= 1.0, "{backend}: {e:?} {h:?}");
            }
        }
    }
}

/// Cases built by hand around the reported one, traced by Embree and the BVH.
#[cfg(feature = "embree")]
mod constructed {
    use super::*;
    use dormant_lab::crosscheck::{reintersect, Fault, TieReason};

    /// Two parallel triangles 1e-4 apart (object space), in an instance about 40 units out.
    fn coincident_pair() -> ([Vec3; 3], [Vec3; 3], Affine3A) {
        let near = [Vec3::new(-0.3, -0.3, 0.0), Vec3::new(0.3, -0.3, 0.0), Vec3::new(0.0, 0.3, 0.0)];
        let far = near.map(|v| v - Vec3::new(0.0, 0.0, 1e-4));
        let xf = Affine3A::from_rotation_translation(Quat::from_rotation_y(0.7), Vec3::new(28.0, 1.5, 27.0));
        (near, far, xf)
    }

    /// A ray from about 38 units out reaching the pair's front face at t ~ 0.41, obliquely.
    fn ray_at_pair(xf: &Affine3A) -> Ray {
        let target = xf.transform_point3(Vec3::new(0.02, 0.01, 0.0));
        let dir = unit(xf.transform_vector3(Vec3::new(0.3, 0.2, -0.6)));
        let ray = Ray::new(target - dir * 0.41, dir);
        assert!((ray.origin.length() - 38.0).abs() < 1.5, "origin {}", ray.origin.length());
        ray
    }

    #[test]
    fn near_coincident_triangles_far_from_the_origin_are_a_tie() {
        let (near, far, xf) = coincident_pair();
        let ray = ray_at_pair(&xf);
        let reference = traced(Backend::Embree, near, Some(xf), 0, &ray);
        let candidate = traced(Backend::Bvh, far, Some(xf), 1, &ray);
        let (a, b) = (reference.hit.unwrap(), candidate.hit.unwrap());
        // As reported: same instance, different triangles, t a little over 1e-4 apart at t = 0.41.
        assert!((a.t - 0.41).abs() < 1e-3 && (b.t - a.t) > 1e-4, "{a:?} {b:?}");
        let v = judge(&ray, &reference, &candidate);
        assert_eq!(v.closest, Verdict::Tie(TieReason::Coincident), "{v:?}");
        assert!(!matches!(v.occlusion, Verdict::Mismatch { .. }), "{v:?}");
        // Either order, either backend on either triangle.
        let swapped = judge(
            &ray,
            &traced(Backend::Bvh, near, Some(xf), 0, &ray),
            &traced(Backend::Embree, far, Some(xf), 1, &ray),
        );
        assert_eq!(swapped.closest, Verdict::Tie(TieReason::Coincident), "{swapped:?}");
    }

    #[test]
    fn a_hit_on_a_farther_triangle_is_a_mismatch() {
        let (near, _, xf) = coincident_pair();
        let behind = near.map(|v| v - Vec3::new(0.0, 0.0, 0.05));
        let ray = ray_at_pair(&xf);
        let reference = traced(Backend::Embree, near, Some(xf), 0, &ray);
        let candidate = traced(Backend::Bvh, behind, Some(xf), 1, &ray);
        let v = judge(&ray, &reference, &candidate);
        assert_eq!(
            v.closest,
            Verdict::Mismatch { reference: None, candidate: Some(Fault::MissedNearerHit) },
            "{v:?}"
        );
        // The mismatch carries both re-intersections and their bounds.
        let [ea, eb] = v.exact.map(Option::unwrap);
        assert!(eb.t - ea.t > 100.0 * (ea.t_bound + eb.t_bound), "{ea:?} {eb:?}");
    }

    #[test]
    fn a_missed_hit_and_a_missed_blocker_are_mismatches() {
        let (near, _, xf) = coincident_pair();
        let ray = ray_at_pair(&xf);
        let reference = traced(Backend::Embree, near, Some(xf), 0, &ray);
        let nothing = Answer { hit: None, triangle: None, occluded: false };
        let v = judge(&ray, &reference, &nothing);
        assert_eq!(v.closest, Verdict::Mismatch { reference: None, candidate: Some(Fault::MissedHit) });
        assert_eq!(v.occlusion, Verdict::Mismatch { reference: None, candidate: Some(Fault::MissedBlocker) });
        // A shadow segment ending well before the triangle is not blocked: claiming so is wrong.
        let short = Ray::segment(ray.origin, ray.dir, 0.0, 0.2);
        let claims = Answer { occluded: true, ..reference };
        let clear = traced(Backend::Bvh, near, Some(xf), 0, &short);
        assert!(clear.hit.is_none() && !clear.occluded);
        let v = judge(&short, &clear, &Answer { hit: reference.hit, triangle: reference.triangle, ..claims });
        assert!(matches!(v.occlusion, Verdict::Mismatch { reference: None, candidate: Some(_) }), "{v:?}");
    }

    #[test]
    fn a_hit_within_the_bound_of_an_edge_or_the_segment_end_is_a_tie() {
        let (near, _, xf) = coincident_pair();
        let ray = ray_at_pair(&xf);
        let reference = traced(Backend::Embree, near, Some(xf), 0, &ray);
        let e = reintersect(&ray, &reference.triangle.unwrap().1).unwrap();
        // The segment ends at the hit: one backend occluded, the other not, is a tie.
        let ending = Ray::segment(ray.origin, ray.dir, 0.0, e.t as f32);
        let a = Answer { occluded: true, ..reference };
        let b = Answer { hit: None, triangle: None, occluded: false };
        let v = judge(&ending, &a, &b);
        assert_eq!(v.closest, Verdict::Tie(TieReason::IntervalEnd), "{v:?}");
        assert_eq!(v.occlusion, Verdict::Tie(TieReason::IntervalEnd), "{v:?}");
        // A ray through a point a hair outside an edge (well within the edge bound) that one
        // backend reports as a hit.
        let world = near.map(|v| xf.transform_point3(v));
        let mid = (world[0] + world[1]) * 0.5;
        let outward = unit(mid - (world[0] + world[1] + world[2]) / 3.0);
        let dir = ray.dir;
        let grazing_edge = Ray::new(mid + outward * 2e-5 - dir * 0.41, dir);
        let hit = reference.hit.map(|h| Hit { t: 0.41, u: 0.5, v: 0.0, ..h });
        let a = Answer { hit, triangle: reference.triangle, occluded: true };
        let e = reintersect(&grazing_edge, &a.triangle.unwrap().1).unwrap();
        assert!(e.edge_margin < 0.0 && -e.edge_margin < e.edge_bound, "{e:?}");
        let v = judge(&grazing_edge, &a, &b);
        assert_eq!(v.closest, Verdict::Tie(TieReason::Edge), "{v:?}");
        assert_eq!(v.occlusion, Verdict::Tie(TieReason::Edge), "{v:?}");
    }
}
