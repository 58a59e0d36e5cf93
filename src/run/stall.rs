//! The stop rule ([`Stall`]): a run ends when its best value has stopped improving, judged
//! from the values alone (never from the true parameters, which a user does not have). The
//! budget stays the ceiling: the rule only ends a run earlier.

use std::collections::VecDeque;

use crate::error::Error;
// For the documentation's links only.
#[cfg(doc)]
use crate::{Minimizer, Optimizer};

/// The stop rule "stalled": after an iteration, the run ends if the best value it has seen
/// did not improve by more than `rtol` (relative) over the last `window` evaluations.
///
/// With `b(e)` the best value seen after `e` evaluations (the running minimum of the
/// values each iteration reports), the run stops at `e` when `e >= window` (counted from
/// where the rule began to judge) and `b(e - window) - b(e) <= rtol * |b(e - window)|`.
/// `b(e - window)` is the best after the last iteration that ended at or before
/// `e - window`.
///
/// - A loss that still decreases never stops it; a converged loss (an exact floor, or
///   improvements below `rtol`) stops it one window after it converged.
/// - Noise: on a noisy objective the best seen keeps improving by chance, so the rule stops
///   later or not at all (the budget then ends the run); it never stops early because of
///   noise. Non-finite values are never a best (a run of NaNs never stops by this rule).
/// - [`Minimizer::stop_when_stalled`] judges the adaptive search from its first generation
///   (and the polish after the paper's loop from the hand-over), with the window a fraction
///   of the budget; [`Optimizer::stop_when_stalled`] judges the paper's loop only once its
///   annealing schedule has ended (before, the loss falls because the spread is annealed,
///   and stopping would skip the annealing the schedule plans over the whole run).
///
/// ```
/// use plateau_free::run::Stall;
///
/// // Judged every 2 evaluations over a window of 6 evaluations.
/// let mut rule = Stall::new(6, 0.0)?;
/// let losses = [5.0, 3.0, 2.0, 1.0, 1.0, 1.0, 1.0];
/// let stops: Vec<bool> = losses.iter().map(|&v| rule.observe(2, v)).collect();
/// // The best (1.0) was reached after 8 evaluations; 6 later (at 14) the rule stops.
/// assert_eq!(stops, [false, false, false, false, false, false, true]);
/// # Ok::<(), plateau_free::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Stall {
    window: usize,
    rtol: f64,
    /// Evaluations observed.
    evaluations: usize,
    /// The best value observed (`+inf` before the first finite one).
    #[cfg_attr(feature = "serde", serde(with = "crate::saved::float"))]
    best: f64,
    /// `(evaluations, best)` after each recent iteration: the oldest is the last one at or
    /// before `evaluations - window` (or the rule's start), the newest the current.
    #[cfg_attr(feature = "serde", serde(with = "crate::saved::float_pairs"))]
    marks: VecDeque<(usize, f64)>,
}

/// The window to pass to [`Minimizer::stop_when_stalled`] and
/// [`Optimizer::stop_when_stalled`] when in doubt, a fraction of the budget: twice the
/// smallest window at which the replay of the committed path-tracing runs made no run's
/// parameter error worse (`docs/results/stopping.md`; a window of 0.05 made some worse), for
/// margin, since those runs cover few tasks.
pub const STALL_WINDOW: f64 = 0.2;

impl Stall {
    /// A rule over `window` evaluations with relative tolerance `rtol`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a zero window or an `rtol` that is negative or not
    /// finite.
    pub fn new(window: usize, rtol: f64) -> Result<Stall, Error> {
        if window == 0 {
            return Err(Error::InvalidParameter {
                name: "stall window",
                value: window.into(),
                reason: "must be at least 1 evaluation",
            });
        }
        if !(rtol.is_finite() && rtol >= 0.0) {
            return Err(Error::InvalidParameter {
                name: "stall rtol",
                value: rtol.into(),
                reason: "must be finite and at least 0",
            });
        }
        Ok(Stall {
            window,
            rtol,
            evaluations: 0,
            best: f64::INFINITY,
            marks: VecDeque::from([(0, f64::INFINITY)]),
        })
    }

    /// The rule whose window is `fraction` of `budget` evaluations (rounded up, at least 1).
    ///
    /// # Errors
    /// A fraction outside `(0, 1]` ([`Error::InvalidParameter`]).
    pub fn of_budget(fraction: f64, budget: usize) -> Result<Stall, Error> {
        check_fraction(fraction)?;
        Ok(Stall::checked(fraction, budget))
    }

    /// [`Stall::of_budget`] for a fraction already checked.
    pub(crate) fn checked(fraction: f64, budget: usize) -> Stall {
        Stall {
            window: ((fraction * budget as f64).ceil() as usize).max(1),
            rtol: 0.0,
            evaluations: 0,
            best: f64::INFINITY,
            marks: VecDeque::from([(0, f64::INFINITY)]),
        }
    }

    /// The window, in evaluations.
    pub fn window(&self) -> usize {
        self.window
    }

    /// Takes one iteration: `evaluations` spent in it and `value`, the value it reports (the
    /// smallest of its values, or their mean); returns whether the run should stop here.
    pub fn observe(&mut self, evaluations: usize, value: f64) -> bool {
        self.evaluations += evaluations;
        if value.is_finite() && value < self.best {
            self.best = value;
        }
        self.marks.push_back((self.evaluations, self.best));
        let Some(start) = self.evaluations.checked_sub(self.window) else {
            return false;
        };
        // Keep the last mark at or before the window's start, and those after it.
        while self.marks.len() > 1 && self.marks[1].0 <= start {
            self.marks.pop_front();
        }
        let old = self.marks[0].1;
        // Before a finite best at the window's start there is nothing to compare.
        old.is_finite() && old - self.best <= self.rtol * old.abs()
    }

    /// Checks a read-back rule (its marks in order).
    #[cfg(feature = "serde")]
    pub(crate) fn check(&self) -> Result<(), Error> {
        let ordered = self
            .marks
            .iter()
            .zip(self.marks.iter().skip(1))
            .all(|(a, b)| a.0 <= b.0);
        if self.window == 0 || self.marks.is_empty() || !ordered {
            return Err(Error::InvalidParameter {
                name: "stall",
                value: self.window.into(),
                reason: "a read-back rule needs a window and ordered marks",
            });
        }
        Ok(())
    }
}

/// Checks a window fraction of [`Minimizer::stop_when_stalled`].
pub(crate) fn check_fraction(fraction: f64) -> Result<(), Error> {
    if fraction > 0.0 && fraction <= 1.0 {
        Ok(())
    } else {
        Err(Error::InvalidParameter {
            name: "stop_when_stalled",
            value: fraction.into(),
            reason: "must be a fraction of the budget in (0, 1]: the window over which the best value must improve (STALL_WINDOW = 0.2 is the tested choice)",
        })
    }
}
