//! The optimisation loop: estimate, step, anneal, observe, repeat.

use std::ops::ControlFlow;

use crate::adam::Adam;
use crate::anneal::Annealer;
use crate::check;
use crate::error::Error;
use crate::estimator::{Estimate, GradientEstimator};

/// What the observer sees after each iteration.
#[derive(Debug)]
pub struct Step<'a> {
    /// The iteration, counted from 0.
    pub iteration: usize,
    /// The parameters after this iteration's Adam step.
    pub theta: &'a [f64],
    /// The spread this iteration's gradient was estimated with.
    pub sigma: f64,
    /// The gradient estimate (taken at the parameters before the step).
    pub estimate: &'a Estimate,
}

/// The record of a run: one entry per completed iteration.
#[derive(Debug, Clone, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct History {
    /// Parameters after each iteration (only after the last one when
    /// [`Optimizer::record_theta`] is off).
    pub theta: Vec<Vec<f64>>,
    /// The spread of each iteration.
    pub sigma: Vec<f64>,
    /// The mean value of `f` over each iteration's evaluations.
    pub value: Vec<f64>,
    /// Evaluations of `f` in all.
    pub evaluations: usize,
    /// Whether the observer stopped the run before the last iteration.
    pub stopped_early: bool,
}

impl History {
    /// The parameters after the last completed iteration, if any.
    pub fn last_theta(&self) -> Option<&[f64]> {
        self.theta.last().map(Vec::as_slice)
    }

    /// The number of completed iterations.
    pub fn iterations(&self) -> usize {
        self.sigma.len()
    }
}

/// Minimises an objective with a gradient estimator, Adam and an annealed spread.
///
/// ```
/// use plateau::{Adam, Annealer, Optimizer, PlateauFreeGradient};
///
/// // From x = 2 the step's far side is invisible to a plain gradient: a plateau.
/// let f = |x: &[f64]| if x[0] > 0.5 { 1.0 } else { 0.0 };
/// let mut grad = PlateauFreeGradient::new(f).samples(4).seed(1);
/// let mut opt = Optimizer::new(Adam::new(0.05)?, Annealer::paper(1.0, 300)?);
/// let history = opt.minimize(&mut grad, &[2.0])?;
/// assert!(history.last_theta().unwrap()[0] < 0.5);
/// # Ok::<(), plateau::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct Optimizer {
    adam: Adam,
    annealer: Annealer,
    iterations: usize,
    record_theta: bool,
}

impl Optimizer {
    /// A loop of `annealer.iterations()` iterations.
    #[must_use]
    pub fn new(adam: Adam, annealer: Annealer) -> Self {
        Optimizer {
            iterations: annealer.iterations(),
            adam,
            annealer,
            record_theta: true,
        }
    }

    /// Runs a different number of iterations than the annealer spans (past its end, sigma
    /// stays at its final value).
    #[must_use]
    pub fn iterations(mut self, iterations: usize) -> Self {
        self.iterations = iterations;
        self
    }

    /// Whether the history keeps theta for every iteration (default: yes). Turn it off for
    /// very long parameter vectors; the last theta is always kept.
    #[must_use]
    pub fn record_theta(mut self, record: bool) -> Self {
        self.record_theta = record;
        self
    }

    /// The optimiser (with its moment estimates after a run).
    pub fn adam(&self) -> &Adam {
        &self.adam
    }

    /// The schedule.
    pub fn annealer(&self) -> &Annealer {
        &self.annealer
    }

    /// Runs from `start` to the end.
    ///
    /// # Errors
    /// Whatever the estimator or Adam report (bad input, non-finite values of `f`); the run
    /// stops at the first error.
    pub fn minimize<G: GradientEstimator + ?Sized>(
        &mut self,
        estimator: &mut G,
        start: &[f64],
    ) -> Result<History, Error> {
        self.minimize_with(estimator, start, |_| ControlFlow::Continue(()))
    }

    /// Runs from `start`, calling `observer` after every iteration; the observer stops the run
    /// by returning `ControlFlow::Break(())`. Adam's state is reset at the start of every run.
    ///
    /// # Errors
    /// As [`Optimizer::minimize`].
    pub fn minimize_with<G, O>(
        &mut self,
        estimator: &mut G,
        start: &[f64],
        mut observer: O,
    ) -> Result<History, Error>
    where
        G: GradientEstimator + ?Sized,
        O: FnMut(&Step<'_>) -> ControlFlow<()>,
    {
        check::theta(start)?;
        self.adam.reset();
        let mut theta = start.to_vec();
        let mut history = History::default();
        for iteration in 0..self.iterations {
            let sigma = self.annealer.sigma(iteration);
            let estimate = estimator.estimate(&theta, sigma)?;
            self.adam.step(&mut theta, &estimate.gradient)?;
            history.sigma.push(sigma);
            history.value.push(estimate.mean_value);
            history.evaluations += estimate.evaluations;
            if self.record_theta || iteration + 1 == self.iterations {
                history.theta.push(theta.clone());
            }
            let step = Step {
                iteration,
                theta: &theta,
                sigma,
                estimate: &estimate,
            };
            if observer(&step).is_break() {
                history.stopped_early = iteration + 1 < self.iterations;
                if !self.record_theta && history.stopped_early {
                    history.theta.push(theta.clone());
                }
                break;
            }
        }
        Ok(history)
    }
}
