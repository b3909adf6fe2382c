//! `dormant render --resume`: a render killed mid-sequence, stopped by a signal, or failed by
//! its disk (full, read-only, past the file size limit) and resumed leaves the files of an
//! uninterrupted run (frames byte for byte, statistics in every field but the timings), a
//! resumed static stretch copies the kept frames' files, and the statistics of another
//! configuration, or records the replay does not reach, are refused. One render at a time
//! writes into a folder; a killed one does not lock out the next.

use crate::common;

use std::ffi::OsString;
use std::path::Path;
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

use common::cli::{dormant, exits_with, read_json, read_stats, succeeds};
use common::scenes;
use serde_json::Value;

/// A slice of the tiny scene, every sixth frame (40 frames), islands integrated (baked, so the
/// geometry cache serves their wakes), an albedo pass and EXRs: every output kind, and about
/// 0.1 s a frame, so that a kill lands mid-sequence.
fn tiny_run(out: &Path) -> Vec<OsString> {
    let mut args: Vec<OsString> =
        ["--quiet", "render", "--size", "96x54", "--spp", "16", "--frames", "90..330"]
            .iter()
            .chain(&["--frame-step", "6", "--integration", "always", "--integrate-as", "baked"])
            .chain(&["--aov", "albedo", "--exr", "--out"])
            .map(OsString::from)
            .collect();
    args.push(out.into());
    args.push(scenes::shipped("tiny").into());
    args
}

fn run(args: &[OsString], extra: &[&str]) -> Output {
    succeeds(dormant().args(args).args(extra))
}

fn frame_count(dir: &Path) -> usize {
    let names = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap());
    names.filter(|n| n.starts_with("frame_") && n.ends_with(".png") && n.matches('.').count() == 1).count()
}

/// Whether a stats.json field holds a measured time, or follows from measured times: the
/// fields a repeated run may change (docs/stats-format.md).
fn is_timing(field: &str) -> bool {
    // `_ms`: stage times, totals, medians and the cost model's fits (`build_ms_intercept`,
    // `trace_ms_mean`, ...); `baked`/`resting`: its measured trace penalties; the resting
    // scene's rebuild schedule (always false with --integrate-as baked, as here).
    field.contains("_ms")
        || ["mrays_per_second", "estimate", "baked", "resting", "rest_rebuilt", "rest_rebuilds"]
            .contains(&field)
}

fn without_timings(value: &Value) -> Value {
    match value {
        Value::Object(map) => Value::Object(
            map.iter().filter(|(k, _)| !is_timing(k)).map(|(k, v)| (k.clone(), without_timings(v))).collect(),
        ),
        Value::Array(items) => Value::Array(items.iter().map(without_timings).collect()),
        other => other.clone(),
    }
}

/// What a frame traced and reused: the first frame a resumed run renders traces in full what
/// the uninterrupted run may have taken from its store (the same image), so these may differ
/// there, in the totals, and in the frames after it: a blocked shadow ray's horizon follows
/// the blocker the tracer meets first, which depends on the frame it was traced in (a ray may
/// gain blockers while its result stays) and on how the scene was built.
const TRACED_COUNTS: [&str; 7] = [
    "rays",
    "neighbour_rays",
    "samples_traced",
    "samples_reused",
    "pixels_traced",
    "full_frame",
    "traced_share",
];

/// stats.csv without its timing columns, and without what was traced from frame
/// `first_resumed` on.
fn csv_without_timings(dir: &Path, first_resumed: u64) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(dir.join("stats.csv")).unwrap();
    let rows: Vec<Vec<&str>> = text.lines().map(|l| l.split(',').collect()).collect();
    let keep: Vec<usize> = (0..rows[0].len()).filter(|&i| !is_timing(rows[0][i])).collect();
    rows.iter()
        .map(|r| {
            let resumed = r[0].parse::<u64>().is_ok_and(|f| f >= first_resumed);
            let traced = |i: usize| resumed && TRACED_COUNTS.contains(&rows[0][i]);
            keep.iter().map(|&i| if traced(i) { String::new() } else { r[i].to_string() }).collect()
        })
        .collect()
}

/// `stats` without what was traced from frame `first_resumed` on and in the totals.
fn without_traced_counts(mut stats: Value, first_resumed: u64) -> Value {
    for frame in stats["frames"].as_array_mut().unwrap() {
        if frame["frame"].as_u64().is_some_and(|f| f >= first_resumed) {
            TRACED_COUNTS.iter().for_each(|k| _ = frame.as_object_mut().unwrap().remove(*k));
        }
    }
    let totals = stats["summary"]["totals"].as_object_mut().unwrap();
    TRACED_COUNTS.iter().for_each(|k| _ = totals.remove(*k));
    stats
}

/// Every file of `whole` but the plot (timings) is in `resumed` with the same bytes, the
/// statistics are equal but for timings and what was traced from the first resumed frame,
/// `first_resumed`, on, and no temporary file is left.
fn assert_same_outputs(whole: &Path, resumed: &Path, first_resumed: u64) {
    let mut compared = 0;
    for entry in std::fs::read_dir(whole).unwrap() {
        let name = entry.unwrap().file_name().into_string().unwrap();
        if name.starts_with("frame_") {
            let a = std::fs::read(whole.join(&name)).unwrap();
            assert!(a == std::fs::read(resumed.join(&name)).unwrap(), "{name} differs after resuming");
            compared += 1;
        }
    }
    assert!(compared > 0);
    let stats = |dir: &Path| without_traced_counts(without_timings(&read_stats(dir)), first_resumed);
    let (a, b) = (stats(whole), stats(resumed));
    let (frames_a, frames_b) = (a["frames"].as_array().unwrap(), b["frames"].as_array().unwrap());
    assert_eq!(frames_a.len(), frames_b.len());
    for (fa, fb) in frames_a.iter().zip(frames_b) {
        assert_eq!(fa, fb, "stats.json: a frame differs");
    }
    assert_eq!(a, b, "stats.json differs");
    let csv = |dir: &Path| csv_without_timings(dir, first_resumed);
    assert_eq!(csv(whole), csv(resumed), "stats.csv differs");
    assert!(resumed.join("report.png").is_file());
    assert_eq!(temporaries(resumed), Vec::<String>::new(), "left behind");
}

/// Starts `args` (stderr piped) and waits until `ready` holds; the run must not end before.
fn start_until(args: &[OsString], ready: impl Fn() -> bool) -> Child {
    let mut child = dormant().args(args).stdout(Stdio::null()).stderr(Stdio::piped()).spawn().unwrap();
    let deadline = Instant::now() + Duration::from_secs(300);
    while !ready() && Instant::now() < deadline {
        assert!(child.try_wait().unwrap().is_none(), "the run ended too soon");
        std::thread::sleep(Duration::from_millis(5));
    }
    child
}

/// Starts `args` and kills it (SIGKILL) once its stats.json records `frames` frames, or
/// once half of `tiny_run`'s 40 frames are written: stats.json is rewritten at intervals that
/// grow with the cost of its last write, so after one slow write it may next be written only
/// at the end (CI of c61b1be: killed with 40 of 40 frames written).
fn kill_after(args: &[OsString], out: &Path, frames: usize) {
    let mut child =
        start_until(args, || recorded_frames(out) >= frames || (out.is_dir() && frame_count(out) >= 20));
    child.kill().unwrap();
    child.wait().unwrap();
}

#[test]
fn killed_render_resumes_to_the_files_of_an_uninterrupted_run() {
    let dir = tempfile::tempdir().unwrap();
    let (whole, killed) = (dir.path().join("whole"), dir.path().join("killed"));
    run(&tiny_run(&whole), &[]);
    let total = frame_count(&whole);
    assert_eq!(total, 40);
    assert!(read_stats(&whole)["summary"]["totals"]["islands_reactivated"].as_u64().unwrap() > 0);

    kill_after(&tiny_run(&killed), &killed, 4);
    let recorded = read_stats(&killed)["frames"].as_array().unwrap().len();
    let written = frame_count(&killed);
    // stats.json is always written after the first frame.
    assert!(recorded >= 1 && written < total, "killed with {written} of {total} frames written");

    let report = dir.path().join("resume.json");
    let mut args = tiny_run(&killed);
    args.splice(0..0, [OsString::from("--json"), report.clone().into()]);
    run(&args, &["--resume"]);
    let report = read_json(&report);
    let kept = report["kept_frames"].as_u64().unwrap() as usize;
    assert_eq!(kept, recorded, "the frames stats.json recorded are kept");
    assert_eq!(report["frames"].as_array().unwrap().len(), total - kept, "only the rest is rendered");
    let first_resumed = read_stats(&whole)["frames"][kept]["frame"].as_u64().unwrap();
    assert_same_outputs(&whole, &killed, first_resumed);
}

/// Sends `signal` (a `kill -s` name) to `child`.
fn send(child: &Child, signal: &str) {
    succeeds(Command::new("kill").args(["-s", signal, &child.id().to_string()]));
}

/// The frames `out`'s stats.json records (0 while there is none).
fn recorded_frames(out: &Path) -> usize {
    std::fs::read(out.join("stats.json"))
        .ok()
        .and_then(|b| serde_json::from_slice::<Value>(&b).ok())
        .map_or(0, |s| s["frames"].as_array().map_or(0, Vec::len))
}

/// Starts `args` and, once `ready` holds, sends it `signals` one after another; returns its
/// exit code and stderr.
fn signal_when(args: &[OsString], ready: impl Fn() -> bool, signals: &[&str]) -> (Option<i32>, String) {
    let child = start_until(args, ready);
    for signal in signals {
        send(&child, signal);
        // Apart, so that the kernel does not merge two of one kind before they are handled.
        std::thread::sleep(Duration::from_millis(50));
    }
    let output = child.wait_with_output().unwrap();
    (output.status.code(), String::from_utf8_lossy(&output.stderr).into_owned())
}

#[test]
fn render_stopped_by_sigterm_finishes_its_frame_exits_143_and_resumes_to_an_uninterrupted_run() {
    let dir = tempfile::tempdir().unwrap();
    let (whole, stopped) = (dir.path().join("whole"), dir.path().join("stopped"));
    run(&tiny_run(&whole), &[]);
    let total = frame_count(&whole);

    let (code, stderr) = signal_when(&tiny_run(&stopped), || recorded_frames(&stopped) >= 4, &["TERM"]);
    assert_eq!(code, Some(143), "{stderr}");
    assert!(stderr.contains("stopped by SIGTERM after frame") && stderr.contains("--resume"), "{stderr}");
    // The frame in flight was finished: every recorded frame has its files, nothing else is.
    let recorded = read_stats(&stopped)["frames"].as_array().unwrap().len();
    assert!(recorded >= 4 && recorded < total, "stopped with {recorded} of {total} frames");
    assert_eq!(frame_count(&stopped), recorded);
    assert_eq!(temporaries(&stopped), Vec::<String>::new(), "left behind");

    resume_to_whole(&tiny_run(&stopped), &whole, &stopped, recorded);
}

#[test]
fn sigusr1_and_sigint_stop_a_render_with_128_plus_their_number() {
    for (signal, code) in [("USR1", 138), ("INT", 130)] {
        let dir = tempfile::tempdir().unwrap();
        let ready = || recorded_frames(dir.path()) >= 1;
        let (exit, stderr) = signal_when(&tiny_run(dir.path()), ready, &[signal]);
        assert_eq!(exit, Some(code), "SIG{signal}: {stderr}");
        assert!(stderr.contains(&format!("stopped by SIG{signal}")), "{stderr}");
        assert_eq!(frame_count(dir.path()), read_stats(dir.path())["frames"].as_array().unwrap().len());
    }
}

#[test]
fn a_second_signal_stops_a_render_without_finishing_its_frame() {
    // Frames of a second or more: once the first is written, the second is still tracing
    // when both signals arrive, and no further frame may appear.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let args: Vec<OsString> =
        ["--quiet", "render", "--size", "640x360", "--spp", "64", "--frames", "100..104"]
            .iter()
            .map(OsString::from)
            .chain([OsString::from("--out"), out.clone().into(), scenes::shipped("tiny").into()])
            .collect();
    let (code, stderr) = signal_when(&args, || frame_count_or_zero(&out) >= 1, &["TERM", "TERM"]);
    assert_eq!(code, Some(143), "{stderr}");
    assert_eq!(frame_count(&out), 1, "the frame in flight was finished");
}

/// `out`'s temporary files (`.NAME.PID.tmp`).
fn temporaries(out: &Path) -> Vec<String> {
    let names = std::fs::read_dir(out).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap());
    names.filter(|n| n.ends_with(".tmp")).collect()
}

/// Runs `cmd`, which must fail as [`failed_on_disk`] says.
fn fails_on_disk(cmd: &mut Command, out: &Path, cause: &str) -> usize {
    let output = cmd.output().unwrap();
    failed_on_disk(&output, out, cause)
}

/// A render into `out` that ended with `output` must have failed with exit code 1 naming a
/// file of `out` and `cause`, leaving no temporary file; returns how many frames its
/// stats.json records.
fn failed_on_disk(output: &Output, out: &Path, cause: &str) -> usize {
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains(&out.display().to_string()) && stderr.contains(cause), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(temporaries(out), Vec::<String>::new(), "left behind");
    recorded_frames(out)
}

/// Resumes `args`, a run into `out` that recorded `recorded` frames before it ended, and
/// requires the files of the uninterrupted run in `whole`.
fn resume_to_whole(args: &[OsString], whole: &Path, out: &Path, recorded: usize) {
    run(args, &["--resume"]);
    let first_resumed = read_stats(whole)["frames"][recorded]["frame"].as_u64().unwrap();
    assert_same_outputs(whole, out, first_resumed);
}

#[test]
fn a_file_past_the_size_limit_fails_the_render_naming_it_and_resume_finishes_it() {
    // PNGs only: each frame's files stay under the limit while stats.json grows past it.
    let png_run =
        |out: &Path| -> Vec<OsString> { tiny_run(out).into_iter().filter(|a| a != "--exr").collect() };
    let dir = tempfile::tempdir().unwrap();
    let (whole, limited) = (dir.path().join("whole"), dir.path().join("limited"));
    run(&png_run(&whole), &[]);
    let mut limit = Command::new("prlimit");
    limit.args(["--fsize=20000", "--"]).arg(env!("CARGO_BIN_EXE_dormant")).args(png_run(&limited));
    let recorded = fails_on_disk(&mut limit, &limited, "File too large");
    assert!(recorded > 0 && recorded < frame_count(&whole), "failed after {recorded} frames");
    resume_to_whole(&png_run(&limited), &whole, &limited, recorded);
}

/// A tmpfs of `size` mounted on `dir` for a test, unmounted when dropped; `None` where this
/// process may not mount (not root, or no CAP_SYS_ADMIN in a container).
struct SmallDisk<'a> {
    dir: &'a Path,
}

impl<'a> SmallDisk<'a> {
    fn mount(dir: &'a Path, size: &str) -> Option<Self> {
        std::fs::create_dir_all(dir).unwrap();
        let ok = Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={size}"), "tmpfs"])
            .arg(dir)
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success());
        if !ok {
            eprintln!("skipped: cannot mount a tmpfs here (needs root)");
        }
        ok.then_some(Self { dir })
    }

    /// Remounts with `options` (`size=64m`, `ro`, `rw`); a read-only remount waits while a
    /// file is open for writing (EBUSY).
    fn remount(&self, options: &str) {
        let deadline = Instant::now() + Duration::from_secs(30);
        loop {
            let status = Command::new("mount")
                .args(["-o", &format!("remount,{options}")])
                .arg(self.dir)
                .stderr(Stdio::null())
                .status()
                .unwrap();
            if status.success() {
                return;
            }
            assert!(Instant::now() < deadline, "cannot remount {} {options}", self.dir.display());
            std::thread::sleep(Duration::from_millis(2));
        }
    }
}

impl Drop for SmallDisk<'_> {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg("-l").arg(self.dir).status();
    }
}

#[test]
fn a_full_disk_fails_the_render_naming_the_file_and_resume_finishes_it_once_there_is_room() {
    let dir = tempfile::tempdir().unwrap();
    let (whole, full) = (dir.path().join("whole"), dir.path().join("full"));
    // The whole run writes 5.6 MB; 2 MB fill up part-way.
    let Some(disk) = SmallDisk::mount(&full, "2m") else { return };
    run(&tiny_run(&whole), &[]);
    let recorded = fails_on_disk(dormant().args(tiny_run(&full)), &full, "No space left on device");
    assert!(recorded < frame_count(&whole), "failed after {recorded} frames");
    disk.remount("size=64m");
    resume_to_whole(&tiny_run(&full), &whole, &full, recorded);
}

#[test]
fn a_disk_turned_read_only_fails_the_render_and_resume_finishes_it_once_writable() {
    let dir = tempfile::tempdir().unwrap();
    let (whole, disk_dir) = (dir.path().join("whole"), dir.path().join("disk"));
    let Some(disk) = SmallDisk::mount(&disk_dir, "64m") else { return };
    run(&tiny_run(&whole), &[]);
    let out = disk_dir.join("out");
    let child = start_until(&tiny_run(&out), || recorded_frames(&out) >= 4);
    disk.remount("ro");
    let recorded = failed_on_disk(&child.wait_with_output().unwrap(), &out, "Read-only file system");
    disk.remount("rw");
    resume_to_whole(&tiny_run(&out), &whole, &out, recorded);
}

#[test]
fn a_second_render_into_a_folder_in_use_exits_75_naming_the_first() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let first = start_until(&tiny_run(&out), || frame_count_or_zero(&out) >= 1);
    let stderr = exits_with(dormant().args(tiny_run(&out)).arg("--resume"), 75);
    assert!(
        stderr.contains("is in use by another render") && stderr.contains(&format!("pid {}", first.id())),
        "{stderr}"
    );
    let output = first.wait_with_output().unwrap();
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    assert_eq!(frame_count(&out), 40, "the first render finished undisturbed");
    assert!(!out.join(".dormant.lock").exists(), "the lock file is removed at the end");
}

#[test]
fn a_killed_render_does_not_lock_out_the_next() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    kill_after(&tiny_run(&out), &out, 1);
    assert!(out.join(".dormant.lock").exists(), "a killed render leaves its lock file");
    run(&tiny_run(&out), &["--resume"]);
    assert_eq!(frame_count(&out), 40);
}

/// [`frame_count`], 0 while `dir` does not exist.
fn frame_count_or_zero(dir: &Path) -> usize {
    if dir.is_dir() {
        frame_count(dir)
    } else {
        0
    }
}

#[test]
fn resumed_static_frames_copy_the_kept_frames_files() {
    let dir = tempfile::tempdir().unwrap();
    // Six crates dropped onto the ground: at rest (bit for bit) from about frame 70 on.
    let scene = scenes::copy_data("settle", dir.path());
    let settle_run = |out: &Path| -> Vec<OsString> {
        let args = ["--quiet", "render", "--size", "48x27", "--spp", "2", "--frames", "50..100"];
        let mut args: Vec<OsString> = args
            .iter()
            .chain(&["--aov", "depth", "--exr", "--integration", "always"])
            .map(OsString::from)
            .collect();
        args.extend([OsString::from("--out"), out.into(), scene.clone().into()]);
        args
    };
    let (whole, cut) = (dir.path().join("whole"), dir.path().join("cut"));
    run(&settle_run(&whole), &[]);
    // A kill as it can land: the statistics hold frame `first_missing`, but one of its files
    // (the EXR) and every later frame are not written yet. It reuses a kept frame's image.
    let frames = read_stats(&whole)["frames"].as_array().unwrap().clone();
    let reused = |f: &Value| f["reused"].as_bool().unwrap();
    let first_missing =
        frames.windows(2).find(|w| reused(&w[0]) && reused(&w[1])).unwrap()[1]["frame"].as_u64().unwrap();
    copy_dir(&whole, &cut);
    for entry in std::fs::read_dir(&cut).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let frame = name.strip_prefix("frame_").and_then(|n| n[..4].parse::<u64>().ok());
        if frame.is_some_and(|f| f > first_missing) || name == format!("frame_{first_missing:04}.exr") {
            std::fs::remove_file(path).unwrap();
        }
    }
    run(&settle_run(&cut), &["--resume"]);
    assert_same_outputs(&whole, &cut, first_missing);
    assert!(read_stats(&cut)["summary"]["totals"]["reused_frames"].as_u64().unwrap() > 2);
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let path = entry.unwrap().path();
        std::fs::copy(&path, to.join(path.file_name().unwrap())).unwrap();
    }
}

#[test]
fn resume_refuses_the_statistics_of_another_configuration() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let short = |spp: &str| -> Vec<OsString> {
        ["--quiet", "render", "--size", "32x18", "--spp", spp, "--frames", "100..110", "--resume", "--out"]
            .iter()
            .map(OsString::from)
            .chain([out.clone().into(), scenes::shipped("tiny").into()])
            .collect()
    };
    // Nothing to resume in a new directory: every frame renders.
    run(&short("2"), &[]);
    assert_eq!(frame_count(&out), 10);
    let before = std::fs::read(out.join("stats.json")).unwrap();
    let frame = std::fs::read(out.join("frame_0105.png")).unwrap();
    let stderr = exits_with(dormant().args(short("4")), 2);
    assert!(stderr.contains("stats.json") && stderr.contains("spp 2 there, 4 now"), "{stderr}");
    assert_eq!(std::fs::read(out.join("stats.json")).unwrap(), before, "stats.json was touched");
    assert_eq!(std::fs::read(out.join("frame_0105.png")).unwrap(), frame, "a frame was touched");
    // A kept record that the replay does not reach (here: edited) is refused too.
    let mut edited: Value = serde_json::from_slice(&before).unwrap();
    let instances = edited["frames"][2]["instances"].as_u64().unwrap();
    edited["frames"][2]["instances"] = (instances + 1).into();
    std::fs::write(out.join("stats.json"), serde_json::to_vec(&edited).unwrap()).unwrap();
    let stderr = exits_with(dormant().args(short("2")), 2);
    assert!(
        stderr.contains("stats.json") && stderr.contains("frame 102") && stderr.contains("instances"),
        "{stderr}"
    );
    // --resume needs a sequence.
    exits_with(dormant().args(["render", "--resume", "--out"]).arg(&out), 2);
}
