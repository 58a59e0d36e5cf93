//! [`Interrupt`]: a stop asked from outside the run.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// A stop asked from outside a run: a Ctrl-C handler, another thread, a GUI's button, the
/// Python bindings' signal check. Clones share one flag; a [`crate::lifecycle::Driver`]
/// given one checks it before every ask and, once it is triggered, ends the run with
/// [`crate::Stop::Interrupted`] and the best point so far.
///
/// The library installs no signal handler itself: signals belong to the application (it
/// may have its own Ctrl-C handling, run in an interpreter that has one, or be a library
/// itself), so the application decides what triggers the interrupt.
///
/// ```
/// use plateau_free::lifecycle::{Driver, Interrupt};
/// use plateau_free::{Minimizer, Stop};
///
/// let stop = Interrupt::new();
/// let from_f = stop.clone();
/// // The objective itself asks for the stop at its 50th call (any thread could).
/// let calls = std::sync::atomic::AtomicUsize::new(0);
/// let f = |x: &[f64]| {
///     if calls.fetch_add(1, std::sync::atomic::Ordering::Relaxed) == 49 {
///         from_f.trigger();
///     }
///     x[0] * x[0]
/// };
/// let best = Minimizer::new(f).budget(10_000).run_with(&[3.0], Driver::new().interrupt(stop))?;
/// assert_eq!(best.stop, Stop::Interrupted);
/// assert!(best.evaluations < 100 && best.fun < 9.0);
/// # Ok::<(), plateau_free::lifecycle::Failure<plateau_free::Minimum>>(())
/// ```
#[derive(Debug, Clone, Default)]
pub struct Interrupt(Arc<AtomicBool>);

impl Interrupt {
    /// A flag not yet triggered.
    pub fn new() -> Interrupt {
        Interrupt::default()
    }

    /// Asks every run that holds a clone to stop at its next turn.
    pub fn trigger(&self) {
        self.0.store(true, Ordering::SeqCst);
    }

    /// Whether the stop was asked.
    ///
    /// ```
    /// let i = plateau_free::lifecycle::Interrupt::new();
    /// assert!(!i.is_triggered());
    /// i.clone().trigger();
    /// assert!(i.is_triggered());
    /// i.reset();
    /// assert!(!i.is_triggered());
    /// ```
    pub fn is_triggered(&self) -> bool {
        self.0.load(Ordering::SeqCst)
    }

    /// Clears the flag (for the next run).
    pub fn reset(&self) {
        self.0.store(false, Ordering::SeqCst);
    }
}
