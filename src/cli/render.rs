use std::path::{Path, PathBuf};

use clap::Args;

use super::CliError;
use crate::accel::{self, Backend};
use crate::integrate::{
    describe_scene, FrameStats, IntegrationPolicy, ManagerOptions, SceneAssets, SceneManager,
};
use crate::physics::{self, SimulateOptions, Trajectory};
use crate::render::{
    self, AmbientOcclusion, Aov, AovIntegrator, DirectLighting, Integrator, PathTracer, RenderScene,
    RenderSettings, RenderStats, SequenceOptions, SequenceScene,
};
use crate::report::{self, FrameRecord, PhysicsSource, RunInfo, RunStats};
use crate::scene::file::SceneFile;

/// Image size as `WIDTHxHEIGHT`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Size {
    pub width: u32,
    pub height: u32,
}

impl std::str::FromStr for Size {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let parse = |v: &str| v.trim().parse::<u32>().ok().filter(|&n| (1..=16384).contains(&n));
        match s.split_once(['x', 'X']) {
            Some((w, h)) => match (parse(w), parse(h)) {
                (Some(width), Some(height)) => Ok(Size { width, height }),
                _ => Err(format!("'{s}': width and height must be whole numbers from 1 to 16384")),
            },
            None => Err(format!("'{s}': expected WIDTHxHEIGHT, e.g. 1280x720")),
        }
    }
}

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
    #[command(flatten)]
    pub scene: super::SceneSource,
    /// Output directory; frames are written as frame_NNNN.png.
    #[arg(long, value_name = "DIR", default_value = "out/render")]
    pub out: PathBuf,
    /// Image size.
    #[arg(long, value_name = "WxH", default_value = "960x540")]
    pub size: Size,
    /// Samples per pixel.
    #[arg(long, value_name = "N", default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub spp: u32,
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
    /// baked (debug: instanced bodies blue, integrated ones orange, environment grey).
    #[arg(long, value_enum, value_delimiter = ',', value_name = "KIND")]
    pub aov: Vec<Aov>,
    /// With SCENE or --trajectory: when sleeping islands are baked into the static scene.
    #[arg(long, value_enum, default_value_t = IntegrationPolicy::Auto)]
    pub integration: IntegrationPolicy,
    /// With SCENE or --trajectory: serve reactivations from the geometry cache.
    #[arg(long, value_enum, default_value_t = CacheSwitch::On)]
    pub cache: CacheSwitch,
    /// With SCENE or --trajectory: also encode the frames as DIR/video.mp4 (needs ffmpeg on PATH).
    #[arg(long)]
    pub video: bool,
    /// Exposure multiplier applied before tone mapping.
    #[arg(long, default_value_t = 1.0)]
    pub exposure: f32,
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

/// The scene's simulation: read from `path` (checked against the scene) or run now.
pub(super) fn load_trajectory(
    file: &SceneFile,
    options: &SimulateOptions,
    path: Option<&Path>,
) -> Result<Trajectory, CliError> {
    load_trajectory_timed(file, options, path, &mut |_| {})
}

/// [`load_trajectory`], calling `on_step` with each simulated frame (nothing when read).
pub(super) fn load_trajectory_timed(
    file: &SceneFile,
    options: &SimulateOptions,
    path: Option<&Path>,
    on_step: &mut dyn FnMut(physics::SimulatedFrame),
) -> Result<Trajectory, CliError> {
    match path {
        Some(path) => {
            let expected =
                options.effective_scene(file).map_err(super::simulate::physics_error)?.source_hash();
            Trajectory::read(path, expected).map_err(|e| CliError::Input(e.to_string()))
        }
        None => physics::simulate_observed(file, options, on_step).map_err(super::simulate::physics_error),
    }
}

/// A trajectory and the scene recorded in it, checked against each other.
fn recorded_scene(path: &Path) -> Result<(SceneFile, SimulateOptions, Trajectory), CliError> {
    let input = |e: &dyn std::fmt::Display| CliError::Input(e.to_string());
    let trajectory = Trajectory::read_unchecked(path).map_err(|e| input(&e))?;
    let Some(recorded) = &trajectory.scene else {
        return Err(CliError::Input(format!(
            "{}: scene: the trajectory does not record its scene (format version 1); pass the SCENE \
             file too",
            path.display()
        )));
    };
    let file = recorded
        .scene_file()
        .map_err(|e| CliError::Input(format!("{}: the scene recorded in it: {e}", path.display())))?;
    let options = recorded.options.clone();
    let hash = options.effective_scene(&file).map_err(super::simulate::physics_error)?.source_hash();
    if hash != trajectory.scene_hash {
        return Err(CliError::Input(format!(
            "{}: scene: the recorded scene does not hash to the trajectory's scene_hash (damaged file)",
            path.display()
        )));
    }
    Ok((file, options, trajectory))
}

/// `range` (default: every frame) checked against a trajectory of `total` frames.
/// `flag` names the option in the error.
pub(super) fn check_range(flag: &str, range: Option<FrameRange>, total: u32) -> Result<FrameRange, CliError> {
    let range = range.unwrap_or(FrameRange { start: 0, end: total });
    if range.end > total {
        return Err(CliError::Input(format!(
            "{flag} {}..{}: the trajectory has {total} frames (0..{total})",
            range.start, range.end
        )));
    }
    Ok(range)
}

pub(super) fn run(
    args: &RenderArgs,
    threads: Option<usize>,
    quiet: bool,
    json: &super::JsonOutput,
) -> Result<(), CliError> {
    let backend = choose_backend(args.backend)?;
    if !args.exposure.is_finite() || args.exposure <= 0.0 {
        return Err(CliError::Input(format!("--exposure {}: must be a positive number", args.exposure)));
    }
    if args.video {
        if args.scene_file.is_none() && args.trajectory.is_none() {
            return Err(CliError::Input(
                "--video needs a SCENE file or --trajectory (a sequence of frames)".into(),
            ));
        }
        if !render::ffmpeg_available() {
            return Err(CliError::Input(render::VideoError::FfmpegMissing.to_string()));
        }
    }
    std::fs::create_dir_all(&args.out).map_err(|e| {
        CliError::Runtime(format!("cannot create output directory {}: {e}", args.out.display()))
    })?;
    let integrator = integrator(args.mode, args.max_depth);
    let runtime = |e: &dyn std::fmt::Display| CliError::Runtime(e.to_string());
    let mut records = Vec::new();
    // Per-frame statistics of a sequence (stats.json / stats.csv), and the physics step time of
    // each simulated frame when the simulation runs in this process.
    let mut frame_records: Vec<FrameRecord> = Vec::new();
    let mut physics_ms: Vec<f64> = Vec::new();
    let progress = super::progress::hidden();
    let mut write_frame = |index: u32,
                           film: &render::Film,
                           aovs: &[(Aov, render::Film)],
                           stats: &RenderStats,
                           scene_stats: Option<&FrameStats>| {
        let path = args.out.join(format!("frame_{index:04}.png"));
        render::write_png_atomic(film, args.exposure, &path).map_err(|e| runtime(&e))?;
        if args.exr {
            render::write_exr_atomic(film, &path.with_extension("exr")).map_err(|e| runtime(&e))?;
        }
        let mut aov_paths = Vec::new();
        for (aov, film) in aovs {
            let aov_path = args.out.join(format!("frame_{index:04}.{}.png", aov.name()));
            render::write_aov_png_atomic(film, *aov, &aov_path).map_err(|e| runtime(&e))?;
            if args.exr {
                render::write_exr_atomic(film, &aov_path.with_extension("exr")).map_err(|e| runtime(&e))?;
            }
            aov_paths.push(aov_path);
        }
        if !quiet && !json.is_requested() {
            progress.suspend(|| {
                println!(
                    "rendered {} ({}x{}, {} spp, {:?} mode, {backend}): {:.2} s, {} rays, {:.1} Mrays/s",
                    path.display(),
                    args.size.width,
                    args.size.height,
                    args.spp,
                    args.mode,
                    stats.seconds,
                    stats.rays,
                    stats.mrays_per_second()
                )
            });
        }
        records.push(serde_json::json!({ "frame": index, "path": path, "rays": stats.rays,
            "seconds": stats.seconds, "mrays_per_second": stats.mrays_per_second(), "aovs": aov_paths,
            "scene": scene_stats }));
        Ok::<(), CliError>(())
    };

    // A sequence: a scene file, maybe with a trajectory of it, or a trajectory alone with the
    // scene recorded in it.
    let sequence_source = match (&args.scene_file, &args.trajectory) {
        (Some(path), _) => {
            let file = SceneFile::load(path).map_err(|e| CliError::Input(e.to_string()))?;
            Some((file, SimulateOptions { count: args.scene.count, frames: None }, None))
        }
        (None, Some(path)) => {
            let (file, options, trajectory) = recorded_scene(path)?;
            if args.scene.count.is_some_and(|c| options.count != Some(c)) {
                return Err(CliError::Input(format!(
                    "--count: {} was simulated with its own object count; simulate again to change it",
                    path.display()
                )));
            }
            Some((file, options, Some(trajectory)))
        }
        (None, None) => None,
    };
    let scene_name = match sequence_source {
        None => {
            if args.frames.is_some() {
                return Err(CliError::Input("--frames needs a SCENE file or --trajectory".into()));
            }
            let description = args.scene.load()?;
            let mut accel = accel::create(backend, threads).map_err(|e| runtime(&e))?;
            let scene = RenderScene::build(&description, accel.as_mut()).map_err(|e| runtime(&e))?;
            let query = accel.query().map_err(|e| runtime(&e))?;
            let settings =
                RenderSettings { width: args.size.width, height: args.size.height, spp: args.spp, frame: 0 };
            let (film, stats) = render::render_frame(&scene, query, integrator.as_ref(), &settings)
                .map_err(|e| runtime(&e))?;
            let mut aovs = Vec::new();
            for &aov in &args.aov {
                let (film, _) = render::render_frame(&scene, query, &AovIntegrator(aov), &settings)
                    .map_err(|e| runtime(&e))?;
                aovs.push((aov, film));
            }
            write_frame(0, &film, &aovs, &stats, None)?;
            description.name
        }
        Some((file, options, preloaded)) => {
            let trajectory = match preloaded {
                Some(t) => t,
                None => {
                    let simulate_bar = super::progress::frames_bar(quiet, "simulating", None);
                    let t =
                        load_trajectory_timed(&file, &options, args.trajectory.as_deref(), &mut |step| {
                            simulate_bar.set_length(u64::from(step.frames));
                            simulate_bar.inc(1);
                            physics_ms.push(step.step_ms);
                        })?;
                    simulate_bar.finish_and_clear();
                    t
                }
            };
            let physics_source =
                if args.trajectory.is_some() { PhysicsSource::Trajectory } else { PhysicsSource::Simulated };
            let physics_total_ms =
                (physics_source == PhysicsSource::Simulated).then(|| physics_ms.iter().sum::<f64>());
            let range = check_range("--frames", args.frames, trajectory.frames.len() as u32)?;
            let assets = SceneAssets::load(&file).map_err(|e| CliError::Input(e.to_string()))?;
            let template = describe_scene(&assets, 0.0);
            let sequence = SequenceOptions {
                start: range.start,
                end: range.end,
                step: file.spec().render.frame_step.max(1),
                width: args.size.width,
                height: args.size.height,
                spp: args.spp,
            };
            let manager_options = ManagerOptions {
                policy: args.integration,
                cache: args.cache == CacheSwitch::On,
                planned_frames: Some(sequence.frame_count()),
                ..ManagerOptions::default()
            };
            let accel = accel::create(backend, threads).map_err(|e| runtime(&e))?;
            let mut manager = SceneManager::new(accel, &template, &trajectory.bodies, manager_options)
                .map_err(|e| runtime(&e))?;
            let scene = SequenceScene { trajectory: &trajectory, assets: &assets, template: &template };
            super::progress::become_frames_bar(
                &progress,
                quiet,
                "rendering",
                u64::from(sequence.frame_count()),
            );
            let (mut rays, mut trace_seconds) = (0u64, 0.0f64);
            let mut frame_paths = Vec::new();
            render::render_sequence(
                &scene,
                &mut manager,
                integrator.as_ref(),
                &args.aov,
                &sequence,
                &mut |f| {
                    write_frame(f.index, f.film, &f.aovs, &f.render, Some(f.stats))?;
                    frame_paths.push(args.out.join(format!("frame_{:04}.png", f.index)));
                    let physics = physics_ms.get(f.index as usize).copied();
                    frame_records.push(FrameRecord::new(f.stats, f.render.mrays_per_second(), physics));
                    rays += f.render.rays;
                    trace_seconds += f.render.seconds;
                    let mrays = if trace_seconds > 0.0 { rays as f64 / trace_seconds / 1e6 } else { 0.0 };
                    progress.set_message(format!(
                        "frame {} | {mrays:.1} Mrays/s | {} islands integrated",
                        f.index, f.stats.integrated_islands
                    ));
                    progress.inc(1);
                    Ok::<(), CliError>(())
                },
            )?;
            progress.finish_and_clear();
            let info = RunInfo {
                scene: template.name.clone(),
                backend: backend.to_string(),
                mode: json_name(&args.mode),
                integration: json_name(&args.integration),
                cache_enabled: args.cache == CacheSwitch::On,
                width: args.size.width,
                height: args.size.height,
                spp: args.spp,
                physics: physics_source,
            };
            let run_stats = RunStats::new(
                info,
                std::mem::take(&mut frame_records),
                manager.cache_stats(),
                manager.cost_model(),
                physics_total_ms,
            );
            run_stats.write(&args.out).map_err(|e| runtime(&e))?;
            report::write_report_png(&run_stats, &args.out.join("report.png")).map_err(|e| runtime(&e))?;
            if args.video {
                let fps = 1.0 / (f64::from(trajectory.timestep) * f64::from(sequence.step));
                let video = args.out.join("video.mp4");
                render::encode_video(&args.out, &frame_paths, fps, &video).map_err(|e| match e {
                    render::VideoError::FfmpegMissing => CliError::Input(e.to_string()),
                    e => runtime(&e),
                })?;
                if !quiet && !json.is_requested() {
                    println!("wrote {} ({} frames, {fps:.2} fps)", video.display(), frame_paths.len());
                }
            }
            template.name
        }
    };
    json.emit(&serde_json::json!({
        "scene": scene_name,
        "backend": backend,
        "width": args.size.width,
        "height": args.size.height,
        "spp": args.spp,
        "mode": args.mode,
        "integration": args.scene_file.as_ref().map(|_| args.integration),
        "frames": records,
    }))
}

/// A value's JSON name (a unit enum's serde name).
fn json_name(value: &impl serde::Serialize) -> String {
    match serde_json::to_value(value) {
        Ok(serde_json::Value::String(s)) => s,
        Ok(other) => other.to_string(),
        Err(_) => String::new(),
    }
}

/// `--cache on|off`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum CacheSwitch {
    On,
    Off,
}

/// A half-open range of frames, `A..B`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameRange {
    pub start: u32,
    pub end: u32,
}

impl std::str::FromStr for FrameRange {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let (a, b) = s.split_once("..").ok_or_else(|| format!("'{s}': expected A..B, e.g. 0..120"))?;
        let parse =
            |v: &str| v.trim().parse::<u32>().map_err(|_| format!("'{s}': '{v}' is not a frame number"));
        let range = FrameRange { start: parse(a)?, end: parse(b)? };
        if range.start >= range.end {
            return Err(format!("'{s}': the range is empty (A must be less than B)"));
        }
        Ok(range)
    }
}

#[cfg(test)]
mod tests {
    use super::Size;

    #[test]
    fn frame_ranges_parse_and_reject() {
        use super::FrameRange;
        assert_eq!("3..10".parse::<FrameRange>(), Ok(FrameRange { start: 3, end: 10 }));
        for bad in ["10..3", "5..5", "a..3", "3", "-1..4"] {
            assert!(bad.parse::<FrameRange>().is_err(), "{bad}");
        }
    }

    #[test]
    fn size_parses_and_rejects() {
        assert_eq!("640x360".parse::<Size>(), Ok(Size { width: 640, height: 360 }));
        assert!("640".parse::<Size>().is_err());
        assert!("0x10".parse::<Size>().is_err());
        assert!("axb".parse::<Size>().is_err());
        assert!("20000x10".parse::<Size>().is_err());
    }
}
