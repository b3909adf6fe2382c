//! The binned-SAH builder builds the two halves of large ranges in parallel: the tree must not
//! depend on the thread count (the cross-check and the tests rely on reproducible trees), and
//! a tree built in parallel must still answer every ray as brute force does.

use super::common::*;
use crate::accel::bvh::{BuildParams, BvhAccel};
use crate::accel::{Accelerator, HitObject};
use crate::geometry::Aabb;
use glam::Vec3;
use proptest::prelude::*;

/// `f` in a rayon pool of `threads` threads.
fn in_pool<R: Send>(threads: usize, f: impl FnOnce() -> R + Send) -> R {
    rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap().install(f)
}

/// `n` boxes: scattered small ones, a dense cluster, and some that coincide exactly (ranges
/// whose centroids all coincide are split by count, not by SAH).
fn boxes(n: usize, seed: u64) -> Vec<Aabb> {
    let mut next = unit_rng(seed);
    (0..n)
        .map(|i| {
            let c = match i % 10 {
                0..=5 => Vec3::new(next(), next(), next()) * 1000.0,
                6..=8 => Vec3::new(next(), next(), next()) * 5.0,
                _ => Vec3::splat(3.0),
            };
            let e = Vec3::new(next(), next(), next()) * 4.0 + 0.01;
            Aabb::from_points([c, c + e])
        })
        .collect()
}

fn build_at(threads: usize, bounds: &[Aabb], params: BuildParams) -> BuiltTree {
    in_pool(threads, || build_tree(bounds, params))
}

#[test]
fn build_is_the_same_at_one_and_two_threads() {
    let bounds = boxes(60_000, 11);
    for params in [BuildParams::FAST, BuildParams::TOP_LEVEL, BuildParams::BALANCED, BuildParams::QUALITY] {
        let one = build_at(1, &bounds, params);
        check_built_tree(&one, &bounds).unwrap();
        for _ in 0..2 {
            assert!(build_at(2, &bounds, params) == one, "{params:?}: two threads built another tree");
        }
    }
}

fn config(cases: u32) -> ProptestConfig {
    ProptestConfig { cases, failure_persistence: None, ..ProptestConfig::default() }
}

/// Parameters that build ranges of 64 primitives and more in parallel (the smallest
/// threshold), so small inputs take the parallel path too.
fn eager(params: BuildParams) -> BuildParams {
    BuildParams { parallel_threshold: 64, ..params }
}

proptest! {
    #![proptest_config(config(24))]

    #[test]
    fn parallel_build_is_valid_and_thread_independent(n in 1usize..3000, seed in any::<u64>(), preset in 0usize..4) {
        let params = eager([BuildParams::FAST, BuildParams::TOP_LEVEL, BuildParams::BALANCED, BuildParams::QUALITY][preset]);
        let bounds = boxes(n, seed);
        let one = build_at(1, &bounds, params);
        check_built_tree(&one, &bounds).map_err(TestCaseError::fail)?;
        prop_assert!(build_at(2, &bounds, params) == one);
    }

    #[test]
    fn parallel_build_matches_brute_force(
        mesh in soup(Vec3::ZERO, 10.0, 2.0, 200..1500),
        seed in any::<u64>(),
    ) {
        let params = eager(BuildParams::QUALITY);
        let mut hits = Vec::new();
        for threads in [1, 2] {
            let mut accel = BvhAccel::with_params(params, eager(BuildParams::TOP_LEVEL), Some(threads));
            let id = accel.add_static(&mesh).unwrap();
            accel.commit().unwrap();
            let q = accel.query().unwrap();
            let tris = ref_tris(HitObject::Static(id), &mesh);
            let rays = rays_for(&[&mesh], seed, 64, 15.0);
            for ray in &rays {
                check_hit(ray, q.intersect(ray), &tris, 1e-5).map_err(TestCaseError::fail)?;
                check_any(ray, q.intersect_p(ray), &tris).map_err(TestCaseError::fail)?;
            }
            hits.push(rays.iter().map(|r| q.intersect(r)).collect::<Vec<_>>());
        }
        prop_assert_eq!(&hits[0], &hits[1]);
    }
}
