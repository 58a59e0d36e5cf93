//! The paper's loop, written once: [`Optimizer`] (Adam and an annealed spread) and one
//! iteration of it: the next spread from the annealer ([`Optimizer::next_sigma`]), Adam's
//! step along a gradient estimate and the record ([`Optimizer::advance`]), and the state
//! to continue from ([`Optimizer::begin`], [`Optimizer::state_of`]).
//!
//! Two drivers ask this engine for the next spread and tell it the estimate: the callback
//! form (`optimize.rs`: [`Optimizer::minimize_from`], with any [`GradientEstimator`], whose
//! estimate is one call), and ask-and-tell (`ask_tell.rs`: [`PaperAskTell`], with the
//! plateau-free estimator split into its points and their values; and, in `crate::baseline`,
//! `BaselineAskTell`, with a baseline estimator).

mod ask_tell;

pub use ask_tell::PaperAskTell;

use crate::adam::Adam;
use crate::anneal::Annealer;
use crate::check;
use crate::error::Error;
use crate::estimator::Estimate;
use crate::run::{check_fraction, History, HistoryKeep, OptimizerState, RunError, Stall};
// For the documentation's links only.
#[cfg(doc)]
use crate::GradientEstimator;

/// Minimises an objective with a gradient estimator, Adam and an annealed spread.
///
/// ```
/// use plateau_free::{Adam, Annealer, Optimizer, PlateauFreeGradient};
///
/// // From x = 2 the step's far side is invisible to a plain gradient: a plateau.
/// let f = |x: &[f64]| if x[0] > 0.5 { 1.0 } else { 0.0 };
/// let mut grad = PlateauFreeGradient::new(f).samples(4).seed(1);
/// let mut opt = Optimizer::new(Adam::new(0.05)?, Annealer::paper(1.0, 300)?);
/// let history = opt.minimize(&mut grad, &[2.0])?;
/// assert!(history.last_theta().unwrap()[0] < 0.5);
/// # Ok::<(), plateau_free::Error>(())
/// ```
#[derive(Debug, Clone)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Optimizer {
    adam: Adam,
    annealer: Annealer,
    iterations: usize,
    record_theta: bool,
    keep: HistoryKeep,
    /// [`Optimizer::stop_when_stalled`]'s window (a fraction of the run's evaluations), the
    /// rule once it judges (past the schedule), and whether it ended the run.
    #[cfg_attr(feature = "serde", serde(default, with = "crate::saved::float_option"))]
    stall_window: Option<f64>,
    #[cfg_attr(feature = "serde", serde(default))]
    stall: Option<Stall>,
    #[cfg_attr(feature = "serde", serde(default))]
    stalled: bool,
}

impl Optimizer {
    /// A loop of `annealer.iterations()` iterations.
    #[must_use]
    pub fn new(adam: Adam, annealer: Annealer) -> Self {
        Optimizer {
            iterations: annealer.iterations(),
            adam,
            annealer,
            record_theta: false,
            keep: HistoryKeep::default(),
            stall_window: None,
            stall: None,
            stalled: false,
        }
    }

    /// Ends the loop when the mean value of its estimates has not improved over the last
    /// `window` of its evaluations (a fraction in `(0, 1]` of iterations x evaluations per
    /// estimate; [`crate::run::STALL_WINDOW`] is the tested choice): the rule [`Stall`] fed each
    /// estimate's mean value. Default: off. It judges only the iterations past the annealing
    /// schedule ([`Optimizer::iterations`] beyond [`Annealer::iterations`]): within the
    /// schedule the loss falls because the spread is annealed, and an early stop would skip
    /// the annealing planned over the whole run. A run continued from a state
    /// ([`Optimizer::minimize_from`]) judges afresh from there.
    ///
    /// ```
    /// use plateau_free::{Adam, Annealer, Optimizer, PlateauFreeGradient};
    ///
    /// // A floor: |x| < 1 is optimal. 100 iterations of schedule, up to 900 more past it.
    /// let f = |x: &[f64]| (x[0].abs() - 1.0).max(0.0);
    /// let mut grad = PlateauFreeGradient::new(f).samples(4).seed(2);
    /// let mut opt = Optimizer::new(Adam::new(0.1)?, Annealer::paper(0.5, 100)?)
    ///     .iterations(1000)
    ///     .stop_when_stalled(0.1)?;
    /// let history = opt.minimize(&mut grad, &[3.0])?;
    /// assert!(opt.stalled());
    /// assert!(history.iterations() < 1000);
    /// assert!(history.last_theta().unwrap()[0].abs() < 1.0);
    /// # Ok::<(), plateau_free::Error>(())
    /// ```
    ///
    /// # Errors
    /// A window outside `(0, 1]` ([`Error::InvalidParameter`]).
    pub fn stop_when_stalled(mut self, window: f64) -> Result<Self, Error> {
        check_fraction(window)?;
        self.stall_window = Some(window);
        Ok(self)
    }

    /// Whether the stop rule ([`Optimizer::stop_when_stalled`]) ended the last run.
    pub fn stalled(&self) -> bool {
        self.stalled
    }

    setters! {
        /// Runs a different number of iterations than the annealer spans (past its end, sigma
        /// stays at its final value).
        iterations(iterations: usize) => iterations = iterations;

        /// Whether the history keeps theta for every iteration (default: no, since it costs `8n`
        /// bytes an iteration: 80 MB per 10 iterations at `n = 10^6`). The last theta is always
        /// kept, overwritten in place.
        record_theta(record: bool) => record_theta = record;

        /// How much of the per-iteration record the run keeps (default: the last million
        /// iterations, [`HistoryKeep::default`]): a run of `10^12` iterations keeps its memory
        /// bounded. [`HistoryKeep::All`] keeps every iteration.
        keep_history(keep: HistoryKeep) => keep = keep;
    }

    /// The optimiser (with its moment estimates after a run).
    pub fn adam(&self) -> &Adam {
        &self.adam
    }

    /// The schedule.
    pub fn annealer(&self) -> &Annealer {
        &self.annealer
    }

    /// Starts or continues a run from `state`, for either driver: checks the state (and,
    /// with bounds on Adam, that theta lies inside the box), sets Adam's moments, and hands
    /// Adam's box to the estimator through `set_bounds` (every point it evaluates is then
    /// clamped onto the box). Returns the run's progress and the stream position to set.
    ///
    /// # Errors
    /// A state that [`OptimizerState::validate`] rejects or that lies outside the box (the
    /// state comes back unused), or `set_bounds`'s error.
    pub(crate) fn begin(
        &mut self,
        state: OptimizerState,
        set_bounds: impl FnOnce(&[f64], &[f64]) -> Result<(), Error>,
    ) -> Result<(Progress, Option<u64>), RunError> {
        let (progress, position) = self.resume(state)?;
        if let Some((lower, upper)) = self.adam.box_bounds() {
            if let Err(error) = set_bounds(lower, upper) {
                return Err(RunError {
                    error,
                    state: Box::new(self.state_of(progress, position)),
                });
            }
        }
        Ok((progress, position))
    }

    /// Unpacks a state to continue from: checks it, sets Adam's moments, clears the
    /// history's early stop; returns the rest and the stream position to set.
    fn resume(&mut self, state: OptimizerState) -> Result<(Progress, Option<u64>), RunError> {
        let mut checked = state.validate();
        if let (Ok(()), Some((lower, upper))) = (&checked, self.adam.box_bounds()) {
            let what = if state.iteration == 0 {
                "start"
            } else {
                "theta"
            };
            checked = check::inside(what, &state.theta, lower, upper);
        }
        if let Err(error) = checked {
            return Err(RunError {
                error,
                state: Box::new(state),
            });
        }
        if let Err(error) = self.adam.set_moments(state.adam.clone()) {
            // Unreachable after `validate`, but a state is never half-used.
            return Err(RunError {
                error,
                state: Box::new(state),
            });
        }
        let OptimizerState {
            iteration,
            theta,
            adam: _,
            stream_position,
            mut history,
        } = state;
        history.stopped_early = false;
        self.stall = None;
        self.stalled = false;
        let progress = Progress {
            iteration,
            theta,
            history,
        };
        Ok((progress, stream_position))
    }

    /// A read-back optimiser against theta's dimension `n` (Adam's moments and box).
    #[cfg(feature = "serde")]
    pub(crate) fn check(&self, n: usize) -> Result<(), crate::error::Error> {
        self.adam.check_dim(n)
    }

    /// The spread of the next iteration, or `None` when the run is complete.
    pub(crate) fn next_sigma(&self, progress: &Progress) -> Option<f64> {
        (!self.stalled && progress.iteration < self.iterations)
            .then(|| self.annealer.sigma(progress.iteration))
    }

    /// Completes an iteration: Adam's step along the estimate, and the record. On error
    /// nothing has changed (Adam leaves theta and its moments untouched when it fails).
    pub(crate) fn advance(
        &mut self,
        progress: &mut Progress,
        sigma: f64,
        estimate: &Estimate,
    ) -> Result<(), Error> {
        self.adam.step(&mut progress.theta, &estimate.gradient)?;
        let history = &mut progress.history;
        history.sigma.push(sigma);
        history.value.push(estimate.mean_value);
        history.evaluations += estimate.evaluations;
        match history.theta.last_mut() {
            Some(last) if !self.record_theta => last.copy_from_slice(&progress.theta),
            _ => history.theta.push(progress.theta.clone()),
        }
        history.trim(self.keep, false);
        self.judge(progress.iteration, estimate);
        progress.iteration += 1;
        Ok(())
    }

    /// The stop rule on an iteration's estimate, past the schedule.
    fn judge(&mut self, iteration: usize, estimate: &Estimate) {
        let Some(fraction) = self.stall_window else {
            return;
        };
        if iteration < self.annealer.iterations() {
            return;
        }
        let evaluations = self.iterations.saturating_mul(estimate.evaluations);
        let rule = self
            .stall
            .get_or_insert_with(|| Stall::checked(fraction, evaluations));
        self.stalled |= rule.observe(estimate.evaluations, estimate.mean_value);
    }

    /// The state of a run at `progress` whose streams stand at `position`.
    pub(crate) fn state_of(&self, progress: Progress, position: Option<u64>) -> OptimizerState {
        let mut history = progress.history;
        self.trim_exact(&mut history);
        OptimizerState {
            iteration: progress.iteration,
            theta: progress.theta,
            adam: self.adam.moments(),
            stream_position: position,
            history,
        }
    }

    /// The history of a run ended at `progress`: its last theta the point the run ended at,
    /// `stopped_early` if iterations remained, trimmed to what [`Optimizer::keep_history`]
    /// keeps.
    pub(crate) fn ended(&self, progress: Progress) -> History {
        let stopped_early = self.next_sigma(&progress).is_some();
        let Progress {
            theta, mut history, ..
        } = progress;
        history.stopped_early = stopped_early;
        if history.theta.is_empty() {
            history.theta.push(theta);
        }
        self.trim_exact(&mut history);
        history
    }

    /// Trims a history that a run hands back to exactly what [`Optimizer::keep_history`] keeps.
    pub(crate) fn trim_exact(&self, history: &mut History) {
        history.trim(self.keep, true);
    }
}

/// A run between iterations: the part of [`OptimizerState`] that neither Adam nor the
/// estimator holds.
#[derive(Debug, Clone)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub(crate) struct Progress {
    /// Iterations completed.
    pub(crate) iteration: usize,
    /// The current parameters.
    pub(crate) theta: Vec<f64>,
    /// The record of the completed iterations.
    pub(crate) history: History,
}
