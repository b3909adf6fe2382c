//! Encoding a rendered sequence's PNG frames into an H.264 MP4 with `ffmpeg`, an external
//! program that must be on `PATH`. The frames are listed in an ffconcat file (so sequences
//! rendered every n-th frame work), one per video frame; odd sizes are scaled to even ones
//! (yuv420p). The video is written to a temporary file and renamed.

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// How to get ffmpeg, for the message when it is missing.
const FFMPEG_HINT: &str =
    "install ffmpeg (Debian/Ubuntu: `apt-get install ffmpeg`; Fedora: `dnf install ffmpeg`; \
                               macOS: `brew install ffmpeg`) or leave out --video";

#[derive(Debug, thiserror::Error)]
pub(super) enum VideoError {
    #[error("--video needs ffmpeg, which was not found on PATH: {FFMPEG_HINT}")]
    FfmpegMissing,
    #[error("no frames to encode")]
    NoFrames,
    #[error("cannot write {path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    #[error("ffmpeg failed ({status}) encoding {path}: {stderr}")]
    Ffmpeg { path: PathBuf, status: String, stderr: String },
}

/// Whether `ffmpeg -version` runs.
pub(super) fn ffmpeg_available() -> bool {
    Command::new("ffmpeg")
        .arg("-version")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// Encodes `frames` (PNG files in `dir`, in order) at `fps` into `out`.
pub(super) fn encode_video(dir: &Path, frames: &[PathBuf], fps: f64, out: &Path) -> Result<(), VideoError> {
    if frames.is_empty() {
        return Err(VideoError::NoFrames);
    }
    if !ffmpeg_available() {
        return Err(VideoError::FfmpegMissing);
    }
    // Rounded to 1/1000 frames per second: a timestep stored as f32 gives 59.99999... for 60.
    let fps = if fps.is_finite() && fps > 0.0 { (fps * 1000.0).round().max(1.0) / 1000.0 } else { 30.0 };
    let pid = std::process::id();
    let list = dir.join(format!(".video-frames.{pid}.ffconcat"));
    let tmp = dir.join(format!(".video.{pid}.tmp.mp4"));
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| VideoError::Io { path, source }
    };
    let mut text = String::from("ffconcat version 1.0\n");
    for frame in frames {
        let absolute = std::path::absolute(frame).map_err(io(frame))?;
        let escaped = absolute.to_string_lossy().replace('\'', "'\\''");
        text.push_str(&format!("file '{escaped}'\n"));
    }
    std::fs::File::create(&list).and_then(|mut f| f.write_all(text.as_bytes())).map_err(io(&list))?;
    let output = Command::new("ffmpeg")
        // `-r` on the input: one listed image per frame at `fps`.
        .args(["-y", "-loglevel", "error", "-f", "concat", "-safe", "0", "-r", &fps.to_string(), "-i"])
        .arg(&list)
        .args(["-vf", "scale=trunc(iw/2)*2:trunc(ih/2)*2"])
        .args(["-c:v", "libx264", "-pix_fmt", "yuv420p", "-f", "mp4"])
        .arg(&tmp)
        .stdin(Stdio::null())
        .output();
    let _ = std::fs::remove_file(&list);
    let output = output.map_err(io(Path::new("ffmpeg")))?;
    if !output.status.success() {
        let _ = std::fs::remove_file(&tmp);
        return Err(VideoError::Ffmpeg {
            path: out.to_path_buf(),
            status: output.status.to_string(),
            stderr: String::from_utf8_lossy(&output.stderr).trim().to_string(),
        });
    }
    std::fs::rename(&tmp, out).map_err(|source| {
        let _ = std::fs::remove_file(&tmp);
        VideoError::Io { path: out.to_path_buf(), source }
    })
}
