use std::path::PathBuf;

use clap::Args;

use super::{CliError, JsonOutput};
use dormant::physics::{self, PhysicsError, SimulateOptions};
use dormant::scene::file::SceneFile;

/// A scene file plus the overrides every physics command accepts.
#[derive(Debug, Args)]
pub struct PhysicsScene {
    /// Scene file (TOML; see docs/scene-format.md), or an animated glTF file.
    #[arg(value_name = "SCENE")]
    pub scene: PathBuf,
    /// Total dynamic objects, spread over the scene's spawners and structures (whole copies)
    /// in proportion.
    #[arg(long, value_name = "N")]
    pub count: Option<u32>,
    /// Frames to simulate instead of the scene's own count.
    #[arg(long, value_name = "N")]
    pub frame_count: Option<u32>,
    /// Directory that relative asset paths in the scene resolve against.
    #[arg(long, value_name = "DIR")]
    pub assets: Option<PathBuf>,
    /// With a glTF file as SCENE: frames per second to sample its animation at (files from
    /// dormant's export record it; Blender's do not).
    #[arg(long, value_name = "FPS")]
    pub fps: Option<f64>,
}

impl PhysicsScene {
    pub fn load(&self) -> Result<(SceneFile, SimulateOptions), CliError> {
        let file = SceneFile::load_with_fps(&self.scene, self.assets.as_deref(), self.fps)
            .map_err(|e| CliError::Input(e.to_string()))?;
        Ok((file, SimulateOptions { count: self.count, frames: self.frame_count }))
    }
}

/// Bad scenes and options are input errors; anything else failed while running.
pub(super) fn physics_error(e: PhysicsError) -> CliError {
    match e {
        PhysicsError::Scene(_) | PhysicsError::Option { .. } | PhysicsError::Collider { .. } => {
            CliError::Input(e.to_string())
        }
    }
}

#[derive(Debug, Args)]
pub struct SimulateArgs {
    #[command(flatten)]
    pub scene: PhysicsScene,
    /// Trajectory file to write (poses, sleep states and island events of every frame).
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
}

pub(super) fn run(args: &SimulateArgs, quiet: bool, json_out: &JsonOutput) -> Result<(), CliError> {
    let (file, options) = args.scene.load()?;
    // Like `render --out`, the trajectory's directory is created, and before simulating, so a
    // path that cannot be written fails at once rather than after the whole simulation.
    if let Some(dir) = args.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| {
            CliError::Runtime(format!("cannot create the directory of {}: {e}", args.out.display()))
        })?;
    }
    let bar = super::progress::frames_bar(quiet, "simulating", None);
    let trajectory = physics::simulate_observed(&file, &options, &mut |step| {
        bar.set_length(u64::from(step.frames));
        bar.inc(1);
    })
    .map_err(physics_error)?;
    bar.finish_and_clear();
    trajectory.write_atomic(&args.out).map_err(|e| CliError::Runtime(e.to_string()))?;
    let stats = trajectory.island_stats();
    let json = serde_json::json!({ "trajectory": args.out, "islands": stats });
    json_out.emit(&json)?;
    if !quiet && !json_out.is_requested() {
        println!(
            "wrote {}: {} frames, {} of {} bodies asleep at the end ({:.1}%), {} islands formed, {} woken, \
             {} asleep at the end; island size mean {:.1} (max {}); mean sleep {:.0} frames",
            args.out.display(),
            stats.frames,
            stats.asleep_bodies_at_end,
            stats.dynamic_bodies_at_end,
            100.0 * stats.asleep_fraction_at_end,
            stats.islands_formed,
            stats.islands_woken,
            stats.islands_asleep_at_end,
            stats.size_mean,
            stats.size_max,
            stats.mean_sleep_frames_all
        );
    }
    Ok(())
}
