//! The paper's loop in its callback form: [`Optimizer::minimize`] and its relatives drive the
//! loop's engine (`method/paper/`: the next spread, Adam's step, the record) with any
//! [`GradientEstimator`], whose estimate is one call, and an observer after every iteration.
//! Its ask-and-tell form is [`crate::PaperAskTell`], on the same engine.

use std::ops::ControlFlow;

use crate::adam::AdamMoments;
use crate::error::Error;
use crate::estimator::GradientEstimator;
use crate::method::Optimizer;
use crate::run::{History, OptimizerState, RunError, Step};

impl Optimizer {
    /// Runs from `start` to the end.
    ///
    /// With bounds on Adam ([`crate::Adam::bounds`]), `start` must lie inside the box, the
    /// estimator is handed the box ([`GradientEstimator::set_bounds`]) so that `f` is only
    /// evaluated inside it, and every step is projected onto it.
    ///
    /// # Errors
    /// A start outside Adam's bounds ([`Error::OutsideBounds`]) or an estimator that cannot
    /// keep its points inside them ([`Error::BoundsUnsupported`]), both before anything is
    /// evaluated; whatever the estimator or Adam report (bad input, non-finite values of
    /// `f`); the run stops at the first error. To keep the history of the good iterations
    /// and the state to continue from, use [`Optimizer::run`].
    pub fn minimize<G: GradientEstimator + ?Sized>(
        &mut self,
        estimator: &mut G,
        start: &[f64],
    ) -> Result<History, Error> {
        self.minimize_with(estimator, start, |_| ControlFlow::Continue(()))
    }

    /// Runs from `start`, calling `observer` after every iteration; the observer stops the run
    /// by returning `ControlFlow::Break(())`. Adam's state is reset at the start of every run;
    /// the estimator's streams continue from where they are.
    ///
    /// # Errors
    /// As [`Optimizer::minimize`]: the error alone ([`Optimizer::run`] keeps the rest).
    pub fn minimize_with<G, O>(
        &mut self,
        estimator: &mut G,
        start: &[f64],
        observer: O,
    ) -> Result<History, Error>
    where
        G: GradientEstimator + ?Sized,
        O: FnMut(&Step<'_>) -> ControlFlow<()>,
    {
        self.run(estimator, start, observer).map_err(Error::from)
    }

    /// [`Optimizer::minimize_with`], keeping what the run has on error: a [`RunError`]
    /// carries the error, the history of the good iterations and the state to continue from
    /// ([`Optimizer::minimize_from`]).
    ///
    /// ```
    /// use std::ops::ControlFlow;
    /// use plateau_free::{Adam, Annealer, Error, Optimizer, PlateauFreeGradient};
    ///
    /// // f fails once theta has moved below -0.5.
    /// let f = |x: &[f64]| if x[0] < -0.5 { f64::NAN } else { x[0] };
    /// let mut grad = PlateauFreeGradient::new(f).samples(4);
    /// let mut opt = Optimizer::new(Adam::new(0.1)?, Annealer::constant(0.01, 100)?);
    /// let err = opt.run(&mut grad, &[0.0], |_| ControlFlow::Continue(())).unwrap_err();
    /// assert!(matches!(err.error, Error::NonFiniteValue { .. }));
    /// let kept = err.history().iterations();
    /// assert!(kept > 0 && err.history().last_theta().unwrap()[0] >= -0.5 - 0.2);
    /// # Ok::<(), plateau_free::Error>(())
    /// ```
    ///
    /// # Errors
    /// As [`Optimizer::minimize`], with the history and the state.
    pub fn run<G, O>(
        &mut self,
        estimator: &mut G,
        start: &[f64],
        observer: O,
    ) -> Result<History, RunError>
    where
        G: GradientEstimator + ?Sized,
        O: FnMut(&Step<'_>) -> ControlFlow<()>,
    {
        let state = OptimizerState::new(start).map_err(|error| RunError {
            error,
            state: Box::new(OptimizerState {
                iteration: 0,
                theta: start.to_vec(),
                adam: AdamMoments::default(),
                stream_position: None,
                history: History::default(),
            }),
        })?;
        let state = self.minimize_from(estimator, state, observer)?;
        let mut history = state.history;
        // The documented `history.last_theta().unwrap()` must hold even for zero iterations.
        if history.theta.is_empty() {
            history.theta.push(state.theta);
        }
        Ok(history)
    }

    /// Continues a run from `state` (a fresh [`OptimizerState::new`], or one returned by an
    /// earlier run or a [`RunError`], possibly saved and loaded) up to the optimiser's last
    /// iteration, calling `observer` after every iteration; returns the state at the end,
    /// its history extended. Adam's moments and the estimator's stream position are set
    /// from the state, so an interrupted and continued run is bit for bit the run that was
    /// never interrupted (with the same configuration). See [`OptimizerState`].
    ///
    /// # Errors
    /// [`Error::InvalidState`] for a state that [`OptimizerState::validate`] rejects (the
    /// state comes back unused in the [`RunError`]); otherwise as [`Optimizer::minimize`].
    pub fn minimize_from<G, O>(
        &mut self,
        estimator: &mut G,
        state: OptimizerState,
        mut observer: O,
    ) -> Result<OptimizerState, RunError>
    where
        G: GradientEstimator + ?Sized,
        O: FnMut(&Step<'_>) -> ControlFlow<()>,
    {
        let (mut progress, position) =
            self.begin(state, |lower, upper| estimator.set_bounds(lower, upper))?;
        if let Some(position) = position {
            estimator.set_stream_position(position);
        }
        while let Some(sigma) = self.next_sigma(&progress) {
            let position = estimator.stream_position();
            // Adam leaves theta and its moments untouched when it fails, and the estimator
            // does not touch theta: on either error the state is that of the last good
            // iteration.
            let result = estimator
                .estimate(&progress.theta, sigma)
                .and_then(|e| self.advance(&mut progress, sigma, &e).map(|()| e));
            let estimate = match result {
                Ok(estimate) => estimate,
                Err(error) => {
                    return Err(RunError {
                        error,
                        state: Box::new(self.state_of(progress, position)),
                    })
                }
            };
            let step = Step {
                iteration: progress.iteration - 1,
                theta: &progress.theta,
                sigma,
                estimate: &estimate,
            };
            if observer(&step).is_break() {
                progress.history.stopped_early = self.next_sigma(&progress).is_some();
                break;
            }
        }
        Ok(self.state_of(progress, estimator.stream_position()))
    }
}
