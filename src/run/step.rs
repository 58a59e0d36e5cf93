//! [`Step`]: what the observer of the paper's loop in its callback form
//! ([`crate::Optimizer::minimize_with`]) sees after each iteration.

use crate::estimator::Estimate;

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
