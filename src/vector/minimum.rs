//! [`VectorMinimum`]: what a least-squares run gives back.

/// The result of a [`super::LeastSquares`] run: the best point evaluated and its outputs.
#[derive(Debug, Clone, PartialEq)]
pub struct VectorMinimum {
    /// The best point evaluated (the start, or a step's point).
    pub x: Vec<f64>,
    /// Its sum of squares `sum_i r_i(x)^2`.
    pub fun: f64,
    /// Its outputs.
    pub residuals: Vec<f64>,
    /// Steps taken.
    pub nit: usize,
    /// Jacobian estimates made.
    pub jacobians: usize,
    /// Evaluations of `r` (at most the budget).
    pub nfev: usize,
    /// Evaluations with a non-finite output ([`super::LeastSquares::on_failure`]); never the best
    /// point (`fun` is infinite only when every evaluation failed).
    pub failures: usize,
}
