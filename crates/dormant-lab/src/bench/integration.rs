//! `dormant bench integration`: one simulated scene rendered under the integration policies
//! `never`, `always` and `auto`, for each integration form (baked, resting), `auto` with and
//! without lookahead, and optionally the baked form with the geometry cache off, in one
//! process on the same trajectory, frames and rays, in lockstep (each frame is rendered by
//! every configuration before the next frame).
//!
//! Per configuration it keeps every frame's stage times; the ratios compare whole frames
//! (reactivate + integrate + update + commit + trace), so integration's own costs count
//! against it. The settled phase is the frames where at least 90% of the dynamic bodies
//! present are asleep. `never` is a fair baseline: it commits nothing when nothing moved, and
//! its top level on Embree is the HIGH-quality instance BVH, the fastest to build and to trace
//! of the qualities tried: docs/lab/accelerators.md#2026-11-22-embrees-instance-top-level-built-at-high

use std::collections::BTreeMap;
use std::time::Instant;

use serde::Serialize;

use super::accel as accel_bench;
use super::persistent_tree::{FragmentedTree, MostFragmented};
use crate::crosscheck::camera_rays;
use dormant::accel::{self, AccelError, Backend};
use dormant::physics::{BodyKind, BodyState};
use dormant::render::{AdaptiveSampling, Integrator, PixelFilter};
use dormant::residency::{
    CacheStats, CostModelState, FrameStats, IntegrationForm, IntegrationPolicy, IntegrationSettings,
    ManagerOptions, ReactivationPath, SceneManager, StageTimes,
};
use dormant::scene::{SceneDescription, StaticMesh};
use dormant::sequence::{
    FrameRenderer, FrameSelection, ReuseMode, SeedMode, Sequence, SequenceError, DEFAULT_REUSE_BYTES,
};

/// What to run.
pub struct IntegrationBenchOptions {
    pub backend: Backend,
    pub frames: FrameSelection,
    /// Image of every traced frame.
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub threads: Option<usize>,
    /// Also build and trace the backend's alternative static structures (Embree's flat
    /// MEDIUM and HIGH rebuilds, seconds each on large scenes:
    /// docs/lab/integration.md#2026-11-22-the-baked-form-only-atrium-and-monastery-variant); the
    /// rebuild of `rebuild_over_insert` is always measured.
    pub static_variants: bool,
    /// Integration forms compared; the first is the one `ratios` describes.
    pub forms: Vec<IntegrationForm>,
    /// Also run the baked form's `always` and `auto` with the geometry cache off.
    pub cache_variants: bool,
    /// Motion blur's shutter for every configuration (0: off). With a shutter, `never` and
    /// the first form's `auto` also run without blur, in the same lockstep, for the cost of
    /// blur.
    pub shutter: f32,
}

/// One configuration of the benchmark.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct BenchConfig {
    pub policy: IntegrationPolicy,
    pub form: IntegrationForm,
    pub cache: bool,
    /// `auto` knows each island's wake frame (else it estimates).
    pub lookahead: bool,
    /// Runs without motion blur in a benchmark with a shutter (the blur-off reference).
    pub unblurred: bool,
}

impl BenchConfig {
    const NEVER: BenchConfig = BenchConfig {
        policy: IntegrationPolicy::Never,
        form: IntegrationForm::Baked,
        cache: false,
        lookahead: false,
        unblurred: false,
    };

    /// `always`, baked, cache on, with lookahead: the run whose static scene the static
    /// variants are made from.
    const ALWAYS_BAKED: BenchConfig = BenchConfig {
        policy: IntegrationPolicy::Always,
        form: IntegrationForm::Baked,
        cache: true,
        lookahead: true,
        unblurred: false,
    };

    /// A short name for tables: `never`, `auto resting`, `auto baked, cache off`, `auto resting, online`.
    pub fn name(&self) -> String {
        let unblurred = if self.unblurred { ", no blur" } else { "" };
        if self.policy == IntegrationPolicy::Never {
            return format!("{}{unblurred}", self.policy);
        }
        let mut name = format!("{} {}{unblurred}", self.policy, self.form);
        if self.form == IntegrationForm::Baked && !self.cache {
            name.push_str(", cache off");
        }
        if self.policy == IntegrationPolicy::Auto && !self.lookahead {
            name.push_str(", online");
        }
        name
    }

    fn settings(&self) -> IntegrationSettings {
        IntegrationSettings {
            policy: self.policy,
            form: self.form,
            cache: self.cache,
            lookahead: self.lookahead,
        }
    }
}

/// The configurations run, in report order: `never`; per form `always` and `auto` (cache on,
/// lookahead); `auto` without lookahead for the first form; with `cache_variants`, the baked
/// form's `always` and `auto` with the cache off; with a shutter, `never` and the first form's
/// `auto` without blur.
fn configs(options: &IntegrationBenchOptions) -> Vec<BenchConfig> {
    let mut configs = vec![BenchConfig::NEVER];
    let on = |policy, form| BenchConfig { policy, form, cache: true, lookahead: true, unblurred: false };
    for &form in &options.forms {
        configs.push(on(IntegrationPolicy::Always, form));
        configs.push(on(IntegrationPolicy::Auto, form));
    }
    if let Some(&form) = options.forms.first() {
        configs.push(BenchConfig { lookahead: false, ..on(IntegrationPolicy::Auto, form) });
    }
    if options.cache_variants && options.forms.contains(&IntegrationForm::Baked) {
        for policy in [IntegrationPolicy::Always, IntegrationPolicy::Auto] {
            configs.push(BenchConfig { cache: false, ..on(policy, IntegrationForm::Baked) });
        }
    }
    if options.shutter > 0.0 {
        configs.push(BenchConfig { unblurred: true, ..BenchConfig::NEVER });
        if let Some(&form) = options.forms.first() {
            configs.push(BenchConfig { unblurred: true, ..on(IntegrationPolicy::Auto, form) });
        }
    }
    configs
}

/// Mean milliseconds per stage over some frames.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct StageMeans {
    pub frames: usize,
    #[serde(flatten)]
    pub stages: StageTimes,
    pub frame_ms: f64,
}

/// One configuration's run.
#[derive(Clone, Debug, Serialize)]
pub struct PolicyRun {
    #[serde(flatten)]
    pub config: BenchConfig,
    pub name: String,
    pub total_ms: f64,
    pub all: StageMeans,
    pub settled: StageMeans,
    pub islands_integrated: u64,
    pub islands_reactivated: u64,
    /// Integrate stage ms per integrated island.
    pub integrate_ms_per_island: f64,
    /// Mean reactivate stage ms over the frames that reactivated something.
    pub reactivate_ms_per_frame_with_wakes: f64,
    pub reactivations_by_removal: u64,
    pub reactivations_from_cache: u64,
    pub integrated_at_end: usize,
    pub instances_at_end: usize,
    pub resting_at_end: usize,
    /// Frames that rebuilt the resting scene.
    pub rest_rebuilds: u64,
    pub rays: u64,
    pub decisions_integrate: u64,
    pub decisions_decline: u64,
    pub cache_stats: CacheStats,
    pub cost_model: CostModelState,
    /// Whole-frame ms, one per rendered frame (for plots).
    pub frame_ms: Vec<f64>,
}

/// The headline numbers.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct IntegrationRatios {
    /// Settled-phase mean frame time, `never` over `auto` (cache on); NaN without settled
    /// frames.
    pub settled_speedup: f64,
    /// Whole-run frame time, `never` over `auto` (cache on).
    pub run_speedup: f64,
    /// `auto` over the better of `never` and `always` (cache on), whole run.
    pub auto_over_best: f64,
    /// A from-scratch build of the final static scene of `always` in the baked form over the
    /// mean integration of one island in that run (NaN when the baked form did not run).
    pub rebuild_over_insert: f64,
    /// Share of `auto`'s cache requests (baked form: the cache serves baked islands) whose
    /// entry held 90-99% of the requested islands.
    pub partial_hit_90_99_fraction: f64,
    /// What integration could reach on the settled frames: `never`'s frame over its trace
    /// plus its commit times the awake share (the frame if sleeping bodies cost nothing to
    /// commit and traced as fast as instanced ones); NaN without settled frames.
    pub ceiling: f64,
    /// `settled_speedup` over `ceiling`.
    pub of_ceiling: f64,
    /// The form's trace penalty: `always`'s settled trace over `never`'s (whole run without
    /// settled frames).
    pub trace_penalty: f64,
    /// `auto` without lookahead over `auto` with it, whole run: what knowing the future gains
    /// (NaN when not run).
    pub lookahead_gain: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct IntegrationBenchReport {
    pub scene: String,
    pub backend: Backend,
    pub bodies: usize,
    pub frames_rendered: u32,
    /// Index of each rendered frame in the trajectory.
    pub frames: Vec<u32>,
    pub settled_frames: usize,
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    /// Per-frame share of present dynamic bodies asleep.
    pub asleep_fraction: Vec<f64>,
    /// Integration forms compared; `ratios` describes the first.
    pub forms: Vec<IntegrationForm>,
    pub runs: Vec<PolicyRun>,
    /// From-scratch builds of `always`'s final static scene: the first is the rebuild of
    /// `rebuild_over_insert`; the others are the alternatives docs/design.md weighs.
    pub static_variants: Vec<StaticVariant>,
    pub rebuild_ms: f64,
    pub rebuild_triangles: usize,
    pub mean_insert_ms: f64,
    /// The BVH's persistent static tree after the run over a fresh build of the same
    /// triangles, trace time of the primary and of the bounce rays (the target: at most
    /// 1.05); `None` without that variant.
    pub persistent_over_fresh_trace: Option<PersistentOverFresh>,
    /// The persistent tree where the run left it in the most pieces, against a fresh build of
    /// the same triangles: the target's real test, since after the run the tree is one
    /// rebuilt block ([`crate::bench::persistent_tree`]). `None` without static variants or
    /// on Embree.
    pub persistent_most_fragmented: Option<FragmentedTree>,
    pub ratios: IntegrationRatios,
    /// The same ratios for every form compared.
    pub ratios_by_form: BTreeMap<String, IntegrationRatios>,
    pub cache_histogram_buckets: [&'static str; 12],
}

impl IntegrationBenchReport {
    /// The run of `policy` in the first form, cache on, with lookahead; `never` has only one
    /// run (form, cache and lookahead play no part in it).
    pub fn cache_on(&self, policy: IntegrationPolicy) -> Option<&PolicyRun> {
        self.forms.first().and_then(|&form| self.run_of(policy, form))
    }

    /// The run of `policy` in `form`, cache on, with lookahead (`never`: its only run).
    pub fn run_of(&self, policy: IntegrationPolicy, form: IntegrationForm) -> Option<&PolicyRun> {
        find_run(&self.runs, policy, form)
    }
}

/// The run of `policy` in `form` with the cache on and lookahead (`never`: its only run).
fn find_run(runs: &[PolicyRun], policy: IntegrationPolicy, form: IntegrationForm) -> Option<&PolicyRun> {
    let want = match policy {
        IntegrationPolicy::Never => BenchConfig::NEVER,
        policy => BenchConfig { policy, form, cache: true, lookahead: true, unblurred: false },
    };
    runs.iter().find(|r| r.config == want)
}

fn means<'a>(frames: impl Iterator<Item = &'a FrameStats>) -> StageMeans {
    let (stages, frames) = StageTimes::mean(frames.map(|f| &f.stages));
    StageMeans { frames, stages, frame_ms: stages.frame_ms() }
}

/// What [`run_lockstep`] reports to as it goes: `progress` gets (frames rendered, frames
/// planned) after each frame, `watch` each configuration's manager (by index) after it
/// rendered a trajectory frame.
struct Observers<'a> {
    progress: &'a mut dyn FnMut(u32, u32),
    watch: &'a mut dyn FnMut(usize, u32, &SceneManager),
}

/// Runs every configuration in lockstep, frame by frame (rotating which goes first), so load
/// from other processes on a shared machine falls on all of them alike. Returns each one's
/// per-frame statistics and its manager at the end.
fn run_lockstep(
    sequence: &Sequence,
    renderer: &FrameRenderer<'_>,
    options: &IntegrationBenchOptions,
    configs: &[ManagerOptions],
    observers: Observers<'_>,
) -> Result<Vec<(Vec<FrameStats>, SceneManager)>, SequenceError> {
    let mut managers = Vec::with_capacity(configs.len());
    for c in configs {
        managers.push(sequence.manager(options.backend, options.threads, c.clone())?);
    }
    let mut frames = vec![Vec::new(); configs.len()];
    let total = options.frames.count();
    let mut rendered = 0;
    sequence.replay(&options.frames, &mut managers, &mut |frame, managers| {
        let n = managers.len();
        for k in 0..n {
            let i = (k + rendered as usize) % n;
            // Each manager's own shutter (the blur-off references have none).
            let renderer = FrameRenderer { shutter: managers[i].options().shutter, ..*renderer };
            sequence.render_frame(&mut managers[i], frame, &renderer)?;
            frames[i].push(managers[i].last_frame().clone());
            (observers.watch)(i, frame.index, &managers[i]);
        }
        rendered += 1;
        (observers.progress)(rendered, total);
        Ok::<(), SequenceError>(())
    })?;
    Ok(frames.into_iter().zip(managers).collect())
}

/// One way to hold a final static scene: its from-scratch build time and primary-ray trace.
#[derive(Clone, Debug, Serialize)]
pub struct StaticVariant {
    pub name: String,
    /// NaN (JSON null) for the persistent tree, which is not built from scratch.
    pub build_ms: f64,
    pub primary_trace_ms: f64,
    /// Cosine-distributed bounces from the first variant's primary hits.
    pub bounce_trace_ms: f64,
    /// SAH cost of the BVH's static tree (JSON null on Embree), to tell a worse tree from a
    /// noisy timing: after the atrium's run the persistent tree is one rebuilt block with the
    /// fresh build's cost and leaves, so their trace ratio there is the benchmark's noise:
    /// docs/lab/persistent-tree.md#2026-12-03-the-tree-after-the-run-is-the-fresh-builds
    pub sah_cost: Option<f32>,
}

/// See [`IntegrationBenchReport::persistent_over_fresh_trace`].
#[derive(Clone, Copy, Debug, Serialize)]
pub struct PersistentOverFresh {
    pub primary: f64,
    pub bounce: f64,
}

impl PersistentOverFresh {
    fn of(variants: &[StaticVariant]) -> Option<Self> {
        let fresh = variants.first()?;
        let tree = variants.iter().find(|v| v.name == PERSISTENT_TREE)?;
        Some(Self {
            primary: tree.primary_trace_ms / fresh.primary_trace_ms,
            bounce: tree.bounce_trace_ms / fresh.bounce_trace_ms,
        })
    }
}

/// The backend's ways to build the final static scene of `manager` (environment plus every
/// integrated island) from scratch, and for the BVH its persistent static tree as the run left
/// it, each traced with the same primary rays and diffuse bounces from their hits. The first
/// is the build dormant uses.
fn static_variants(
    manager: &SceneManager,
    template: &SceneDescription,
    options: &IntegrationBenchOptions,
) -> Result<(Vec<StaticVariant>, usize), AccelError> {
    let mut statics: Vec<StaticMesh> = template.statics.clone();
    statics.extend(manager.integrated_meshes().map(|m| StaticMesh { mesh: m.clone(), material: 0 }));
    let triangles = statics.iter().map(|s| s.mesh.triangle_count()).sum();
    let scene = SceneDescription { statics, ..template.clone() };
    let mut built = Vec::new();
    let mut factories = variant_factories(options);
    if !options.static_variants {
        factories.truncate(1);
    }
    for (name, make) in factories {
        let mut accel = make()?;
        let start = Instant::now();
        for s in &scene.statics {
            accel.add_static(&s.mesh)?;
        }
        accel.commit()?;
        built.push(BuiltVariant { name, build_ms: start.elapsed().as_secs_f64() * 1e3, accel });
    }
    if options.static_variants {
        built.extend(persistent_static_tree(manager, options)?);
    }
    let primary = camera_rays(&scene, 640, 360);
    let bounce = accel_bench::bounce_rays(built[0].accel.query()?, &primary);
    let queries = built.iter().map(|v| v.accel.query()).collect::<Result<Vec<_>, _>>()?;
    let best = accel_bench::best_traces(&queries, &primary, &bounce);
    let variants = built
        .into_iter()
        .zip(best)
        .map(|(BuiltVariant { name, build_ms, accel }, (primary_trace_ms, bounce_trace_ms))| StaticVariant {
            name,
            build_ms,
            primary_trace_ms,
            bounce_trace_ms,
            sah_cost: accel.static_sah_cost(),
        })
        .collect();
    Ok((variants, triangles))
}

/// A static scene built one way, before it is traced.
struct BuiltVariant {
    name: String,
    build_ms: f64,
    accel: Box<dyn accel::Accelerator>,
}

/// The BVH's persistent static tree as the run left it, after every insert, removal and
/// cache restore, restored into an accelerator of its own so that it is traced alone as the
/// fresh builds are (the target: within 5% of a fresh build of the same triangles). Its
/// build time is not measured (NaN). Embree's static scene is rebuilt per island, not kept as
/// one tree, so it has no such variant.
fn persistent_static_tree(
    manager: &SceneManager,
    options: &IntegrationBenchOptions,
) -> Result<Option<BuiltVariant>, AccelError> {
    if options.backend != Backend::Bvh {
        return Ok(None);
    }
    let Some(snapshot) = manager.static_snapshot() else {
        return Ok(None);
    };
    let mut accel = accel::create(Backend::Bvh, options.threads)?;
    accel.restore_static_scene(&snapshot)?;
    accel.commit()?;
    Ok(Some(BuiltVariant { name: PERSISTENT_TREE.to_string(), build_ms: f64::NAN, accel }))
}

/// The name of the [`persistent_static_tree`] variant.
pub const PERSISTENT_TREE: &str = "bvh persistent tree after the run";

type Factory = Box<dyn Fn() -> Result<Box<dyn accel::Accelerator>, AccelError>>;

fn variant_factories(options: &IntegrationBenchOptions) -> Vec<(String, Factory)> {
    let threads = options.threads;
    match options.backend {
        #[cfg(feature = "embree")]
        Backend::Embree => {
            use dormant::accel::embree::{EmbreeAccel, EmbreeBuildParams};
            use dormant_embree::{BuildQuality, Device};
            let with = |params: EmbreeBuildParams| -> Factory {
                Box::new(move || Ok(Box::new(EmbreeAccel::with_device(Device::new(threads)?, params)?)))
            };
            let d = EmbreeBuildParams::DEFAULT;
            vec![
                ("embree two-level (dynamic, low top, medium meshes)".into(), with(d)),
                (
                    "embree flat medium".into(),
                    with(EmbreeBuildParams { static_scene: BuildQuality::Medium, ..d }),
                ),
                (
                    "embree flat high".into(),
                    with(EmbreeBuildParams { static_scene: BuildQuality::High, ..d }),
                ),
            ]
        }
        backend => {
            vec![(format!("{backend} from-scratch build"), Box::new(move || accel::create(backend, threads)))]
        }
    }
}

/// How every configuration renders its frames.
fn renderer<'a>(integrator: &'a dyn Integrator, options: &IntegrationBenchOptions) -> FrameRenderer<'a> {
    FrameRenderer {
        integrator,
        aovs: &[],
        width: options.width,
        height: options.height,
        spp: options.spp,
        adaptive: AdaptiveSampling::OFF,
        filter: PixelFilter::default(),
        // Every frame traced, and noise decorrelated as in a per-frame-seeded render.
        seed: SeedMode::PerFrame,
        seed_offset: 0,
        reuse: ReuseMode::Off,
        reuse_budget: DEFAULT_REUSE_BYTES,
        shutter: options.shutter,
    }
}

/// The scene manager options of each configuration.
fn config_manager_options(
    sequence: &Sequence,
    configs: &[BenchConfig],
    options: &IntegrationBenchOptions,
) -> Vec<ManagerOptions> {
    configs
        .iter()
        .map(|c| ManagerOptions {
            shutter: if c.unblurred { 0.0 } else { options.shutter },
            ..sequence.manager_options(&options.frames, c.settings())
        })
        .collect()
}

/// See the module docs. `progress` gets (frames rendered, frames planned) after each frame.
pub fn bench_integration(
    sequence: &Sequence,
    integrator: &dyn Integrator,
    options: &IntegrationBenchOptions,
    progress: &mut dyn FnMut(u32, u32),
) -> Result<IntegrationBenchReport, SequenceError> {
    let asleep_fraction = asleep_fractions(sequence, &options.frames);
    let settled: Vec<bool> = asleep_fraction.iter().map(|&a| a >= 0.9).collect();
    let configs = configs(options);
    let manager_options = config_manager_options(sequence, &configs, options);
    // Only the BVH keeps a persistent static tree to watch.
    let watched = configs
        .iter()
        .position(|&c| c == BenchConfig::ALWAYS_BAKED)
        .filter(|_| options.static_variants && options.backend == Backend::Bvh);
    let mut most_fragmented = MostFragmented::default();
    let observers = Observers {
        progress,
        watch: &mut |i, frame, manager| {
            if Some(i) == watched {
                most_fragmented.observe(frame, manager);
            }
        },
    };
    let results =
        run_lockstep(sequence, &renderer(integrator, options), options, &manager_options, observers)?;
    let mut runs = Vec::new();
    let (mut variants, mut rebuild_triangles, mut mean_insert_ms) = (Vec::new(), 0, 0.0);
    for (config, (frames, manager)) in configs.into_iter().zip(results) {
        let run = policy_run(config, &frames, &settled, &manager);
        if config == BenchConfig::ALWAYS_BAKED {
            (variants, rebuild_triangles) = static_variants(&manager, &sequence.template, options)?;
            mean_insert_ms = run.integrate_ms_per_island;
        }
        runs.push(run);
    }
    let rebuild_ms = variants.first().map_or(0.0, |v| v.build_ms);
    let awake = settled_awake_share(&asleep_fraction, &settled);
    let rebuild_over_insert = if mean_insert_ms > 0.0 { rebuild_ms / mean_insert_ms } else { f64::NAN };
    let ratios_by_form: BTreeMap<String, IntegrationRatios> = options
        .forms
        .iter()
        .map(|&form| (form.to_string(), ratios(&runs, form, awake, rebuild_over_insert)))
        .collect();
    let ratios =
        options.forms.first().map_or_else(IntegrationRatios::default, |f| ratios_by_form[&f.to_string()]);
    let persistent_over_fresh_trace = PersistentOverFresh::of(&variants);
    let persistent_most_fragmented = most_fragmented.measure(&sequence.template, options.threads)?;
    Ok(IntegrationBenchReport {
        scene: sequence.template.name.clone(),
        backend: options.backend,
        bodies: sequence.trajectory.bodies.len(),
        frames_rendered: options.frames.count(),
        frames: options.frames.frames(),
        settled_frames: settled.iter().filter(|s| **s).count(),
        width: options.width,
        height: options.height,
        spp: options.spp,
        asleep_fraction,
        forms: options.forms.clone(),
        runs,
        static_variants: variants,
        rebuild_ms,
        rebuild_triangles,
        mean_insert_ms,
        persistent_over_fresh_trace,
        persistent_most_fragmented,
        ratios,
        ratios_by_form,
        cache_histogram_buckets: CacheStats::FRACTION_BUCKETS,
    })
}

/// The mean awake share (of present dynamic bodies) over the settled frames, or over all
/// frames when none settled.
fn settled_awake_share(asleep_fraction: &[f64], settled: &[bool]) -> f64 {
    let pick: Vec<f64> =
        asleep_fraction.iter().zip(settled).filter(|(_, s)| **s).map(|(a, _)| 1.0 - a).collect();
    let all: Vec<f64> = asleep_fraction.iter().map(|a| 1.0 - a).collect();
    let v = if pick.is_empty() { &all } else { &pick };
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

/// Per rendered frame, the share of the present dynamic bodies asleep, from the trajectory.
fn asleep_fractions(sequence: &Sequence, selection: &FrameSelection) -> Vec<f64> {
    let trajectory = &sequence.trajectory;
    let dynamic: Vec<bool> = trajectory.bodies.iter().map(|b| b.kind == BodyKind::Dynamic).collect();
    let mut fractions = Vec::new();
    let mut replay = trajectory.replay();
    while let Some(f) = replay.next_frame() {
        if !selection.selects(f.index) {
            continue;
        }
        let (mut present, mut asleep) = (0usize, 0usize);
        for (s, d) in f.states.iter().zip(&dynamic) {
            if *d && *s != BodyState::Absent {
                present += 1;
                asleep += usize::from(*s == BodyState::Asleep);
            }
        }
        fractions.push(if present == 0 { 0.0 } else { asleep as f64 / present as f64 });
    }
    fractions
}

/// One configuration's report from its frames (`settled` marks the settled ones) and its
/// manager at the end.
fn policy_run(
    config: BenchConfig,
    frames: &[FrameStats],
    settled: &[bool],
    manager: &SceneManager,
) -> PolicyRun {
    let sum = |f: &dyn Fn(&FrameStats) -> u64| frames.iter().map(f).sum::<u64>();
    let integrated = sum(&|f| u64::from(f.islands_integrated));
    PolicyRun {
        config,
        name: config.name(),
        total_ms: frames.iter().map(|f| f.frame_ms()).sum(),
        all: means(frames.iter()),
        settled: means(frames.iter().zip(settled).filter(|(_, s)| **s).map(|(f, _)| f)),
        islands_integrated: integrated,
        islands_reactivated: sum(&|f| u64::from(f.islands_reactivated)),
        integrate_ms_per_island: match integrated {
            0 => 0.0,
            n => frames.iter().map(|f| f.stages.integrate_ms).sum::<f64>() / n as f64,
        },
        reactivate_ms_per_frame_with_wakes: means(frames.iter().filter(|f| f.islands_reactivated > 0))
            .stages
            .reactivate_ms,
        reactivations_by_removal: sum(&|f| u64::from(f.reactivation_path == Some(ReactivationPath::Removal))),
        reactivations_from_cache: sum(&|f| {
            u64::from(matches!(f.reactivation_path, Some(ReactivationPath::Cache(_))))
        }),
        integrated_at_end: frames.last().map_or(0, |f| f.integrated_islands),
        instances_at_end: frames.last().map_or(0, |f| f.instances),
        resting_at_end: frames.last().map_or(0, |f| f.resting_bodies),
        rest_rebuilds: sum(&|f| u64::from(f.rest_rebuilt)),
        rays: sum(&|f| f.rays),
        decisions_integrate: sum(&|f| f.decisions.iter().filter(|d| d.integrate).count() as u64),
        decisions_decline: sum(&|f| f.decisions.iter().filter(|d| !d.integrate).count() as u64),
        cache_stats: manager.cache_stats(),
        cost_model: manager.cost_model(),
        frame_ms: frames.iter().map(|f| f.frame_ms()).collect(),
    }
}

/// The headline ratios of `form` from the runs; `awake` is the settled frames' mean awake
/// share, `rebuild_over_insert` the baked form's.
fn ratios(
    runs: &[PolicyRun],
    form: IntegrationForm,
    awake: f64,
    rebuild_over_insert: f64,
) -> IntegrationRatios {
    let nan = f64::NAN;
    let (Some(never), Some(always), Some(auto)) = (
        find_run(runs, IntegrationPolicy::Never, form),
        find_run(runs, IntegrationPolicy::Always, form),
        find_run(runs, IntegrationPolicy::Auto, form),
    ) else {
        return IntegrationRatios::default();
    };
    let settled = never.settled.frames > 0;
    // NaN (null in JSON) when no frame settled.
    let settled_speedup =
        if settled { never.settled.frame_ms / auto.settled.frame_ms.max(1e-9) } else { nan };
    let n = &never.settled.stages;
    let ceiling =
        if settled { never.settled.frame_ms / (n.trace_ms + n.commit_ms * awake).max(1e-9) } else { nan };
    let (never_trace, always_trace) = if settled {
        (n.trace_ms, always.settled.stages.trace_ms)
    } else {
        (never.all.stages.trace_ms, always.all.stages.trace_ms)
    };
    let online = runs.iter().find(|r| r.config == BenchConfig { lookahead: false, ..auto.config });
    IntegrationRatios {
        settled_speedup,
        run_speedup: never.total_ms / auto.total_ms.max(1e-9),
        auto_over_best: auto.total_ms / never.total_ms.min(always.total_ms).max(1e-9),
        // Measured on the baked form (the insert it times), whatever form these ratios describe.
        rebuild_over_insert,
        // The geometry cache serves baked islands only.
        partial_hit_90_99_fraction: find_run(runs, IntegrationPolicy::Auto, IntegrationForm::Baked)
            .map_or(nan, |r| r.cache_stats.partial_90_99_fraction()),
        ceiling,
        of_ceiling: settled_speedup / ceiling,
        trace_penalty: always_trace / never_trace.max(1e-9),
        lookahead_gain: online.map_or(nan, |o| o.total_ms / auto.total_ms.max(1e-9)),
    }
}
