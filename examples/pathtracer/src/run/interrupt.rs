//! Ctrl-C: the first SIGINT triggers the library's [`Interrupt`], and the run's driver stops
//! it after its current iteration (the run then writes its checkpoint and outputs); a second
//! one exits at once with code 130.
//!
//! The interrupt is process-wide and triggered only by the handler the command line
//! installs ([`install_handler`]); library callers and tests stop a run with
//! [`super::Control::stop_after`] instead.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::LazyLock;

use plateau_free::lifecycle::Interrupt;

/// The exit code of a process stopped by SIGINT (128 + 2), by shell convention.
pub const EXIT_CODE: i32 = 130;

/// The process's interrupt, which Ctrl-C triggers.
static CTRL_C: LazyLock<Interrupt> = LazyLock::new(Interrupt::new);

/// Whether Ctrl-C has been pressed (once).
pub fn requested() -> bool {
    CTRL_C.is_triggered()
}

/// Installs the SIGINT handler: the first signal triggers [`ctrl_c`] and says on stderr what
/// happens next; the second exits at once with [`EXIT_CODE`] (the files already written stay
/// whole: every checkpoint is replaced atomically). Installing twice is harmless.
pub fn install_handler() {
    static COUNT: AtomicUsize = AtomicUsize::new(0);
    let _ = ctrlc::set_handler(|| {
        if COUNT.fetch_add(1, Ordering::SeqCst) == 0 {
            CTRL_C.trigger();
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
