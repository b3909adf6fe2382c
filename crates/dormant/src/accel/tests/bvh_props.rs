//! Property tests of the pure-Rust BVH backend against an f64 brute-force reference, on every
//! SIMD path this CPU runs (each scene is checked once per path, and the paths must agree hit
//! for hit).

use super::common::*;
use crate::accel::bvh::{BuildParams, BvhAccel, SimdPath, StaticBvh};
use crate::accel::{create, AccelError, Accelerator, Backend, HitObject, SceneQuery, StaticId};
use crate::geometry::{Ray, TriangleMesh};
use glam::{Affine3A, Quat, Vec3};
use proptest::prelude::*;

fn config(cases: u32) -> ProptestConfig {
    ProptestConfig { cases, failure_persistence: None, ..ProptestConfig::default() }
}

/// Brute force on every SIMD path, ray by ray and in packets (`intersect_packet`,
/// `intersect_p_packet`) of 8 (the renderer's) and 3 (a partial one), and every path's single
/// rays hit what the portable path's do.
fn check_scene(q: &dyn SceneQuery, rays: &[Ray], tris: &[RefTri], rel: f64) -> Result<(), TestCaseError> {
    let portable: Vec<_> = SimdPath::with_override(SimdPath::Portable, || {
        rays.iter().map(|r| (q.intersect(r), q.intersect_p(r))).collect()
    });
    for path in SimdPath::supported() {
        SimdPath::with_override(path, || {
            for (ray, expected) in rays.iter().zip(&portable) {
                let (hit, any) = (q.intersect(ray), q.intersect_p(ray));
                check_hit(ray, hit, tris, rel).map_err(|e| TestCaseError::fail(format!("{path:?}: {e}")))?;
                check_any(ray, any, tris).map_err(|e| TestCaseError::fail(format!("{path:?}: {e}")))?;
                prop_assert_eq!(&(hit, any), expected, "{:?} against portable, ray {:?}", path, ray);
            }
            for group in [8, 3] {
                let mut hits = vec![None; rays.len()];
                let mut any = vec![false; rays.len()];
                for ((r, h), a) in rays.chunks(group).zip(hits.chunks_mut(group)).zip(any.chunks_mut(group)) {
                    q.intersect_packet(r, h);
                    q.intersect_p_packet(r, a);
                }
                for ((ray, hit), any) in rays.iter().zip(hits).zip(any) {
                    let packet = |e| TestCaseError::fail(format!("{path:?}, packets of {group}: {e}"));
                    check_hit(ray, hit, tris, rel).map_err(packet)?;
                    check_any(ray, any, tris).map_err(packet)?;
                }
            }
            Ok(())
        })?;
    }
    Ok(())
}

/// Islands: small clusters of `n` triangles around `c`, built deterministically from `seed`.
fn clusters(specs: &[(Vec3, usize)], seed: u64) -> Vec<TriangleMesh> {
    specs.iter().enumerate().map(|(k, (c, n))| cluster(*c, *n, seed.wrapping_add(k as u64))).collect()
}

/// A persistent tree built from `base` (mesh 100) that never relinks on its own.
fn tree_over(base: &TriangleMesh) -> StaticBvh {
    let mut tree = StaticBvh::new(BuildParams::QUALITY);
    tree.rebuild_fraction = f32::INFINITY;
    tree.apply(&[], &[(StaticId(100), base)]).unwrap();
    tree
}

proptest! {
    #![proptest_config(config(48))]

    #[test]
    fn closest_hit_matches_brute_force(
        a in soup(Vec3::ZERO, 10.0, 3.0, 1..300),
        b in soup(Vec3::new(5.0, 0.0, 0.0), 2.0, 0.5, 0..50),
        seed in any::<u64>(),
    ) {
        let mut accel = create(Backend::Bvh, Some(1)).unwrap();
        let ia = accel.add_static(&a).unwrap();
        let ib = accel.add_static(&b).unwrap();
        let report = accel.commit().unwrap();
        prop_assert_eq!(report.built_triangles + report.skipped_triangles, a.triangle_count() + b.triangle_count());
        let mut tris = ref_tris(HitObject::Static(ia), &a);
        tris.extend(ref_tris(HitObject::Static(ib), &b));
        let rays = rays_for(&[&a, &b], seed, 96, 15.0);
        check_scene(accel.query().unwrap(), &rays, &tris, 1e-5)?;
    }

    #[test]
    fn insert_remove_matches_fresh_build(
        base in soup(Vec3::ZERO, 10.0, 2.0, 50..300),
        islands in prop::collection::vec((vec3(10.0), 1usize..40), 1..8),
        ops in prop::collection::vec((any::<bool>(), 0usize..8), 1..16),
        seed in any::<u64>(),
        island_seed in any::<u64>(),
    ) {
        let islands = clusters(&islands, island_seed);
        let mut tree = tree_over(&base);
        let mut live = vec![false; islands.len()];
        for (add, k) in ops {
            let k = k % islands.len();
            let id = StaticId(k as u32);
            if add && !live[k] {
                tree.insert(id, &islands[k]).unwrap();
                live[k] = true;
            } else if !add && live[k] {
                prop_assert!(tree.remove(id));
                live[k] = false;
            }
            tree.check_invariants().map_err(TestCaseError::fail)?;
            let mut meshes: Vec<(StaticId, &TriangleMesh)> = vec![(StaticId(100), &base)];
            meshes.extend((0..islands.len()).filter(|&k| live[k]).map(|k| (StaticId(k as u32), &islands[k])));
            let mut fresh = StaticBvh::new(BuildParams::QUALITY);
            fresh.apply(&[], &meshes).unwrap();
            prop_assert_eq!(fresh.triangles(), tree.triangles());
            let tris: Vec<RefTri> = meshes.iter().flat_map(|(id, m)| ref_tris(HitObject::Static(*id), m)).collect();
            let all: Vec<&TriangleMesh> = meshes.iter().map(|(_, m)| *m).chain(islands.iter()).collect();
            let rays = rays_for(&all, seed, 48, 12.0);
            let (inc, fr) = (tree.snapshot(), fresh.snapshot());
            check_scene(&inc, &rays, &tris, 1e-5)?;
            // A snapshot rebuilt into one block (what `bench integration` traces the persistent
            // tree against) holds the same triangles in one piece and finds the same hits.
            let rebuilt = inc.rebuilt(BuildParams::QUALITY);
            prop_assert_eq!(rebuilt.triangles(), tree.triangles());
            prop_assert_eq!(rebuilt.block_subtrees(), usize::from(tree.triangles() > 0));
            prop_assert!(inc.block_subtrees() >= rebuilt.block_subtrees());
            for ray in &rays {
                prop_assert_eq!(rebuilt.intersect(ray).map(|h| h.t), fr.intersect(ray).map(|h| h.t));
            }
            for path in SimdPath::supported() {
                SimdPath::with_override(path, || {
                    for ray in &rays {
                        let (a, b) = (inc.intersect(ray), fr.intersect(ray));
                        prop_assert_eq!(a.map(|h| h.t), b.map(|h| h.t), "{:?} ray {:?}", path, ray);
                        prop_assert_eq!(inc.intersect_p(ray), fr.intersect_p(ray));
                    }
                    Ok(())
                })?;
            }
        }
    }

    /// A commit (`apply`) makes the overlay afresh over every live block, re-braided: one
    /// block per island inserted since the first build, the environment opened into at most
    /// four pieces per block (at least 64 in all), the islands whole; hits those of brute force
    /// and of a fresh build throughout, removals included.
    #[test]
    fn commits_rebraid_over_every_live_block(
        base in soup(Vec3::ZERO, 10.0, 2.0, 50..300),
        islands in prop::collection::vec((vec3(10.0), 1usize..40), 2..8),
        batches in prop::collection::vec(prop::collection::vec((any::<bool>(), 0usize..8), 1..4), 1..6),
        seed in any::<u64>(),
    ) {
        let islands = clusters(&islands, seed);
        let mut tree = tree_over(&base);
        let mut live = vec![false; islands.len()];
        for batch in batches {
            let (mut adds, mut removes) = (Vec::new(), Vec::new());
            for (add, k) in batch {
                let k = k % islands.len();
                if add && !live[k] {
                    adds.push((StaticId(k as u32), &islands[k]));
                    live[k] = true;
                } else if !add && live[k] && !adds.iter().any(|(id, _)| *id == StaticId(k as u32)) {
                    removes.push(StaticId(k as u32));
                    live[k] = false;
                }
            }
            let update = tree.apply(&removes, &adds).unwrap();
            prop_assert!(!update.rebuilt && !update.relinked);
            tree.check_invariants().map_err(TestCaseError::fail)?;
            let snap = tree.snapshot();
            let usable = |m: &TriangleMesh| (0..m.triangle_count()).any(|i| m.triangle_is_valid(i));
            let blocks = 1 + (0..islands.len()).filter(|&k| live[k] && usable(&islands[k])).count();
            prop_assert_eq!(snap.blocks(), blocks);
            let most = if blocks == 1 { 1 } else { (4 * blocks).max(64) };
            prop_assert!(snap.block_subtrees() >= blocks && snap.block_subtrees() <= most);
            let mut meshes: Vec<(StaticId, &TriangleMesh)> = vec![(StaticId(100), &base)];
            meshes.extend((0..islands.len()).filter(|&k| live[k]).map(|k| (StaticId(k as u32), &islands[k])));
            let tris: Vec<RefTri> = meshes.iter().flat_map(|(id, m)| ref_tris(HitObject::Static(*id), m)).collect();
            let all: Vec<&TriangleMesh> = std::iter::once(&base).chain(islands.iter()).collect();
            let rays = rays_for(&all, seed, 48, 12.0);
            check_scene(&snap, &rays, &tris, 1e-5)?;
            let fresh = snap.rebuilt(BuildParams::QUALITY);
            for ray in &rays {
                prop_assert_eq!(snap.intersect(ray).map(|h| h.t), fresh.intersect(ray).map(|h| h.t));
            }
        }
    }

    #[test]
    fn accel_static_updates_match_brute_force(
        base_a in soup(Vec3::ZERO, 10.0, 2.0, 20..200),
        base_b in soup(Vec3::new(0.0, -5.0, 0.0), 10.0, 2.0, 0..100),
        islands in prop::collection::vec((vec3(10.0), 1usize..30), 1..6),
        ops in prop::collection::vec((0u8..4, 0usize..8), 1..12),
        seed in any::<u64>(),
    ) {
        let islands: Vec<TriangleMesh> = islands
            .iter()
            .enumerate()
            .map(|(k, (c, n))| cluster(*c, *n, seed.wrapping_add(k as u64)))
            .collect();
        let mut accel = BvhAccel::new(Some(1));
        let ia = accel.add_static(&base_a).unwrap();
        let ib = accel.add_static(&base_b).unwrap();
        accel.commit().unwrap();
        let mut live: Vec<(StaticId, &TriangleMesh)> = vec![(ia, &base_a), (ib, &base_b)];
        let mut snapshots = Vec::new();
        for (op, k) in ops {
            match op {
                // Add an island (the insertion path, or a rebuild past the budget).
                0 | 1 => {
                    let m = &islands[k % islands.len()];
                    live.push((accel.add_static(m).unwrap(), m));
                }
                // Remove something (an island, or a base mesh, which rebuilds).
                2 => {
                    if !live.is_empty() {
                        let (id, _) = live.remove(k % live.len());
                        accel.remove_static(id).unwrap();
                    }
                }
                // Snapshot now, restore a previous one.
                _ => {
                    snapshots.push((accel.snapshot_static_scene().unwrap(), live.clone()));
                    let (snap, l) = snapshots[k % snapshots.len()].clone();
                    accel.restore_static_scene(&snap).unwrap();
                    live = l;
                }
            }
            accel.commit().unwrap();
            accel.static_tree().check_invariants().map_err(TestCaseError::fail)?;
            let tris: Vec<RefTri> = live.iter().flat_map(|(id, m)| ref_tris(HitObject::Static(*id), m)).collect();
            let all: Vec<&TriangleMesh> = [&base_a, &base_b].into_iter().chain(islands.iter()).collect();
            let rays = rays_for(&all, seed, 48, 12.0);
            check_scene(accel.query().unwrap(), &rays, &tris, 1e-5)?;
        }
    }

    /// Meshes declared permanent (an island that never wakes) are merged with the base into
    /// one block when the tree relinks; the others keep their own blocks and stay removable
    /// without a rebuild; hits stay those of brute force throughout, removals included.
    #[test]
    fn permanent_meshes_merge_at_relink_and_the_rest_stay_removable(
        base in soup(Vec3::ZERO, 10.0, 2.0, 50..200),
        islands in prop::collection::vec((vec3(10.0), 1usize..40, any::<bool>()), 2..8),
        seed in any::<u64>(),
    ) {
        let meshes: Vec<TriangleMesh> = islands
            .iter()
            .enumerate()
            .map(|(k, (c, n, _))| cluster(*c, *n, seed.wrapping_add(k as u64)))
            .collect();
        let mut tree = StaticBvh::new(BuildParams::QUALITY);
        // Every insert past the first build relinks.
        tree.rebuild_fraction = 0.0;
        tree.apply(&[], &[(StaticId(100), &base)]).unwrap();
        let mut live: Vec<(StaticId, &TriangleMesh)> = vec![(StaticId(100), &base)];
        for (k, m) in meshes.iter().enumerate() {
            let id = StaticId(k as u32);
            if islands[k].2 {
                tree.set_permanent(id);
            }
            let update = tree.apply(&[], &[(id, m)]).unwrap();
            prop_assert!(update.relinked);
            tree.check_invariants().map_err(TestCaseError::fail)?;
            live.push((id, m));
        }
        for (k, (_, n, permanent)) in islands.iter().enumerate() {
            // A merged mesh shares the rebuilt block (removing it rebuilds); the rest do not.
            prop_assert_eq!(tree.removal_rebuilds(StaticId(k as u32)), *permanent && *n > 0, "island {}", k);
        }
        let all: Vec<&TriangleMesh> = std::iter::once(&base).chain(meshes.iter()).collect();
        let rays = rays_for(&all, seed, 48, 12.0);
        for remove in [0u32, 1] {
            let tris: Vec<RefTri> = live.iter().flat_map(|(id, m)| ref_tris(HitObject::Static(*id), m)).collect();
            check_scene(&tree.snapshot(), &rays, &tris, 1e-5)?;
            prop_assert!(tree.remove(StaticId(remove)));
            live.retain(|(id, _)| *id != StaticId(remove));
            tree.check_invariants().map_err(TestCaseError::fail)?;
        }
        let tris: Vec<RefTri> = live.iter().flat_map(|(id, m)| ref_tris(HitObject::Static(*id), m)).collect();
        check_scene(&tree.snapshot(), &rays, &tris, 1e-5)?;
    }

    #[test]
    fn old_snapshot_is_unchanged(
        base in soup(Vec3::ZERO, 8.0, 2.0, 20..200),
        extra in prop::collection::vec(soup(Vec3::ZERO, 8.0, 1.0, 1..30), 1..6),
        seed in any::<u64>(),
    ) {
        let mut tree = StaticBvh::new(BuildParams::BALANCED);
        tree.rebuild_fraction = f32::INFINITY;
        tree.apply(&[], &[(StaticId(0), &base)]).unwrap();
        let old = tree.snapshot();
        let all: Vec<&TriangleMesh> = std::iter::once(&base).chain(extra.iter()).collect();
        let rays = rays_for(&all, seed, 64, 10.0);
        let before: Vec<_> = rays.iter().map(|r| old.intersect(r)).collect();
        for (i, m) in extra.iter().enumerate() {
            tree.insert(StaticId(i as u32 + 1), m).unwrap();
        }
        tree.check_invariants().map_err(TestCaseError::fail)?;
        let mid = tree.snapshot();
        tree.remove(StaticId(0));
        tree.remove(StaticId(1));
        tree.check_invariants().map_err(TestCaseError::fail)?;
        let after: Vec<_> = rays.iter().map(|r| old.intersect(r)).collect();
        prop_assert_eq!(&before, &after);
        prop_assert!(old.contains(StaticId(0)) && !tree.contains(StaticId(0)));
        prop_assert!(mid.contains(StaticId(1)));
        // The old snapshot shares nothing it does not own with the current tree after the
        // base was removed, but `mid` shares the inserted blocks with the current tree.
        let m = mid.memory();
        prop_assert!(m.unique_bytes <= m.total_bytes);
        tree.restore(old.clone());
        prop_assert_eq!(tree.triangles(), old.triangles());
        let restored: Vec<_> = rays.iter().map(|r| tree.snapshot().intersect(r)).collect();
        prop_assert_eq!(before, restored);
    }

    #[test]
    fn instancing_matches_baked_triangles(
        protos in prop::collection::vec(soup(Vec3::ZERO, 2.0, 1.0, 1..40), 1..4),
        placements in prop::collection::vec((0usize..4, vec3(1.0), -3.0f32..3.0, vec3(1.0), vec3(10.0)), 1..16),
        ground in soup(Vec3::new(0.0, -8.0, 0.0), 8.0, 2.0, 0..40),
        moved in prop::collection::vec((0usize..16, vec3(10.0)), 0..4),
        seed in any::<u64>(),
        shared_leaves in any::<bool>(),
    ) {
        // Top-level leaves of up to eight instances (`BuildParams::FAST`) as well as the
        // default one: the two-level traversal enters a leaf's instances one after the other.
        let mut accel = if shared_leaves {
            BvhAccel::with_params(BuildParams::QUALITY, BuildParams::FAST, Some(1))
        } else {
            BvhAccel::new(Some(1))
        };
        let pids: Vec<_> = protos.iter().map(|p| accel.add_prototype(p).unwrap()).collect();
        let gid = accel.add_static(&ground).unwrap();
        let xf = |axis: Vec3, angle: f32, scale: Vec3, t: Vec3| {
            let axis = if axis.length() > 1e-3 { axis.normalize() } else { Vec3::Y };
            let scale = Vec3::splat(0.3) + scale.abs() * 2.0;
            Affine3A::from_scale_rotation_translation(scale, Quat::from_axis_angle(axis, angle), t)
        };
        let mut placed = Vec::new();
        for (p, axis, angle, scale, t) in &placements {
            let p = p % protos.len();
            let m = xf(*axis, *angle, *scale, *t);
            placed.push((accel.add_instance(pids[p], m).unwrap(), p, m));
        }
        accel.commit().unwrap();
        let check = |accel: &BvhAccel, placed: &[(crate::accel::InstanceId, usize, Affine3A)]| -> Result<(), TestCaseError> {
            let baked: Vec<TriangleMesh> = placed.iter().map(|(_, p, m)| protos[*p].transformed(m)).collect();
            let mut tris = ref_tris(HitObject::Static(gid), &ground);
            for ((id, _, _), b) in placed.iter().zip(&baked) {
                tris.extend(ref_tris(HitObject::Instance(*id), b));
            }
            let all: Vec<&TriangleMesh> = baked.iter().chain(std::iter::once(&ground)).collect();
            let rays = rays_for(&all, seed, 96, 14.0);
            check_scene(accel.query().unwrap(), &rays, &tris, 2e-3)
        };
        check(&accel, &placed)?;
        // Move and remove some instances, then check again.
        for (k, t) in moved {
            let k = k % placed.len();
            placed[k].2 = Affine3A::from_translation(t) * placed[k].2;
            accel.set_instance_transform(placed[k].0, placed[k].2).unwrap();
        }
        let gone = placed.remove(0);
        accel.remove_instance(gone.0).unwrap();
        prop_assert!(matches!(accel.query(), Err(AccelError::NotCommitted)));
        let report = accel.commit().unwrap();
        prop_assert_eq!(report.instances, placed.len());
        check(&accel, &placed)?;
    }
}

proptest! {
    // One leaf test per case: cheap, so many cases.
    #![proptest_config(config(2000))]

    #[test]
    fn leaf_test_matches_one_triangle_test_on_every_path(
        tris in prop::collection::vec((vec3(4.0), vec3(4.0), vec3(4.0)), 1..=12),
        shared in any::<bool>(),
        on_grid in any::<bool>(),
        origin in vec3(8.0),
        target in vec3(3.0),
        aim_at in 0usize..12,
        t_max in prop_oneof![Just(f32::INFINITY), 0.1f32..2.0],
    ) {
        // On an integer grid, rays through vertices and edges give edge functions of exactly
        // zero in f32, which send lanes to the f64 fallback (only those that may be inside).
        let snap = |p: Vec3| if on_grid { p.round() } else { p };
        let mut tris: Vec<[Vec3; 3]> = tris.iter().map(|(a, b, c)| [snap(*a), snap(*b), snap(*c)]).collect();
        // The triangle aimed at, in any packet of the leaf (the wide paths test two at once).
        let k = aim_at % tris.len();
        if shared && k + 1 < tris.len() {
            // Two triangles sharing an edge, with the ray aimed at the edge's midpoint.
            tris[k + 1] = [tris[k][1], tris[k][0], tris[k + 1][2]];
        }
        let aim = if shared {
            (tris[k][0] + tris[k][1]) * 0.5
        } else if on_grid {
            tris[k][0]
        } else if aim_at % 2 == 0 {
            (tris[k][0] + tris[k][1] + tris[k][2]) / 3.0
        } else {
            target
        };
        let origin = snap(origin);
        prop_assume!(aim != origin);
        let mut ray = Ray::new(origin, aim - origin);
        ray.t_max = t_max;
        let mut expected: Option<(usize, f32, f32, f32)> = None;
        for (i, p) in tris.iter().enumerate() {
            if let Some((t, u, v)) = watertight_hit(&ray, p) {
                if expected.is_none_or(|e| t < e.1) {
                    expected = Some((i, t, u, v));
                }
            }
        }
        let bits = |h: Option<(usize, f32, f32, f32)>| h.map(|(i, t, u, v)| (i, t.to_bits(), u.to_bits(), v.to_bits()));
        for path in SimdPath::supported() {
            // Packets of four, tested one (portable) or two (AVX2, AVX-512) at a time: bit for
            // bit the same triangle, t and barycentrics.
            let (got, occluded) = watertight_hit_leaf(&ray, &tris, path);
            prop_assert_eq!(bits(got), bits(expected), "{:?}", path);
            prop_assert_eq!(occluded, expected.is_some(), "{:?}", path);
        }
    }
}

#[test]
fn degenerate_and_non_finite_input_never_panics() {
    let nan = f32::NAN;
    let inf = f32::INFINITY;
    let positions = vec![
        Vec3::ZERO,
        Vec3::X,
        Vec3::Y,
        Vec3::new(nan, 0.0, 0.0),
        Vec3::new(0.0, inf, 0.0),
        Vec3::new(2.0, 0.0, 0.0),
        Vec3::new(1e-30, 0.0, 0.0),
    ];
    let indices = vec![
        [0, 1, 2], // good
        [0, 0, 1], // repeated vertex
        [0, 1, 5], // collinear
        [0, 1, 3], // NaN
        [0, 4, 2], // infinite
        [0, 6, 2], // tiny but not zero area... or zero after rounding
        [2, 1, 0], // good (back side)
    ];
    let mesh = TriangleMesh::new(positions, indices);
    let valid = (0..mesh.triangle_count()).filter(|&i| mesh.triangle_is_valid(i)).count();
    let mut accel = create(Backend::Bvh, None).unwrap();
    let p = accel.add_prototype(&mesh).unwrap();
    let s = accel.add_static(&mesh).unwrap();
    let all_bad = TriangleMesh::new(vec![Vec3::splat(nan); 3], vec![[0, 1, 2]; 4]);
    let empty_proto = accel.add_prototype(&all_bad).unwrap();
    accel.add_static(&all_bad).unwrap();
    accel.add_static(&TriangleMesh::default()).unwrap();
    accel.add_instance(p, Affine3A::from_translation(Vec3::Z)).unwrap();
    accel.add_instance(empty_proto, Affine3A::IDENTITY).unwrap();
    for bad in [
        Affine3A::from_scale(Vec3::new(1.0, 0.0, 1.0)),
        Affine3A::from_translation(Vec3::splat(nan)),
        Affine3A::from_scale(Vec3::splat(inf)),
        Affine3A::from_scale(Vec3::splat(1e-30)),
        // Invertible, but the world bounds overflow.
        Affine3A::from_scale(Vec3::splat(1e12)) * Affine3A::from_translation(Vec3::splat(1e29)),
    ] {
        assert!(matches!(accel.add_instance(p, bad), Err(AccelError::InvalidTransform { .. })));
    }
    let huge = TriangleMesh::new(vec![Vec3::ZERO, Vec3::X * 1e31, Vec3::Y], vec![[0, 1, 2]]);
    accel.add_static(&huge).unwrap();
    let far = accel
        .add_prototype(&TriangleMesh::new(vec![Vec3::ZERO, Vec3::X * 1e29, Vec3::Y * 1e29], vec![[0, 1, 2]]))
        .unwrap();
    assert!(matches!(
        accel.add_instance(far, Affine3A::from_scale(Vec3::splat(1e12))),
        Err(AccelError::InvalidTransform { .. })
    ));
    let bad_index = TriangleMesh::new(vec![Vec3::ZERO], vec![[0, 1, 2]]);
    assert!(matches!(accel.add_static(&bad_index), Err(AccelError::Mesh(_))));
    let report = accel.commit().unwrap();
    // Both copies of the invalid ones, 4 + 4 all-NaN, and the huge one.
    assert_eq!(report.skipped_triangles, 2 * (mesh.triangle_count() - valid) + 8 + 1);
    // Both copies of the valid ones and the far prototype's triangle.
    assert_eq!(report.built_triangles, 2 * valid + 1);
    let q = accel.query().unwrap();
    let hit = q.intersect(&Ray::new(Vec3::new(0.2, 0.2, 5.0), -Vec3::Z)).unwrap();
    assert_eq!(hit.object, crate::accel::HitObject::Instance(crate::accel::InstanceId(0)));
    let hit = q.intersect(&Ray::new(Vec3::new(0.2, 0.2, 0.5), -Vec3::Z)).unwrap();
    assert_eq!(hit.object, crate::accel::HitObject::Static(s));
    for ray in [
        Ray::new(Vec3::splat(nan), Vec3::Z),
        Ray::new(Vec3::ZERO, Vec3::splat(nan)),
        Ray::new(Vec3::new(0.2, 0.2, 1.0), Vec3::ZERO),
        Ray::new(Vec3::splat(inf), -Vec3::ONE),
        Ray::segment(Vec3::new(0.2, 0.2, 5.0), -Vec3::Z, 3.0, 1.0),
        Ray::segment(Vec3::new(0.2, 0.2, 5.0), -Vec3::Z, nan, nan),
        Ray::new(Vec3::new(0.0, 0.0, 5.0), Vec3::new(0.0, 0.0, -1e-30)),
    ] {
        let _ = q.intersect(&ray);
        let _ = q.intersect_p(&ray);
    }
    accel.remove_static(s).unwrap();
    assert!(accel.remove_static(s).is_err());
    assert!(accel.remove_static(StaticId(999)).is_err());
    accel.commit().unwrap();
}

#[test]
fn queries_need_a_commit() {
    let mut accel = create(Backend::Bvh, None).unwrap();
    assert_eq!(accel.backend(), Backend::Bvh);
    assert!(accel.query().is_ok(), "an empty, unchanged scene can be queried");
    let ground = crate::geometry::primitives::ground_plane(5.0, 0.0, 4);
    let id = accel.add_static(&ground).unwrap();
    assert!(matches!(accel.query(), Err(AccelError::NotCommitted)));
    accel.commit().unwrap();
    let down = Ray::new(Vec3::new(0.1, 1.0, 0.3), Vec3::new(0.0, -2.0, 0.0));
    let hit = accel.query().unwrap().intersect(&down).unwrap();
    assert!((hit.t - 0.5).abs() < 1e-6);
    assert_eq!(hit.object, HitObject::Static(id));
    assert!((hit.ng.y.abs() - 1.0).abs() < 1e-6);
    // A later island is inserted, not rebuilt, and removed again.
    let island = crate::geometry::primitives::cuboid(Vec3::splat(0.1));
    let island = island.transformed(&Affine3A::from_translation(Vec3::new(0.1, 0.5, 0.3)));
    let iid = accel.add_static(&island).unwrap();
    accel.commit().unwrap();
    let hit = accel.query().unwrap().intersect(&down).unwrap();
    assert_eq!(hit.object, HitObject::Static(iid));
    accel.remove_static(iid).unwrap();
    accel.commit().unwrap();
    let hit = accel.query().unwrap().intersect(&down).unwrap();
    assert_eq!(hit.object, HitObject::Static(id));
    assert!("bvh".parse::<Backend>().unwrap() == Backend::Bvh);
}
