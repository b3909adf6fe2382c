//! `dormant render`: its flags, and the wiring of a still of a built-in or asset scene, or of
//! a sequence of a scene file or trajectory (`sequence.rs`), which a signal stops between
//! frames (`stop.rs`), one render per output folder (`output_lock.rs`); each frame's files
//! and report line (`frame_output.rs`).

mod frame_output;
mod output_lock;
mod sequence;
mod settings;
mod stop;
mod video;

use std::path::{Path, PathBuf};

use clap::Args;
use indicatif::ProgressBar;

use super::denoise::DenoiseArgs;
use super::named::named;
use super::CliError;
use dormant::accel::{self, Backend};
use dormant::physics::SimulateOptions;
use dormant::render;
use dormant::render::{
    AmbientOcclusion, Aov, DirectLighting, FilterKind, ImageSize, Integrator, PathTracer, PixelFilter,
    RenderScene, RenderSettings,
};
use dormant::residency::{CacheBudget, IntegrationForm, IntegrationPolicy};
use dormant::scene::file::spec::RenderDef;
use dormant::scene::file::SceneFile;
use dormant::scene::limits::{shutter_problem, MAX_SAMPLES_PER_PIXEL};
use dormant::sequence::output::FrameWriter;
use dormant::sequence::{
    FrameRange, RenderedFrame, ReuseMode, SeedMode, Sequence, SequenceError, SequenceSource,
    DEFAULT_REUSE_BYTES,
};

use frame_output::FrameOutput;
pub(crate) use output_lock::BUSY_EXIT_CODE;
pub(crate) use settings::Preset;
use settings::Settings;
pub(crate) use stop::{exit_code as stop_exit_code, signal_name};

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

impl RenderMode {
    /// The mode's name on the command line (`--mode path`).
    pub fn name(self) -> &'static str {
        match self {
            RenderMode::Path => "path",
            RenderMode::Shaded => "shaded",
            RenderMode::Ao => "ao",
        }
    }
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
    /// With SCENE: render through the file's camera of this name instead of its
    /// `render.camera` (a trajectory of the file still replays: the camera is not physics).
    #[arg(long, value_name = "NAME", requires = "scene_file")]
    pub camera: Option<String>,
    /// With SCENE or --trajectory: render frames A..B (half-open) of the simulation.
    #[arg(long, value_name = "A..B")]
    pub frames: Option<FrameRange>,
    /// With SCENE or --trajectory: render every N-th frame, counted from frame 0 (default:
    /// the preset's, else the scene's render.frame_step, else 1).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub frame_step: Option<u32>,
    /// With a glTF file as SCENE: frames per second to sample its animation at (files from
    /// dormant's export record it; Blender's do not).
    #[arg(long, value_name = "FPS", requires = "scene_file")]
    pub fps: Option<f64>,
    #[command(flatten)]
    pub scene: super::SceneSource,
    /// With SCENE: directory that relative asset paths in the scene file resolve against
    /// (default: the scene file's own directory).
    #[arg(long, value_name = "DIR", requires = "scene_file")]
    pub assets: Option<PathBuf>,
    /// Output directory; frames are written as frame_NNNN.png.
    #[arg(long, value_name = "DIR", default_value = "out/render")]
    pub out: PathBuf,
    /// Named settings between the flags and the scene file: `preview` is --mode shaded,
    /// --size 320x180, --spp 1, --frame-step 1 and no adaptive sampling; `final` the scene
    /// file's settings. A flag given still wins.
    #[arg(long, value_enum)]
    pub preset: Option<Preset>,
    /// Image size (default: the preset's, else the scene's render.width x render.height,
    /// else 960x540).
    #[arg(long, value_name = "WxH")]
    pub size: Option<ImageSize>,
    /// Samples per pixel; with --noise-threshold, the most a pixel gets (default: the
    /// preset's, else the scene's render.samples_per_pixel, else 16).
    #[arg(long, value_name = "N", allow_negative_numbers = true, value_parser = clap::value_parser!(u32).range(1..=MAX_SAMPLES_PER_PIXEL as i64))]
    pub spp: Option<u32>,
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
    /// Rendering mode: path tracing, direct light only, or ambient occlusion (default: the
    /// preset's, else path).
    #[arg(long, value_enum)]
    pub mode: Option<RenderMode>,
    /// Longest path (bounces) in `path` mode.
    #[arg(long, value_name = "N", default_value_t = 6, value_parser = clap::value_parser!(u32).range(1..=64))]
    pub max_depth: u32,
    /// Largest radiance one indirect contribution may add in `path` mode (like Cycles' Clamp
    /// Indirect, which measures a contribution by the sum of its channels, this one by its
    /// largest); 0 turns clamping off, which keeps the estimator unbiased.
    #[arg(long, value_name = "RADIANCE", default_value_t = 4.0)]
    pub clamp_indirect: f32,
    /// Pixel filter: where each pixel's samples land around its centre (docs/design.md,
    /// "Renderer"). Cycles' default is blackman-harris of width 1.5.
    #[arg(long, value_parser = named::<FilterKind>(), default_value_t = FilterKind::Tent)]
    pub filter: FilterKind,
    /// The pixel filter's width in pixels (default: tent 1, box 1, gaussian 1.5,
    /// blackman-harris 1.5; Cycles' Pixel Filter Width).
    #[arg(long, value_name = "PX")]
    pub filter_width: Option<f32>,
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
    #[arg(long, value_parser = named::<Aov>(), value_delimiter = ',', value_name = "KIND")]
    pub aov: Vec<Aov>,
    /// With SCENE or --trajectory: when sleeping islands leave the per-frame build (how they
    /// are held: --integrate-as).
    #[arg(long, value_parser = named::<IntegrationPolicy>(), default_value_t = IntegrationPolicy::Auto)]
    pub integration: IntegrationPolicy,
    /// With SCENE or --trajectory: how integrated islands are held: baked into the static
    /// scene, or as instances in a resting scene rebuilt on a schedule.
    #[arg(long, value_parser = named::<IntegrationForm>(), default_value_t = IntegrationForm::default())]
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
    #[arg(long, value_parser = named::<SeedMode>(), default_value_t = SeedMode::Fixed)]
    pub seed: SeedMode,
    /// Added to every frame's seed, like Cycles' Seed value: renders of the same frames with
    /// different offsets have independent noise.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub seed_offset: u32,
    /// With a fixed seed: how a frame reuses earlier frames' work. `exact`: trace only the
    /// samples that can see something that moved since they were traced (the simulation's
    /// future is known, so each sample's next change is), take the rest from earlier frames,
    /// bit for bit; `static`: only copy the previous frame's files where
    /// nothing moved and the camera stayed (`on` is an alias); `off`: trace every frame.
    #[arg(long, value_parser = named::<ReuseMode>(), default_value_t = ReuseMode::Exact)]
    pub reuse: ReuseMode,
    /// With --reuse exact: memory its store may keep, in MiB. With room for every sample (16
    /// bytes each, plus the pixels) it keeps samples and retraces only those due; else one
    /// value per pixel and pass (20 bytes, 12 more per AOV: a 3840x2160 frame with every AOV
    /// needs 538 MiB), retracing a due pixel whole. The changes ahead are indexed a window
    /// of frames at a time, in up to an eighth of it (64 MiB at most).
    #[arg(long, value_name = "MIB", default_value_t = DEFAULT_REUSE_BYTES >> 20)]
    pub reuse_mib: usize,
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
    #[command(flatten)]
    pub denoising: DenoiseArgs,
    /// With --denoise: also write the image before denoising as frame_NNNN.noisy.png (and
    /// .noisy.exr with --exr), like Cycles' "Noisy Image" pass.
    #[arg(long, requires = "denoise")]
    pub keep_noisy: bool,
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

/// The integrator for a mode; `path` the path tracer's settings in `path` mode.
pub(super) fn integrator(mode: RenderMode, path: PathTracer) -> Box<dyn Integrator> {
    match mode {
        RenderMode::Path => Box::new(path),
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

/// What every frame of a `render` run is made with.
struct RenderJob<'a> {
    pub args: &'a RenderArgs,
    pub settings: Settings,
    pub backend: Backend,
    pub threads: Option<usize>,
    pub integrator: &'a dyn Integrator,
}

pub(super) fn run(
    args: &RenderArgs,
    threads: Option<usize>,
    quiet: bool,
    json: &super::JsonOutput,
) -> Result<(), CliError> {
    let backend = choose_backend(args.backend)?;
    check_flags(args)?;
    let denoiser = args.denoising.denoiser(threads)?;
    // The scene file is read, and a bad one or bad settings refused, before anything is
    // written (a trajectory alone names its scene's settings once it is read, below).
    let source = sequence_source(args)?;
    if let Some(scene) = known_scene_settings(source.as_ref()) {
        checked_settings(args, scene)?;
    }
    let out = output_dir(&args.out)?;
    let _lock = output_lock::OutputLock::acquire(out)?;
    let sequence = source.map(|source| load_sequence(source, quiet)).transpose()?;
    let settings = checked_settings(args, sequence.as_ref().map(|s| &s.render))?;
    let integrator = integrator(settings.mode.value, path_tracer(args));
    let job = RenderJob { args, settings, backend, threads, integrator: integrator.as_ref() };
    let layout = frame_output::layout(args);
    let mut output = FrameOutput {
        writer: FrameWriter { layout: &layout, exposure: args.exposure, denoiser: denoiser.as_ref() },
        settings,
        backend,
        quiet: quiet || json.is_requested(),
        keep_records: json.is_requested(),
        records: Vec::new(),
        kept: 0,
        video_frames: None,
    };
    let scene_name = match &sequence {
        None => render_still(&job, &mut output)?,
        Some(sequence) => sequence::render_sequence(&job, sequence, &mut output, quiet)?,
    };
    json.emit(&serde_json::json!({
        "scene": scene_name,
        "backend": backend,
        "width": settings.size.value.width,
        "height": settings.size.value.height,
        "spp": settings.spp.value,
        "noise_threshold": settings.noise_threshold.value,
        "min_spp": settings.min_spp.value,
        "mode": settings.mode.value,
        "filter": args.filter.to_string(),
        "filter_width": pixel_filter(args)?.width(),
        "clamp_indirect": args.clamp_indirect,
        "denoise": args.denoising.denoise,
        "integration": sequence.is_some().then_some(args.integration),
        "settings_from": settings.sources(),
        "frames": output.records,
        "kept_frames": output.kept,
    }))
}

/// The output directory, created; a path that names a file is an input error.
fn output_dir(out: &Path) -> Result<&Path, CliError> {
    if out.exists() && !out.is_dir() {
        return Err(CliError::Input(format!(
            "--out {}: is a file, not a directory (frames, stats.json and report.png go into a directory)",
            out.display()
        )));
    }
    std::fs::create_dir_all(out)
        .map_err(|e| CliError::Runtime(format!("cannot create output directory {}: {e}", out.display())))?;
    Ok(out)
}

/// The scene file's `[render]` settings as far as they are known before the sequence loads:
/// `Some(None)` for a still (no scene file), the file's for a scene file, `None` for a
/// trajectory alone (its scene is read with it).
fn known_scene_settings(source: Option<&SequenceSource>) -> Option<Option<&RenderDef>> {
    match source {
        None => Some(None),
        Some(SequenceSource::Scene { file, .. }) => Some(Some(&file.spec().render)),
        Some(_) => None,
    }
}

/// The run's settings from its flags, preset and the scene's `[render]` (`scene`), checked:
/// adaptive sampling against the samples per pixel, and exact reuse's budget against the size.
fn checked_settings(args: &RenderArgs, scene: Option<&RenderDef>) -> Result<Settings, CliError> {
    let settings = Settings::resolve(args, scene);
    settings.adaptive()?;
    check_reuse(args, &settings)?;
    Ok(settings)
}

/// The AOV passes a frame renders: the requested ones in order, then the denoiser's guides
/// that were not requested.
fn aov_passes(args: &RenderArgs) -> Vec<Aov> {
    let mut passes = args.aov.clone();
    if args.denoising.denoise {
        passes.extend(render::denoise::GUIDE_AOVS.iter().filter(|g| !args.aov.contains(g)));
    }
    passes
}

/// The path tracer of `--max-depth` and `--clamp-indirect` (0: no clamping).
fn path_tracer(args: &RenderArgs) -> PathTracer {
    let clamp = if args.clamp_indirect == 0.0 { f32::INFINITY } else { args.clamp_indirect };
    PathTracer { max_depth: args.max_depth, clamp_indirect: clamp }
}

/// `--filter` of `--filter-width`.
pub(super) fn pixel_filter(args: &RenderArgs) -> Result<PixelFilter, CliError> {
    PixelFilter::new(args.filter, args.filter_width)
        .map_err(|e| CliError::Input(format!("--filter-width: {e}")))
}

/// Flags that are wrong whatever the scene.
fn check_flags(args: &RenderArgs) -> Result<(), CliError> {
    if !args.exposure.is_finite() || args.exposure <= 0.0 {
        return Err(CliError::Input(format!("--exposure {}: must be a positive number", args.exposure)));
    }
    if !(args.clamp_indirect.is_finite() && args.clamp_indirect >= 0.0) {
        return Err(CliError::Input(format!(
            "--clamp-indirect {}: must be a number, 0 (off) or more",
            args.clamp_indirect
        )));
    }
    pixel_filter(args)?;
    check_shutter(args.shutter)?;
    if args.reuse_mib == 0 {
        return Err(CliError::Input("--reuse-mib 0: must be at least 1".into()));
    }
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
        if !video::ffmpeg_available() {
            return Err(CliError::Input(video::VideoError::FfmpegMissing.to_string()));
        }
    }
    Ok(())
}

/// With exact reuse of a sequence, `--reuse-mib` large enough for a store of one value per
/// pixel and pass at the run's size with the passes rendered.
fn check_reuse(args: &RenderArgs, settings: &Settings) -> Result<(), CliError> {
    // Only a sequence reuses; whether this one does is the reuse decision's.
    if args.scene_file.is_none() && args.trajectory.is_none() {
        return Ok(());
    }
    let budget = sequence::reuse_budget(args)?;
    let size = settings.size.value;
    let decided = args.reuse.decide(args.seed == SeedMode::Fixed, size, &aov_passes(args), budget);
    decided.map(|_| ()).map_err(|e| CliError::Input(format!("--reuse-mib {}: {e}", args.reuse_mib)))
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
    let scene = SceneArgs { file: args.scene_file.as_deref(), assets: args.assets.as_deref(), fps: args.fps };
    let source = sequence_source_of(scene, args.trajectory.as_ref(), args.scene.count)?;
    match (source, &args.camera) {
        (Some(SequenceSource::Scene { file, options, trajectory }), Some(name)) => {
            let file = file.with_render_camera(name).map_err(|e| CliError::Input(e.to_string()))?;
            Ok(Some(SequenceSource::scene(file, options, trajectory)))
        }
        (source, _) => Ok(source),
    }
}

/// A SCENE argument and the flags that say how to read it: `--assets DIR` (relative asset
/// paths), `--fps` (a glTF file's animation).
#[derive(Clone, Copy)]
pub(super) struct SceneArgs<'a> {
    pub file: Option<&'a Path>,
    pub assets: Option<&'a Path>,
    pub fps: Option<f64>,
}

impl SceneArgs<'_> {
    /// The scene file, read and checked; `None` without one.
    pub fn load(&self) -> Result<Option<SceneFile>, CliError> {
        self.file
            .map(|path| SceneFile::load_with_fps(path, self.assets, self.fps))
            .transpose()
            .map_err(|e| CliError::Input(e.to_string()))
    }
}

/// The sequence a SCENE file (with `count` objects), a trajectory, or both give; `None` for
/// neither.
pub(super) fn sequence_source_of(
    scene: SceneArgs<'_>,
    trajectory: Option<&PathBuf>,
    count: Option<u32>,
) -> Result<Option<SequenceSource>, CliError> {
    Ok(match (scene.load()?, trajectory) {
        (Some(file), trajectory) => {
            let options = SimulateOptions { count, frames: None };
            Some(SequenceSource::scene(file, options, trajectory.cloned()))
        }
        (None, Some(path)) => Some(SequenceSource::Recorded { trajectory: path.clone(), count }),
        (None, None) => None,
    })
}

/// The built-in scene or an asset pile, as one frame; returns the scene's name.
fn render_still(job: &RenderJob<'_>, output: &mut FrameOutput<'_>) -> Result<String, CliError> {
    let args = job.args;
    let runtime = |e: &dyn std::fmt::Display| CliError::Runtime(e.to_string());
    let description = args.scene.load()?;
    let mut accel = accel::create(job.backend, job.threads).map_err(|e| runtime(&e))?;
    let scene = RenderScene::build(&description, accel.as_mut()).map_err(|e| runtime(&e))?;
    let query = accel.query().map_err(|e| runtime(&e))?;
    let size = job.settings.size.value;
    let settings = RenderSettings {
        width: size.width,
        height: size.height,
        spp: job.settings.spp.value,
        seed: args.seed_offset,
        adaptive: job.settings.adaptive()?,
        filter: pixel_filter(args)?,
    };
    let (film, stats, aovs) =
        render::render_with_aovs(&scene, query, job.integrator, &settings, &aov_passes(args))
            .map_err(|e| runtime(&e))?;
    let frame = RenderedFrame { index: 0, film, render: stats, aovs, reused_from: None, reuse: None };
    output.write(&frame, None, &ProgressBar::hidden())?;
    Ok(description.name)
}

/// `--cache on|off`, `--lookahead on|off`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Switch {
    On,
    Off,
}
