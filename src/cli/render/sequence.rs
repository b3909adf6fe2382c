//! A sequence's run: the scene manager from the integration flags, the frames through it with
//! their statistics (until the last, or until a stop signal: `stop.rs`), `report.png` and the
//! video, and what `--resume` keeps.

use std::path::{Path, PathBuf};

use indicatif::ProgressBar;

use super::frame_output::{output_error, FrameInFlight, FrameOutput};
use super::settings::Settings;
use super::stop::StopSignals;
use super::{aov_passes, pixel_filter, sequence_error, RenderArgs, RenderJob, RenderMode, Switch};
use crate::cli::CliError;
use dormant::accel::Backend;
use dormant::render::denoise::Denoiser;
use dormant::render::{Aov, RenderStats};
use dormant::residency::{CacheBudget, IntegrationSettings, SceneManager};
use dormant::sequence::output;
use dormant::sequence::stats::{FrameRecord, RunInfo, RunStats, StatsFile};
use dormant::sequence::{FrameRenderer, FrameSelection, ReuseMode, Sequence, SequenceError};

/// The selected frames of `sequence` through one scene manager, with `stats.json` and
/// `stats.csv` written as frames finish, then `report.png` and, with `--video`, `video.mp4`;
/// with `--resume`, the frames an earlier run finished are kept. Returns the scene's name.
pub(super) fn render_sequence(
    job: &RenderJob<'_>,
    sequence: &Sequence,
    output: &mut FrameOutput<'_>,
    quiet: bool,
) -> Result<String, CliError> {
    let args = job.args;
    let settings = &job.settings;
    let frames = sequence
        .select(args.frames, Some(settings.frame_step.value))
        .map_err(|e| sequence_error(e, "--frames"))?;
    let mut manager = scene_manager(args, settings, sequence, &frames, job.backend, job.threads)?;
    let passes = aov_passes(args);
    let renderer = frame_renderer(job, &passes)?;
    let denoise = output.writer.denoiser.map(Denoiser::label);
    let info = run_info(job, sequence, &frames, &renderer, denoise);
    let kept = kept_frames(args.resume, output, &info, &frames)?;
    output.video_frames = args
        .video
        .then(|| kept.iter().map(|r| output.writer.layout.frame_files(r.frame).remove(0)).collect());
    let kept_frames: Vec<_> = kept.iter().map(FrameRecord::kept).collect();
    let mut stats_file = stats_file(args, sequence, &frames, info, kept);
    let progress = crate::cli::progress::frames_bar(quiet, "rendering", Some(u64::from(frames.count())));
    progress.set_position(kept_frames.len() as u64);
    let mut rate = RayRate::default();
    let mut stop = StopSignals::install()?;
    // A frame's files are written while the next one renders (`FrameOutput::start`).
    let mut in_flight: Option<InFlight> = None;
    let rendered =
        sequence.render(&frames, &mut manager, &renderer, &kept_frames, &mut |frame, stats, manager| {
            if let Some(done) = in_flight.take() {
                land(done, output, &mut stats_file, manager, &progress)?;
            }
            let physics = sequence.physics_ms.get(frame.index as usize).copied();
            in_flight = Some((output.start(frame, Some(stats))?, FrameRecord::of(frame, stats, physics)));
            let mrays = rate.add(&frame.render);
            progress.set_message(format!(
                "frame {} | {mrays:.1} Mrays/s | {} islands integrated",
                frame.index, stats.integrated_islands
            ));
            stop.after_frame(frame.index)?;
            Ok::<(), LoopError>(())
        });
    // The last frame, or the one a stop signal came after.
    let landed = in_flight.map_or(Ok(()), |done| land(done, output, &mut stats_file, &manager, &progress));
    // Stopped by a signal, the run writes its statistics (written at intervals so far) only.
    let stopped = LoopError::stop_of(rendered, &args.out)?;
    landed?;
    progress.finish_and_clear();
    let run_stats = stats_file.finish(&manager).map_err(|e| runtime(&e))?;
    if let Some(stopped) = stopped {
        return Err(stopped);
    }
    write_run_outputs(job, sequence, &frames, output, &run_stats)?;
    Ok(sequence.template.name.clone())
}

/// What a finished run writes besides its frames and statistics: report.png, the line saying
/// where they went, and the video.
fn write_run_outputs(
    job: &RenderJob<'_>,
    sequence: &Sequence,
    frames: &FrameSelection,
    output: &mut FrameOutput<'_>,
    run_stats: &RunStats,
) -> Result<(), CliError> {
    let args = job.args;
    crate::report::write_report_png(run_stats, &args.out.join("report.png")).map_err(|e| runtime(&e))?;
    if !output.quiet {
        let dir = args.out.display();
        println!("wrote {dir}/stats.json, {dir}/stats.csv and {dir}/report.png");
    }
    if args.video {
        let fps = 1.0 / (f64::from(sequence.trajectory.timestep) * f64::from(frames.step()));
        let frame_paths = output.video_frames.take().unwrap_or_default();
        encode_video(args, &frame_paths, fps, output.quiet)?;
    }
    Ok(())
}

/// A frame whose files are being written, and its statistics record.
type InFlight = (FrameInFlight, FrameRecord);

/// Waits for the files of a frame in flight, then counts it done: reported, and its record
/// in the statistics, so that a resumed run keeps only frames whose files are complete.
fn land(
    (files, record): InFlight,
    output: &mut FrameOutput<'_>,
    stats_file: &mut StatsFile,
    manager: &SceneManager,
    progress: &ProgressBar,
) -> Result<(), CliError> {
    output.finish(files, progress)?;
    stats_file.push(record, manager).map_err(|e| runtime(&e))?;
    progress.inc(1);
    Ok(())
}

/// How `job` renders each frame, with the AOV `passes`.
fn frame_renderer<'a>(job: &RenderJob<'a>, passes: &'a [Aov]) -> Result<FrameRenderer<'a>, CliError> {
    let args = job.args;
    let settings = &job.settings;
    Ok(FrameRenderer {
        integrator: job.integrator,
        aovs: passes,
        width: settings.size.value.width,
        height: settings.size.value.height,
        spp: settings.spp.value,
        adaptive: settings.adaptive()?,
        filter: pixel_filter(args)?,
        seed: args.seed,
        seed_offset: args.seed_offset,
        reuse: args.reuse,
        reuse_budget: reuse_budget(args)?,
        shutter: settings.shutter.value,
    })
}

/// `--reuse-mib` in bytes (checked against the frames' needs when the sequence starts).
pub(super) fn reuse_budget(args: &RenderArgs) -> Result<usize, CliError> {
    args.reuse_mib
        .checked_mul(1 << 20)
        .ok_or_else(|| CliError::Input(format!("--reuse-mib {}: too large for this machine", args.reuse_mib)))
}

/// A failure while running, as the CLI reports it.
fn runtime(e: &dyn std::fmt::Display) -> CliError {
    CliError::Runtime(e.to_string())
}

/// With `--resume` (`resume`), the records of the frames an earlier run in the output directory
/// finished (and the line saying so); otherwise none.
fn kept_frames(
    resume: bool,
    output: &mut FrameOutput<'_>,
    info: &RunInfo,
    frames: &FrameSelection,
) -> Result<Vec<FrameRecord>, CliError> {
    if !resume {
        return Ok(Vec::new());
    }
    let kept = output::kept_frames(output.writer.layout, info, frames).map_err(output_error)?;
    if !output.quiet {
        println!("{}", resume_summary(&kept, frames));
    }
    output.kept = kept.len();
    Ok(kept)
}

/// The run's statistics file, holding the kept frames' records.
fn stats_file(
    args: &RenderArgs,
    sequence: &Sequence,
    frames: &FrameSelection,
    info: RunInfo,
    kept: Vec<FrameRecord>,
) -> StatsFile {
    let physics_total_ms = (!sequence.physics_ms.is_empty()).then(|| sequence.physics_ms.iter().sum::<f64>());
    // Reserved up front: doubling a long run's records leaves the old buffers behind as holes
    // in the heap, which the soak saw as resident memory growing.
    let mut records = Vec::with_capacity(frames.count() as usize);
    records.extend(kept);
    StatsFile::new(&args.out, info, physics_total_ms, records)
}

/// The run's rays per second so far, for the progress bar.
#[derive(Default)]
struct RayRate {
    rays: u64,
    seconds: f64,
}

impl RayRate {
    /// Adds a frame; returns the Mrays/s over every frame added.
    fn add(&mut self, stats: &RenderStats) -> f64 {
        self.rays += stats.rays;
        self.seconds += stats.seconds;
        if self.seconds > 0.0 {
            self.rays as f64 / self.seconds / 1e6
        } else {
            0.0
        }
    }
}

/// The scene manager of a sequence's run: the integration flags, the geometry cache's
/// budget and the shutter of `settings`.
fn scene_manager(
    args: &RenderArgs,
    settings: &Settings,
    sequence: &Sequence,
    frames: &FrameSelection,
    backend: Backend,
    threads: Option<usize>,
) -> Result<SceneManager, CliError> {
    let integration = IntegrationSettings {
        policy: args.integration,
        form: args.integrate_as,
        cache: args.cache == Switch::On,
        lookahead: args.lookahead == Switch::On,
    };
    let mut manager_options = sequence.manager_options(frames, integration);
    let cache_bytes = args.cache_mib.checked_mul(1 << 20).ok_or_else(|| {
        CliError::Input(format!("--cache-mib {}: too large for this machine", args.cache_mib))
    })?;
    manager_options.cache_budget = CacheBudget { bytes: cache_bytes, entries: args.cache_entries };
    manager_options.shutter = settings.shutter.value;
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
    /// How the frame loop ended: `Some` stop error when a stop signal ended it after a frame,
    /// `None` when every frame rendered; its error otherwise.
    fn stop_of(rendered: Result<(), LoopError>, out: &Path) -> Result<Option<CliError>, CliError> {
        match rendered {
            Ok(()) => Ok(None),
            Err(LoopError::Cli(stopped @ CliError::Stopped { .. })) => Ok(Some(stopped)),
            Err(e) => Err(e.into_cli(out)),
        }
    }

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
    job: &RenderJob<'_>,
    sequence: &Sequence,
    frames: &FrameSelection,
    renderer: &FrameRenderer<'_>,
    denoise: Option<&str>,
) -> RunInfo {
    let (args, settings, backend) = (job.args, &job.settings, job.backend);
    let adaptive = renderer.adaptive;
    RunInfo {
        scene: sequence.template.name.clone(),
        backend: backend.to_string(),
        mode: json_name(&settings.mode.value),
        integration: json_name(&args.integration),
        integrate_as: json_name(&args.integrate_as),
        cache_enabled: args.cache == Switch::On,
        lookahead: args.lookahead == Switch::On,
        width: renderer.width,
        height: renderer.height,
        spp: renderer.spp,
        noise_threshold: adaptive.noise_threshold,
        min_spp: adaptive.is_on().then(|| adaptive.min_spp(renderer.spp)),
        physics: sequence.physics,
        scene_hash: format!("{:016x}", sequence.trajectory.scene_hash),
        trajectory_frames: sequence.frame_count(),
        frame_start: frames.start(),
        frame_end: frames.end(),
        frame_step: frames.step(),
        max_depth: (settings.mode.value == RenderMode::Path).then_some(args.max_depth),
        clamp_indirect: args.clamp_indirect,
        filter: renderer.filter.kind().to_string(),
        filter_width: renderer.filter.width(),
        seed: json_name(&args.seed),
        seed_offset: args.seed_offset,
        reuse: args.reuse != ReuseMode::Off,
        reuse_mode: json_name(&args.reuse),
        exposure: args.exposure,
        aovs: args.aov.iter().map(|a| a.name().to_string()).collect(),
        exr: args.exr,
        denoise: denoise.map(str::to_string),
        keep_noisy: args.keep_noisy,
        shutter: settings.shutter.value,
        settings_from: settings.sources(),
    }
}

/// `video.mp4` from the written frames.
fn encode_video(args: &RenderArgs, frame_paths: &[PathBuf], fps: f64, quiet: bool) -> Result<(), CliError> {
    let video = args.out.join("video.mp4");
    super::video::encode_video(&args.out, frame_paths, fps, &video).map_err(|e| match e {
        super::video::VideoError::FfmpegMissing => CliError::Input(e.to_string()),
        e => CliError::Runtime(e.to_string()),
    })?;
    if !quiet {
        println!("wrote {} ({} frames, {fps:.2} fps)", video.display(), frame_paths.len());
    }
    Ok(())
}

/// A value's JSON name (a unit enum's serde name).
fn json_name(value: &impl serde::Serialize) -> String {
    match serde_json::to_value(value) {
        Ok(serde_json::Value::String(s)) => s,
        Ok(other) => other.to_string(),
        Err(_) => String::new(),
    }
}

/// The line printed before a resumed run renders.
fn resume_summary(kept: &[FrameRecord], selection: &FrameSelection) -> String {
    let total = selection.count();
    match (kept.first(), kept.last()) {
        (Some(first), Some(last)) if kept.len() as u32 == total => {
            format!(
                "resuming: all {total} frames ({}..={}) were finished, none to render",
                first.frame, last.frame
            )
        }
        (Some(first), Some(last)) => format!(
            "resuming: {} of {total} frames ({}..={}) kept from the earlier run, {} to render",
            kept.len(),
            first.frame,
            last.frame,
            total - kept.len() as u32
        ),
        _ => format!("resuming: no finished frame to keep, rendering all {total}"),
    }
}
