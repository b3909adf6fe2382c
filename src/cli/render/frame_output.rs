//! [`FrameOutput`]: each frame written through the library's [`FrameWriter`], its line on
//! stdout, and for `--json` its record.

use std::path::{Path, PathBuf};

use indicatif::ProgressBar;

use super::settings::Settings;
use super::RenderArgs;
use crate::cli::CliError;
use dormant::accel::Backend;
use dormant::residency::FrameStats;
use dormant::sequence::output::{FrameWriter, OutputError, OutputLayout, WrittenFrame};
use dormant::sequence::RenderedFrame;

/// Writes each rendered frame's files and reports it.
pub(super) struct FrameOutput<'a> {
    pub writer: FrameWriter<'a>,
    pub settings: Settings,
    pub backend: Backend,
    /// No per-frame line on stdout (`--quiet`, or the JSON report goes there).
    pub quiet: bool,
    /// Keep each frame's record for the `--json` report. Only then: a long sequence would
    /// otherwise accumulate them for nothing (docs/lab/soak-and-build.md#2026-12-01-the-10000-frame-soak).
    pub keep_records: bool,
    pub records: Vec<serde_json::Value>,
    /// Frames kept from an earlier run (`--resume`), not written again.
    pub kept: usize,
    /// With `--video`: every frame's image, in order, once written.
    pub video_frames: Option<Vec<PathBuf>>,
}

/// A frame whose files are being written on a thread of their own, and what is reported of
/// it once they are.
pub(super) struct FrameInFlight {
    writing: std::thread::JoinHandle<Result<WrittenFrame, OutputError>>,
    /// The image's path.
    path: PathBuf,
    /// Its line on stdout, unless quiet; its `--json` record, when kept.
    line: Option<String>,
    record: Option<serde_json::Value>,
}

impl FrameOutput<'_> {
    /// Starts writing `frame`'s files atomically (a reused frame's are copies of its
    /// source's) on a thread of their own, after denoising on this one: the files of one
    /// frame (encoding, and each file's sync before its rename) are written while the next
    /// renders, and the run waits on them only at [`Self::finish`].
    pub fn start(
        &mut self,
        frame: &RenderedFrame,
        scene_stats: Option<&FrameStats>,
    ) -> Result<FrameInFlight, CliError> {
        let files = self.writer.prepare(frame).map_err(output_error)?;
        let path = files.paths()[0].clone();
        let denoise_seconds = files.denoise_seconds();
        let line = (!self.quiet).then(|| self.summary(&path, frame, denoise_seconds));
        let record =
            self.keep_records.then(|| self.record(frame, scene_stats, files.paths(), denoise_seconds));
        let writing = std::thread::spawn(move || files.write());
        Ok(FrameInFlight { writing, path, line, record })
    }

    /// Waits for a frame's files and reports it.
    pub fn finish(&mut self, frame: FrameInFlight, progress: &ProgressBar) -> Result<(), CliError> {
        let written =
            frame.writing.join().map_err(|_| CliError::Runtime("the frame writer panicked".into()))?;
        written.map_err(output_error)?;
        if let Some(line) = frame.line {
            progress.suspend(|| println!("{line}"));
        }
        self.records.extend(frame.record);
        if let Some(video) = &mut self.video_frames {
            video.push(frame.path);
        }
        Ok(())
    }

    /// Writes `frame`'s files and reports it, waiting for them.
    pub fn write(
        &mut self,
        frame: &RenderedFrame,
        scene_stats: Option<&FrameStats>,
        progress: &ProgressBar,
    ) -> Result<(), CliError> {
        let in_flight = self.start(frame, scene_stats)?;
        self.finish(in_flight, progress)
    }

    /// The frame's `--json` record.
    fn record(
        &self,
        frame: &RenderedFrame,
        scene_stats: Option<&FrameStats>,
        files: &[PathBuf],
        denoise_seconds: Option<f64>,
    ) -> serde_json::Value {
        let layout = self.writer.layout;
        // Files per pass (PNG, and EXR with --exr); the image and the noisy image come first.
        let per_pass = layout.files_per_pass();
        let noisy_path = layout.keep_noisy.then(|| &files[per_pass]);
        let aov_paths: Vec<&PathBuf> = files
            .iter()
            .skip(per_pass * (1 + usize::from(layout.keep_noisy)))
            .filter(|p| p.extension().is_some_and(|e| e == "png"))
            .collect();
        let stats = &frame.render;
        serde_json::json!({ "frame": frame.index, "path": files[0], "rays": stats.rays,
            "seconds": stats.seconds, "mrays_per_second": stats.mrays_per_second(), "aovs": aov_paths,
            "spp_mean": stats.spp.mean, "spp_min": stats.spp.min, "spp_max": stats.spp.max,
            "denoise_seconds": denoise_seconds, "noisy_path": noisy_path,
            "reused_from": frame.reused_from, "reuse": frame.reuse, "scene": scene_stats })
    }

    /// The line printed for a written frame.
    fn summary(&self, path: &Path, frame: &RenderedFrame, denoise_seconds: Option<f64>) -> String {
        if let Some(source) = frame.reused_from {
            return format!(
                "wrote {} (nothing moved since frame {source}: its image, not traced)",
                path.display()
            );
        }
        let stats = &frame.render;
        let spp = if stats.spp.min == stats.spp.max {
            format!("{} spp", stats.spp.max)
        } else {
            format!("{:.1} spp mean, {} to {}", stats.spp.mean, stats.spp.min, stats.spp.max)
        };
        let reuse = match frame.reuse {
            Some(exact) if exact.full.is_none() => {
                let s = exact.stats;
                let share = s.samples_traced as f64 / (s.samples_traced + s.samples_reused).max(1) as f64;
                format!(", {:.1}% of samples traced", 100.0 * share)
            }
            _ => String::new(),
        };
        format!(
            "rendered {} ({}x{}, {}, {} mode, {}): {:.2} s, {} rays, {:.1} Mrays/s{reuse}",
            path.display(),
            self.settings.size.value.width,
            self.settings.size.value.height,
            spp,
            self.settings.mode.value.name(),
            self.backend,
            stats.seconds,
            stats.rays,
            stats.mrays_per_second()
        ) + &denoise_seconds.map(|s| format!(", denoised in {s:.2} s")).unwrap_or_default()
    }
}

/// The output layout `args` ask for.
pub(super) fn layout(args: &RenderArgs) -> OutputLayout {
    OutputLayout { dir: args.out.clone(), exr: args.exr, keep_noisy: args.keep_noisy, aovs: args.aov.clone() }
}

/// An output failure as the CLI reports it: an earlier run's statistics that do not fit are
/// the user's to fix (exit 2), anything else a runtime failure.
pub(super) fn output_error(e: OutputError) -> CliError {
    match e {
        OutputError::Stats(e) => CliError::Input(e.to_string()),
        e => CliError::Runtime(e.to_string()),
    }
}
