//! What a [`Minimizer`] run gives back: the [`Minimum`] and why the run ended ([`Stop`]);
//! and the run's account, which every method keeps the same way ([`Ledger`]: the options,
//! the budget, the evaluations spent, the best point seen).

use std::fmt;

use super::ask::{count, non_finite};
use super::options::{FailurePolicy, Options};
use crate::error::Error;
use crate::objective::Points;
// For the documentation's links only.
#[cfg(doc)]
use crate::Minimizer;

/// Why a run of [`Minimizer`] ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Stop {
    /// The budget of evaluations is spent.
    Budget,
    /// The best value reached [`Minimizer::target`].
    Target,
    /// The search converged (or stalled) and restarts are off ([`Minimizer::restarts`]).
    Converged,
    /// The best value stopped improving ([`Minimizer::stop_when_stalled`], the rule
    /// [`crate::run::Stall`]).
    Stalled,
    /// The run is done before its budget: its restarts converged and keep finding the best
    /// point seen again, so more evaluations would buy nothing.
    Done,
    /// The run was interrupted (Ctrl-C, or a stop asked by the caller): the result holds the best point
    /// seen so far.
    Interrupted,
}

impl Stop {
    /// Whether the run ended at a point it judged an answer: a target reached, or converged
    /// ([`Stop::Converged`], [`Stop::Done`]). A spent budget, a stall or an interrupt is not.
    pub fn success(self) -> bool {
        matches!(self, Stop::Target | Stop::Converged | Stop::Done)
    }
}

impl fmt::Display for Stop {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Stop::Budget => "budget spent",
            Stop::Target => "target reached",
            Stop::Converged => "converged",
            Stop::Stalled => "stalled",
            Stop::Done => "done: the restarts found the best point again",
            Stop::Interrupted => "interrupted",
        })
    }
}

/// The result of a [`Minimizer`] run.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Minimum {
    /// The best point seen. The start is evaluated first, so `f(x) <= f(x0)` always.
    pub x: Vec<f64>,
    /// `f(x)`.
    #[cfg_attr(feature = "serde", serde(with = "crate::saved::float"))]
    pub fun: f64,
    /// Evaluations of `f` spent (at most the budget, whatever the method and the budget).
    pub evaluations: usize,
    /// Iterations (generations of the search distribution, or gradient steps of the paper's
    /// loop).
    pub iterations: usize,
    /// Restarts of the search distribution (0 for the paper's loop).
    pub restarts: usize,
    /// The spread at the end.
    #[cfg_attr(feature = "serde", serde(with = "crate::saved::float"))]
    pub sigma: f64,
    /// Why the run ended.
    pub stop: Stop,
    /// Evaluations whose value was NaN or infinite (or, in the bindings, raised): ranked below
    /// every finite value under [`crate::run::FailurePolicy::Continue`], never the best point.
    #[cfg_attr(feature = "serde", serde(default))]
    pub failures: usize,
}

impl Minimum {
    /// Whether the run ended at a point it judged an answer ([`Stop::success`]).
    pub fn success(&self) -> bool {
        self.stop.success()
    }
}

/// The best point seen and its value.
#[derive(Debug, Clone)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub(crate) struct Best {
    pub(crate) x: Vec<f64>,
    #[cfg_attr(feature = "serde", serde(with = "crate::saved::float"))]
    pub(crate) fun: f64,
}

impl Best {
    /// Nothing seen yet, at the start `x0`.
    pub(crate) fn new(x0: &[f64]) -> Best {
        Best {
            x: x0.to_vec(),
            fun: f64::INFINITY,
        }
    }

    /// Takes every point better than the best so far, in order (the first of equals wins).
    /// A failed point (NaN or an infinity) is never the best.
    pub(crate) fn see(&mut self, points: Points<'_>, values: &[f64]) {
        for (point, &v) in points.iter().zip(values) {
            if v.is_finite() && v < self.fun {
                self.fun = v;
                self.x.copy_from_slice(point);
            }
        }
    }
}

/// A [`Minimizer`] run's account, kept the same way by every method: its options and budget,
/// the evaluations spent and the best point seen.
#[derive(Debug, Clone)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub(crate) struct Ledger {
    pub(crate) options: Options,
    pub(crate) budget: usize,
    pub(crate) evaluations: usize,
    pub(crate) best: Best,
    /// Evaluations told whose value was NaN or infinite.
    #[cfg_attr(feature = "serde", serde(default))]
    pub(crate) failures: usize,
}

impl Ledger {
    /// Takes the told `values` of the asked `points`: checks their count and, under
    /// [`FailurePolicy::Raise`], that every value is finite (the error names the first that
    /// is not by its index in the run's evaluations), then counts them and keeps the best.
    /// On error nothing has changed.
    pub(crate) fn take(&mut self, points: Points<'_>, values: &[f64]) -> Result<(), Error> {
        count(points.len(), values.len())?;
        if self.options.on_failure == FailurePolicy::Raise {
            non_finite(values, points, self.evaluations)?;
        }
        self.count(points, values);
        Ok(())
    }

    /// Counts values already checked (and their failures) and keeps the best.
    pub(crate) fn count(&mut self, points: Points<'_>, values: &[f64]) {
        self.best.see(points, values);
        self.failures += values.iter().filter(|v| !v.is_finite()).count();
        self.evaluations += values.len();
    }

    /// Whether the best value has reached [`Minimizer::target`].
    pub(crate) fn target_reached(&self) -> bool {
        self.options.target.is_some_and(|t| self.best.fun <= t)
    }

    /// The evaluations the budget has left.
    pub(crate) fn left(&self) -> usize {
        self.budget - self.evaluations
    }

    /// The run's result, with the best point seen.
    pub(crate) fn minimum(
        &self,
        iterations: usize,
        restarts: usize,
        sigma: f64,
        stop: Stop,
    ) -> Minimum {
        Minimum {
            x: self.best.x.clone(),
            fun: self.best.fun,
            evaluations: self.evaluations,
            iterations,
            restarts,
            sigma,
            stop,
            failures: self.failures,
        }
    }
}
