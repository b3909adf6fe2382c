//! Stopping a sequence on a signal. SIGTERM (what Slurm and most schedulers send to end or
//! preempt a job), SIGINT (Ctrl-C) and SIGUSR1 (the warning `sbatch --signal=B:USR1@SECONDS`
//! asks for before a time limit) ask a render to stop after the frame in flight: its files and
//! statistics are written whole, so `render --resume` continues where it stopped. A second
//! such signal ends the process at once (its exit code the same), leaving at most the frame in
//! flight's temporary files, which `--resume` removes.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;

use signal_hook::consts::{SIGINT, SIGTERM, SIGUSR1};
use signal_hook::flag;

use crate::cli::CliError;

/// The signals that stop a render.
const STOP_SIGNALS: [i32; 3] = [SIGTERM, SIGINT, SIGUSR1];

/// The stop signals' handlers, installed for the frame loop; a signal that arrives is kept
/// until the loop looks.
pub(super) struct StopSignals {
    /// The number of the last stop signal that arrived; 0 while none has.
    arrived: Arc<AtomicUsize>,
    /// Frames written since the handlers were installed.
    frames: u64,
}

impl StopSignals {
    /// Installs the handlers: each stop signal is recorded, and once one has arrived the next
    /// ends the process with [`exit_code`] of it. (The handlers stay for the process's life;
    /// a render is its last work.)
    pub(super) fn install() -> Result<Self, CliError> {
        let arrived = Arc::new(AtomicUsize::new(0));
        let armed = Arc::new(AtomicBool::new(false));
        for signal in STOP_SIGNALS {
            let install = || -> std::io::Result<()> {
                // Registered first, so the first signal finds it unarmed: it only arms it.
                flag::register_conditional_shutdown(
                    signal,
                    i32::from(exit_code(signal)),
                    Arc::clone(&armed),
                )?;
                flag::register_usize(signal, Arc::clone(&arrived), signal as usize)?;
                flag::register(signal, Arc::clone(&armed))?;
                Ok(())
            };
            install().map_err(|e| CliError::Runtime(format!("cannot handle signal {signal}: {e}")))?;
        }
        Ok(Self { arrived, frames: 0 })
    }

    /// Called once frame `last_frame` is rendered (its files, in flight, are written before
    /// the run ends): once a stop signal has arrived, the error that ends the frame loop.
    pub(super) fn after_frame(&mut self, last_frame: u32) -> Result<(), CliError> {
        self.frames += 1;
        match self.arrived.load(Ordering::SeqCst) {
            0 => Ok(()),
            signal => Err(CliError::Stopped { signal: signal as i32, last_frame, frames: self.frames }),
        }
    }
}

/// The exit code of a render stopped by `signal`: 128 plus its number, as a shell reports a
/// process the signal ended (143 for SIGTERM, 130 for SIGINT, 138 for SIGUSR1).
pub(crate) fn exit_code(signal: i32) -> u8 {
    (128 + signal) as u8
}

/// `signal`'s name as `kill -l` prints it, with the SIG prefix.
pub(crate) fn signal_name(signal: i32) -> &'static str {
    match signal {
        SIGTERM => "SIGTERM",
        SIGINT => "SIGINT",
        SIGUSR1 => "SIGUSR1",
        _ => "a signal",
    }
}
