//! What a run of the paper's loop ([`Optimizer`]) gives back and continues from: its
//! [`History`] (bounded by [`HistoryKeep`]), its [`OptimizerState`], and the [`RunError`]
//! that carries the state when a run fails. Both forms of the loop, the callback
//! ([`Optimizer::minimize_from`]) and ask-and-tell ([`crate::PaperAskTell`]), share them.

use crate::adam::AdamMoments;
use crate::check;
use crate::error::Error;
// For the documentation's links only.
#[cfg(doc)]
use crate::{GradientEstimator, Optimizer};

/// The record of a run: one entry per completed iteration, of the last iterations only
/// when the run is long ([`HistoryKeep`], [`Optimizer::keep_history`]).
#[derive(Debug, Clone, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct History {
    /// Parameters after each kept iteration when [`Optimizer::record_theta`] is on; otherwise
    /// only the latest point. After [`Optimizer::minimize`] its last entry is always the
    /// point the run ended at: the start itself when no iteration ran.
    pub theta: Vec<Vec<f64>>,
    /// The spread of each kept iteration: entry `i` is iteration `dropped + i`.
    pub sigma: Vec<f64>,
    /// The mean value of `f` over each kept iteration's evaluations (entry `i` is iteration
    /// `dropped + i`).
    pub value: Vec<f64>,
    /// Evaluations of `f` in all (the dropped iterations' included).
    pub evaluations: usize,
    /// Whether the observer stopped the run before the last iteration.
    pub stopped_early: bool,
    /// The number of earliest iterations whose entries were dropped to keep the record's
    /// size bounded ([`HistoryKeep`]); 0 when every iteration is kept.
    #[cfg_attr(feature = "serde", serde(default))]
    pub dropped: usize,
}

impl History {
    /// The parameters the run ended at. After [`Optimizer::minimize`] (or
    /// [`Optimizer::minimize_with`]) this is always `Some`: a run of zero iterations ends
    /// at its start.
    pub fn last_theta(&self) -> Option<&[f64]> {
        self.theta.last().map(Vec::as_slice)
    }

    /// The number of completed iterations (the dropped ones included).
    pub fn iterations(&self) -> usize {
        self.dropped + self.sigma.len()
    }

    /// Drops the oldest entries beyond what `keep` keeps: at once when `exact`, else only
    /// once twice as many are held (so that dropping costs O(1) an iteration on average).
    /// The last theta is always kept.
    pub(crate) fn trim(&mut self, keep: HistoryKeep, exact: bool) {
        let HistoryKeep::Last(k) = keep else {
            return;
        };
        let limit = if exact { k } else { k.saturating_mul(2) };
        let len = self.sigma.len();
        if len > limit {
            let excess = len - k;
            self.sigma.drain(..excess);
            self.value.drain(..excess.min(self.value.len()));
            self.dropped += excess;
        }
        let thetas = self.theta.len();
        if thetas > limit.max(1) {
            self.theta.drain(..thetas - k.max(1));
        }
    }
}

/// How much of the per-iteration record ([`History`]) a run keeps: every iteration, or the
/// last `k` (the default: the last [`HistoryKeep::DEFAULT_LAST`] iterations, so that a run
/// of any length has bounded memory while runs of up to a million iterations keep all).
///
/// An iteration's entry is 16 bytes (its sigma and mean value), and `8 n` more with
/// [`Optimizer::record_theta`]. With `Last(k)`, a run holds at most `2 k` entries while it
/// runs (the oldest are dropped in batches) and exactly the last `k` in what it returns;
/// [`History::dropped`] counts the dropped iterations. `Last(0)` keeps none but the last
/// theta.
///
/// ```
/// use plateau_free::{Adam, Annealer, run::HistoryKeep, Optimizer, PlateauFreeGradient};
///
/// let mut grad = PlateauFreeGradient::new(|x: &[f64]| x[0] * x[0]);
/// let mut opt = Optimizer::new(Adam::new(0.1)?, Annealer::constant(0.1, 100)?)
///     .keep_history(HistoryKeep::Last(10));
/// let history = opt.minimize(&mut grad, &[1.0])?;
/// assert_eq!((history.sigma.len(), history.dropped, history.iterations()), (10, 90, 100));
/// assert_eq!(HistoryKeep::default(), HistoryKeep::Last(1_000_000));
/// # Ok::<(), plateau_free::Error>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum HistoryKeep {
    /// Every iteration: the record grows with the run (16 bytes an iteration, 160 MB for
    /// `10^7` iterations).
    All,
    /// The last `k` iterations.
    Last(usize),
}

impl HistoryKeep {
    /// The number of iterations the default keeps: a million (16 MB, at most 32 MB while a
    /// run is in progress).
    pub const DEFAULT_LAST: usize = 1_000_000;
}

impl Default for HistoryKeep {
    /// `Last(`[`HistoryKeep::DEFAULT_LAST`]`)`.
    fn default() -> Self {
        HistoryKeep::Last(HistoryKeep::DEFAULT_LAST)
    }
}

/// Everything a run needs to continue where it stopped, as a value to keep or save (with
/// the `serde` feature it serialises): continued by [`Optimizer::minimize_from`], it gives
/// bit for bit the run that was never interrupted, provided the optimiser and estimator are
/// configured as before.
///
/// ```
/// use std::ops::ControlFlow;
/// use plateau_free::{Adam, Annealer, Optimizer, run::OptimizerState, PlateauFreeGradient};
///
/// let f = |x: &[f64]| (x[0] - 1.0).abs();
/// let new_opt = || Optimizer::new(Adam::new(0.1).unwrap(), Annealer::constant(0.3, 20).unwrap());
/// let whole = new_opt().minimize(&mut PlateauFreeGradient::new(f).seed(3), &[0.0])?;
///
/// // Stopped after 5 iterations (Ctrl-C, a time limit), then continued by a fresh process.
/// let mut grad = PlateauFreeGradient::new(f).seed(3);
/// let start = OptimizerState::new(&[0.0])?;
/// let saved = new_opt().minimize_from(&mut grad, start, |s| {
///     if s.iteration == 4 { std::ops::ControlFlow::Break(()) } else { ControlFlow::Continue(()) }
/// })?;
/// assert_eq!(saved.iteration, 5);
/// let mut grad = PlateauFreeGradient::new(f).seed(3);
/// let done = new_opt().minimize_from(&mut grad, saved, |_| ControlFlow::Continue(()))?;
/// assert_eq!(done.theta, whole.last_theta().unwrap());
/// assert_eq!(done.history.value, whole.value);
/// # Ok::<(), plateau_free::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct OptimizerState {
    /// Iterations completed; the next iteration has this index (and the annealer's sigma
    /// for it).
    pub iteration: usize,
    /// The current parameters.
    pub theta: Vec<f64>,
    /// Adam's moments and step count.
    pub adam: AdamMoments,
    /// The estimator's [`GradientEstimator::stream_position`] before the next iteration;
    /// `None` leaves the estimator's streams where they are.
    pub stream_position: Option<u64>,
    /// The record of the completed iterations.
    pub history: History,
}

impl OptimizerState {
    /// The state before the first iteration, at `start`.
    ///
    /// # Errors
    /// An empty or non-finite `start`.
    pub fn new(start: &[f64]) -> Result<Self, Error> {
        check::theta(start)?;
        Ok(OptimizerState {
            iteration: 0,
            theta: start.to_vec(),
            adam: AdamMoments::default(),
            stream_position: None,
            history: History::default(),
        })
    }

    /// Checks that the state can be continued from: theta non-empty and finite, Adam's
    /// moments valid and of theta's dimension with one step per iteration, a history of one
    /// entry per iteration whose points have theta's dimension. [`Optimizer::minimize_from`]
    /// calls it before using anything.
    ///
    /// ```
    /// use plateau_free::{Error, run::OptimizerState};
    /// let mut state = OptimizerState::new(&[1.0, 2.0])?;
    /// state.theta[1] = f64::NAN;
    /// assert!(matches!(state.validate(), Err(Error::InvalidState { field: "theta", .. })));
    /// # Ok::<(), plateau_free::Error>(())
    /// ```
    ///
    /// # Errors
    /// [`Error::InvalidState`] naming the part at fault and the value.
    pub fn validate(&self) -> Result<(), Error> {
        let bad = |field: &'static str, reason: String| Err(Error::InvalidState { field, reason });
        let n = self.theta.len();
        if let Err(e) = check::theta(&self.theta) {
            return bad("theta", format!("is unusable: {e}"));
        }
        self.adam.validate()?;
        if self.adam.steps > 0 && self.adam.m.len() != n {
            return bad(
                "adam.m",
                format!("has dimension {}, theta has {n}", self.adam.m.len()),
            );
        }
        if self.adam.steps != self.iteration as u64 {
            return bad(
                "adam.steps",
                format!("= {} after {} iterations", self.adam.steps, self.iteration),
            );
        }
        let h = &self.history;
        if h.dropped.checked_add(h.sigma.len()) != Some(self.iteration)
            || h.value.len() != h.sigma.len()
        {
            return bad(
                "history",
                format!(
                    "has {} sigmas and {} values ({} dropped) for {} iterations",
                    h.sigma.len(),
                    h.value.len(),
                    h.dropped,
                    self.iteration
                ),
            );
        }
        if let Some(p) = h.theta.iter().find(|p| p.len() != n) {
            return bad(
                "history.theta",
                format!("holds a point of dimension {}, theta has {n}", p.len()),
            );
        }
        Ok(())
    }
}

/// A run that ended in an error: the error, and the state after the last good iteration
/// (its history included), from which [`Optimizer::minimize_from`] continues. Resuming
/// repeats the failed iteration with the same random streams.
///
/// Converts into the plain [`Error`] with `?` (dropping the state), and compares equal to
/// an [`Error`] when its error does.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{error} (after {} completed iterations)", state.iteration)]
pub struct RunError {
    /// What went wrong.
    pub error: Error,
    /// The state after the last good iteration.
    pub state: Box<OptimizerState>,
}

impl RunError {
    /// The record of the iterations that completed before the error.
    pub fn history(&self) -> &History {
        &self.state.history
    }
}

impl From<RunError> for Error {
    fn from(e: RunError) -> Error {
        e.error
    }
}

impl PartialEq<Error> for RunError {
    fn eq(&self, other: &Error) -> bool {
        self.error == *other
    }
}
