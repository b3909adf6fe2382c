//! `dormant bench`: argument parsing for the cross-domain benchmarks (accel, render,
//! integration) and physics stepping, and writing their reports.

use std::path::PathBuf;

use clap::{Args, Subcommand};

mod reuse;

use super::denoise::DenoiseArgs;
use super::named::named;
use super::{CliError, JsonOutput, SceneSource};
use dormant::residency::IntegrationForm;
use dormant::scene::limits::MAX_SAMPLES_PER_PIXEL;
use dormant::sequence::{FrameRange, SequenceSource};
use dormant_lab::bench::{
    self, bench_json, AccelBenchOptions, AdaptiveBenchOptions, IntegrationBenchOptions, RenderBenchOptions,
};
use dormant_lab::paper::{self, PaperBenchOptions, PaperPreset, RainAssets};
use dormant_lab::regimes;

#[derive(Debug, Args)]
pub struct BenchArgs {
    #[command(subcommand)]
    pub which: BenchCommand,
}

#[derive(Debug, Subcommand)]
pub enum BenchCommand {
    /// Builders, tracers and incremental insertion: Embree (low/medium/high) against the BVH.
    #[command(
        after_help = "Examples:\n  dormant bench accel --json out/accel.json\n  dormant bench accel --env ../shared/assets/monastery.glb --object ../shared/assets/duck.glb --count 8000 --json out/accel.json"
    )]
    Accel(AccelArgs),
    /// Rendering: Mrays/s per ray type (camera, shadow, bounce) and path-traced samples/s,
    /// every compiled backend on the same scene.
    #[command(
        after_help = "Examples:\n  dormant bench render --json out/render.json\n  dormant bench render --size 1280x720 --spp 16 --runs 1\n  dormant bench render --env ../shared/assets/monastery.glb --object ../shared/assets/duck.glb --count 8000 --json out/render.json"
    )]
    Render(RenderBenchArgs),
    /// Adaptive sampling: relative MSE against a high-spp reference of uniform frames at
    /// several spp and adaptive frames at several noise thresholds (optionally denoised), and
    /// the samples adaptive sampling needs for each uniform frame's error.
    #[command(
        after_help = "Examples:\n  dormant bench adaptive --size 480x270 --reference out/ref-480.exr --json out/adaptive.json\n  dormant bench adaptive --thresholds 0.02,0.04 --adaptive-spp 128 --denoise"
    )]
    Adaptive(AdaptiveBenchArgs),
    /// Integration policies never/always/auto, cache on and off, on one simulated scene.
    #[command(
        after_help = "Examples:\n  dormant bench integration scenes/atrium.toml --json out/integration.json\n  dormant bench integration scenes/tiny.toml --backend bvh --size 160x90"
    )]
    Integration(IntegrationArgs),
    /// Exact temporal reuse: one sequence rendered every frame in full and with `--reuse
    /// exact`, in turn: speed-up beside its bound (1 / the traced share), first frame, horizon
    /// cost, store memory, and whether every frame is the same bits.
    #[command(
        after_help = "Examples:\n  dormant bench reuse scenes/demolition.toml --frames 600..720 --json out/reuse.json\n  dormant bench reuse scenes/tiny.toml --size 160x90 --spp 4 --frames 0..60 --runs 1"
    )]
    Reuse(reuse::ReuseArgs),
    /// The paper's experiments: the atrium with 8,000 objects (and an asset rain over --env
    /// when given), simulated once and rendered under never/always/auto with the cache on and
    /// off by every backend; writes paper.json, paper.md and figures into --out.
    #[command(
        after_help = "Examples:\n  dormant bench paper --out out/paper                 the atrium, 8,000 objects\n  dormant bench paper --quick --out out/paper-quick   scaled down (1,000 objects)\n  dormant bench paper --env ../shared/assets/monastery.glb --object ../shared/assets/duck.glb \\\n      --object ../shared/assets/teddy.glb --object ../shared/assets/soccerball.glb --out docs/paper"
    )]
    Paper(PaperArgs),
    /// Where integration pays: a scene simulated at several body counts, rendered under never,
    /// always and auto by every backend at several per-frame ray budgets; writes regimes.json,
    /// regimes.md and regimes.png into --out.
    #[command(
        after_help = "Examples:\n  dormant bench regimes scenes/demolition.toml --out out/regimes\n  dormant bench regimes scenes/demolition.toml --quick --out out/regimes-quick"
    )]
    Regimes(RegimesArgs),
    /// Embree's top level of N instances as one instance geometry each against one instance
    /// array, still and moving over the shutter: update, commit and trace (what motion blur
    /// costs Embree's top level).
    #[cfg(feature = "embree")]
    #[command(after_help = "Examples:\n  dormant bench instances --count 8000 --json out/instances.json")]
    Instances(InstancesArgs),
    /// Physics step time with every body awake against most asleep.
    #[command(after_help = "Examples:\n  dormant bench physics scenes/atrium.toml --json out/physics.json")]
    Physics(PhysicsArgs),
}

#[derive(Debug, Args)]
pub struct PaperArgs {
    /// Output directory for paper.json, paper.md and figures/.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Scaled-down workloads (the atrium with 1,000 objects) instead of the paper's sizes.
    #[arg(long)]
    pub quick: bool,
    /// Environment glTF of the monastery variant: objects rain onto it (needs --object).
    #[arg(long, value_name = "GLB", requires = "object")]
    pub env: Option<PathBuf>,
    /// Object glTF of the monastery variant; repeat for a mix.
    #[arg(long, value_name = "GLB", requires = "env")]
    pub object: Vec<PathBuf>,
    /// Backends to compare (repeat; default: every compiled one).
    #[arg(long)]
    pub backend: Vec<dormant::accel::Backend>,
}

#[derive(Debug, Args)]
pub struct RegimesArgs {
    /// Scene file to simulate at each count.
    #[arg(value_name = "SCENE")]
    pub scene: PathBuf,
    /// Directory that relative asset paths in the scene resolve against.
    #[arg(long, value_name = "DIR")]
    pub assets: Option<PathBuf>,
    /// Output directory for regimes.json, regimes.md and regimes.png.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Dynamic bodies of each simulation (comma-separated).
    #[arg(long, value_name = "N,...", value_delimiter = ',', default_value = "2000,8000,50000,150000")]
    pub counts: Vec<u32>,
    /// Frames to simulate (default: the scene's).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub frame_count: Option<u32>,
    /// Per-frame ray budgets (comma-separated; default: all).
    #[arg(long, value_enum, value_delimiter = ',')]
    pub budgets: Vec<regimes::Budget>,
    /// Backends to compare (repeat; default: every compiled one).
    #[arg(long)]
    pub backend: Vec<dormant::accel::Backend>,
    /// The integration form measured.
    #[arg(long, value_parser = named::<IntegrationForm>(), default_value_t = IntegrationForm::default())]
    pub integrate_as: IntegrationForm,
    /// Frames rendered per preview cell.
    #[arg(long, value_name = "N", default_value_t = 150)]
    pub preview_frames: u32,
    /// Settled frames rendered per production cell.
    #[arg(long, value_name = "N", default_value_t = 4)]
    pub production_frames: u32,
    /// Consecutive frames of a production cell's reuse measurement (from the start of the last
    /// quarter).
    #[arg(long, value_name = "N", default_value_t = 12, value_parser = clap::value_parser!(u32).range(1..))]
    pub reuse_frames: u32,
    /// Scaled down for tests: counts 300 and 1200 over 240 frames, 24 preview frames, one
    /// production frame at 160x90 (3 consecutive for reuse).
    #[arg(long)]
    pub quick: bool,
}

#[cfg(feature = "embree")]
#[derive(Debug, Args)]
pub struct InstancesArgs {
    /// Instances in the top level.
    #[arg(long, value_name = "N", default_value_t = 8000, value_parser = clap::value_parser!(u32).range(1..))]
    pub count: u32,
    /// Rays traced per measurement.
    #[arg(long, value_name = "N", default_value_t = 200_000)]
    pub rays: usize,
    /// Updates, commits and traces per row (median commit, best trace).
    #[arg(long, value_name = "N", default_value_t = 7, value_parser = clap::value_parser!(u32).range(1..))]
    pub runs: u32,
}

#[derive(Debug, Args)]
pub struct PhysicsArgs {
    #[command(flatten)]
    pub scene: super::simulate::PhysicsScene,
    /// Frames measured in each phase.
    #[arg(long, value_name = "N", default_value_t = 60)]
    pub measure_frames: u32,
}

#[derive(Debug, Args)]
pub struct IntegrationArgs {
    #[command(flatten)]
    pub scene: super::simulate::PhysicsScene,
    /// Replay this trajectory (from `dormant simulate` with the same options) instead of
    /// simulating.
    #[arg(long, value_name = "FILE")]
    pub trajectory: Option<PathBuf>,
    /// Ray tracing backend (default: the first compiled in, Embree preferred).
    #[arg(long)]
    pub backend: Option<dormant::accel::Backend>,
    /// Render frames A..B (half-open) of the simulation.
    #[arg(long, value_name = "A..B", alias = "range")]
    pub frames: Option<FrameRange>,
    /// Render every N-th frame (default: the scene's render.frame_step).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub frame_step: Option<u32>,
    /// Image size of each traced frame.
    #[arg(long, value_name = "WxH", default_value = "320x180")]
    pub size: dormant::render::ImageSize,
    /// Samples per pixel.
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=MAX_SAMPLES_PER_PIXEL as i64))]
    pub spp: u32,
    /// What each frame traces: by default the interactive preview (primary and shadow rays),
    /// where structure updates are a sizeable part of a frame.
    #[arg(long, value_enum, default_value_t = super::render::RenderMode::Shaded)]
    pub mode: super::render::RenderMode,
    /// The integration form the ratios describe; the other form runs too (`always`, `auto`).
    #[arg(long, value_parser = named::<IntegrationForm>(), default_value_t = IntegrationForm::default())]
    pub integrate_as: IntegrationForm,
    /// Compare this form only.
    #[arg(long)]
    pub one_form: bool,
    /// Also run the baked form's `always` and `auto` with the geometry cache off.
    #[arg(long)]
    pub cache_variants: bool,
    /// Motion blur: every configuration renders with this shutter (a fraction of the frame
    /// interval, 0 to 1), and `never` and `auto` also run without blur, in the same lockstep.
    #[arg(long, value_name = "S", default_value_t = 0.0, allow_negative_numbers = true)]
    pub shutter: f32,
}

#[derive(Debug, Args)]
pub struct AccelArgs {
    #[command(flatten)]
    pub scene: SceneSource,
    /// Primary rays: one per pixel of an image of this size.
    #[arg(long, value_name = "WxH", default_value = "1280x720")]
    pub size: dormant::render::ImageSize,
    /// Repetitions of each build and trace measurement; the best is reported.
    #[arg(long, value_name = "N", default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..))]
    pub runs: u32,
    /// Only the builds (no traces, inserts or forms): what `make instruction-check` counts.
    #[arg(long)]
    pub builds_only: bool,
    /// Only this backend (default: every compiled one).
    #[arg(long)]
    pub backend: Option<dormant::accel::Backend>,
}

#[derive(Debug, Args)]
pub struct RenderBenchArgs {
    #[command(flatten)]
    pub scene: SceneSource,
    /// Size of the rendered frame; the ray sets have one camera ray per pixel.
    #[arg(long, value_name = "WxH", default_value = "640x360")]
    pub size: dormant::render::ImageSize,
    /// Samples per pixel of the path-traced frame.
    #[arg(long, value_name = "N", default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=MAX_SAMPLES_PER_PIXEL as i64))]
    pub spp: u32,
    /// Repetitions of each measurement; the best is reported.
    #[arg(long, value_name = "N", default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..))]
    pub runs: u32,
    /// Build Embree's scenes in robust mode (RTC_SCENE_FLAG_ROBUST: a watertight triangle
    /// test and conservative box tests, as the BVH always has), to compare like for like.
    #[arg(long)]
    pub embree_robust: bool,
}

#[derive(Debug, Args)]
pub struct AdaptiveBenchArgs {
    #[command(flatten)]
    pub scene: SceneSource,
    /// Ray tracing backend (default: the first compiled in).
    #[arg(long)]
    pub backend: Option<dormant::accel::Backend>,
    /// Image size of the frames and the reference.
    #[arg(long, value_name = "WxH", default_value = "480x270")]
    pub size: dormant::render::ImageSize,
    /// Longest path (bounces).
    #[arg(long, value_name = "N", default_value_t = 6, value_parser = clap::value_parser!(u32).range(1..=64))]
    pub max_depth: u32,
    /// Samples per pixel of the reference (rendered with another seed than the frames).
    #[arg(long, value_name = "N", default_value_t = 1024, value_parser = clap::value_parser!(u32).range(1..=MAX_SAMPLES_PER_PIXEL as i64))]
    pub reference_spp: u32,
    /// Reference EXR: read when it exists at --size, else rendered and written there.
    #[arg(long, value_name = "FILE")]
    pub reference: Option<PathBuf>,
    /// Samples per pixel of the uniform frames.
    #[arg(long, value_name = "N,...", value_delimiter = ',', default_value = "16,32,64,128")]
    pub uniform_spp: Vec<u32>,
    /// Noise thresholds of the adaptive frames.
    #[arg(long, value_name = "T,...", value_delimiter = ',', default_value = "0.08,0.04,0.02,0.01")]
    pub thresholds: Vec<f32>,
    /// Most samples per pixel of the adaptive frames.
    #[arg(long, value_name = "N", default_value_t = 256)]
    pub adaptive_spp: u32,
    /// Adaptive sampling's minimum (default: as `render --min-spp`).
    #[arg(long, value_name = "N")]
    pub min_spp: Option<u32>,
    // Also denoise every frame (`--denoise`, as `render`'s) and report its error.
    #[command(flatten)]
    pub denoising: DenoiseArgs,
}

pub(super) fn run(
    args: &BenchArgs,
    threads: Option<usize>,
    quiet: bool,
    json: &JsonOutput,
) -> Result<(), CliError> {
    match &args.which {
        BenchCommand::Accel(a) => accel(a, threads, quiet, json),
        BenchCommand::Render(r) => render(r, threads, quiet, json),
        BenchCommand::Adaptive(a) => adaptive(a, threads, quiet, json),
        BenchCommand::Physics(p) => physics(p, quiet, json),
        BenchCommand::Integration(i) => integration(i, threads, quiet, json),
        BenchCommand::Reuse(r) => reuse::reuse(r, threads, quiet, json),
        BenchCommand::Paper(p) => paper(p, threads, quiet, json),
        BenchCommand::Regimes(r) => regimes(r, threads, quiet, json),
        #[cfg(feature = "embree")]
        BenchCommand::Instances(i) => instances(i, threads, quiet, json),
    }
}

fn paper(args: &PaperArgs, threads: Option<usize>, quiet: bool, json: &JsonOutput) -> Result<(), CliError> {
    let backends = chosen_backends(&args.backend)?;
    let rain = args.env.as_ref().map(|env| RainAssets { env: env.clone(), objects: args.object.clone() });
    let options = PaperBenchOptions {
        preset: if args.quick { PaperPreset::Quick } else { PaperPreset::Full },
        rain,
        backends,
        threads,
    };
    create_out_dir(&args.out)?;
    let mut log = timed_log("bench paper", quiet);
    let report = paper::bench_paper(&options, &mut log).map_err(|e| match e.is_input() {
        true => CliError::Input(e.to_string()),
        false => CliError::Runtime(e.to_string()),
    })?;
    let written = paper::write_paper(&report, &args.out).map_err(|e| CliError::Runtime(e.to_string()))?;
    json.emit(&bench_json(&report))?;
    print_written(&written, json, quiet);
    Ok(())
}

fn integration(
    args: &IntegrationArgs,
    threads: Option<usize>,
    quiet: bool,
    json: &JsonOutput,
) -> Result<(), CliError> {
    let backend = super::render::choose_backend(args.backend)?;
    super::render::check_shutter(Some(args.shutter))?;
    let (file, options) = args.scene.load()?;
    let source = SequenceSource::scene(file, options, args.trajectory.clone());
    let sequence = super::render::load_sequence(source, quiet)?;
    let frames = sequence
        .select(args.frames, args.frame_step)
        .map_err(|e| super::render::sequence_error(e, "--frames"))?;
    let options = IntegrationBenchOptions {
        backend,
        frames,
        width: args.size.width,
        height: args.size.height,
        spp: args.spp,
        threads,
        static_variants: true,
        forms: if args.one_form {
            vec![args.integrate_as]
        } else {
            IntegrationForm::starting_with(args.integrate_as)
        },
        cache_variants: args.cache_variants,
        shutter: args.shutter,
    };
    let integrator = super::render::integrator(args.mode, dormant::render::PathTracer::default());
    let mut progress = |done: u32, total: u32| {
        if !quiet && (done % 50 == 0 || done == total) {
            eprintln!("bench integration: frame {done} of {total}");
        }
    };
    let report = bench::bench_integration(&sequence, integrator.as_ref(), &options, &mut progress)?;
    emit(&bench_json(&report), json, quiet)
}

fn regimes(
    args: &RegimesArgs,
    threads: Option<usize>,
    quiet: bool,
    json: &JsonOutput,
) -> Result<(), CliError> {
    let scene = dormant::scene::file::SceneFile::load_with_assets(&args.scene, args.assets.as_deref())
        .map_err(|e| CliError::Input(e.to_string()))?;
    let backends = chosen_backends(&args.backend)?;
    let budgets = if args.budgets.is_empty() { regimes::Budget::ALL.to_vec() } else { args.budgets.clone() };
    let (counts, frame_count, sizes) = match args.quick {
        true => {
            let sizes = regimes::RegimeSizes { preview_frames: 24, production_frames: 1, reuse_frames: 3 };
            (vec![300, 1200], Some(240), sizes)
        }
        false => (
            args.counts.clone(),
            args.frame_count,
            regimes::RegimeSizes {
                preview_frames: args.preview_frames,
                production_frames: args.production_frames,
                reuse_frames: args.reuse_frames,
            },
        ),
    };
    let options = regimes::RegimesOptions {
        scene,
        counts,
        frame_count,
        backends,
        budgets,
        form: args.integrate_as,
        sizes,
        quick: args.quick,
        threads,
    };
    create_out_dir(&args.out)?;
    let mut log = timed_log("bench regimes", quiet);
    let report = regimes::bench_regimes(&options, &mut log)?;
    let written = regimes::write_regimes(&report, &args.out).map_err(|e| CliError::Runtime(e.to_string()))?;
    json.emit(&bench_json(&report))?;
    print_written(&written, json, quiet);
    Ok(())
}

/// The backends named on the command line, or every compiled one.
fn chosen_backends(named: &[dormant::accel::Backend]) -> Result<Vec<dormant::accel::Backend>, CliError> {
    if named.is_empty() {
        return Ok(dormant::accel::Backend::compiled());
    }
    named.iter().map(|&b| super::render::choose_backend(Some(b))).collect()
}

/// Creates a report's output directory: before minutes of benchmarking, not after.
fn create_out_dir(out: &std::path::Path) -> Result<(), CliError> {
    std::fs::create_dir_all(out)
        .map_err(|e| CliError::Runtime(format!("cannot create output directory {}: {e}", out.display())))
}

/// Progress lines on stderr, prefixed with `label` and the seconds since this call.
fn timed_log(label: &'static str, quiet: bool) -> impl FnMut(&str) {
    let start = std::time::Instant::now();
    move |line: &str| {
        if !quiet {
            eprintln!("{label} [{:>5.0} s] {line}", start.elapsed().as_secs_f64());
        }
    }
}

/// Names the files a report wrote, unless quiet or the JSON goes to stdout.
fn print_written(written: &[std::path::PathBuf], json: &JsonOutput, quiet: bool) {
    if !quiet && !json.is_requested() {
        for path in written {
            println!("wrote {}", path.display());
        }
    }
}

fn physics(args: &PhysicsArgs, quiet: bool, json: &JsonOutput) -> Result<(), CliError> {
    let (file, simulate) = args.scene.load()?;
    let options = dormant_lab::bench::PhysicsBenchOptions { simulate, measure_frames: args.measure_frames };
    let report =
        dormant_lab::bench::bench_physics(&file, &options).map_err(super::simulate::physics_error)?;
    emit(&bench_json(&report), json, quiet)
}

fn emit(json: &serde_json::Value, out: &JsonOutput, quiet: bool) -> Result<(), CliError> {
    out.emit(json)?;
    if !quiet && !out.is_requested() {
        println!("{json:#}");
    }
    Ok(())
}

#[cfg(feature = "embree")]
fn instances(
    args: &InstancesArgs,
    threads: Option<usize>,
    quiet: bool,
    json: &JsonOutput,
) -> Result<(), CliError> {
    let opts = bench::InstancesBenchOptions {
        count: args.count as usize,
        rays: args.rays,
        runs: args.runs,
        threads,
    };
    let report = bench::bench_instances(&opts).map_err(|e| CliError::Runtime(e.to_string()))?;
    emit(&bench_json(&report), json, quiet)
}

fn accel(args: &AccelArgs, threads: Option<usize>, quiet: bool, json: &JsonOutput) -> Result<(), CliError> {
    let desc = args.scene.load()?;
    let opts = AccelBenchOptions {
        width: args.size.width,
        height: args.size.height,
        runs: args.runs,
        threads,
        builds_only: args.builds_only,
        backend: args.backend,
        ..AccelBenchOptions::default()
    };
    let report = bench::bench_accel(&desc, &opts).map_err(|e| CliError::Runtime(e.to_string()))?;
    emit(&bench_json(&report), json, quiet)
}

fn render(
    args: &RenderBenchArgs,
    threads: Option<usize>,
    quiet: bool,
    json: &JsonOutput,
) -> Result<(), CliError> {
    let desc = args.scene.load()?;
    let opts = RenderBenchOptions {
        width: args.size.width,
        height: args.size.height,
        spp: args.spp,
        runs: args.runs,
        threads,
        embree_robust: args.embree_robust,
    };
    let report = bench::bench_render(&desc, &opts).map_err(|e| CliError::Runtime(e.to_string()))?;
    emit(&bench_json(&report), json, quiet)
}

fn adaptive(
    args: &AdaptiveBenchArgs,
    threads: Option<usize>,
    quiet: bool,
    json: &JsonOutput,
) -> Result<(), CliError> {
    let desc = args.scene.load()?;
    let input = |flag: &str, what: &str| Err(CliError::Input(format!("{flag}: {what}")));
    if args.uniform_spp.iter().chain([&args.adaptive_spp]).any(|&s| !(1..=MAX_SAMPLES_PER_PIXEL).contains(&s))
    {
        return input("--uniform-spp/--adaptive-spp", &format!("must be from 1 to {MAX_SAMPLES_PER_PIXEL}"));
    }
    if args.thresholds.iter().any(|&t| !(t.is_finite() && t > 0.0)) {
        return input("--thresholds", "must be numbers greater than 0");
    }
    if args.min_spp.is_some_and(|m| m == 0 || m > args.adaptive_spp) {
        return input("--min-spp", "must be from 1 to --adaptive-spp");
    }
    let denoiser = args.denoising.denoiser(threads)?;
    let opts = AdaptiveBenchOptions {
        backend: super::render::choose_backend(args.backend)?,
        width: args.size.width,
        height: args.size.height,
        max_depth: args.max_depth,
        reference_spp: args.reference_spp,
        reference: args.reference.clone(),
        uniform_spp: args.uniform_spp.clone(),
        thresholds: args.thresholds.clone(),
        adaptive_spp: args.adaptive_spp,
        min_spp: args.min_spp,
        denoiser,
    };
    let mut log = timed_log("bench adaptive", quiet);
    let report = bench::bench_adaptive(&desc, &opts, threads, &mut log)
        .map_err(|e| CliError::Runtime(e.to_string()))?;
    emit(&serde_json::to_value(&report).expect("bench report serialises"), json, quiet)
}
