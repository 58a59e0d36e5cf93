//! The paper's loop, written once: [`Optimizer`] (Adam and an annealed spread) and one
//! iteration of it: the next spread from the annealer ([`Optimizer::next_sigma`]), Adam's
//! step along a gradient estimate and the record ([`Optimizer::advance`]), and the state
//! to continue from ([`Optimizer::begin`], [`Optimizer::state_of`]).
//!
//! Two drivers ask this engine for the next spread and tell it the estimate: the callback
//! form (`optimize.rs`: [`Optimizer::minimize_from`], with any [`GradientEstimator`], whose
//! estimate is one call), and ask-and-tell (`ask_tell.rs`: [`PaperAskTell`], with the
//! plateau-free estimator split into its points and their values).

mod ask_tell;

pub use ask_tell::PaperAskTell;

use crate::adam::Adam;
use crate::anneal::Annealer;
use crate::check;
use crate::error::Error;
use crate::estimator::Estimate;
use crate::run::{History, HistoryKeep, OptimizerState, RunError};
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
        }
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
        (progress.iteration < self.iterations).then(|| self.annealer.sigma(progress.iteration))
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
        progress.iteration += 1;
        Ok(())
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
