//! `dormant bench reuse`: its flags, wired to [`dormant_lab::bench::bench_reuse`].

use std::path::PathBuf;

use clap::Args;

use super::super::denoise::DenoiseArgs;
use super::super::named::named;
use super::super::render::{
    check_shutter, choose_backend, integrator, load_sequence, sequence_error, RenderMode,
};
use super::super::simulate::PhysicsScene;
use super::super::{CliError, JsonOutput};
use super::emit;
use dormant::render::{AdaptiveSampling, Aov, ImageSize};
use dormant::residency::{IntegrationForm, IntegrationPolicy, IntegrationSettings};
use dormant::scene::limits::MAX_SAMPLES_PER_PIXEL;
use dormant::sequence::{FrameRange, ReuseMode, SequenceSource, DEFAULT_REUSE_BYTES};
use dormant_lab::bench::{bench_json, bench_reuse, ReuseBenchOptions};

#[derive(Debug, Args)]
pub struct ReuseArgs {
    #[command(flatten)]
    pub scene: PhysicsScene,
    /// Replay this trajectory (from `dormant simulate` with the same options) instead of
    /// simulating.
    #[arg(long, value_name = "FILE")]
    pub trajectory: Option<PathBuf>,
    /// Render through the scene file's camera of this name, as `render --camera`.
    #[arg(long, value_name = "NAME")]
    pub camera: Option<String>,
    /// Ray tracing backend (default: the first compiled in, Embree preferred).
    #[arg(long)]
    pub backend: Option<dormant::accel::Backend>,
    /// Render frames A..B (half-open) of the simulation.
    #[arg(long, value_name = "A..B")]
    pub frames: Option<FrameRange>,
    /// Render every N-th frame (default: the scene's render.frame_step).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub frame_step: Option<u32>,
    /// Image size.
    #[arg(long, value_name = "WxH", default_value = "960x540")]
    pub size: ImageSize,
    /// Samples per pixel; with --noise-threshold, the most a pixel gets.
    #[arg(long, value_name = "N", default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..=MAX_SAMPLES_PER_PIXEL as i64))]
    pub spp: u32,
    /// Adaptive sampling's noise level, as `render --noise-threshold`; 0 (off) unless given,
    /// whatever the scene's render.noise_threshold (a benchmark keeps its own defaults).
    #[arg(long, value_name = "T", default_value_t = 0.0)]
    pub noise_threshold: f32,
    /// With --noise-threshold: as `render --min-spp`.
    #[arg(long, value_name = "N")]
    pub min_spp: Option<u32>,
    /// What each frame traces.
    #[arg(long, value_enum, default_value_t = RenderMode::Path)]
    pub mode: RenderMode,
    /// AOV passes rendered with each frame (compared too).
    #[arg(long, value_parser = named::<Aov>(), value_delimiter = ',', value_name = "KIND")]
    pub aov: Vec<Aov>,
    /// When sleeping islands are integrated (both modes alike).
    #[arg(long, value_parser = named::<IntegrationPolicy>(), default_value_t = IntegrationPolicy::Auto)]
    pub integration: IntegrationPolicy,
    /// The run without reuse integrates under this policy instead (e.g. `never`: reuse and
    /// integration together against neither).
    #[arg(long, value_parser = named::<IntegrationPolicy>(), value_name = "POLICY")]
    pub off_integration: Option<IntegrationPolicy>,
    /// How integrated islands are held.
    #[arg(long, value_parser = named::<IntegrationForm>(), default_value_t = IntegrationForm::default())]
    pub integrate_as: IntegrationForm,
    /// Motion blur's shutter, as `render --shutter`; 0 (off) unless given, whatever the
    /// scene's render.shutter (a benchmark keeps its own defaults).
    #[arg(long, value_name = "S", default_value_t = 0.0)]
    pub shutter: f32,
    /// Exact reuse's memory, in MiB, as `render --reuse-mib`.
    #[arg(long, value_name = "MIB", default_value_t = DEFAULT_REUSE_BYTES >> 20)]
    pub reuse_mib: usize,
    // Denoise every frame (`--denoise`, as `render`'s), within its frame's time.
    #[command(flatten)]
    pub denoising: DenoiseArgs,
    /// Runs of each mode; the speed-up's spread is over them.
    #[arg(long, value_name = "N", default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..))]
    pub runs: u32,
}

pub(super) fn reuse(
    args: &ReuseArgs,
    threads: Option<usize>,
    quiet: bool,
    json: &JsonOutput,
) -> Result<(), CliError> {
    let backend = choose_backend(args.backend)?;
    check_shutter(Some(args.shutter))?;
    if !args.noise_threshold.is_finite() || args.noise_threshold < 0.0 {
        return Err(CliError::Input(format!(
            "--noise-threshold {}: must be 0 or more",
            args.noise_threshold
        )));
    }
    let reuse_budget = args
        .reuse_mib
        .checked_mul(1 << 20)
        .filter(|&b| b > 0)
        .ok_or_else(|| CliError::Input(format!("--reuse-mib {}: must be at least 1", args.reuse_mib)))?;
    let (mut file, options) = args.scene.load()?;
    if let Some(name) = &args.camera {
        file = file.with_render_camera(name).map_err(|e| CliError::Input(e.to_string()))?;
    }
    let sequence = load_sequence(SequenceSource::scene(file, options, args.trajectory.clone()), quiet)?;
    let frames = sequence.select(args.frames, args.frame_step).map_err(|e| sequence_error(e, "--frames"))?;
    let integration = IntegrationSettings {
        policy: args.integration,
        form: args.integrate_as,
        cache: true,
        lookahead: true,
    };
    let options = ReuseBenchOptions {
        backend,
        frames,
        width: args.size.width,
        height: args.size.height,
        spp: args.spp,
        adaptive: AdaptiveSampling { noise_threshold: args.noise_threshold, min_spp: args.min_spp },
        aovs: args.aov.clone(),
        shutter: args.shutter,
        integration,
        off_integration: args.off_integration.map(|policy| IntegrationSettings { policy, ..integration }),
        reuse_budget,
        threads,
        runs: args.runs as usize,
        denoiser: args.denoising.denoiser(threads)?,
    };
    let integrator = integrator(args.mode, dormant::render::PathTracer::default());
    let total = options.frames.count();
    let mut progress = |run: usize, mode: ReuseMode, done: usize| {
        if !quiet && (done % 20 == 0 || done == total as usize) {
            let mode = if mode == ReuseMode::Off { "off" } else { "exact" };
            eprintln!("bench reuse: run {}, --reuse {mode}: frame {done} of {total}", run + 1);
        }
    };
    let report = bench_reuse(&sequence, integrator.as_ref(), &options, &mut progress)
        .map_err(|e| sequence_error(e, "--frames"))?;
    emit(&bench_json(&report), json, quiet)
}
