//! `dormant bench accel`: builders, tracers and incremental insertion of Embree and the BVH on
//! one scene with the same rays.
//!
//! - **build**: the instanced scene (static environment, one prototype, N instances), Embree
//!   at LOW/MEDIUM/HIGH (all its scenes at that quality), at MEDIUM with Embree's robust mode
//!   (`medium-robust`: the watertight guarantees the BVH always gives) and the BVH; best of
//!   three builds (the first in a fresh process, the others reusing its freed memory), since
//!   Embree's single builds vary widely from one run to the next:
//!   docs/lab/accelerators.md#2026-11-22-bench-accel-on-the-monastery-with-8000-ducks-builds-traces-insertion;
//! - **trace**: primary rays (one per pixel) and diffuse-bounce rays (cosine-distributed from
//!   the primary hits, generated once through Embree), closest hit, rayon over all cores; best
//!   of three runs;
//! - **insert**: every body baked into world space in islands of 1% of the bodies; a static
//!   scene holding all but one island gets the last one added and committed (incremental; the
//!   median of several inserts, the island removed between them), against a from-scratch build
//!   of the same final scene (adding every mesh and committing); for the BVH also the SAH cost
//!   of both trees;
//! - **forms** ([`resting`]): the same rays through the integration forms, the last island
//!   awake and the rest instanced, resting or baked; the resting scene's rebuild and the
//!   per-frame commit.

mod resting;

use resting::RestingTiming;

use std::ops::Range;

use glam::Vec2;
use rayon::prelude::*;
use serde::Serialize;

use super::timed;
use crate::crosscheck::camera_rays;
use dormant::accel::{self, AccelError, Accelerator, Backend, SceneQuery, StaticId};
use dormant::geometry::{Ray, TriangleMesh};
use dormant::render::sample_cosine;
use dormant::rng::SplitMix64;
use dormant::scene::SceneDescription;

pub struct AccelBenchOptions {
    pub width: u32,
    pub height: u32,
    /// Fraction of the bodies in the inserted island.
    pub island_fraction: f64,
    /// Repetitions of each build and trace measurement (the best is kept).
    pub runs: u32,
    pub threads: Option<usize>,
    /// Only the builds: no rays, traces, inserts or forms (a build's instruction count).
    pub builds_only: bool,
    /// Only this backend's variants (default: every compiled one).
    pub backend: Option<Backend>,
}

impl Default for AccelBenchOptions {
    fn default() -> Self {
        Self {
            width: 1280,
            height: 720,
            island_fraction: 0.01,
            runs: 3,
            threads: None,
            builds_only: false,
            backend: None,
        }
    }
}

/// Makes an empty accelerator of one backend and configuration.
type AccelFactory = dyn Fn() -> Result<Box<dyn Accelerator>, AccelError>;

#[derive(Clone, Debug, Serialize)]
pub struct BuildTiming {
    pub backend: Backend,
    /// Embree build quality, or `"sah"` for the BVH's binned SAH builder.
    pub quality: String,
    /// The best of `runs_ms`.
    pub ms: f64,
    /// Every build, in order (the first in a process that had not built this scene yet).
    pub runs_ms: Vec<f64>,
    /// The static tree's SAH cost (the BVH's; `None` for Embree).
    pub static_sah_cost: Option<f32>,
}

#[derive(Clone, Debug, Serialize)]
pub struct TraceTiming {
    pub backend: Backend,
    pub quality: String,
    pub primary_ms: f64,
    pub bounce_ms: f64,
    pub primary_mrays_per_s: f64,
    pub bounce_mrays_per_s: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct InsertTiming {
    pub backend: Backend,
    /// Triangles in the final static scene.
    pub triangles: usize,
    /// Triangles in the inserted island.
    pub island_triangles: usize,
    pub rebuild_ms: f64,
    /// Median of `insert_runs_ms`.
    pub insert_ms: f64,
    /// Each insert: the first, then the island removed again and re-inserted.
    pub insert_runs_ms: Vec<f64>,
    /// After the first insert.
    pub sah_after_insert: Option<f32>,
    pub sah_rebuild: Option<f32>,
}

#[derive(Clone, Debug, Serialize)]
pub struct AccelRatios {
    /// BVH trace time over Embree's (MEDIUM), primary and bounce rays together.
    pub bvh_over_embree_trace: f64,
    /// The same against Embree at HIGH.
    pub bvh_over_embree_high_trace: f64,
    /// The same against Embree at MEDIUM in robust mode (conservative box tests, watertight
    /// triangles: the BVH's own guarantees).
    pub bvh_over_embree_robust_trace: f64,
    /// BVH build time of the instanced scene over Embree's (MEDIUM).
    pub bvh_over_embree_build: f64,
    /// The same against Embree at MEDIUM in robust mode.
    pub bvh_over_embree_robust_build: f64,
    pub bvh_rebuild_over_insert: f64,
    pub bvh_insert_sah_over_rebuild: f64,
    pub embree_rebuild_over_insert: f64,
    /// Trace penalty of the resting form (99% resting, 1% awake) over every body instanced,
    /// primary and bounce rays.
    pub embree_resting_trace_over_instanced: f64,
    pub bvh_resting_trace_over_instanced: f64,
    /// The same for the baked form (99% baked, the same 1% awake).
    pub embree_baked_trace_over_instanced: f64,
    pub bvh_baked_trace_over_instanced: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct AccelBenchReport {
    pub scene: String,
    pub static_triangles: usize,
    pub instances: usize,
    pub instanced_triangles: usize,
    pub primary_rays: usize,
    pub bounce_rays: usize,
    pub threads: usize,
    pub build: Vec<BuildTiming>,
    pub trace: Vec<TraceTiming>,
    pub insert: Vec<InsertTiming>,
    pub forms: Vec<RestingTiming>,
    pub ratios: AccelRatios,
}

/// A backend, its build configuration's name, and how to make one.
type Variant = (Backend, String, Box<AccelFactory>);

/// Embree at each build quality, then at MEDIUM in robust mode; none when Embree is not
/// compiled in.
fn embree_variants(threads: Option<usize>) -> Vec<Variant> {
    #[cfg(feature = "embree")]
    {
        use dormant::accel::embree::EmbreeBuildParams;
        use dormant_embree::BuildQuality;
        let at = |name: String, params: EmbreeBuildParams| -> Variant {
            (Backend::Embree, name, Box::new(move || super::embree_with(params, threads)))
        };
        let robust = EmbreeBuildParams { robust: true, ..EmbreeBuildParams::uniform(BuildQuality::Medium) };
        BuildQuality::ALL
            .into_iter()
            .map(|q| at(format!("{q:?}").to_lowercase(), EmbreeBuildParams::uniform(q)))
            .chain([at("medium-robust".into(), robust)])
            .collect()
    }
    #[cfg(not(feature = "embree"))]
    {
        let _ = threads;
        Vec::new()
    }
}

/// Traces `rays` (closest hit) over rayon; returns ms and a checksum that keeps the work alive.
pub(crate) fn trace(query: &dyn SceneQuery, rays: &[Ray]) -> (f64, f64) {
    let (sum, ms) =
        timed(|| rays.par_iter().map(|r| query.intersect(r).map_or(0.0, |h| h.t as f64)).sum::<f64>());
    (ms, sum)
}

/// Each query's best primary and bounce trace milliseconds over nine rounds, round robin, so
/// that machine load falls on every query alike.
pub(crate) fn best_traces(queries: &[&dyn SceneQuery], primary: &[Ray], bounce: &[Ray]) -> Vec<(f64, f64)> {
    let mut best = vec![(f64::INFINITY, f64::INFINITY); queries.len()];
    for _ in 0..9 {
        for (b, q) in best.iter_mut().zip(queries) {
            b.0 = b.0.min(trace(*q, primary).0);
            b.1 = b.1.min(trace(*q, bounce).0);
        }
    }
    best
}

/// Builds `desc` `runs` times (at least once), each from an empty accelerator, the last kept;
/// returns it and every build's milliseconds. Prototypes are built as they are added, so a
/// timing covers loading and commit. The previous build is dropped before the next starts.
fn best_build(
    desc: &SceneDescription,
    make: &AccelFactory,
    runs: u32,
) -> Result<(Box<dyn Accelerator>, Vec<f64>), AccelError> {
    let mut runs_ms = Vec::new();
    let mut build = || -> Result<Box<dyn Accelerator>, AccelError> {
        let (a, ms) = timed(|| -> Result<_, AccelError> {
            let mut a = make()?;
            accel::load_scene(desc, a.as_mut())?;
            a.commit()?;
            Ok(a)
        });
        runs_ms.push(ms);
        a
    };
    let mut built = build()?;
    for _ in 1..runs.max(1) {
        drop(built);
        built = build()?;
    }
    Ok((built, runs_ms))
}

fn best_trace(query: &dyn SceneQuery, rays: &[Ray], runs: u32) -> f64 {
    (0..runs.max(1)).map(|_| trace(query, rays).0).fold(f64::INFINITY, f64::min)
}

/// Cosine-distributed bounce rays from the primary hits.
pub(crate) fn bounce_rays(query: &dyn SceneQuery, primary: &[Ray]) -> Vec<Ray> {
    let mut rng = SplitMix64::new(7);
    let hits: Vec<_> =
        primary.par_iter().map(|r| query.intersect(r).map(|h| (r.at(h.t), h.ng, r.dir))).collect();
    hits.into_iter()
        .flatten()
        .map(|(p, ng, dir)| {
            let n = if ng.dot(dir) > 0.0 { -ng } else { ng };
            let d = sample_cosine(n, Vec2::new(rng.unit(), rng.unit()));
            Ray::spawn(p, n, d)
        })
        .collect()
}

/// The bodies baked into world space, grouped in islands of `island_size` bodies.
fn baked_islands(desc: &SceneDescription, island_size: usize) -> Vec<TriangleMesh> {
    desc.bodies
        .chunks(island_size.max(1))
        .map(|chunk| {
            let mut island = TriangleMesh::default();
            for b in chunk {
                let m = desc.prototypes[b.prototype as usize].mesh.transformed(&b.transform);
                let base = island.positions.len() as u32;
                island.positions.extend(m.positions);
                island.indices.extend(m.indices.iter().map(|t| t.map(|i| i + base)));
            }
            island
        })
        .collect()
}

/// Times the insert of the last island (`runs` times, the median counts) against a rebuild;
/// returns the timing, the grown scene and the last island's id in it.
fn insert_timing(
    backend: Backend,
    desc: &SceneDescription,
    islands: &[TriangleMesh],
    make: &AccelFactory,
    runs: u32,
) -> Result<(InsertTiming, Box<dyn Accelerator>, StaticId), AccelError> {
    let (last, rest) = islands.split_last().expect("at least one island");
    let env: Vec<&TriangleMesh> = desc.statics.iter().map(|s| &s.mesh).collect();

    // The rebuild counts adding the meshes (validation, copies into the backend's buffers) as
    // the insert does for its island.
    let mut fresh = make()?;
    let (result, rebuild_ms) = timed(|| -> Result<(), AccelError> {
        for m in env.iter().copied().chain(islands) {
            fresh.add_static(m)?;
        }
        fresh.commit()?;
        Ok(())
    });
    result?;
    let sah_rebuild = fresh.static_sah_cost();
    drop(fresh);

    let mut grown = make()?;
    for m in env.iter().copied().chain(rest) {
        grown.add_static(m)?;
    }
    grown.commit()?;
    let (mut insert_runs_ms, mut last_id, mut sah_after_insert) = (Vec::new(), None, None);
    for _ in 0..runs.max(1) {
        if let Some(id) = last_id {
            grown.remove_static(id)?;
            grown.commit()?;
        }
        let (result, ms) = timed(|| -> Result<StaticId, AccelError> {
            let id = grown.add_static(last)?;
            grown.commit()?;
            Ok(id)
        });
        last_id = Some(result?);
        insert_runs_ms.push(ms);
        sah_after_insert = sah_after_insert.or_else(|| grown.static_sah_cost());
    }
    let timing = InsertTiming {
        backend,
        triangles: env.iter().copied().chain(islands).map(TriangleMesh::triangle_count).sum(),
        island_triangles: last.triangle_count(),
        rebuild_ms,
        insert_ms: dormant::sequence::stats::median(insert_runs_ms.clone()),
        insert_runs_ms,
        sah_after_insert,
        sah_rebuild,
    };
    Ok((timing, grown, last_id.expect("at least one insert")))
}

/// What [`build_and_trace`] measured, with the bounce rays it made.
struct BuildsAndTraces {
    build: Vec<BuildTiming>,
    trace: Vec<TraceTiming>,
    bounce: Vec<Ray>,
}

/// Builds the scene with every variant and traces the primary and bounce rays through each.
/// The bounce rays are made once, from the first variant's primary hits.
/// With no primary rays (`--builds-only`), only the builds.
fn build_and_trace(
    desc: &SceneDescription,
    primary: &[Ray],
    variants: &[Variant],
    runs: u32,
) -> Result<BuildsAndTraces, AccelError> {
    let mut build = Vec::new();
    let mut trace_timings = Vec::new();
    let mut bounce: Option<Vec<Ray>> = None;
    for (backend, quality, make) in variants {
        let (a, runs_ms) = best_build(desc, make, runs)?;
        let ms = runs_ms.iter().copied().fold(f64::INFINITY, f64::min);
        tracing::info!("{backend}/{quality}: built in {ms:.1} ms (best of {runs_ms:?})");
        let static_sah_cost = a.static_sah_cost();
        build.push(BuildTiming { backend: *backend, quality: quality.clone(), ms, runs_ms, static_sah_cost });
        if primary.is_empty() {
            continue;
        }
        let query = a.query()?;
        let bounce = bounce.get_or_insert_with(|| bounce_rays(query, primary));
        let primary_ms = best_trace(query, primary, runs);
        let bounce_ms = best_trace(query, bounce, runs);
        trace_timings.push(TraceTiming {
            backend: *backend,
            quality: quality.clone(),
            primary_ms,
            bounce_ms,
            primary_mrays_per_s: primary.len() as f64 / primary_ms / 1e3,
            bounce_mrays_per_s: bounce.len() as f64 / bounce_ms / 1e3,
        });
    }
    Ok(BuildsAndTraces { build, trace: trace_timings, bounce: bounce.unwrap_or_default() })
}

/// [`insert_timing`] and then the integration forms ([`resting::resting_timing`], on the grown
/// scene) for every compiled backend, with islands of `island_fraction` of the bodies; none
/// when the scene has no bodies (the forms need two islands).
fn insert_and_forms(
    desc: &SceneDescription,
    opts: &AccelBenchOptions,
    rays: (&[Ray], &[Ray]),
) -> Result<(Vec<InsertTiming>, Vec<RestingTiming>), AccelError> {
    let n = desc.bodies.len();
    let island_size = ((n as f64 * opts.island_fraction).round() as usize).max(1);
    let islands = baked_islands(desc, island_size);
    let (mut inserts, mut forms) = (Vec::new(), Vec::new());
    if islands.is_empty() {
        return Ok((inserts, forms));
    }
    // The last island's bodies: `baked_islands` chunks the bodies in order.
    let awake: Range<usize> = island_size * (islands.len() - 1)..n;
    let threads = opts.threads;
    for backend in Backend::compiled() {
        let (insert, grown, last) =
            insert_timing(backend, desc, &islands, &move || accel::create(backend, threads), opts.runs)?;
        inserts.push(insert);
        if islands.len() > 1 {
            let form = resting::resting_timing(desc, (grown, last), awake.clone(), rays, opts.runs, threads)?;
            forms.push(form);
        }
    }
    Ok((inserts, forms))
}

impl AccelRatios {
    fn new(
        build: &[BuildTiming],
        trace: &[TraceTiming],
        insert: &[InsertTiming],
        forms: &[RestingTiming],
    ) -> Self {
        let find_build =
            |b: Backend, q: &str| build.iter().find(|t| t.backend == b && t.quality == q).map(|t| t.ms);
        let find_trace = |b: Backend, q: &str| {
            trace.iter().find(|t| t.backend == b && t.quality == q).map(|t| t.primary_ms + t.bounce_ms)
        };
        let ratio = |a: Option<f64>, b: Option<f64>| match (a, b) {
            (Some(a), Some(b)) if b > 0.0 => a / b,
            _ => f64::NAN,
        };
        let bvh_insert = insert.iter().find(|t| t.backend == Backend::Bvh);
        let embree_insert = insert.iter().find(|t| t.backend == Backend::Embree);
        let form = |b: Backend, f: fn(&RestingTiming) -> f64| {
            forms.iter().find(|t| t.backend == b).map_or(f64::NAN, f)
        };
        AccelRatios {
            bvh_over_embree_trace: ratio(
                find_trace(Backend::Bvh, "sah"),
                find_trace(Backend::Embree, "medium"),
            ),
            bvh_over_embree_high_trace: ratio(
                find_trace(Backend::Bvh, "sah"),
                find_trace(Backend::Embree, "high"),
            ),
            bvh_over_embree_robust_trace: ratio(
                find_trace(Backend::Bvh, "sah"),
                find_trace(Backend::Embree, "medium-robust"),
            ),
            bvh_over_embree_build: ratio(
                find_build(Backend::Bvh, "sah"),
                find_build(Backend::Embree, "medium"),
            ),
            bvh_over_embree_robust_build: ratio(
                find_build(Backend::Bvh, "sah"),
                find_build(Backend::Embree, "medium-robust"),
            ),
            bvh_rebuild_over_insert: ratio(bvh_insert.map(|t| t.rebuild_ms), bvh_insert.map(|t| t.insert_ms)),
            bvh_insert_sah_over_rebuild: ratio(
                bvh_insert.and_then(|t| t.sah_after_insert).map(f64::from),
                bvh_insert.and_then(|t| t.sah_rebuild).map(f64::from),
            ),
            embree_rebuild_over_insert: ratio(
                embree_insert.map(|t| t.rebuild_ms),
                embree_insert.map(|t| t.insert_ms),
            ),
            embree_resting_trace_over_instanced: form(Backend::Embree, |t| t.resting_trace_over_instanced),
            bvh_resting_trace_over_instanced: form(Backend::Bvh, |t| t.resting_trace_over_instanced),
            embree_baked_trace_over_instanced: form(Backend::Embree, |t| t.baked_trace_over_instanced),
            bvh_baked_trace_over_instanced: form(Backend::Bvh, |t| t.baked_trace_over_instanced),
        }
    }
}

pub fn bench_accel(
    desc: &SceneDescription,
    opts: &AccelBenchOptions,
) -> Result<AccelBenchReport, AccelError> {
    let threads = opts.threads;
    let primary = if opts.builds_only { Vec::new() } else { camera_rays(desc, opts.width, opts.height) };
    let bvh: Variant = (Backend::Bvh, "sah".into(), Box::new(move || accel::create(Backend::Bvh, threads)));
    let variants: Vec<Variant> = embree_variants(threads)
        .into_iter()
        .chain([bvh])
        .filter(|(backend, _, _)| opts.backend.is_none_or(|b| b == *backend))
        .collect();
    let BuildsAndTraces { build, trace, bounce } = build_and_trace(desc, &primary, &variants, opts.runs)?;
    let (insert, forms) = if opts.builds_only {
        (Vec::new(), Vec::new())
    } else {
        insert_and_forms(desc, opts, (&primary, &bounce))?
    };
    Ok(AccelBenchReport {
        scene: desc.name.clone(),
        static_triangles: desc.statics.iter().map(|s| s.mesh.triangle_count()).sum(),
        instances: desc.bodies.len(),
        instanced_triangles: desc
            .bodies
            .iter()
            .map(|b| desc.prototypes[b.prototype as usize].mesh.triangle_count())
            .sum(),
        primary_rays: primary.len(),
        bounce_rays: bounce.len(),
        threads: threads.unwrap_or_else(rayon::current_num_threads),
        ratios: AccelRatios::new(&build, &trace, &insert, &forms),
        build,
        trace,
        insert,
        forms,
    })
}
