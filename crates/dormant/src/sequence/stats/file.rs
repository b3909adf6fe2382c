//! `stats.json` and `stats.csv` on disk while a run goes on: rewritten as its frames finish,
//! so that a killed run keeps the statistics of what it finished, and read back by
//! `render --resume`, which keeps the records of the frames an earlier run of the same
//! configuration finished.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use serde::Deserialize;

use super::record::{FrameRecord, RunInfo, RunStats, STATS_FORMAT, STATS_VERSION};
use super::StatsError;
use crate::residency::SceneManager;

/// The files are rewritten after a frame once at least this many times the last write's
/// duration has passed since it: every frame when frames are slow, and at most about 5% of
/// the run's time when they are fast (a write grows with the frames recorded).
const WRITE_INTERVAL_OVER_COST: u32 = 50;

/// The statistics of a run in progress, written into its directory as frames finish.
pub struct StatsFile {
    dir: PathBuf,
    run: RunInfo,
    physics_total_ms: Option<f64>,
    frames: Vec<FrameRecord>,
    written_at: Instant,
    write_cost: Duration,
}

impl StatsFile {
    /// A run of `run` writing into `dir`, starting with the records of the frames `kept`
    /// from an earlier run (`render --resume`; empty otherwise). `physics_total_ms`: the
    /// simulation's time when it ran in this process.
    pub fn new(dir: &Path, run: RunInfo, physics_total_ms: Option<f64>, kept: Vec<FrameRecord>) -> Self {
        Self {
            dir: dir.to_path_buf(),
            run,
            physics_total_ms,
            frames: kept,
            written_at: Instant::now(),
            write_cost: Duration::ZERO,
        }
    }

    /// Adds a finished frame's record, and rewrites the files when due (always after the
    /// first frame).
    pub fn push(&mut self, record: FrameRecord, manager: &SceneManager) -> Result<(), StatsError> {
        self.frames.push(record);
        if self.written_at.elapsed() >= self.write_cost * WRITE_INTERVAL_OVER_COST {
            self.write(manager)?;
        }
        Ok(())
    }

    /// Writes the files after the last frame; returns the run's statistics.
    pub fn finish(mut self, manager: &SceneManager) -> Result<RunStats, StatsError> {
        let stats = self.take_stats(manager);
        stats.write(&self.dir)?;
        Ok(stats)
    }

    fn write(&mut self, manager: &SceneManager) -> Result<(), StatsError> {
        let start = Instant::now();
        let stats = self.take_stats(manager);
        let written = stats.write(&self.dir);
        // The records move back: a long run's are not copied at every write.
        self.frames = stats.frames;
        written?;
        self.written_at = Instant::now();
        self.write_cost = self.written_at - start;
        tracing::debug!(frames = self.frames.len(), ms = self.write_cost.as_secs_f64() * 1e3, "wrote stats");
        Ok(())
    }

    /// The run's statistics so far, holding the records moved out of `self`.
    fn take_stats(&mut self, manager: &SceneManager) -> RunStats {
        let frames = std::mem::take(&mut self.frames);
        RunStats::new(
            self.run.clone(),
            frames,
            manager.cache_stats(),
            manager.cost_model(),
            self.physics_total_ms,
        )
    }
}

/// The parts of a stats.json that `--resume` reads.
#[derive(Deserialize)]
struct Stored {
    format: String,
    version: u32,
    run: serde_json::Value,
    frames: serde_json::Value,
}

/// The frame records of the earlier run whose stats.json is in `dir`, which must have been a
/// run of `run`'s configuration; `None` when `dir` holds no stats.json.
pub(crate) fn read_kept_frames(dir: &Path, run: &RunInfo) -> Result<Option<Vec<FrameRecord>>, StatsError> {
    let path = dir.join("stats.json");
    match std::fs::read(&path) {
        Ok(bytes) => StatsFile::kept_records(&path, &bytes, run).map(Some),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(source) => Err(StatsError::Read { path, source }),
    }
}

impl StatsFile {
    /// The frame records of `bytes`, a stats.json read from `path` (which errors name), that
    /// a run of `run`'s configuration must have written: what `render --resume` keeps. A file
    /// of another format version or another run header is [`StatsError::OtherRun`], naming
    /// the fields that differ.
    pub fn kept_records(path: &Path, bytes: &[u8], run: &RunInfo) -> Result<Vec<FrameRecord>, StatsError> {
        let parse = |source| StatsError::Parse { path: path.to_path_buf(), source };
        let stored: Stored = serde_json::from_slice(bytes).map_err(parse)?;
        let path = path.to_path_buf();
        if stored.format != STATS_FORMAT || stored.version != STATS_VERSION {
            let differences = format!(
                "{} version {} there, {STATS_FORMAT} version {STATS_VERSION} now",
                stored.format, stored.version
            );
            return Err(StatsError::OtherRun { path, differences });
        }
        let earlier = RunInfo::deserialize(&stored.run).ok();
        if !earlier.as_ref().is_some_and(|e| same_run(e, run)) {
            // Through the typed header when it reads, so that both sides print alike.
            let then = earlier.and_then(|r| serde_json::to_value(r).ok()).unwrap_or(stored.run);
            return Err(StatsError::OtherRun { path, differences: differences(&then, run) });
        }
        Vec::<FrameRecord>::deserialize(&stored.frames).map_err(parse)
    }
}

/// Whether `then` and `now` describe the same run: every field alike but where the settings
/// came from.
fn same_run(then: &RunInfo, now: &RunInfo) -> bool {
    RunInfo { settings_from: now.settings_from.clone(), ..then.clone() } == *now
}

/// The fields of `now` that `then` (a stats.json's `run`) lacks or holds otherwise, as
/// `field X there, Y now` (where settings came from is not compared).
fn differences(then: &serde_json::Value, now: &RunInfo) -> String {
    let now = serde_json::to_value(now).expect("run headers serialise");
    let mut out = Vec::new();
    for (field, value) in now.as_object().into_iter().flatten().filter(|(f, _)| *f != "settings_from") {
        match then.get(field) {
            Some(old) if old == value => {}
            Some(old) => out.push(format!("{field} {old} there, {value} now")),
            None => out.push(format!("{field} absent there, {value} now")),
        }
    }
    if out.is_empty() {
        "its run header does not read".into()
    } else {
        out.join("; ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn differences_name_each_field() {
        let now = RunInfo {
            scene: "tiny".into(),
            backend: "embree".into(),
            mode: "path".into(),
            integration: "auto".into(),
            integrate_as: "resting".into(),
            cache_enabled: true,
            lookahead: true,
            width: 8,
            height: 8,
            spp: 4,
            noise_threshold: 0.0,
            min_spp: None,
            physics: crate::sequence::PhysicsSource::Simulated,
            scene_hash: "00000000000000ff".into(),
            trajectory_frames: 10,
            frame_start: 0,
            frame_end: 10,
            frame_step: 1,
            max_depth: Some(6),
            clamp_indirect: 4.0,
            filter: "tent".into(),
            filter_width: 1.0,
            seed: "fixed".into(),
            seed_offset: 0,
            reuse: true,
            reuse_mode: "exact".into(),
            exposure: 1.1,
            aovs: vec!["albedo".into()],
            exr: false,
            denoise: None,
            keep_noisy: false,
            shutter: 0.0,
            settings_from: Default::default(),
        };
        let mut then = serde_json::to_value(&now).unwrap();
        assert_eq!(differences(&then, &now), "its run header does not read");
        then["spp"] = 8.into();
        then.as_object_mut().unwrap().remove("exr");
        assert_eq!(differences(&then, &now), "exr absent there, false now; spp 8 there, 4 now");
    }
}
