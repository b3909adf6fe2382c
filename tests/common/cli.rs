//! The `dormant` binary end to end: the command, running it to an expected exit, and reading
//! the JSON and trajectories it writes.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The `dormant` binary of this build.
pub fn dormant() -> Command {
    Command::new(env!("CARGO_BIN_EXE_dormant"))
}

/// Runs `cmd`, which must succeed (exit 0); returns its output. A failure names the command
/// and shows its stderr.
pub fn succeeds(cmd: &mut Command) -> Output {
    let output = cmd.output().unwrap();
    assert!(output.status.success(), "{cmd:?}: {}", String::from_utf8_lossy(&output.stderr));
    output
}

/// Runs `cmd`, which must exit with `code`; returns its stderr. A wrong exit names the command
/// and shows its stderr.
pub fn exits_with(cmd: &mut Command, code: i32) -> String {
    let output = cmd.output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert_eq!(output.status.code(), Some(code), "{cmd:?}: {stderr}");
    stderr
}

/// The JSON file at `path`.
pub fn read_json(path: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

/// The stats.json a sequence render wrote into `dir`.
pub fn read_stats(dir: &Path) -> serde_json::Value {
    read_json(&dir.join("stats.json"))
}

/// `scenes/tiny.toml` simulated (`dormant --quiet simulate`, with `extra` flags) into
/// `dir/tiny.traj`, which is returned.
pub fn simulate_tiny(dir: &Path, extra: &[&str]) -> PathBuf {
    let traj = dir.join("tiny.traj");
    succeeds(
        dormant()
            .args(["--quiet", "simulate"])
            .args(extra)
            .arg("--out")
            .arg(&traj)
            .arg(super::scenes::shipped("tiny")),
    );
    traj
}
