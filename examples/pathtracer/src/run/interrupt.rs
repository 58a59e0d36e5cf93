//! Ctrl-C: the first SIGINT asks the running loop to stop after its current iteration (it
//! then writes its checkpoint and outputs); a second one exits at once with code 130.
//!
//! The flag is process-wide and set only by the handler the command line installs
//! ([`install_handler`]); library callers and tests stop a run with
//! [`super::Control::stop_after`] instead.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// The exit code of a process stopped by SIGINT (128 + 2), by shell convention.
pub const EXIT_CODE: i32 = 130;

static REQUESTED: AtomicBool = AtomicBool::new(false);

/// Whether Ctrl-C has been pressed (once).
pub fn requested() -> bool {
    REQUESTED.load(Ordering::SeqCst)
}

/// Installs the SIGINT handler: the first signal sets the flag and says on stderr what
/// happens next; the second exits at once with [`EXIT_CODE`] (the files already written stay
/// whole: every checkpoint is replaced atomically). Installing twice is harmless.
pub fn install_handler() {
    static COUNT: AtomicUsize = AtomicUsize::new(0);
    let _ = ctrlc::set_handler(|| {
        if COUNT.fetch_add(1, Ordering::SeqCst) == 0 {
            REQUESTED.store(true, Ordering::SeqCst);
            eprintln!(
                "\ninterrupted: finishing the current iteration, then writing the checkpoint and the outputs (Ctrl-C again to quit at once)"
            );
        } else {
            std::process::exit(EXIT_CODE);
        }
    });
}

/// The error a command returns when a run was interrupted after writing what it had: the
/// command line prints it and exits with [`EXIT_CODE`].
#[derive(Debug)]
pub struct Interrupted {
    /// The command that continues the work.
    pub resume: String,
}

impl std::fmt::Display for Interrupted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "interrupted; to continue: {}", self.resume)
    }
}

impl std::error::Error for Interrupted {}
