//! The runs that `drive.rs` drives for Python, behind one trait ([`DrivenRun`]): the
//! `_AskTell`'s [`Run`] (`minimize`'s methods) and the `_LeastSquares`'
//! [`LeastSquaresAskTell`] (`least_squares`).

use super::*;
use crate::ask_tell::{best_of, copy_of, last_step_of, Run};
use crate::drive::state_error;
use plateau_free::lifecycle::AskAndTell;
use plateau_free::{vector::LeastSquaresAskTell, Ask};

/// A run that `drive.rs`'s `Driven` drives for Python: the `_AskTell`'s [`Run`] or a
/// [`LeastSquaresAskTell`]. What the library's [`AskAndTell`] says, plus what Python needs:
/// the callback's argument, a bit-exact copy, the serde state and the end test.
pub(crate) trait DrivenRun: Sized + serde::Serialize {
    /// The next points and their seeds; None once the run has ended.
    fn ask_points(&mut self) -> Result<Option<Ask<'_>>, Error>;
    /// The asked points' values, [`DrivenRun::values_per_point`] a point.
    fn tell_values(&mut self, values: &[f64]) -> Result<(), Error>;
    /// Values per point: 1, or a least-squares run's outputs.
    fn values_per_point(&self) -> usize;
    /// As [`AskAndTell::evaluations`].
    fn evaluations(&self) -> usize;
    /// As [`AskAndTell::budget`].
    fn budget(&self) -> Option<usize>;
    /// As [`AskAndTell::iteration`].
    fn iteration(&self) -> usize;
    /// As [`AskAndTell::sigma`].
    fn sigma(&self) -> f64;
    /// As [`AskAndTell::best_value`].
    fn best_value(&self) -> f64;
    /// The library's settings of the run, for a checkpoint's identity.
    fn identity(&self) -> Vec<(&'static str, String)>;
    /// Whether the run has ended (a checkpoint of a finished run says so).
    fn is_done(&self) -> bool;
    /// A bit-exact copy (the run so far, for a run that ends early).
    fn copy(&self) -> Self;
    /// Replaces the run with the state a checkpoint kept, checked; unchanged on error.
    fn restore_state(&mut self, state: serde_json::Value) -> Result<(), Error>;
    /// The callback's third argument after an iteration (see `Driven::after_iteration`).
    fn info(&self, py: Python<'_>, shape: &[usize]) -> PyResult<Py<PyAny>>;
    /// The library's error that ended the run, for Python.
    fn python_error(&self, error: Error) -> PyErr {
        value_error(error)
    }
}

impl DrivenRun for Run {
    fn ask_points(&mut self) -> Result<Option<Ask<'_>>, Error> {
        Run::ask_points(self)
    }
    fn tell_values(&mut self, values: &[f64]) -> Result<(), Error> {
        Run::tell_values(self, values)
    }
    fn values_per_point(&self) -> usize {
        1
    }
    fn evaluations(&self) -> usize {
        Run::evaluations(self)
    }
    fn budget(&self) -> Option<usize> {
        Run::budget(self)
    }
    fn iteration(&self) -> usize {
        Run::iteration(self)
    }
    fn sigma(&self) -> f64 {
        Run::sigma(self)
    }
    fn best_value(&self) -> f64 {
        Run::best_value(self)
    }
    fn identity(&self) -> Vec<(&'static str, String)> {
        Run::identity(self)
    }
    fn is_done(&self) -> bool {
        Run::is_done(self)
    }
    fn copy(&self) -> Self {
        // The run's own serde state read back: it holds only numbers, so this cannot fail.
        copy_of(self).expect("a run's serde state reads back")
    }
    fn restore_state(&mut self, state: serde_json::Value) -> Result<(), Error> {
        *self = serde_json::from_value(state)
            .map_err(|e| state_error(format!("damaged state: {e}")))?;
        Ok(())
    }
    /// The adaptive search's best `(x, fun)` (None before any value), or the paper loop's
    /// last step.
    fn info(&self, py: Python<'_>, shape: &[usize]) -> PyResult<Py<PyAny>> {
        Ok(match self {
            Run::Adaptive(_) => best_of(py, self, shape)?.into_pyobject(py)?.unbind(),
            Run::Paper(_) => last_step_of(py, self, shape)?.into_pyobject(py)?.unbind(),
        })
    }
    fn python_error(&self, error: Error) -> PyErr {
        match (self, error) {
            (Run::Paper(p), error @ Error::NonFiniteValue { .. }) if p.final_asked => {
                PyValueError::new_err(format!("{error}: the final evaluation must be finite"))
            }
            (_, error) => value_error(error),
        }
    }
}

impl DrivenRun for LeastSquaresAskTell {
    fn ask_points(&mut self) -> Result<Option<Ask<'_>>, Error> {
        AskAndTell::ask(self)
    }
    fn tell_values(&mut self, values: &[f64]) -> Result<(), Error> {
        AskAndTell::tell(self, values)
    }
    fn values_per_point(&self) -> usize {
        AskAndTell::values_per_point(self)
    }
    fn evaluations(&self) -> usize {
        AskAndTell::evaluations(self)
    }
    fn budget(&self) -> Option<usize> {
        AskAndTell::budget(self)
    }
    fn iteration(&self) -> usize {
        AskAndTell::iteration(self)
    }
    fn sigma(&self) -> f64 {
        AskAndTell::sigma(self)
    }
    fn best_value(&self) -> f64 {
        AskAndTell::best_value(self)
    }
    fn identity(&self) -> Vec<(&'static str, String)> {
        AskAndTell::identity(self)
    }
    fn is_done(&self) -> bool {
        self.finish().is_ok()
    }
    fn copy(&self) -> Self {
        self.clone()
    }
    /// Through the library's restore, which checks the vectors against the pattern.
    fn restore_state(&mut self, state: serde_json::Value) -> Result<(), Error> {
        let bytes = serde_json::to_vec(&state).map_err(state_error)?;
        AskAndTell::restore(self, &bytes)
    }
    /// The current point and its sum of squares, `(x, fun)`.
    fn info(&self, py: Python<'_>, _shape: &[usize]) -> PyResult<Py<PyAny>> {
        let x = self.theta().to_vec().into_pyarray(py);
        Ok((x, self.fun()).into_pyobject(py)?.into_any().unbind())
    }
}
