//! The command line: parses arguments, sets up logging and thread pools, and wires the
//! domains together. No rendering or geometry logic lives here.

mod bench;
mod denoise;
mod export;
mod info;
mod named;
mod progress;
mod render;
mod simulate;
mod verify;

use std::process::ExitCode;

use std::path::{Path, PathBuf};

use clap::{Args, Parser, Subcommand};

use dormant::scene::{self, SceneDescription};

/// Errors that end a command, with the exit code they map to.
#[derive(Debug, thiserror::Error)]
pub(crate) enum CliError {
    /// Bad flags or input files: exit code 2.
    #[error("{0}")]
    Input(String),
    /// Failures while running: exit code 1.
    #[error("{0}")]
    Runtime(String),
    /// A render stopped by a signal after the frame in flight (`render/stop.rs`): exit code
    /// 128 plus the signal's number.
    #[error(
        "stopped by {} after frame {last_frame} ({frames} frames written by this run); `render --resume` with the same options continues",
        render::signal_name(*.signal)
    )]
    Stopped { signal: i32, last_frame: u32, frames: u64 },
    /// Another render writes into the output folder (`render/output_lock.rs`): exit code 75.
    #[error("{0}")]
    Busy(String),
}

/// Render failures while running (bad scenes are caught as input before rendering starts).
impl From<dormant::render::RenderError> for CliError {
    fn from(e: dormant::render::RenderError) -> Self {
        CliError::Runtime(e.to_string())
    }
}

/// Bad scenes, trajectories and options are input; a failed render or build is runtime.
impl From<dormant::sequence::SequenceError> for CliError {
    fn from(e: dormant::sequence::SequenceError) -> Self {
        if e.is_input() {
            CliError::Input(e.to_string())
        } else {
            CliError::Runtime(e.to_string())
        }
    }
}

impl CliError {
    pub fn exit_code(&self) -> u8 {
        match self {
            CliError::Input(_) => 2,
            CliError::Runtime(_) => 1,
            CliError::Stopped { signal, .. } => render::stop_exit_code(*signal),
            CliError::Busy(_) => render::BUSY_EXIT_CODE,
        }
    }
}

#[derive(Debug, Parser)]
#[command(
    name = "dormant",
    version,
    about = "Offline renderer for physics-simulated scenes that takes sleeping islands out of the per-frame ray tracing structure",
    after_help = "Examples:\n  dormant render --out out/demo          render the built-in default scene\n  dormant render --size 1280x720 --spp 64 --out out/hq\n  dormant info                           versions and compiled backends as JSON"
)]
pub(crate) struct Cli {
    /// Worker threads for rendering and Embree's builder (default: all cores).
    #[arg(long, global = true, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub threads: Option<u32>,
    /// Print only errors.
    #[arg(long, short, global = true)]
    pub quiet: bool,
    #[command(flatten)]
    pub json: JsonOutput,
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub(crate) enum Command {
    /// Render a scene file, a glTF file or a trajectory to PNG frames (or, without one, a
    /// still of the built-in scene).
    #[command(
        after_help = "Settings: a flag given on the command line, else --preset's value, else the scene file's [render], else the built-in default (960x540, 16 spp, path).\n\nExamples:\n  dormant render --out out/demo\n  dormant render scenes/tiny.toml --out out/tiny               the scene's size and samples\n  dormant render scenes/tiny.toml --preset preview --out out/p  shaded, 320x180, 1 spp\n  dormant render --size 640x360 --spp 4 --backend embree --out /tmp/preview",
        mut_arg("count", |a| a.help("Objects: the heap's size with --env/--object (default 8000), or with a SCENE file the total dynamic objects, spread over its spawners and structures (whole copies) in proportion"))
    )]
    Render(render::RenderArgs),
    /// Simulate a scene file with Rapier and record its trajectory and island events.
    #[command(
        after_help = "Examples:\n  dormant simulate scenes/tiny.toml --out out/tiny.traj\n  dormant simulate scenes/atrium.toml --count 8000 --out out/atrium.traj --json out/atrium-islands.json"
    )]
    Simulate(simulate::SimulateArgs),
    /// Trace the same rays through Embree and the BVH and compare the hits.
    #[command(
        mut_arg("count", |a| a.help("Objects: the heap's size with --env/--object (default 8000), or with a SCENE file the total dynamic objects, spread over its spawners and structures (whole copies) in proportion")),
        after_help = "Examples:\n  dormant verify --json out/verify.json\n  dormant verify --env ../shared/assets/monastery.glb --object ../shared/assets/duck.glb --count 8000"
    )]
    Verify(verify::VerifyArgs),
    /// Benchmarks, run side by side in one process; results as JSON.
    Bench(bench::BenchArgs),
    /// Write a sequence's frames (mesh sources, sun, sky, lights, camera and every body's
    /// pose) as JSON for another renderer (scripts/compare-cycles.py builds it in Blender),
    /// and/or the whole sequence as an animated glTF binary (--gltf).
    #[command(
        after_help = "Examples:\n  dormant export --trajectory out/rain.traj --frames 0..120 --out out/rain.json\n  dormant export scenes/tiny.toml --gltf out/tiny.glb"
    )]
    Export(export::ExportArgs),
    /// Print dormant's version, the Embree library and header versions, the Open Image
    /// Denoise library version, and the compiled backends, as JSON.
    Info,
}

/// Parses the process arguments, runs the command and returns the exit code.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    init_logging(cli.quiet);
    survive_file_size_limit();
    match run(&cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e @ CliError::Stopped { .. }) => {
            eprintln!("dormant: {e}");
            ExitCode::from(e.exit_code())
        }
        Err(e) => {
            eprintln!("dormant: error: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}

/// Handles SIGXFSZ, which a write past the file size limit (`ulimit -f`, RLIMIT_FSIZE) raises:
/// its default action kills the process mid-write; handled, the write fails with EFBIG, which
/// ends the command with an error naming the file, its temporary file removed.
fn survive_file_size_limit() {
    let noticed = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    if let Err(e) = signal_hook::flag::register(signal_hook::consts::SIGXFSZ, noticed) {
        tracing::warn!("cannot handle SIGXFSZ ({e}): a file past the size limit will kill the process");
    }
}

fn init_logging(quiet: bool) {
    let default = if quiet { "error" } else { "warn" };
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new(default));
    let _ = tracing_subscriber::fmt().with_env_filter(filter).with_writer(std::io::stderr).try_init();
}

pub(crate) fn run(cli: &Cli) -> Result<(), CliError> {
    if let Some(n) = cli.threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n as usize)
            .build_global()
            .map_err(|e| CliError::Runtime(format!("cannot start {n} worker threads: {e}")))?;
    }
    let threads = cli.threads.map(|n| n as usize);
    // A bad DORMANT_SIMD is a usage error before any work (the library would fall back).
    dormant::accel::bvh::SimdPath::activate_from_env().map_err(|e| CliError::Input(e.to_string()))?;
    match &cli.command {
        Command::Render(args) => render::run(args, threads, cli.quiet, &cli.json),
        Command::Simulate(args) => simulate::run(args, cli.quiet, &cli.json),
        Command::Verify(args) => verify::run(args, threads, cli.quiet, &cli.json),
        Command::Bench(args) => bench::run(args, threads, cli.quiet, &cli.json),
        Command::Export(args) => export::run(args, cli.quiet, &cli.json),
        Command::Info => info::run(threads, &cli.json),
    }
}

/// Which scene a command works on: the built-in default, or an environment glTF with a heap of
/// object glTFs.
#[derive(Debug, Args)]
pub(crate) struct SceneSource {
    /// Static environment glTF (with --object: a heap of objects on its floor).
    #[arg(long, value_name = "GLB", requires = "object")]
    pub env: Option<PathBuf>,
    /// Object glTF, instanced --count times.
    #[arg(long, value_name = "GLB", requires = "env")]
    pub object: Option<PathBuf>,
    /// Objects in the heap of --env/--object (default 8000).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    pub count: Option<u32>,
}

impl SceneSource {
    pub fn load(&self) -> Result<SceneDescription, CliError> {
        match (&self.env, &self.object) {
            (Some(env), Some(object)) => {
                scene::asset_pile(env, object, self.count.unwrap_or(8000) as usize, 1)
                    .map_err(|e| CliError::Input(e.to_string()))
            }
            _ if self.count.is_some() => {
                Err(CliError::Input("--count needs --env and --object, or a SCENE file".into()))
            }
            _ => Ok(scene::default_scene()),
        }
    }
}

/// Writes pretty JSON atomically (temporary file, then rename).
pub(crate) fn write_json_atomic(path: &Path, value: &serde_json::Value) -> Result<(), CliError> {
    let text = serde_json::to_string_pretty(value).expect("JSON values serialise");
    dormant::atomic_file::write_atomic(path, text.as_bytes())
        .map_err(|e| CliError::Runtime(format!("cannot write {}: {e}", path.display())))
}

/// `--json [FILE]` (global: before or after the command): write the command's report as JSON
/// to FILE, or to stdout when FILE is omitted or `-`.
#[derive(Debug, Args)]
pub(crate) struct JsonOutput {
    /// Write the report as JSON to FILE (stdout if FILE is omitted or -).
    #[arg(long = "json", value_name = "FILE", num_args = 0..=1, default_missing_value = "-", global = true)]
    pub path: Option<PathBuf>,
}

impl JsonOutput {
    pub fn is_requested(&self) -> bool {
        self.path.is_some()
    }

    /// Emits `value` where `--json` asked for it; does nothing without `--json`.
    pub fn emit(&self, value: &serde_json::Value) -> Result<(), CliError> {
        match &self.path {
            None => Ok(()),
            Some(p) if p.as_os_str() == "-" => {
                println!("{value:#}");
                Ok(())
            }
            Some(p) => write_json_atomic(p, value),
        }
    }
}
