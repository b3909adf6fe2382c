//! `render --resume`: the frames an interrupted run in the output directory finished, which
//! are kept instead of rendered again.

use std::collections::BTreeMap;

use super::render::{frame_files, RenderArgs};
use super::CliError;
use dormant::sequence::stats::{self, FrameRecord, RunInfo};
use dormant::sequence::FrameSelection;

/// The files of a sequence's run besides its frames.
const OUTPUTS: [&str; 3] = ["stats.json", "stats.csv", "report.png"];

/// The records of the frames kept from an earlier run in `args.out`: the selected frames,
/// from the first on, whose files (image, EXR, AOVs: every file this run would write for them)
/// are all present and whose record the directory's stats.json holds, up to the first that
/// is not; it and every frame after it render again. Frames and statistics are written
/// atomically, so a present file is whole. Nothing is kept without a stats.json; one from
/// another configuration is an input error, so that two runs' outputs never mix. The
/// temporary files a killed run left in the directory are removed.
pub(super) fn kept_frames(
    args: &RenderArgs,
    run: &RunInfo,
    selection: &FrameSelection,
) -> Result<Vec<FrameRecord>, CliError> {
    let ours = |name: &str| name.starts_with("frame_") || OUTPUTS.contains(&name);
    dormant::atomic_file::remove_stale_temporaries(&args.out, ours).map_err(|e| {
        CliError::Runtime(format!("cannot remove the temporary files left in {}: {e}", args.out.display()))
    })?;
    let Some(records) =
        stats::read_kept_frames(&args.out, run).map_err(|e| CliError::Input(e.to_string()))?
    else {
        return Ok(Vec::new());
    };
    let mut records: BTreeMap<u32, FrameRecord> = records.into_iter().map(|r| (r.frame, r)).collect();
    let mut kept = Vec::new();
    for index in selection.frames() {
        let complete = frame_files(args, index).iter().all(|f| f.is_file());
        match records.remove(&index) {
            Some(record) if complete => kept.push(record),
            _ => break,
        }
    }
    Ok(kept)
}

/// The line printed before a resumed run renders.
pub(super) fn summary(kept: &[FrameRecord], selection: &FrameSelection) -> String {
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
