//! Criterion benchmarks of the pure-Rust BVH backend on a synthetic scene: a 125k-triangle
//! static environment (ground plus boxes and spheres) and 8,000 instances of a 4k-triangle
//! sphere. Measures build, trace (closest and any hit) and insertion of a 1% island against a
//! full static rebuild. Run with `cargo bench -p dormant-bench` (the BVH alone: the library without Embree).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BatchSize, Criterion, Throughput};
use dormant::accel::bvh::{BuildParams, BvhAccel, StaticBvh};
use dormant::accel::{Accelerator, StaticId};
use dormant::geometry::{primitives, Ray, TriangleMesh};
use glam::{Affine3A, Quat, Vec3};

struct Rng(u64);

impl Rng {
    fn f(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
}

fn merge(meshes: &[TriangleMesh]) -> TriangleMesh {
    let mut out = TriangleMesh::default();
    for m in meshes {
        let base = out.positions.len() as u32;
        out.positions.extend(&m.positions);
        out.indices.extend(m.indices.iter().map(|t| t.map(|i| i + base)));
    }
    out
}

/// About 125k triangles: a ground grid plus randomly placed boxes and spheres.
fn environment(rng: &mut Rng) -> TriangleMesh {
    let mut parts = vec![primitives::ground_plane(100.0, 0.0, 100)];
    while parts.iter().map(TriangleMesh::triangle_count).sum::<usize>() < 125_000 {
        let c = Vec3::new(rng.f() * 180.0 - 90.0, rng.f() * 10.0, rng.f() * 180.0 - 90.0);
        let m = if rng.f() < 0.5 {
            primitives::uv_sphere(1.0 + rng.f() * 3.0, 24, 12)
        } else {
            primitives::cuboid(Vec3::new(1.0 + rng.f() * 5.0, 1.0 + rng.f() * 8.0, 1.0 + rng.f() * 5.0))
        };
        parts.push(
            m.transformed(&Affine3A::from_rotation_translation(Quat::from_rotation_y(rng.f() * 6.0), c)),
        );
    }
    merge(&parts)
}

/// A pile of small boxes near `c`, `triangles` triangles in all (an island going to sleep).
fn island(rng: &mut Rng, triangles: usize) -> TriangleMesh {
    let c = Vec3::new(rng.f() * 160.0 - 80.0, 0.0, rng.f() * 160.0 - 80.0);
    let mut parts: Vec<TriangleMesh> = Vec::new();
    while parts.iter().map(TriangleMesh::triangle_count).sum::<usize>() < triangles {
        let o = c + Vec3::new(rng.f() * 6.0, rng.f() * 3.0, rng.f() * 6.0);
        let xf = Affine3A::from_rotation_translation(Quat::from_rotation_y(rng.f() * 6.0), o);
        parts.push(primitives::cuboid(Vec3::splat(0.2 + rng.f() * 0.3)).transformed(&xf));
    }
    merge(&parts)
}

fn camera_rays(side: usize) -> Vec<Ray> {
    let from = Vec3::new(-60.0, 30.0, -60.0);
    let f = (-from).normalize();
    let r = f.cross(Vec3::Y).normalize();
    let u = r.cross(f);
    (0..side * side)
        .map(|i| {
            let (x, y) = ((i % side) as f32 / side as f32 - 0.5, (i / side) as f32 / side as f32 - 0.5);
            Ray::new(from, f + 1.2 * (x * r + y * u))
        })
        .collect()
}

fn scene(rng: &mut Rng, env: &TriangleMesh) -> BvhAccel {
    let mut accel = BvhAccel::new(None);
    accel.add_static(env).unwrap();
    let duck = primitives::uv_sphere(1.0, 64, 32);
    let p = accel.add_prototype(&duck).unwrap();
    for _ in 0..8000 {
        let c = Vec3::new(rng.f() * 180.0 - 90.0, 2.0 + rng.f() * 20.0, rng.f() * 180.0 - 90.0);
        let axis = Vec3::new(rng.f(), rng.f(), rng.f() + 0.1).normalize();
        let xf = Affine3A::from_scale_rotation_translation(
            Vec3::splat(0.3 + rng.f() * 0.7),
            Quat::from_axis_angle(axis, rng.f() * 6.0),
            c,
        );
        accel.add_instance(p, xf).unwrap();
    }
    accel.commit().unwrap();
    accel
}

fn benches(c: &mut Criterion) {
    let mut rng = Rng(0x1234_5678_9abc_def1);
    let env = environment(&mut rng);

    let mut g = c.benchmark_group("build");
    g.sample_size(10);
    g.throughput(Throughput::Elements(env.triangle_count() as u64));
    for (name, p) in [("fast", BuildParams::FAST), ("quality", BuildParams::QUALITY)] {
        g.bench_function(format!("static_125k_{name}"), |b| {
            b.iter(|| {
                let mut t = StaticBvh::new(p);
                t.apply(&[], &[(StaticId(0), &env)]).unwrap();
                black_box(t.triangles())
            })
        });
    }
    g.finish();

    let accel = scene(&mut rng, &env);
    let q = accel.query().unwrap();
    let rays = camera_rays(256);
    let mut g = c.benchmark_group("trace");
    g.sample_size(10);
    g.throughput(Throughput::Elements(rays.len() as u64));
    g.bench_function("closest_primary", |b| {
        b.iter(|| rays.iter().filter(|r| q.intersect(r).is_some()).count())
    });
    g.bench_function("any_primary", |b| b.iter(|| rays.iter().filter(|r| q.intersect_p(r)).count()));
    g.finish();

    let mut base = StaticBvh::new(BuildParams::QUALITY);
    base.rebuild_fraction = f32::INFINITY;
    base.apply(&[], &[(StaticId(0), &env)]).unwrap();
    let snap = base.snapshot();
    let isl = island(&mut rng, env.triangle_count() / 100);
    let mut g = c.benchmark_group("update");
    g.sample_size(10);
    g.bench_function("insert_1pct_island", |b| {
        b.iter_batched(
            || snap.clone(),
            |s| {
                base.restore(s);
                base.insert(StaticId(1), &isl).unwrap();
            },
            BatchSize::SmallInput,
        )
    });
    // What a commit does (`apply`): the island's block, then the overlay re-braided over both.
    g.bench_function("commit_1pct_island", |b| {
        b.iter_batched(
            || snap.clone(),
            |s| {
                base.restore(s);
                base.apply(&[], &[(StaticId(1), &isl)]).unwrap();
            },
            BatchSize::SmallInput,
        )
    });
    g.bench_function("rebuild_with_island", |b| {
        b.iter(|| {
            let mut t = StaticBvh::new(BuildParams::QUALITY);
            t.apply(&[], &[(StaticId(0), &env), (StaticId(1), &isl)]).unwrap();
            black_box(t.triangles())
        })
    });
    g.finish();
}

criterion_group!(bvh, benches);
criterion_main!(bvh);
