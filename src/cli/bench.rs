use clap::{Args, Subcommand};

use super::{CliError, JsonOutput, SceneSource};
use crate::bench::{self, AccelBenchOptions};

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
    /// Physics step time with every body awake against most asleep.
    #[command(after_help = "Examples:\n  dormant bench physics scenes/atrium.toml --json out/physics.json")]
    Physics(PhysicsArgs),
}

#[derive(Debug, Args)]
pub struct PhysicsArgs {
    #[command(flatten)]
    pub scene: super::simulate::PhysicsScene,
    /// Frames measured in each phase.
    #[arg(long, value_name = "N", default_value_t = 60)]
    pub measure_frames: u32,
    #[command(flatten)]
    pub json: JsonOutput,
}

#[derive(Debug, Args)]
pub struct AccelArgs {
    #[command(flatten)]
    pub scene: SceneSource,
    /// Primary rays: one per pixel of an image of this size.
    #[arg(long, value_name = "WxH", default_value = "1280x720")]
    pub size: super::render::Size,
    /// Repetitions of each trace measurement; the best is reported.
    #[arg(long, value_name = "N", default_value_t = 3)]
    pub runs: u32,
    #[command(flatten)]
    pub json: JsonOutput,
}

pub(super) fn run(args: &BenchArgs, threads: Option<usize>, quiet: bool) -> Result<(), CliError> {
    match &args.which {
        BenchCommand::Accel(a) => accel(a, threads, quiet),
        BenchCommand::Physics(p) => physics(p, quiet),
    }
}

fn physics(args: &PhysicsArgs, quiet: bool) -> Result<(), CliError> {
    let (file, simulate) = args.scene.load()?;
    let options = crate::physics::PhysicsBenchOptions { simulate, measure_frames: args.measure_frames };
    let report = crate::physics::bench(&file, &options).map_err(super::simulate::physics_error)?;
    emit(&serde_json::to_value(&report).expect("bench report serialises"), &args.json, quiet)
}

fn emit(json: &serde_json::Value, out: &JsonOutput, quiet: bool) -> Result<(), CliError> {
    out.emit(json)?;
    if !quiet && !out.is_requested() {
        println!("{json:#}");
    }
    Ok(())
}

fn accel(args: &AccelArgs, threads: Option<usize>, quiet: bool) -> Result<(), CliError> {
    let desc = args.scene.load()?;
    let opts = AccelBenchOptions {
        width: args.size.width,
        height: args.size.height,
        trace_runs: args.runs,
        threads,
        ..AccelBenchOptions::default()
    };
    let report = bench::bench_accel(&desc, &opts).map_err(|e| CliError::Runtime(e.to_string()))?;
    emit(&serde_json::to_value(&report).expect("bench report serialises"), &args.json, quiet)
}
