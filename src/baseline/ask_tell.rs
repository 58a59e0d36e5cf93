//! The paper's loop with a baseline estimator ([`FiniteDifference`], [`Spsa`]), asked and
//! told: [`BaselineAskTell`].
//!
//! A baseline's points do not depend on the values of the points before them, so an
//! estimate is drawn twice with the estimator's own code: once on a tape that records the
//! points and answers 0 (the ask), once on a tape that answers the told values in the same
//! order (the tell). Both draws start at the same stream position, so they are the same
//! points; the second gives the estimate the callback form would have given.

use std::cell::{Cell, RefCell};

use super::{FiniteDifference, Spsa};
use crate::check;
use crate::error::Error;
use crate::estimator::{Estimate, GradientEstimator};
use crate::method::{Optimizer, Progress};
use crate::objective::{Objective, Points};
use crate::run::{count, Ask, History, OptimizerState};

/// Which baseline estimates the gradient of a [`BaselineAskTell`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Baseline {
    /// Central finite differences of step `step` ([`FiniteDifference`]): `2 n` points.
    FiniteDifference {
        /// The difference's step (finite, positive).
        step: f64,
    },
    /// Simultaneous perturbation ([`Spsa`]): 2 points.
    Spsa,
}

/// The paper's loop ([`Optimizer`]) with a baseline estimator, asked and told: each
/// iteration asks for the points of one estimate and takes Adam's step when their values are
/// told, bit for bit the callback form ([`Optimizer::minimize`] with the same estimator and
/// seed). Made by [`Optimizer::ask_tell_baseline`]. With the `serde` feature it is saved and
/// read back at any tell, as [`crate::PaperAskTell`] is.
///
/// ```
/// use plateau_free::baseline::{Baseline, Spsa};
/// use plateau_free::{Adam, Annealer, Optimizer};
///
/// let f = |x: &[f64]| (x[0] - 1.0).powi(2) + x[1] * x[1];
/// let opt = || Optimizer::new(Adam::new(0.05).unwrap(), Annealer::paper(0.3, 100).unwrap());
///
/// let mut run = opt().ask_tell_baseline(Baseline::Spsa, 4, &[0.0, 0.5])?;
/// while let Some(ask) = run.ask()? {
///     let values: Vec<f64> = ask.points().iter().map(f).collect();
///     run.tell(&values)?;
/// }
/// let told = run.finish();
///
/// // The callback form: the same run, bit for bit.
/// let called = opt().minimize(&mut Spsa::new(f).seed(4), &[0.0, 0.5])?;
/// assert_eq!(told, called);
/// # Ok::<(), plateau_free::Error>(())
/// ```
#[derive(Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct BaselineAskTell {
    optimizer: Optimizer,
    baseline: Baseline,
    seed: u64,
    /// Adam's box, handed to the estimator (its points are clamped onto it).
    bounds: Option<(Vec<f64>, Vec<f64>)>,
    /// Estimates drawn: the stream position of the next.
    position: u64,
    progress: Progress,
    /// The asked points, their seeds and the iteration's spread, while they wait for values.
    asked: Option<Asked>,
    /// The estimate of the last completed iteration.
    last: Option<Estimate>,
}

#[derive(Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
struct Asked {
    sigma: f64,
    points: Vec<f64>,
    seeds: Vec<u64>,
}

/// The objective of a baseline's draw: records every point and seed asked of it, and answers
/// 0 (recording) or the told values in order (replaying).
struct Tape<'a> {
    values: Option<&'a [f64]>,
    points: RefCell<Vec<f64>>,
    seeds: RefCell<Vec<u64>>,
    next: Cell<usize>,
}

impl Objective for &Tape<'_> {
    fn evaluate(&self, point: &[f64], seed: u64) -> f64 {
        self.points.borrow_mut().extend_from_slice(point);
        self.seeds.borrow_mut().push(seed);
        let k = self.next.get();
        self.next.set(k + 1);
        self.values.and_then(|v| v.get(k).copied()).unwrap_or(0.0)
    }
}

impl Optimizer {
    /// An ask-and-tell run of this loop from `start` with `baseline`'s estimates, seeded by
    /// `seed` (see [`BaselineAskTell`]). Adam's moments start afresh.
    ///
    /// # Errors
    /// An empty or non-finite `start`, one outside Adam's bounds, or a finite difference's
    /// step that is not finite and positive.
    pub fn ask_tell_baseline(
        mut self,
        baseline: Baseline,
        seed: u64,
        start: &[f64],
    ) -> Result<BaselineAskTell, Error> {
        if let Baseline::FiniteDifference { step } = baseline {
            check::positive("step", step)?;
        }
        let state = OptimizerState::new(start)?;
        let mut bounds = None;
        let (progress, position) = self
            .begin(state, |lower, upper| {
                bounds = Some((lower.to_vec(), upper.to_vec()));
                Ok(())
            })
            .map_err(Error::from)?;
        Ok(BaselineAskTell {
            optimizer: self,
            baseline,
            seed,
            bounds,
            position: position.unwrap_or(0),
            progress,
            asked: None,
            last: None,
        })
    }
}

impl BaselineAskTell {
    /// One estimate at the current theta with spread `sigma` on `tape`, from the current
    /// stream position.
    fn draw(&self, tape: &Tape<'_>, sigma: f64) -> Result<Estimate, Error> {
        let theta = &self.progress.theta;
        let mut estimator: Box<dyn GradientEstimator + '_> = match self.baseline {
            Baseline::FiniteDifference { step } => {
                Box::new(FiniteDifference::new(tape, step)?.seed(self.seed))
            }
            Baseline::Spsa => Box::new(Spsa::new(tape).seed(self.seed)),
        };
        if let Some((lower, upper)) = &self.bounds {
            estimator.set_bounds(lower, upper)?;
        }
        estimator.set_stream_position(self.position);
        estimator.estimate(theta, sigma)
    }

    /// The points of the next estimate and their seeds, or `None` once every iteration is
    /// done.
    ///
    /// # Errors
    /// [`Error::AskPending`] if the last asked points still wait for their values; the
    /// estimator's refusal of theta or the spread, or a point that overflows.
    pub fn ask(&mut self) -> Result<Option<Ask<'_>>, Error> {
        if self.asked.is_some() {
            return Err(Error::AskPending);
        }
        let Some(sigma) = self.optimizer.next_sigma(&self.progress) else {
            return Ok(None);
        };
        let tape = Tape {
            values: None,
            points: RefCell::default(),
            seeds: RefCell::default(),
            next: Cell::new(0),
        };
        self.draw(&tape, sigma)?;
        let asked = self.asked.insert(Asked {
            sigma,
            points: tape.points.into_inner(),
            seeds: tape.seeds.into_inner(),
        });
        let points = Points::new(&asked.points, self.progress.theta.len());
        Ok(Some(Ask::new(points, &asked.seeds)))
    }

    /// Tells the values of the asked points, in their order: finishes the estimate and takes
    /// Adam's step.
    ///
    /// # Errors
    /// [`Error::NothingAsked`], [`Error::TellCount`], or [`Error::NonFiniteValue`] (the
    /// baselines redraw nothing): the run is unchanged and the same points wait for their
    /// values. An estimate or a step that overflows leaves the run at the last completed
    /// iteration: the next ask draws the same points again.
    pub fn tell(&mut self, values: &[f64]) -> Result<(), Error> {
        let Some(asked) = &self.asked else {
            return Err(Error::NothingAsked);
        };
        count(asked.seeds.len(), values.len())?;
        let sigma = asked.sigma;
        let tape = Tape {
            values: Some(values),
            points: RefCell::default(),
            seeds: RefCell::default(),
            next: Cell::new(0),
        };
        let estimate = self.draw(&tape, sigma)?;
        debug_assert_eq!(
            *tape.points.borrow(),
            asked.points,
            "a baseline's draw repeats"
        );
        self.asked = None;
        self.optimizer
            .advance(&mut self.progress, sigma, &estimate)?;
        self.position += 1;
        self.last = Some(estimate);
        Ok(())
    }

    /// Whether every iteration is done (the next ask gives `None`).
    pub fn is_done(&self) -> bool {
        self.optimizer.next_sigma(&self.progress).is_none()
    }

    /// Iterations completed.
    pub fn iteration(&self) -> usize {
        self.progress.iteration
    }

    /// The current parameters (after the last completed iteration's step).
    pub fn theta(&self) -> &[f64] {
        &self.progress.theta
    }

    /// The baseline and its seed.
    pub fn baseline(&self) -> (Baseline, u64) {
        (self.baseline, self.seed)
    }

    /// The record of the completed iterations.
    pub fn history(&self) -> &History {
        &self.progress.history
    }

    /// The gradient estimate of the last completed iteration.
    pub fn last_estimate(&self) -> Option<&Estimate> {
        self.last.as_ref()
    }

    /// The optimiser (Adam with its moments so far, the annealer).
    pub fn optimizer(&self) -> &Optimizer {
        &self.optimizer
    }

    /// Ends the run where it stands: the [`History`] that [`Optimizer::minimize`] returns.
    pub fn finish(self) -> History {
        self.optimizer.ended(self.progress)
    }

    /// The history as it stands, for a run ended early ([`BaselineAskTell::finish`] without
    /// the end).
    pub(crate) fn so_far(&self) -> History {
        self.optimizer.ended(self.progress.clone())
    }
}
