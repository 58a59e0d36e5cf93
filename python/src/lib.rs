//! Python bindings of `plateau`: the extension module `plateau._plateau`, re-exported (with
//! `minimize`, `Sampling` and the result types) by the Python package `plateau`
//! (`python/plateau/__init__.py`, the code in `python/plateau/_minimize.py` and beside it).
//!
//! How a Python objective runs: every estimate, and every run of `plateau::Minimizer`
//! (`plateau.minimize(fun, x0, budget=...)`), is computed with the GIL released
//! ([`Python::detach`]); each call of `fun` re-attaches, checks for pending signals (so Ctrl-C
//! stops a run within one call of `fun`), builds one numpy array for the point (or one
//! `(N, n)` array for a whole batch, copied in a single `memcpy`), calls `fun` and reads the
//! value. The first exception raised by `fun` is kept and the remaining evaluations of the
//! estimate are skipped; it is then raised unchanged (type, message, traceback).

use std::ops::ControlFlow;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

use numpy::{
    IntoPyArray, PyArray1, PyArrayDyn, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods,
};
use plateau::baseline::{FiniteDifference as RsFiniteDifference, Spsa as RsSpsa};
use plateau::{
    Adam as RsAdam, Annealer as RsAnnealer, Error, GradientEstimator, Minimizer as RsMinimizer,
    Minimum as RsMinimum, Objective, Optimizer, PlateauFreeGradient as RsPlateauFreeGradient,
    Points, Sampling, Schedule, Stop, Strategy,
};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyFloat, PyInt};

mod adaptive;
mod ask_tell;
mod convert;
mod estimators;
mod objective;
mod paper_loop;
mod reference;
mod schedule;

use adaptive::*;
use ask_tell::*;
use convert::*;
use estimators::*;
use objective::*;
use paper_loop::*;
use reference::*;
use schedule::*;

/// The Rust extension of the Python package `plateau`; use `import plateau`.
#[pymodule]
fn _plateau(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyPlateauFreeGradient>()?;
    m.add_class::<PyFiniteDifference>()?;
    m.add_class::<PySpsa>()?;
    m.add_class::<PyAnnealer>()?;
    m.add_class::<PyAdam>()?;
    m.add_class::<PyAskTell>()?;
    m.add_function(wrap_pyfunction!(_minimize, m)?)?;
    m.add_function(wrap_pyfunction!(_rust_reference_estimates, m)?)?;
    m.add_function(wrap_pyfunction!(_minimize_adaptive, m)?)?;
    m.add_function(wrap_pyfunction!(_rust_reference_minimize, m)?)?;
    m.add_function(wrap_pyfunction!(_rust_reference_minimize_adaptive, m)?)?;
    m.add_function(wrap_pyfunction!(_rust_seconds_per_evaluation, m)?)?;
    m.add("PAPER_SIGMA_MIN", plateau::PAPER_SIGMA_MIN)?;
    m.add("PAPER_WARMUP", plateau::PAPER_WARMUP)?;
    Ok(())
}
