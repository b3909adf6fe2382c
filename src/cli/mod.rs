//! The command line: parses arguments, sets up logging and thread pools, and wires the
//! domains together. No rendering or geometry logic lives here.

mod info;
mod render;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

pub use info::InfoReport;

/// Errors that end a command, with the exit code they map to.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// Bad flags or input files: exit code 2.
    #[error("{0}")]
    Input(String),
    /// Failures while running: exit code 1.
    #[error("{0}")]
    Runtime(String),
}

impl CliError {
    pub fn exit_code(&self) -> u8 {
        match self {
            CliError::Input(_) => 2,
            CliError::Runtime(_) => 1,
        }
    }
}

#[derive(Debug, Parser)]
#[command(
    name = "dormant",
    version,
    about = "Offline renderer for physics-simulated scenes that bakes sleeping islands into the static scene",
    after_help = "Examples:\n  dormant render --out out/demo          render the built-in default scene\n  dormant render --size 1280x720 --spp 64 --out out/hq\n  dormant info                           versions and compiled backends as JSON"
)]
pub struct Cli {
    /// Worker threads for rendering and Embree's builder (default: all cores).
    #[arg(long, global = true, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub threads: Option<u32>,
    /// Print only errors.
    #[arg(long, short, global = true)]
    pub quiet: bool,
    /// Print results as JSON on stdout.
    #[arg(long, global = true)]
    pub json: bool,
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Render the built-in default scene to a PNG.
    #[command(
        after_help = "Examples:\n  dormant render --out out/demo\n  dormant render --size 640x360 --spp 4 --backend embree --out /tmp/preview"
    )]
    Render(render::RenderArgs),
    /// Print dormant's version, the Embree library and header versions, and the compiled
    /// backends, as JSON.
    Info,
}

/// Parses the process arguments, runs the command and returns the exit code.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    init_logging(cli.quiet);
    match run(&cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("dormant: error: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}

fn init_logging(quiet: bool) {
    let default = if quiet { "error" } else { "warn" };
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new(default));
    let _ = tracing_subscriber::fmt().with_env_filter(filter).with_writer(std::io::stderr).try_init();
}

pub fn run(cli: &Cli) -> Result<(), CliError> {
    if let Some(n) = cli.threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n as usize)
            .build_global()
            .map_err(|e| CliError::Runtime(format!("cannot start {n} worker threads: {e}")))?;
    }
    let threads = cli.threads.map(|n| n as usize);
    match &cli.command {
        Command::Render(args) => render::run(args, threads, cli.quiet, cli.json),
        Command::Info => info::run(threads),
    }
}
