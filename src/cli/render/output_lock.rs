//! One writer per output folder. A render holds an exclusive lock (flock(2), through
//! `File::try_lock`) on `OUT/.dormant.lock` while it writes into `OUT`, with a note of its pid,
//! host and start inside; a second render into the same folder (a resubmitted task while the
//! first still runs) stops before writing anything, with [`BUSY_EXIT_CODE`] and the holder's
//! note. The kernel releases the lock when its process dies however it dies, so a killed run
//! never locks out the next one (`--resume`, or a requeued task). The file is removed when the
//! render ends; a killed run leaves it, and the next render reuses it.
//!
//! Where it holds across hosts: on a local disk and on NFSv4 (where a dead client's lock lapses
//! with its lease, about 90 s); on Lustre only when mounted with `flock` (with `localflock`,
//! only against a second render on the same node).

use std::fs::{File, OpenOptions, TryLockError};
use std::io::{Read, Write};
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};
use std::time::{SystemTime, UNIX_EPOCH};

use crate::cli::CliError;

/// The lock file's name in the output folder.
const LOCK_FILE: &str = ".dormant.lock";

/// The exit code of a render refused because another one writes into its folder: sysexits'
/// EX_TEMPFAIL, "try again later" (not 2: nothing is wrong with the input).
pub(crate) const BUSY_EXIT_CODE: u8 = 75;

/// The held lock on an output folder; released (and its file removed) when dropped.
pub(super) struct OutputLock {
    file: File,
    path: PathBuf,
}

impl OutputLock {
    /// Locks `out` (an existing directory) for this process, or says who holds it. The lock is
    /// taken on a read-only descriptor and the note written through another one, closed at
    /// once: a file open for writing all run long would keep its filesystem from being
    /// remounted read-only.
    pub(super) fn acquire(out: &Path) -> Result<Self, CliError> {
        let path = out.join(LOCK_FILE);
        let io_error = |e: std::io::Error| CliError::Runtime(format!("cannot lock {}: {e}", path.display()));
        // The holder removes the file before it unlocks: a lock won on a file no longer at the
        // path guards nothing, so open it again.
        for _ in 0..100 {
            OpenOptions::new().write(true).create(true).truncate(false).open(&path).map_err(io_error)?;
            let mut file = match File::open(&path) {
                Ok(file) => file,
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => continue,
                Err(e) => return Err(io_error(e)),
            };
            match file.try_lock() {
                Ok(()) => {}
                Err(TryLockError::WouldBlock) => return Err(busy(out, &mut file)),
                Err(TryLockError::Error(e)) => return Err(io_error(e)),
            }
            let here = std::fs::metadata(&path).ok().map(|m| (m.dev(), m.ino()));
            let locked = file.metadata().map_err(io_error)?;
            if here == Some((locked.dev(), locked.ino())) {
                write_note(&path).map_err(io_error)?;
                return Ok(Self { file, path });
            }
        }
        Err(CliError::Runtime(format!("cannot lock {}: it keeps being replaced", path.display())))
    }
}

impl Drop for OutputLock {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
        let _ = self.file.unlock();
    }
}

/// Writes this process's note into the lock file at `path`: `pid=... host=... start=UNIX_SECONDS`.
fn write_note(path: &Path) -> std::io::Result<()> {
    let host = std::fs::read_to_string("/proc/sys/kernel/hostname").unwrap_or_default();
    let start = unix_seconds();
    let mut file = OpenOptions::new().write(true).truncate(true).open(path)?;
    writeln!(file, "pid={} host={} start={start}", std::process::id(), host.trim())?;
    file.sync_data()
}

/// The error for `out`, whose lock `file` another process holds, naming it from its note.
fn busy(out: &Path, file: &mut File) -> CliError {
    let mut note = String::new();
    let _ = file.read_to_string(&mut note);
    let field = |key: &str| {
        note.split_whitespace().find_map(|f| f.strip_prefix(key)?.strip_prefix('=')).map(str::to_string)
    };
    let since = field("start").and_then(|s| s.parse::<u64>().ok()).map(|s| unix_seconds().saturating_sub(s));
    let holder = match (field("pid"), field("host"), since) {
        (Some(pid), Some(host), Some(s)) => format!("pid {pid} on {host}, running for {s} s"),
        _ => "a process that has not written its note yet".to_string(),
    };
    CliError::Busy(format!(
        "{} is in use by another render ({holder}): wait for it to end, or give another --out",
        out.display()
    ))
}

/// Seconds since the Unix epoch (0 on a clock set before it).
fn unix_seconds() -> u64 {
    SystemTime::now().duration_since(UNIX_EPOCH).map_or(0, |d| d.as_secs())
}
