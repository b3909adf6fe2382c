//! The scene manager's scenes against all-instanced references, on both backends:
//! - simulated frames: integrated scenes give the same hits (same body and prototype triangle)
//!   as the same frame with every body an instance;
//! - random sleep/wake sequences (baked: 3 cases x 2 strategies x 2,000 events = 12,000 events
//!   per backend; resting: 3 x 2,000): every scene the manager serves, including static scenes
//!   restored from the geometry cache, gives the same hits as a from-scratch build of the same
//!   island set.

use crate::common;

use common::scenes;
use dormant::accel::{self, load_scene, Backend, LoadedObjectMap, ObjectMap, SceneQuery};
use dormant::geometry::{primitives, Ray};
use dormant::physics::trajectory::ReplayFrame;
use dormant::physics::{
    BodyId, BodyInfo, BodyKind, BodyPose, BodyState, IslandEvent, IslandId, SimulateOptions,
};
use dormant::residency::{
    CacheBudget, FrameStats, IntegrationForm, IntegrationPolicy, IntegrationSettings, ManagerOptions,
    ReactivationPath, ReactivationStrategy, SceneManager, TraceKind,
};
use dormant::scene::{Body, Camera, Material, Prototype, SceneDescription, Sky, StaticMesh, Sun};
use dormant::sequence::{
    FrameRange, FrameRenderer, ReuseMode, SeedMode, Sequence, SequenceError, SequenceSource,
};
use dormant_lab::crosscheck::{camera_rays, compare, surface_rays, MappedQuery, VerifyReport};
use glam::{Quat, Vec3};
use proptest::prelude::*;

fn backends() -> Vec<Backend> {
    Backend::compiled().to_vec()
}

/// Every compiled backend with each of `policies` in every integration form.
fn configurations(policies: &[IntegrationPolicy]) -> Vec<(Backend, IntegrationPolicy, IntegrationForm)> {
    let mut out = Vec::new();
    for backend in backends() {
        for &policy in policies {
            for form in IntegrationForm::ALL {
                out.push((backend, policy, form));
            }
        }
    }
    out
}

/// Compares the manager's committed scene with `reference` (every body an instance).
/// `body_ids[i]` is the body of `reference.bodies[i]`.
fn check_against(
    backend: Backend,
    manager: &SceneManager,
    reference: &SceneDescription,
    body_ids: &[BodyId],
    rays: &[Ray],
) -> VerifyReport {
    let mut fresh = accel::create(backend, Some(2)).unwrap();
    let loaded = load_scene(reference, fresh.as_mut()).unwrap();
    fresh.commit().unwrap();
    let map = LoadedObjectMap::with_body_ids(reference, &loaded, body_ids);
    compare(
        reference,
        MappedQuery { query: fresh.query().unwrap(), objects: &map },
        MappedQuery { query: manager.query().unwrap(), objects: manager },
        rays,
    )
}

fn assert_agrees(report: &VerifyReport, what: &str) {
    assert_eq!(report.mismatches, 0, "{what}: {:#?}", report.examples);
    assert!(report.ties * 100 <= report.rays, "{what}: {} ties in {} rays", report.ties, report.rays);
}

/// `scenes/tiny.toml`, simulated.
fn tiny() -> Sequence {
    let source = SequenceSource::scene(scenes::load("tiny"), SimulateOptions::default(), None);
    Sequence::load(source, &mut |_| {}).unwrap()
}

#[test]
fn integrated_frames_hit_like_all_instanced_frames() {
    let sequence = tiny();
    let every_fourth = sequence.select(None, Some(4)).unwrap();
    for (backend, policy, form) in configurations(&[IntegrationPolicy::Always, IntegrationPolicy::Auto]) {
        {
            let settings = IntegrationSettings { policy, form, ..IntegrationSettings::default() };
            let options = sequence.manager_options(&every_fourth, settings);
            let mut manager = sequence.manager(backend, Some(2), options).unwrap();
            let (mut compared, mut integrated_seen, mut reactivated) = (0, 0, 0);
            let mut check = |f: &ReplayFrame<'_>, managers: &mut [SceneManager]| {
                let manager = &mut managers[0];
                let stats = manager.prepare(f).unwrap().clone();
                manager.record_trace(0.0, 0, TraceKind::Typical);
                reactivated += stats.islands_reactivated;
                if f.index % 40 == 0 {
                    let reference = sequence.describe_frame(f);
                    let mut rays = camera_rays(&reference, 48, 32);
                    rays.extend(surface_rays(&reference, 1500, u64::from(f.index)));
                    let present: Vec<BodyId> = f.present_bodies().collect();
                    let report = check_against(backend, manager, &reference, &present, &rays);
                    assert_agrees(&report, &format!("{backend} {policy} {form} frame {}", f.index));
                    compared += 1;
                    integrated_seen = integrated_seen.max(stats.integrated_islands);
                }
                Ok::<(), SequenceError>(())
            };
            sequence.replay(&every_fourth, std::slice::from_mut(&mut manager), &mut check).unwrap();
            assert!(compared >= 10);
            // (`auto` may rightly decline everything in a scene this small.)
            if policy == IntegrationPolicy::Always {
                assert!(integrated_seen > 0, "{backend}: nothing was integrated");
                assert!(reactivated > 0, "{backend}: the sweeper and the explosion wake integrated islands");
            }
        }
    }
}

/// The update stage visits only the bodies the replay says changed since the frame prepared
/// before, with those integration or reactivation placed anew and the blurred ones. A manager
/// driven by `Sequence::replay` (which keeps those changes) must serve the same hits, at
/// every time of the shutter, as one whose frames come from a replay that never restarts
/// its changes, so that it visits every body.
#[test]
fn visiting_only_changed_bodies_gives_the_scene_a_visit_of_every_body_gives() {
    let sequence = tiny();
    let every_third = sequence.select(None, Some(3)).unwrap();
    for (backend, policy, form) in configurations(&[IntegrationPolicy::Always, IntegrationPolicy::Never]) {
        let what = format!("{backend} {policy} {form}");
        let manager = || {
            let settings = IntegrationSettings { policy, form, ..IntegrationSettings::default() };
            let options = ManagerOptions { shutter: 0.5, ..sequence.manager_options(&every_third, settings) };
            sequence.manager(backend, Some(2), options).unwrap()
        };
        let (mut visiting_all, mut replay, mut replayed) = (manager(), sequence.trajectory.replay(), 0);
        let mut changed = manager();
        let mut check = |f: &ReplayFrame<'_>, managers: &mut [SceneManager]| {
            let (a, b) = (&mut managers[0], &mut visiting_all);
            while replayed < f.index {
                b.observe(replay.next_frame().unwrap().events);
                replayed += 1;
            }
            let g = replay.next_frame().unwrap();
            b.observe(g.events);
            replayed += 1;
            let counts =
                |s: &FrameStats| (s.instances, s.integrated_islands, s.resting_bodies, s.islands_reactivated);
            let (sa, sb) = (counts(a.prepare(f).unwrap()), counts(b.prepare(&g).unwrap()));
            assert_eq!(sa, sb, "{what} frame {}", f.index);
            a.record_trace(0.0, 0, TraceKind::Typical);
            b.record_trace(0.0, 0, TraceKind::Typical);
            let reference = sequence.describe_frame(f);
            let mut rays = camera_rays(&reference, 24, 16);
            rays.extend(surface_rays(&reference, 300, u64::from(f.index)));
            for (i, ray) in rays.iter_mut().enumerate() {
                ray.time = (i % 5) as f32 / 4.0;
            }
            // The same accelerator calls in the same order build the same scenes: equal hits,
            // bit for bit, on the same bodies.
            let (qa, qb) = (a.query().unwrap(), b.query().unwrap());
            for ray in &rays {
                let answer = |q: &dyn SceneQuery, m: &SceneManager| {
                    let hit = q.intersect(ray);
                    (
                        hit,
                        hit.and_then(|h| m.resolve(h.object, h.prim)).and_then(|r| r.body),
                        q.intersect_p(ray),
                    )
                };
                assert_eq!(answer(qa, a), answer(qb, b), "{what} frame {}: {ray:?}", f.index);
            }
            Ok::<(), SequenceError>(())
        };
        sequence.replay(&every_third, std::slice::from_mut(&mut changed), &mut check).unwrap();
    }
}

/// A synthetic world for the property test: bodies on a grid of cells (so they never touch),
/// islands formed from random awake bodies, woken at random.
struct World {
    cells: Vec<Vec3>,
    prototypes: Vec<u32>,
    poses: Vec<BodyPose>,
    states: Vec<BodyState>,
    sleeping: Vec<(IslandId, Vec<BodyId>)>,
    next_island: u64,
}

impl World {
    fn new(bodies: usize, rng: &mut u64) -> Self {
        let side = (bodies as f32).sqrt().ceil() as usize;
        let cells =
            (0..bodies).map(|i| Vec3::new((i % side) as f32 * 3.0, 1.0, (i / side) as f32 * 3.0)).collect();
        let prototypes = (0..bodies).map(|_| (next(rng) % 2) as u32).collect();
        let mut w = World {
            cells,
            prototypes,
            poses: Vec::new(),
            states: vec![BodyState::Awake; bodies],
            sleeping: Vec::new(),
            next_island: 1,
        };
        w.poses = (0..bodies).map(|i| w.jitter(i, rng)).collect();
        w
    }

    fn jitter(&self, body: usize, rng: &mut u64) -> BodyPose {
        let r = |rng: &mut u64| (next(rng) % 1000) as f32 / 1000.0 - 0.5;
        BodyPose {
            translation: self.cells[body] + Vec3::new(r(rng), r(rng), r(rng)) * 0.8,
            rotation: Quat::from_rotation_y(r(rng) * 6.0) * Quat::from_rotation_x(r(rng)),
        }
    }

    /// One frame: a few islands sleep or wake, awake bodies move. Returns the events.
    fn step(&mut self, rng: &mut u64) -> Vec<IslandEvent> {
        let mut events = Vec::new();
        for _ in 0..1 + next(rng) % 3 {
            let wake = !self.sleeping.is_empty() && next(rng) % 2 == 0;
            if wake {
                let (island, bodies) = self.sleeping.swap_remove((next(rng) as usize) % self.sleeping.len());
                for b in bodies {
                    self.states[b.0 as usize] = BodyState::Awake;
                }
                events.push(IslandEvent::Woke { island });
            } else {
                let awake: Vec<usize> =
                    (0..self.states.len()).filter(|&b| self.states[b] == BodyState::Awake).collect();
                if awake.is_empty() {
                    continue;
                }
                let n = 1 + (next(rng) as usize) % 6;
                let start = (next(rng) as usize) % awake.len();
                let mut bodies: Vec<BodyId> = (0..n.min(awake.len()))
                    .map(|k| BodyId(awake[(start + k) % awake.len()] as u32))
                    .collect();
                bodies.sort();
                for b in &bodies {
                    self.states[b.0 as usize] = BodyState::Asleep;
                }
                let island = IslandId(self.next_island);
                self.next_island += 1;
                let poses = bodies.iter().map(|b| self.poses[b.0 as usize]).collect();
                events.push(IslandEvent::Slept { island, bodies: bodies.clone(), poses });
                self.sleeping.push((island, bodies));
            }
        }
        for b in 0..self.states.len() {
            if self.states[b] == BodyState::Awake && next(rng) % 4 == 0 {
                self.poses[b] = self.jitter(b, rng);
            }
        }
        events
    }

    fn description(&self, template: &SceneDescription) -> SceneDescription {
        SceneDescription {
            bodies: (0..self.poses.len())
                .map(|b| Body { prototype: self.prototypes[b], transform: self.poses[b].to_affine() })
                .collect(),
            ..template.clone()
        }
    }
}

fn next(state: &mut u64) -> u64 {
    // SplitMix64.
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

fn template() -> SceneDescription {
    SceneDescription {
        name: "sleep-wake".into(),
        materials: vec![Material::diffuse(Vec3::splat(0.5))],
        statics: vec![StaticMesh { mesh: primitives::ground_plane(60.0, 0.0, 4), material: 0 }],
        prototypes: vec![
            Prototype { name: "box".into(), mesh: primitives::cuboid(Vec3::new(0.5, 0.3, 0.4)), material: 0 },
            Prototype { name: "ball".into(), mesh: primitives::uv_sphere(0.45, 12, 8), material: 0 },
        ],
        bodies: Vec::new(),
        camera: Camera::pinhole(Vec3::new(20.0, 25.0, -15.0), Vec3::new(20.0, 0.0, 20.0), Vec3::Y, 60.0),
        sun: Sun { direction: Vec3::Y, irradiance: Vec3::ONE, angular_radius_deg: 1.0 },
        sky: Sky::DAYLIGHT,
        lights: Vec::new(),
        textures: Vec::new(),
    }
}

/// Runs `events` sleep/wake events through a manager and checks its scene against a fresh
/// build every `check_every` frames and after every cache-served reactivation. Returns
/// (events, checks, cache-served reactivations).
fn run_sleep_wake(
    backend: Backend,
    form: IntegrationForm,
    reactivation: ReactivationStrategy,
    seed: u64,
    events: usize,
    check_every: u32,
) -> (usize, u32, u32) {
    let mut rng = seed;
    let bodies = 400;
    let mut world = World::new(bodies, &mut rng);
    let template = template();
    let infos: Vec<BodyInfo> = world
        .prototypes
        .iter()
        .map(|&p| BodyInfo { prototype: p, kind: BodyKind::Dynamic, spawn_frame: 0 })
        .collect();
    let options = ManagerOptions {
        policy: IntegrationPolicy::Always,
        cache: true,
        reactivation,
        // Few entries, so lookups see evictions, partial hits and misses.
        cache_budget: CacheBudget { bytes: 64 << 20, entries: 12 },
        form,
        ..ManagerOptions::default()
    };
    let mut manager =
        SceneManager::new(accel::create(backend, Some(2)).unwrap(), &template, &infos, options).unwrap();
    let (mut seen, mut checks, mut served) = (0, 0, 0);
    let mut frame = 0u32;
    while seen < events {
        let evs = world.step(&mut rng);
        seen += evs.len();
        manager.observe(&evs);
        let replayed = ReplayFrame::still(frame, &world.states, &world.poses, &evs);
        let stats = manager.prepare(&replayed).unwrap().clone();
        manager.record_trace(0.0, 0, TraceKind::Typical);
        let from_cache = matches!(stats.reactivation_path, Some(ReactivationPath::Cache(_)));
        served += u32::from(from_cache);
        if from_cache || frame % check_every == 0 {
            let reference = world.description(&template);
            let mut rays = surface_rays(&reference, 600, u64::from(frame) ^ seed);
            rays.extend(camera_rays(&reference, 24, 16));
            let ids: Vec<BodyId> = (0..bodies as u32).map(BodyId).collect();
            let report = check_against(backend, &manager, &reference, &ids, &rays);
            assert_agrees(&report, &format!("{backend} seed {seed} frame {frame}"));
            checks += 1;
        }
        frame += 1;
    }
    (seen, checks, served)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 3, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn cache_served_scenes_equal_fresh_builds(seed in any::<u64>()) {
        for backend in backends() {
            // Cheapest: removals (islands keep their own blocks); cache first: restores.
            for strategy in [ReactivationStrategy::Cheapest, ReactivationStrategy::CacheFirst] {
                let (events, checks, served) =
                    run_sleep_wake(backend, IntegrationForm::Baked, strategy, seed, 2000, 25);
                prop_assert!(events >= 2000 && checks > 30, "{events} events, {checks} checks");
                if backend == Backend::Bvh && strategy == ReactivationStrategy::CacheFirst {
                    prop_assert!(served > 100, "the BVH serves reactivations from the cache: {served}");
                }
            }
        }
    }

    #[test]
    fn resting_scenes_equal_fresh_builds(seed in any::<u64>()) {
        for backend in backends() {
            let (events, checks, _) =
                run_sleep_wake(backend, IntegrationForm::Resting, ReactivationStrategy::Cheapest, seed, 2000, 25);
            prop_assert!(events >= 2000 && checks > 30, "{events} events, {checks} checks");
        }
    }
}

#[test]
fn never_always_and_auto_render_the_same_images() {
    use dormant::render::{Film, PathTracer};
    let sequence = tiny();
    let frames = sequence.select(Some(FrameRange { start: 0, end: 480 }), Some(40)).unwrap();
    let integrator = PathTracer::default();
    let renderer = FrameRenderer {
        seed: SeedMode::PerFrame,
        reuse: ReuseMode::Off,
        ..FrameRenderer::new(&integrator, 64, 36, 4)
    };
    for backend in backends() {
        let mut films: Vec<Vec<Film>> = Vec::new();
        let mut integrated = 0;
        let runs =
            configurations(&[IntegrationPolicy::Never, IntegrationPolicy::Always, IntegrationPolicy::Auto]);
        for (_, policy, form) in runs.into_iter().filter(|(b, ..)| *b == backend) {
            let settings = IntegrationSettings { policy, form, ..IntegrationSettings::default() };
            let mut manager =
                sequence.manager(backend, Some(2), sequence.manager_options(&frames, settings)).unwrap();
            let mut images = Vec::new();
            sequence
                .render(&frames, &mut manager, &renderer, &[], &mut |f, stats, _| {
                    integrated = integrated.max(stats.integrated_islands);
                    images.push(f.film.clone());
                    Ok::<(), SequenceError>(())
                })
                .unwrap();
            films.push(images);
        }
        assert!(integrated > 0);
        // Integrated and instanced bodies are hit alike up to float tolerance, so the images
        // may differ only where a ray's hit point moved by rounding: RMSE of linear radiance
        // under 1e-5 per frame (measured: about 2e-8).
        let mut worst = 0.0f64;
        for other in &films[1..] {
            for (i, (a, b)) in films[0].iter().zip(other).enumerate() {
                let se: f64 = a
                    .pixels
                    .iter()
                    .zip(&b.pixels)
                    .map(|(p, q)| f64::from((*p - *q).length_squared()) / 3.0)
                    .sum();
                let rmse = (se / a.pixels.len() as f64).sqrt();
                assert!(rmse < 1e-5, "{backend} frame {}: RMSE {rmse}", i as u32 * 40);
                worst = worst.max(rmse);
            }
        }
        eprintln!("{backend}: largest RMSE between policies {worst:.2e}");
    }
}

#[test]
fn baked_debug_view_shows_integrated_bodies_in_orange() {
    use dormant::render::{Aov, AovIntegrator};
    let sequence = tiny();
    let frames = sequence.select(Some(FrameRange { start: 0, end: 480 }), Some(60)).unwrap();
    let integrator = AovIntegrator(Aov::Baked);
    let renderer = FrameRenderer {
        seed: SeedMode::PerFrame,
        reuse: ReuseMode::Off,
        ..FrameRenderer::new(&integrator, 96, 54, 1)
    };
    let orange = |p: glam::Vec3| p.x > 1.5 * p.z && p.x > 0.1;
    for (policy, expect_baked) in [(IntegrationPolicy::Never, false), (IntegrationPolicy::Always, true)] {
        let options = ManagerOptions { policy, ..ManagerOptions::default() };
        let mut manager = sequence.manager(Backend::Bvh, Some(2), options).unwrap();
        let mut baked_pixels = 0;
        sequence
            .render(&frames, &mut manager, &renderer, &[], &mut |f, _, _| {
                baked_pixels += f.film.pixels.iter().filter(|p| orange(**p)).count();
                Ok::<(), SequenceError>(())
            })
            .unwrap();
        assert_eq!(baked_pixels > 0, expect_baked, "{policy}: {baked_pixels} orange pixels");
    }
}
