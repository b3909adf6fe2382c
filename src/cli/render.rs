//! `dormant render`: a still of a built-in or asset scene, or a sequence of a scene file or
//! trajectory; the files each frame writes and the run's statistics.

use std::borrow::Cow;
use std::path::{Path, PathBuf};

use clap::Args;
use indicatif::ProgressBar;

use super::CliError;
use dormant::accel::{self, Backend};
use dormant::physics::SimulateOptions;
use dormant::render::{
    self, AdaptiveSampling, AmbientOcclusion, Aov, DenoiseError, Denoiser, DirectLighting, Film, ImageSize,
    Integrator, PathTracer, RenderScene, RenderSettings,
};
use dormant::residency::{
    CacheBudget, FrameStats, IntegrationForm, IntegrationPolicy, IntegrationSettings, SceneManager,
};
use dormant::scene::file::SceneFile;
use dormant::scene::limits::{shutter_problem, MAX_SAMPLES_PER_PIXEL};
use dormant::sequence::stats::{FrameRecord, RunInfo, StatsFile};
use dormant::sequence::{
    FrameRange, FrameRenderer, FrameSelection, KeptFrame, RenderedFrame, SeedMode, Sequence, SequenceError,
    SequenceSource,
};

/// What a render computes per pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum RenderMode {
    /// Path tracing: sun, sky and indirect light, MIS, GGX metallic-roughness.
    Path,
    /// Direct light only (sun and sky with shadows): the quick preview.
    Shaded,
    /// Ambient occlusion within one scene unit.
    Ao,
}

#[derive(Debug, Args)]
pub struct RenderArgs {
    /// Scene file to simulate and render (default: the built-in scene, or --env/--object).
    #[arg(value_name = "SCENE", conflicts_with_all = ["env", "object"])]
    pub scene_file: Option<PathBuf>,
    /// Replay this trajectory (from `dormant simulate`) instead of simulating; without SCENE,
    /// render the scene recorded in it.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["env", "object"])]
    pub trajectory: Option<PathBuf>,
    /// With SCENE or --trajectory: render frames A..B (half-open) of the simulation.
    #[arg(long, value_name = "A..B")]
    pub frames: Option<FrameRange>,
    /// With SCENE or --trajectory: render every N-th frame, counted from frame 0 (default:
    /// the scene's render.frame_step).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub frame_step: Option<u32>,
    #[command(flatten)]
    pub scene: super::SceneSource,
    /// Output directory; frames are written as frame_NNNN.png.
    #[arg(long, value_name = "DIR", default_value = "out/render")]
    pub out: PathBuf,
    /// Image size.
    #[arg(long, value_name = "WxH", default_value = "960x540")]
    pub size: ImageSize,
    /// Samples per pixel; with --noise-threshold, the most a pixel gets.
    #[arg(long, value_name = "N", default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..=MAX_SAMPLES_PER_PIXEL as i64))]
    pub spp: u32,
    /// Adaptive sampling: the noise level left in the image. A pixel stops once its estimated
    /// relative error (the standard error of its mean over its value, the value at least 0.1)
    /// is at most T x sqrt(σ), σ the relative spread of its samples: T is the noise left in a
    /// pixel with σ = 1, e.g. 0.07; 0 = off, every pixel gets --spp (default: the scene's
    /// render.noise_threshold, else 0).
    #[arg(long, value_name = "T", allow_negative_numbers = true)]
    pub noise_threshold: Option<f32>,
    /// With --noise-threshold: samples every pixel gets before its error is first checked
    /// (then every 4); default: the scene's render.min_spp, else max(8, √spp), at most spp.
    #[arg(long, value_name = "N")]
    pub min_spp: Option<u32>,
    /// Rendering mode: path tracing, direct light only, or ambient occlusion.
    #[arg(long, value_enum, default_value_t = RenderMode::Path)]
    pub mode: RenderMode,
    /// Longest path (bounces) in `path` mode.
    #[arg(long, value_name = "N", default_value_t = 6, value_parser = clap::value_parser!(u32).range(1..=64))]
    pub max_depth: u32,
    /// Ray tracing backend (default: the first compiled in, Embree preferred).
    #[arg(long)]
    pub backend: Option<Backend>,
    /// Also write linear HDR radiance as frame_NNNN.exr.
    #[arg(long)]
    pub exr: bool,
    /// Also write these passes (comma-separated) as frame_NNNN.KIND.png, and as .exr with
    /// --exr: albedo (textured base colour), normal (shading normal), depth (distance),
    /// baked (debug: instanced bodies blue, integrated ones orange, environment grey), spp
    /// (camera samples per pixel, grey up to the frame's most; the counts in the EXR).
    #[arg(long, value_enum, value_delimiter = ',', value_name = "KIND")]
    pub aov: Vec<Aov>,
    /// With SCENE or --trajectory: when sleeping islands are baked into the static scene.
    #[arg(long, value_enum, default_value_t = IntegrationPolicy::Auto)]
    pub integration: IntegrationPolicy,
    /// With SCENE or --trajectory: how integrated islands are held: baked into the static
    /// scene, or as instances in a resting scene rebuilt on a schedule.
    #[arg(long, value_enum, default_value_t = IntegrationForm::default())]
    pub integrate_as: IntegrationForm,
    /// With SCENE or --trajectory: serve reactivations of baked islands from the geometry cache.
    #[arg(long, value_enum, default_value_t = Switch::On)]
    pub cache: Switch,
    /// With SCENE or --trajectory: memory the geometry cache's saved scenes may keep alive
    /// beyond the live scene, in MiB (least valuable entries are evicted beyond it).
    #[arg(long, value_name = "MIB", default_value_t = CacheBudget::DEFAULT.bytes >> 20)]
    pub cache_mib: usize,
    /// With SCENE or --trajectory: most saved scenes in the geometry cache at once.
    #[arg(long, value_name = "N", default_value_t = CacheBudget::DEFAULT.entries)]
    pub cache_entries: usize,
    /// With SCENE or --trajectory: let `auto` use the run's known future (each island's true
    /// remaining sleep over the rendered frames) instead of estimating it.
    #[arg(long, value_enum, default_value_t = Switch::On)]
    pub lookahead: Switch,
    /// How frames seed the sampler: one seed for all (like Cycles' default; a frame where
    /// nothing moved is then the previous image, copied instead of traced) or the frame number
    /// (noise changes from frame to frame).
    #[arg(long, value_enum, default_value_t = SeedMode::Fixed)]
    pub seed: SeedMode,
    /// With a fixed seed: copy the previous frame's files for frames where nothing moved and
    /// the camera stayed, instead of tracing them (`off` traces every frame).
    #[arg(long, value_enum, default_value_t = Switch::On)]
    pub reuse: Switch,
    /// With SCENE or --trajectory: continue a run that was interrupted in --out DIR. Frames
    /// whose files are all there and whose statistics DIR/stats.json holds are not rendered
    /// again (the island events and decisions up to them are replayed); the rest are. DIR's
    /// stats.json must come from the same options (exit 2 otherwise); without one, every
    /// frame renders.
    #[arg(long)]
    pub resume: bool,
    /// With SCENE or --trajectory: also encode the frames as DIR/video.mp4 (needs ffmpeg on PATH).
    #[arg(long)]
    pub video: bool,
    /// With SCENE or --trajectory: motion blur. The shutter as a fraction of the frame interval
    /// (the trajectory's timestep), centred on each frame, from 0 (off) to 1; default: the
    /// scene's render.shutter, else 0. Cycles' default when blur is on is 0.5.
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    pub shutter: Option<f32>,
    /// Exposure multiplier applied before tone mapping.
    #[arg(long, default_value_t = 1.0)]
    pub exposure: f32,
    /// Denoise each image with Intel Open Image Denoise (OIDN 2, CPU), guided by the albedo and
    /// normal passes (rendered for it even when --aov does not ask for them). Needs the
    /// `oidn` feature, which `scripts/setup.sh` makes available.
    #[arg(long)]
    pub denoise: bool,
    /// With --denoise: also write the image before denoising as frame_NNNN.noisy.png (and
    /// .noisy.exr with --exr), like Cycles' "Noisy Image" pass.
    #[arg(long, requires = "denoise")]
    pub keep_noisy: bool,
    /// With --denoise: denoise the albedo and normal guides first (like Cycles' "Accurate"
    /// prefilter): less error on fine texture edges, about six times the denoising time.
    #[arg(long, requires = "denoise")]
    pub denoise_prefilter: bool,
}

/// The requested backend, or the first compiled in.
pub(super) fn choose_backend(requested: Option<Backend>) -> Result<Backend, CliError> {
    match requested {
        Some(b) if !b.is_compiled() => {
            Err(CliError::Input(format!("backend '{b}' is not compiled into this build")))
        }
        Some(b) => Ok(b),
        None => Backend::compiled().first().copied().ok_or_else(|| {
            CliError::Input(
                "no ray tracing backend is compiled in: Embree is not compiled in (build with the default \
                 feature `embree`)"
                    .into(),
            )
        }),
    }
}

/// The integrator for a mode.
pub(super) fn integrator(mode: RenderMode, max_depth: u32) -> Box<dyn Integrator> {
    match mode {
        RenderMode::Path => Box::new(PathTracer { max_depth, ..PathTracer::default() }),
        RenderMode::Shaded => Box::new(DirectLighting),
        RenderMode::Ao => Box::new(AmbientOcclusion { radius: 1.0 }),
    }
}

/// A sequence error as the CLI reports it; `flag` names the option that gave a frame range.
pub(super) fn sequence_error(e: SequenceError, flag: &str) -> CliError {
    match e {
        SequenceError::Range { .. } => CliError::Input(format!("{flag} {e}")),
        e if e.is_input() => CliError::Input(e.to_string()),
        e => CliError::Runtime(e.to_string()),
    }
}

/// Loads a sequence from `source`, with a progress bar while it simulates.
pub(super) fn load_sequence(source: SequenceSource, quiet: bool) -> Result<Sequence, CliError> {
    let bar = super::progress::frames_bar(quiet, "simulating", None);
    let sequence = Sequence::load(source, &mut |step| {
        bar.set_length(u64::from(step.frames));
        bar.inc(1);
    })
    .map_err(|e| sequence_error(e, ""))?;
    bar.finish_and_clear();
    Ok(sequence)
}

pub(super) fn run(
    args: &RenderArgs,
    threads: Option<usize>,
    quiet: bool,
    json: &super::JsonOutput,
) -> Result<(), CliError> {
    let backend = choose_backend(args.backend)?;
    check_flags(args)?;
    let denoiser = args
        .denoise
        .then(|| Denoiser::new(threads).map(|d| d.prefilter(args.denoise_prefilter)))
        .transpose()
        .map_err(denoise_error)?;
    std::fs::create_dir_all(&args.out).map_err(|e| {
        CliError::Runtime(format!("cannot create output directory {}: {e}", args.out.display()))
    })?;
    let integrator = integrator(args.mode, args.max_depth);
    let mut writer = FrameWriter {
        args,
        backend,
        denoiser: denoiser.as_ref(),
        quiet: quiet || json.is_requested(),
        keep_records: json.is_requested(),
        records: Vec::new(),
        kept: 0,
    };
    let (scene_name, is_sequence) = match sequence_source(args)? {
        None => (render_still(args, backend, threads, integrator.as_ref(), &mut writer)?, false),
        Some(source) => {
            let sequence = load_sequence(source, quiet)?;
            (
                render_sequence(args, &sequence, backend, threads, integrator.as_ref(), &mut writer, quiet)?,
                true,
            )
        }
    };
    json.emit(&serde_json::json!({
        "scene": scene_name,
        "backend": backend,
        "width": args.size.width,
        "height": args.size.height,
        "spp": args.spp,
        "noise_threshold": args.noise_threshold,
        "min_spp": args.min_spp,
        "mode": args.mode,
        "denoise": args.denoise,
        "integration": is_sequence.then_some(args.integration),
        "frames": writer.records,
        "kept_frames": writer.kept,
    }))
}

/// A denoiser that cannot start: a missing library (or a build without it) is the user's to
/// fix (exit 2), anything else a runtime failure.
fn denoise_error(e: DenoiseError) -> CliError {
    if e.is_missing_library() {
        CliError::Input(e.to_string())
    } else {
        CliError::Runtime(e.to_string())
    }
}

/// The AOV passes a frame renders: the requested ones in order, then the denoiser's guides
/// that were not requested.
fn aov_passes(args: &RenderArgs) -> Vec<Aov> {
    let mut passes = args.aov.clone();
    if args.denoise {
        passes.extend(render::denoise::GUIDE_AOVS.iter().filter(|g| !args.aov.contains(g)));
    }
    passes
}

/// Flags that are wrong whatever the scene.
fn check_flags(args: &RenderArgs) -> Result<(), CliError> {
    if !args.exposure.is_finite() || args.exposure <= 0.0 {
        return Err(CliError::Input(format!("--exposure {}: must be a positive number", args.exposure)));
    }
    check_shutter(args.shutter)?;
    let sequence = args.scene_file.is_some() || args.trajectory.is_some();
    if !sequence {
        for (flag, given) in [
            ("--frames", args.frames.is_some()),
            ("--frame-step", args.frame_step.is_some()),
            ("--resume", args.resume),
            ("--shutter", args.shutter.is_some()),
        ] {
            if given {
                return Err(CliError::Input(format!("{flag} needs a SCENE file or --trajectory")));
            }
        }
    }
    if args.video {
        if !sequence {
            return Err(CliError::Input(
                "--video needs a SCENE file or --trajectory (a sequence of frames)".into(),
            ));
        }
        if !render::ffmpeg_available() {
            return Err(CliError::Input(render::VideoError::FfmpegMissing.to_string()));
        }
    }
    Ok(())
}

/// Adaptive sampling from `--noise-threshold` and `--min-spp`, else from the scene file of
/// `sequence` (`render.noise_threshold`, `render.min_spp`), else off; each checked naming the
/// flag or field it came from.
fn adaptive_sampling(args: &RenderArgs, sequence: Option<&Sequence>) -> Result<AdaptiveSampling, CliError> {
    let file = sequence.map(|s| s.adaptive).unwrap_or_default();
    let noise_threshold = args.noise_threshold.unwrap_or(file.noise_threshold);
    if !(noise_threshold.is_finite() && noise_threshold >= 0.0) {
        return Err(CliError::Input(format!(
            "--noise-threshold {noise_threshold}: must be a number, 0 (off) or more"
        )));
    }
    let adaptive = AdaptiveSampling { noise_threshold, min_spp: args.min_spp.or(file.min_spp) };
    if !adaptive.is_on() {
        return match args.min_spp {
            Some(_) => Err(CliError::Input(
                "--min-spp needs adaptive sampling: --noise-threshold (or the scene's render.noise_threshold) \
                 above 0"
                    .into(),
            )),
            None => Ok(AdaptiveSampling::OFF),
        };
    }
    match adaptive.min_spp {
        Some(min) if min == 0 || min > args.spp => {
            let from = if args.min_spp.is_some() { "--min-spp" } else { "the scene's render.min_spp" };
            Err(CliError::Input(format!("{from} {min}: must be from 1 to --spp ({})", args.spp)))
        }
        _ => Ok(adaptive),
    }
}

/// `--shutter S` (render, verify, bench integration): from 0 to 1.
pub(super) fn check_shutter(shutter: Option<f32>) -> Result<(), CliError> {
    match shutter.and_then(shutter_problem) {
        Some(problem) => Err(CliError::Input(format!("--shutter {problem}"))),
        None => Ok(()),
    }
}

/// A sequence: a scene file, maybe with a trajectory of it, or a trajectory alone with the
/// scene recorded in it; `None` for a still.
fn sequence_source(args: &RenderArgs) -> Result<Option<SequenceSource>, CliError> {
    sequence_source_of(args.scene_file.as_deref(), args.trajectory.as_ref(), args.scene.count)
}

/// The sequence a SCENE file (with `count` objects), a trajectory, or both give; `None` for
/// neither.
pub(super) fn sequence_source_of(
    scene_file: Option<&Path>,
    trajectory: Option<&PathBuf>,
    count: Option<u32>,
) -> Result<Option<SequenceSource>, CliError> {
    Ok(match (scene_file, trajectory) {
        (Some(path), trajectory) => {
            let file = SceneFile::load(path).map_err(|e| CliError::Input(e.to_string()))?;
            let options = SimulateOptions { count, frames: None };
            Some(SequenceSource::scene(file, options, trajectory.cloned()))
        }
        (None, Some(path)) => Some(SequenceSource::Recorded { trajectory: path.clone(), count }),
        (None, None) => None,
    })
}

/// The built-in scene or an asset pile, as one frame; returns the scene's name.
fn render_still(
    args: &RenderArgs,
    backend: Backend,
    threads: Option<usize>,
    integrator: &dyn Integrator,
    writer: &mut FrameWriter<'_>,
) -> Result<String, CliError> {
    let runtime = |e: &dyn std::fmt::Display| CliError::Runtime(e.to_string());
    let description = args.scene.load()?;
    let mut accel = accel::create(backend, threads).map_err(|e| runtime(&e))?;
    let scene = RenderScene::build(&description, accel.as_mut()).map_err(|e| runtime(&e))?;
    let query = accel.query().map_err(|e| runtime(&e))?;
    let settings = RenderSettings {
        width: args.size.width,
        height: args.size.height,
        spp: args.spp,
        seed: 0,
        adaptive: adaptive_sampling(args, None)?,
    };
    let (film, stats, aovs) =
        render::render_with_aovs(&scene, query, integrator, &settings, &aov_passes(args))
            .map_err(|e| runtime(&e))?;
    let frame = RenderedFrame { index: 0, film, render: stats, aovs, reused_from: None };
    writer.write(&frame, None, &ProgressBar::hidden())?;
    Ok(description.name)
}

/// The selected frames of `sequence` through one scene manager, with `stats.json` and
/// `stats.csv` written as frames finish, then `report.png` and, with `--video`, `video.mp4`;
/// with `--resume`, the frames an earlier run finished are kept. Returns the scene's name.
fn render_sequence(
    args: &RenderArgs,
    sequence: &Sequence,
    backend: Backend,
    threads: Option<usize>,
    integrator: &dyn Integrator,
    writer: &mut FrameWriter<'_>,
    quiet: bool,
) -> Result<String, CliError> {
    let frames = sequence.select(args.frames, args.frame_step).map_err(|e| sequence_error(e, "--frames"))?;
    let mut manager = scene_manager(args, sequence, &frames, backend, threads)?;
    let passes = aov_passes(args);
    let renderer = FrameRenderer {
        integrator,
        aovs: &passes,
        width: args.size.width,
        height: args.size.height,
        spp: args.spp,
        adaptive: adaptive_sampling(args, Some(sequence))?,
        seed: args.seed,
        reuse_static: args.reuse == Switch::On,
        shutter: shutter(args, sequence),
    };
    let denoise = writer.denoiser.map(Denoiser::label);
    let info = run_info(args, sequence, backend, &frames, renderer.adaptive, denoise);
    let kept = if args.resume { super::resume::kept_frames(args, &info, &frames)? } else { Vec::new() };
    if args.resume && !writer.quiet {
        println!("{}", super::resume::summary(&kept, &frames));
    }
    writer.kept = kept.len();
    let mut frame_paths: Vec<PathBuf> = match args.video {
        true => kept.iter().map(|r| frame_files(args, r.frame).remove(0)).collect(),
        false => Vec::new(),
    };
    let kept_frames: Vec<KeptFrame> = kept.iter().map(FrameRecord::kept).collect();
    let physics_total_ms = (!sequence.physics_ms.is_empty()).then(|| sequence.physics_ms.iter().sum::<f64>());
    // Reserved up front: doubling a long run's records leaves the old buffers behind as holes
    // in the heap (resident memory jumped 1.2 MB at 8,192 frames in the soak).
    let mut records = Vec::with_capacity(frames.count() as usize);
    records.extend(kept);
    let mut stats_file = StatsFile::new(&args.out, info, physics_total_ms, records);
    let progress = super::progress::frames_bar(quiet, "rendering", Some(u64::from(frames.count())));
    progress.set_position(kept_frames.len() as u64);
    let (mut rays, mut trace_seconds) = (0u64, 0.0f64);
    let runtime = |e: &dyn std::fmt::Display| CliError::Runtime(e.to_string());
    let rendered =
        sequence.render(&frames, &mut manager, &renderer, &kept_frames, &mut |frame, stats, manager| {
            let path = writer.write(frame, Some(stats), &progress)?;
            if args.video {
                frame_paths.push(path);
            }
            let physics = sequence.physics_ms.get(frame.index as usize).copied();
            let record = FrameRecord::new(stats, &frame.render, physics);
            stats_file.push(record, manager).map_err(|e| runtime(&e))?;
            rays += frame.render.rays;
            trace_seconds += frame.render.seconds;
            let mrays = if trace_seconds > 0.0 { rays as f64 / trace_seconds / 1e6 } else { 0.0 };
            progress.set_message(format!(
                "frame {} | {mrays:.1} Mrays/s | {} islands integrated",
                frame.index, stats.integrated_islands
            ));
            progress.inc(1);
            Ok::<(), LoopError>(())
        });
    rendered.map_err(|e| e.into_cli(&args.out))?;
    progress.finish_and_clear();
    let run_stats = stats_file.finish(&manager).map_err(|e| runtime(&e))?;
    crate::report::write_report_png(&run_stats, &args.out.join("report.png")).map_err(|e| runtime(&e))?;
    if args.video {
        let fps = 1.0 / (f64::from(sequence.trajectory.timestep) * f64::from(frames.step()));
        encode_video(args, &frame_paths, fps, writer.quiet)?;
    }
    Ok(sequence.template.name.clone())
}

/// The scene manager of a sequence's run: the integration flags, and the geometry cache's
/// budget.
fn scene_manager(
    args: &RenderArgs,
    sequence: &Sequence,
    frames: &FrameSelection,
    backend: Backend,
    threads: Option<usize>,
) -> Result<SceneManager, CliError> {
    let settings = IntegrationSettings {
        policy: args.integration,
        form: args.integrate_as,
        cache: args.cache == Switch::On,
        lookahead: args.lookahead == Switch::On,
    };
    let mut manager_options = sequence.manager_options(frames, settings);
    let cache_bytes = args.cache_mib.checked_mul(1 << 20).ok_or_else(|| {
        CliError::Input(format!("--cache-mib {}: too large for this machine", args.cache_mib))
    })?;
    manager_options.cache_budget = CacheBudget { bytes: cache_bytes, entries: args.cache_entries };
    manager_options.shutter = shutter(args, sequence);
    sequence.manager(backend, threads, manager_options).map_err(|e| sequence_error(e, "--frames"))
}

/// What stops a sequence's render loop: the sequence, or writing a frame's files.
enum LoopError {
    Sequence(SequenceError),
    Cli(CliError),
}

impl From<SequenceError> for LoopError {
    fn from(e: SequenceError) -> Self {
        LoopError::Sequence(e)
    }
}

impl From<CliError> for LoopError {
    fn from(e: CliError) -> Self {
        LoopError::Cli(e)
    }
}

impl LoopError {
    /// The error as the CLI reports it; a kept frame that does not replay names the statistics
    /// file in `out` it was kept from.
    fn into_cli(self, out: &Path) -> CliError {
        match self {
            LoopError::Sequence(e @ SequenceError::KeptMismatch { .. }) => CliError::Input(format!(
                "{}: {e}; remove it to render every frame again",
                out.join("stats.json").display()
            )),
            LoopError::Sequence(e) => sequence_error(e, "--frames"),
            LoopError::Cli(e) => e,
        }
    }
}

/// The header of the run's statistics: every option that decides its images and statistics.
fn run_info(
    args: &RenderArgs,
    sequence: &Sequence,
    backend: Backend,
    frames: &FrameSelection,
    adaptive: AdaptiveSampling,
    denoise: Option<&str>,
) -> RunInfo {
    RunInfo {
        scene: sequence.template.name.clone(),
        backend: backend.to_string(),
        mode: json_name(&args.mode),
        integration: json_name(&args.integration),
        integrate_as: json_name(&args.integrate_as),
        cache_enabled: args.cache == Switch::On,
        lookahead: args.lookahead == Switch::On,
        width: args.size.width,
        height: args.size.height,
        spp: args.spp,
        noise_threshold: adaptive.noise_threshold,
        min_spp: adaptive.is_on().then(|| adaptive.min_spp(args.spp)),
        physics: sequence.physics,
        scene_hash: format!("{:016x}", sequence.trajectory.scene_hash),
        trajectory_frames: sequence.frame_count(),
        frame_start: frames.start(),
        frame_end: frames.end(),
        frame_step: frames.step(),
        max_depth: (args.mode == RenderMode::Path).then_some(args.max_depth),
        seed: json_name(&args.seed),
        reuse: args.reuse == Switch::On,
        exposure: args.exposure,
        aovs: args.aov.iter().map(|a| a.name().to_string()).collect(),
        exr: args.exr,
        denoise: denoise.map(str::to_string),
        keep_noisy: args.keep_noisy,
        shutter: shutter(args, sequence),
    }
}

/// The run's shutter: `--shutter`, else the scene's `render.shutter`.
fn shutter(args: &RenderArgs, sequence: &Sequence) -> f32 {
    args.shutter.unwrap_or(sequence.shutter)
}

/// `video.mp4` from the written frames.
fn encode_video(args: &RenderArgs, frame_paths: &[PathBuf], fps: f64, quiet: bool) -> Result<(), CliError> {
    let video = args.out.join("video.mp4");
    render::encode_video(&args.out, frame_paths, fps, &video).map_err(|e| match e {
        render::VideoError::FfmpegMissing => CliError::Input(e.to_string()),
        e => CliError::Runtime(e.to_string()),
    })?;
    if !quiet {
        println!("wrote {} ({} frames, {fps:.2} fps)", video.display(), frame_paths.len());
    }
    Ok(())
}

/// Writes each rendered frame's files (image, EXR, noisy image, AOVs), denoising the image
/// first with `--denoise`, and, for `--json`, keeps its JSON record.
struct FrameWriter<'a> {
    args: &'a RenderArgs,
    backend: Backend,
    /// With `--denoise`: the device every frame goes through.
    denoiser: Option<&'a Denoiser>,
    /// No per-frame line on stdout (`--quiet`, or the JSON report goes there).
    quiet: bool,
    /// Keep each frame's record for the `--json` report. Only then: a record is about 5.5 kB,
    /// which a long sequence would otherwise accumulate for nothing (some 55 MB over the
    /// soak's 10,000 frames, docs/performance.md#soak-make-soak).
    keep_records: bool,
    records: Vec<serde_json::Value>,
    /// Frames kept from an earlier run (`--resume`), not written again.
    kept: usize,
}

impl FrameWriter<'_> {
    /// Writes `frame`'s files atomically (a reused frame's are copies of its source's);
    /// returns the image's path.
    fn write(
        &mut self,
        frame: &RenderedFrame,
        scene_stats: Option<&FrameStats>,
        progress: &ProgressBar,
    ) -> Result<PathBuf, CliError> {
        let (args, index) = (self.args, frame.index);
        let files = frame_files(args, index);
        let denoise_seconds = match frame.reused_from {
            Some(source) => {
                for (from, to) in frame_files(args, source).iter().zip(&files) {
                    copy_atomic(from, to)?;
                }
                None
            }
            None => self.write_images(frame, &files)?,
        };
        let path = files[0].clone();
        let stats = &frame.render;
        if !self.quiet {
            progress.suspend(|| println!("{}", self.summary(&path, frame, denoise_seconds)));
        }
        if !self.keep_records {
            return Ok(path);
        }
        // Files per pass (PNG, and EXR with --exr); the image and the noisy image come first.
        let per_pass = if args.exr { 2 } else { 1 };
        let noisy_path = args.keep_noisy.then(|| &files[per_pass]);
        let aov_paths: Vec<&PathBuf> = files
            .iter()
            .skip(per_pass * (1 + usize::from(args.keep_noisy)))
            .filter(|p| p.extension().is_some_and(|e| e == "png"))
            .collect();
        self.records.push(serde_json::json!({ "frame": index, "path": path, "rays": stats.rays,
            "seconds": stats.seconds, "mrays_per_second": stats.mrays_per_second(), "aovs": aov_paths,
            "spp_mean": stats.spp.mean, "spp_min": stats.spp.min, "spp_max": stats.spp.max,
            "denoise_seconds": denoise_seconds, "noisy_path": noisy_path,
            "reused_from": frame.reused_from, "scene": scene_stats }));
        Ok(path)
    }

    /// Encodes the image (denoised with `--denoise`), the noisy image (`--keep-noisy`) and
    /// the requested AOVs of a traced frame to `files` (from [`frame_files`]); returns the
    /// seconds denoising took.
    fn write_images(&self, frame: &RenderedFrame, files: &[PathBuf]) -> Result<Option<f64>, CliError> {
        let runtime = |e: &dyn std::fmt::Display| CliError::Runtime(e.to_string());
        let mut files = files.iter();
        let mut next = || files.next().expect("frame_files lists every file");
        let exr = self.args.exr;
        let (image, denoise_seconds) = self.denoised(frame)?;
        let noisy = self.args.keep_noisy.then_some(&frame.film);
        for film in std::iter::once(image.as_ref()).chain(noisy) {
            render::write_png_atomic(film, self.args.exposure, next()).map_err(|e| runtime(&e))?;
            if exr {
                render::write_exr_atomic(film, next()).map_err(|e| runtime(&e))?;
            }
        }
        // The requested passes come first; the denoiser's extra guides are not written.
        for (aov, film) in frame.aovs.iter().take(self.args.aov.len()) {
            render::write_aov_png_atomic(film, *aov, next()).map_err(|e| runtime(&e))?;
            if exr {
                render::write_exr_atomic(film, next()).map_err(|e| runtime(&e))?;
            }
        }
        Ok(denoise_seconds)
    }

    /// The frame's image, denoised with `--denoise` (its guides are among the frame's AOVs),
    /// and the seconds denoising took.
    fn denoised<'f>(&self, frame: &'f RenderedFrame) -> Result<(Cow<'f, Film>, Option<f64>), CliError> {
        let Some(denoiser) = self.denoiser else {
            return Ok((Cow::Borrowed(&frame.film), None));
        };
        let guide = |kind: Aov| {
            frame.aovs.iter().find(|(a, _)| *a == kind).map(|(_, f)| f).expect("--denoise renders its guides")
        };
        let (film, seconds) =
            denoiser.denoise(&frame.film, guide(Aov::Albedo), guide(Aov::Normal)).map_err(denoise_error)?;
        Ok((Cow::Owned(film), Some(seconds)))
    }

    /// The line printed for a written frame.
    fn summary(&self, path: &Path, frame: &RenderedFrame, denoise_seconds: Option<f64>) -> String {
        let args = self.args;
        if let Some(source) = frame.reused_from {
            return format!(
                "wrote {} (nothing moved since frame {source}: its image, not traced)",
                path.display()
            );
        }
        let stats = &frame.render;
        let spp = if stats.spp.min == stats.spp.max {
            format!("{} spp", stats.spp.max)
        } else {
            format!("{:.1} spp mean, {} to {}", stats.spp.mean, stats.spp.min, stats.spp.max)
        };
        format!(
            "rendered {} ({}x{}, {}, {:?} mode, {}): {:.2} s, {} rays, {:.1} Mrays/s",
            path.display(),
            args.size.width,
            args.size.height,
            spp,
            args.mode,
            self.backend,
            stats.seconds,
            stats.rays,
            stats.mrays_per_second()
        ) + &denoise_seconds.map(|s| format!(", denoised in {s:.2} s")).unwrap_or_default()
    }
}

/// The files frame `index` writes, in order: the image (PNG, then EXR with `--exr`), the
/// image before denoising with `--keep-noisy`, then each requested AOV pass the same way.
pub(super) fn frame_files(args: &RenderArgs, index: u32) -> Vec<PathBuf> {
    let base = args.out.join(format!("frame_{index:04}"));
    let mut names = vec![String::new()];
    if args.keep_noisy {
        names.push(".noisy".to_string());
    }
    names.extend(args.aov.iter().map(|a| format!(".{}", a.name())));
    let mut files = Vec::new();
    for name in names {
        files.push(PathBuf::from(format!("{}{name}.png", base.display())));
        if args.exr {
            files.push(PathBuf::from(format!("{}{name}.exr", base.display())));
        }
    }
    files
}

/// Copies `from` to `to` atomically (temporary file, then rename).
fn copy_atomic(from: &Path, to: &Path) -> Result<(), CliError> {
    let bytes = std::fs::read(from)
        .map_err(|e| CliError::Runtime(format!("cannot read {} to reuse it: {e}", from.display())))?;
    dormant::atomic_file::write_atomic(to, &bytes)
        .map_err(|e| CliError::Runtime(format!("cannot write {}: {e}", to.display())))
}

/// A value's JSON name (a unit enum's serde name).
fn json_name(value: &impl serde::Serialize) -> String {
    match serde_json::to_value(value) {
        Ok(serde_json::Value::String(s)) => s,
        Ok(other) => other.to_string(),
        Err(_) => String::new(),
    }
}

/// `--cache on|off`, `--lookahead on|off`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Switch {
    On,
    Off,
}
