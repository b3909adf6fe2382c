//! `dormant export`: a sequence's frames (mesh sources, lights, camera, body poses) as JSON
//! for another renderer. The content is `sequence::SequenceExport`'s; this only wires flags.

use std::path::PathBuf;

use clap::Args;

use super::render::{load_sequence, sequence_error, sequence_source_of};
use super::{write_json_atomic, CliError, JsonOutput};
use dormant::sequence::FrameRange;

#[derive(Debug, Args)]
pub struct ExportArgs {
    /// Scene file to simulate (or whose trajectory --trajectory is).
    #[arg(value_name = "SCENE")]
    pub scene_file: Option<PathBuf>,
    /// Trajectory (from `dormant simulate`) to replay; without SCENE, the scene recorded in it.
    #[arg(long, value_name = "FILE")]
    pub trajectory: Option<PathBuf>,
    /// Export frames A..B (half-open; default: all).
    #[arg(long, value_name = "A..B")]
    pub frames: Option<FrameRange>,
    /// Export every N-th frame, counted from frame 0 (default: the scene's render.frame_step).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub frame_step: Option<u32>,
    /// With SCENE: total dynamic objects, as `dormant simulate --count`.
    #[arg(long, value_name = "N")]
    pub count: Option<u32>,
    /// JSON file to write (format `dormant-export-1`, see docs/design.md).
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
}

pub(super) fn run(args: &ExportArgs, quiet: bool, json_out: &JsonOutput) -> Result<(), CliError> {
    let source = sequence_source_of(args.scene_file.as_deref(), args.trajectory.as_ref(), args.count)?
        .ok_or_else(|| CliError::Input("export needs a SCENE file or --trajectory".into()))?;
    let sequence = load_sequence(source, quiet)?;
    let selection =
        sequence.select(args.frames, args.frame_step).map_err(|e| sequence_error(e, "--frames"))?;
    let export = sequence.export(&selection);
    let value = serde_json::to_value(&export).map_err(|e| CliError::Runtime(e.to_string()))?;
    write_json_atomic(&args.out, &value)?;
    let summary = serde_json::json!({
        "export": args.out,
        "frames": export.frames.len(),
        "bodies": export.body_prototypes.len(),
    });
    json_out.emit(&summary)?;
    if !quiet && !json_out.is_requested() {
        println!(
            "wrote {}: {} frames, {} bodies",
            args.out.display(),
            export.frames.len(),
            export.body_prototypes.len()
        );
    }
    Ok(())
}
