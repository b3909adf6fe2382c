//! The frames an interrupted run in an output directory finished, which `render --resume`
//! keeps instead of rendering them again.

use std::collections::BTreeMap;

use super::{OutputError, OutputLayout};
use crate::atomic_file::remove_stale_temporaries;
use crate::sequence::stats::{read_kept_frames, FrameRecord, RunInfo};
use crate::sequence::FrameSelection;

/// The files of a sequence's run besides its frames.
const RUN_FILES: [&str; 3] = ["stats.json", "stats.csv", "report.png"];

/// The records of the frames kept from an earlier run in `layout.dir`: the selected frames,
/// from the first on, whose files (every file this run would write for them) are all present
/// and whose record the directory's stats.json holds, up to the first that is not; it and
/// every frame after it render again. Frames and statistics are written atomically, so a
/// present file is whole. Nothing is kept without a stats.json; one from another
/// configuration is an error ([`OutputError::Stats`]), so that two runs' outputs never mix.
/// The temporary files a killed run left in the directory are removed.
pub fn kept_frames(
    layout: &OutputLayout,
    run: &RunInfo,
    selection: &FrameSelection,
) -> Result<Vec<FrameRecord>, OutputError> {
    let ours = |name: &str| name.starts_with("frame_") || RUN_FILES.contains(&name);
    remove_stale_temporaries(&layout.dir, ours)
        .map_err(|source| OutputError::Stale { dir: layout.dir.clone(), source })?;
    let Some(records) = read_kept_frames(&layout.dir, run)? else {
        return Ok(Vec::new());
    };
    let mut records: BTreeMap<u32, FrameRecord> = records.into_iter().map(|r| (r.frame, r)).collect();
    let mut kept = Vec::new();
    for index in selection.frames() {
        let complete = layout.frame_files(index).iter().all(|f| f.is_file());
        match records.remove(&index) {
            Some(record) if complete => kept.push(record),
            _ => break,
        }
    }
    Ok(kept)
}
