//! Progress bars on stderr for long commands (frames simulated, frames rendered). Hidden with
//! `--quiet`, and by indicatif itself when stderr is not a terminal.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

const TEMPLATE: &str = "{prefix:>10} [{bar:30}] {pos}/{len} frames, {elapsed} elapsed, ETA {eta} {msg}";

fn style() -> ProgressStyle {
    ProgressStyle::with_template(TEMPLATE)
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> ")
}

/// A bar that draws nothing (until [`become_frames_bar`] gives it a target).
pub(super) fn hidden() -> ProgressBar {
    ProgressBar::hidden()
}

/// A bar counting frames on stderr; hidden when `quiet` or stderr is not a terminal.
pub(super) fn frames_bar(quiet: bool, prefix: &'static str, frames: Option<u64>) -> ProgressBar {
    let bar = hidden();
    become_frames_bar(&bar, quiet, prefix, frames.unwrap_or(0));
    bar
}

/// Turns `bar` into a frame counter of `frames` on stderr (hidden when `quiet` or stderr is not
/// a terminal: indicatif's stderr target draws only to a terminal).
pub(super) fn become_frames_bar(bar: &ProgressBar, quiet: bool, prefix: &'static str, frames: u64) {
    bar.set_style(style());
    bar.set_prefix(prefix);
    bar.set_length(frames);
    bar.set_position(0);
    if !quiet {
        bar.set_draw_target(ProgressDrawTarget::stderr());
    }
}
