//! The vector (least-squares) method from Python: `_LeastSquares`, which
//! `plateau_free.least_squares(fun, x0, ...)` (`python/plateau_free/_least_squares.py`)
//! runs on the library's driver (`drive.rs`, as `minimize`'s runs). Nothing here calls
//! Python: the caller evaluates the asked points and tells their output vectors back.

use super::*;
use plateau_free::{
    vector::Acceptance, vector::LeastSquaresAskTell, vector::Sparsity, LeastSquares,
};

/// The run behind `plateau_free.least_squares`: `plateau_free::vector::LeastSquaresAskTell`.
///
/// `ask()` gives `(X, seeds)`: `X` a float64 array of shape `(k, n)`, `seeds` a uint64 array
/// of length `k`, or None once the budget is spent. `tell(outputs)` takes `k * m` floats
/// (the outputs of the points, row by row; a point with a non-finite output is a failure,
/// counted under `on_failure='continue'`, a ValueError under `'raise'`). Every error is a
/// ValueError naming the value; calls from several threads run one at a time.
#[pyclass(module = "plateau_free._native", name = "_LeastSquares", frozen)]
pub(crate) struct PyLeastSquares {
    run: Guarded<LeastSquaresAskTell>,
}

impl PyLeastSquares {
    /// A copy of the run, for the library's driver.
    pub(crate) fn copy_run(&self, py: Python<'_>) -> PyResult<LeastSquaresAskTell> {
        Ok(self.run.lock(py)?.clone())
    }

    /// Replaces the run (with the driven run's end).
    pub(crate) fn put_run(&self, py: Python<'_>, run: LeastSquaresAskTell) -> PyResult<()> {
        *self.run.lock(py)? = run;
        Ok(())
    }
}

/// `"continue"` or `"raise"`.
fn failure_policy(name: &str) -> PyResult<FailurePolicy> {
    match name {
        "continue" => Ok(FailurePolicy::Continue),
        "raise" => Ok(FailurePolicy::Raise),
        other => Err(PyValueError::new_err(format!(
            "on_failure = {other:?} is not a policy: use 'continue' or 'raise'"
        ))),
    }
}

/// `"descent"` or `"always"`.
fn acceptance(name: &str) -> PyResult<Acceptance> {
    match name {
        "descent" => Ok(Acceptance::Descent),
        "always" => Ok(Acceptance::Always),
        other => Err(PyValueError::new_err(format!(
            "acceptance = {other:?} is invalid: expected 'descent' or 'always'"
        ))),
    }
}

#[pymethods]
impl PyLeastSquares {
    /// A run from `x0` for `outputs` outputs; `sparsity`: `(output, parameter)` pairs, or
    /// None for every output on every parameter; `on_failure`: `'continue'` or `'raise'`.
    #[new]
    #[pyo3(signature = (x0, outputs, sparsity, budget, sigma0, pairs, memory, damping, max_step, acceptance_name, smoothed_residuals, bounds, seed, on_failure="continue"))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        x0: Vec<f64>,
        outputs: usize,
        sparsity: Option<Vec<(usize, usize)>>,
        budget: usize,
        sigma0: f64,
        pairs: usize,
        memory: usize,
        damping: f64,
        max_step: f64,
        acceptance_name: &str,
        smoothed_residuals: bool,
        bounds: Option<(Vec<f64>, Vec<f64>)>,
        seed: u64,
        on_failure: &str,
    ) -> PyResult<Self> {
        let n = x0.len();
        let pattern = match sparsity {
            None => Sparsity::dense(outputs, n.max(1)),
            Some(pairs) => Sparsity::from_pairs(outputs, n.max(1), &pairs),
        }
        .map_err(value_error)?;
        let mut options = LeastSquares::new(pattern)
            .budget(budget)
            .sigma0(sigma0)
            .pairs(pairs)
            .memory(memory)
            .damping(damping)
            .max_step(max_step)
            .acceptance(acceptance(acceptance_name)?)
            .smoothed_residuals(smoothed_residuals)
            .seed(seed)
            .on_failure(failure_policy(on_failure)?);
        if let Some((lower, upper)) = bounds {
            options = options.bounds(lower, upper);
        }
        let run = options.ask_tell(&x0).map_err(value_error)?;
        Ok(PyLeastSquares {
            run: Guarded::new(run),
        })
    }

    /// `(X, seeds)`: the next points, shape `(k, n)`, and their uint64 seeds; None once the
    /// budget is spent.
    #[allow(clippy::type_complexity)]
    fn ask<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<Option<(Bound<'py, PyAny>, Bound<'py, PyArray1<u64>>)>> {
        let mut run = self.run.lock(py)?;
        let Some(ask) = run.ask().map_err(value_error)? else {
            return Ok(None);
        };
        let shape = vec![ask.len(), ask.points().dim()];
        let points = ask.points().as_flat().to_vec().into_pyarray(py);
        let seeds = ask.seeds().to_vec().into_pyarray(py);
        Ok(Some((points.reshape(shape)?.into_any(), seeds)))
    }

    /// Tells the outputs of the asked points: `k * m` floats, row by row.
    fn tell(&self, py: Python<'_>, outputs: Vec<f64>) -> PyResult<()> {
        self.run.lock(py)?.tell(&outputs).map_err(value_error)
    }

    /// Evaluations told so far.
    #[getter]
    fn evaluations(&self, py: Python<'_>) -> PyResult<usize> {
        Ok(self.run.lock(py)?.evaluations())
    }

    /// Whether the run has ended (`ask` gave None).
    #[getter]
    fn done(&self, py: Python<'_>) -> PyResult<bool> {
        Ok(self.run.lock(py)?.finish().is_ok())
    }

    /// `(x, fun, residuals, nit, jacobians, nfev)` of the best point so far.
    #[allow(clippy::type_complexity)]
    fn result(&self, py: Python<'_>) -> PyResult<(Vec<f64>, f64, Vec<f64>, usize, usize, usize)> {
        let r = self.run.lock(py)?.result();
        Ok((r.x, r.fun, r.residuals, r.nit, r.jacobians, r.nfev))
    }
}
