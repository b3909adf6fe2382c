//! `dormant render SCENE --video`: a clear input error (exit 2) without ffmpeg, and an MP4
//! next to the frames with it (that half skips when ffmpeg is not installed).

use crate::common;

use std::process::Command;

use common::cli::{dormant, exits_with, succeeds};

fn ffmpeg_installed() -> bool {
    Command::new("ffmpeg").arg("-version").output().is_ok_and(|o| o.status.success())
}

#[test]
fn video_without_ffmpeg_is_an_input_error_that_says_how_to_install_it() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("v");
    let stderr = exits_with(
        dormant()
            .args([
                "render",
                "scenes/tiny.toml",
                "--size",
                "16x9",
                "--spp",
                "1",
                "--frames",
                "0..3",
                "--video",
            ])
            .arg("--out")
            .arg(&out)
            .env("PATH", dir.path())
            .current_dir(env!("CARGO_MANIFEST_DIR")),
        2,
    );
    assert!(stderr.contains("ffmpeg") && stderr.contains("apt-get install ffmpeg"), "{stderr}");
    assert!(!out.exists(), "nothing is rendered when the video cannot be made");
}

#[test]
fn video_is_written_next_to_the_frames() {
    if !ffmpeg_installed() {
        eprintln!("skipped: ffmpeg is not installed");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("v");
    succeeds(
        dormant()
            .args(["render", "scenes/tiny.toml", "--size", "33x19", "--spp", "1", "--frames", "0..12"])
            .args(["--video", "--quiet", "--out"])
            .arg(&out)
            .current_dir(env!("CARGO_MANIFEST_DIR")),
    );
    let video = std::fs::metadata(out.join("video.mp4")).unwrap();
    assert!(video.len() > 0);
    let leftovers: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .filter_map(Result::ok)
        .filter(|e| e.file_name().to_string_lossy().starts_with('.'))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}
