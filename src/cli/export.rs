//! `dormant export`: a sequence's frames (mesh sources, lights, camera, body poses) as JSON
//! for another renderer, and/or the whole sequence as an animated glTF binary. The content is
//! `sequence::SequenceExport`'s and `sequence::gltf_export`'s; this only wires flags.

use std::path::PathBuf;

use clap::Args;

use super::render::{load_sequence, sequence_error, sequence_source_of, SceneArgs};
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
    /// Export frames A..B (half-open; default: all). JSON only: refused with --gltf.
    #[arg(long, value_name = "A..B")]
    pub frames: Option<FrameRange>,
    /// Export every N-th frame, counted from frame 0 (default: the scene's render.frame_step).
    /// JSON only: the glTF file has every frame.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    pub frame_step: Option<u32>,
    /// With SCENE: total dynamic objects, as `dormant simulate --count`.
    #[arg(long, value_name = "N")]
    pub count: Option<u32>,
    /// With a glTF file as SCENE: frames per second to sample its animation at.
    #[arg(long, value_name = "FPS", requires = "scene_file")]
    pub fps: Option<f64>,
    /// With SCENE: directory that relative asset paths in the scene file resolve against
    /// (default: the scene file's own directory).
    #[arg(long, value_name = "DIR", requires = "scene_file")]
    pub assets: Option<PathBuf>,
    /// JSON file to write (format `dormant-export-1`, see docs/design.md).
    #[arg(long, value_name = "FILE", required_unless_present = "gltf")]
    pub out: Option<PathBuf>,
    /// glTF binary (.glb) to write: meshes, materials, a node per body and one animation of
    /// every frame (format `dormant-gltf-1`, see docs/design.md). With --out, both are written.
    #[arg(long, value_name = "FILE")]
    pub gltf: Option<PathBuf>,
}

pub(super) fn run(args: &ExportArgs, quiet: bool, json_out: &JsonOutput) -> Result<(), CliError> {
    if args.gltf.is_some() && args.frames.is_some() {
        return Err(CliError::Input(
            "--frames: the glTF export has every frame (key times are absolute); drop --frames or --gltf"
                .into(),
        ));
    }
    let scene = SceneArgs { file: args.scene_file.as_deref(), assets: args.assets.as_deref(), fps: args.fps };
    let source = sequence_source_of(scene, args.trajectory.as_ref(), args.count)?
        .ok_or_else(|| CliError::Input("export needs a SCENE file or --trajectory".into()))?;
    let sequence = load_sequence(source, quiet)?;
    let mut summary = serde_json::Map::new();
    if let Some(out) = &args.out {
        let selection =
            sequence.select(args.frames, args.frame_step).map_err(|e| sequence_error(e, "--frames"))?;
        let export = sequence.export(&selection);
        let value = serde_json::to_value(&export).map_err(|e| CliError::Runtime(e.to_string()))?;
        write_json_atomic(out, &value)?;
        summary.insert("export".into(), serde_json::json!(out));
        summary.insert("frames".into(), serde_json::json!(export.frames.len()));
        summary.insert("bodies".into(), serde_json::json!(export.body_prototypes.len()));
        report(quiet, json_out, || {
            format!(
                "wrote {}: {} frames, {} bodies",
                out.display(),
                export.frames.len(),
                export.body_prototypes.len()
            )
        });
    }
    if let Some(path) = &args.gltf {
        let written = sequence.write_gltf(path).map_err(|e| CliError::Runtime(e.to_string()))?;
        summary.insert("gltf".into(), serde_json::json!({ "path": path, "summary": written }));
        report(quiet, json_out, || {
            format!(
                "wrote {}: {} bytes, {} frames, {} bodies, {} nodes",
                path.display(),
                written.bytes,
                written.frames,
                written.bodies,
                written.nodes
            )
        });
    }
    json_out.emit(&serde_json::Value::Object(summary))
}

/// Prints `line` unless quiet or the report goes out as JSON.
fn report(quiet: bool, json_out: &JsonOutput, line: impl FnOnce() -> String) {
    if !quiet && !json_out.is_requested() {
        println!("{}", line());
    }
}
