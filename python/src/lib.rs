//! Python bindings of `plateau-free`: the extension module `plateau_free._native`, re-exported (with
//! `minimize`, `Sampling` and the result types) by the Python package `plateau_free`
//! (`python/plateau_free/__init__.py`, the code in `python/plateau_free/_minimize.py` and beside it).
//!
//! How a Python objective runs. Every `plateau_free.minimize` run is one of the library's
//! ask-and-tell state machines (`_AskTell`), driven by the library's `lifecycle::Driver`
//! (`drive.rs`: failures, Ctrl-C, progress, history, checkpoints), with the asked points
//! evaluated by Python (`python/plateau_free/_evaluate.py`) where `workers` says. The
//! estimators called directly compute with the GIL released ([`Python::detach`]); each call of `fun`
//! re-attaches, checks for pending signals (so Ctrl-C stops a run within one call of `fun`),
//! builds one numpy array for the point (or one `(N, n)` array for a whole batch, copied in a
//! single `memcpy`), calls `fun` and reads the value. The first exception raised by `fun` is
//! kept and the remaining evaluations of the estimate are skipped; it is then raised unchanged
//! (type, message, traceback).
//!
//! Threads: every pyclass with state (the estimators, `Adam`, `_AskTell`) is `frozen` and keeps
//! that state behind a mutex, taken with the GIL released ([`locking::Guarded`]): calls on one
//! object from several threads run one at a time, and a thread waiting for the lock never
//! holds the GIL that the thread holding it needs to call `fun`.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

use numpy::{
    IntoPyArray, PyArray1, PyArrayDyn, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods,
};
use plateau_free::baseline::{FiniteDifference as RsFiniteDifference, Spsa as RsSpsa};
use plateau_free::{
    anneal::Schedule, objective::Points, run::FailurePolicy, run::HistoryKeep, run::Metric,
    run::Strategy, Adam as RsAdam, Annealer as RsAnnealer, Error, GradientEstimator,
    Minimizer as RsMinimizer, Minimum as RsMinimum, Objective, Optimizer,
    PlateauFreeGradient as RsPlateauFreeGradient, Sampling, Stop,
};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyBytes, PyDict, PyFloat, PyInt, PyString, PyTuple, PyType};

mod adaptive;
mod ask_tell;
mod convert;
mod drive;
mod driven_runs;
mod estimators;
mod least_squares;
mod locking;
mod loops;
mod objective;
mod record;
mod reference;
mod schedule;

use adaptive::*;
use ask_tell::*;
use convert::*;
use estimators::*;
use least_squares::*;
use locking::*;
use loops::*;
use objective::*;
use record::*;
use reference::*;
use schedule::*;

/// Replaces the file `path` by `data` atomically (the library's `replace_file`: a temporary
/// file beside it, fsync, rename); on error the file is as before. `plateau_free.minimize`'s
/// checkpoint files are written with it.
#[pyfunction]
fn _replace_file(py: Python<'_>, path: std::path::PathBuf, data: Vec<u8>) -> PyResult<()> {
    py.detach(|| plateau_free::lifecycle::replace_file(&path, &data))
        .map_err(|e| {
            pyo3::exceptions::PyOSError::new_err(format!(
                "checkpoint {} not written: {e}",
                path.display()
            ))
        })
}

/// The Rust extension of the Python package `plateau-free`; use `import plateau_free`.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // The distribution's version is Cargo's (maturin reads it too): written once, in the
    // workspace's Cargo.toml.
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add(
        "OptionTypeError",
        option_type_error_class(m.py())?.bind(m.py()),
    )?;
    m.add_class::<PyPlateauFreeGradient>()?;
    m.add_class::<PyFiniteDifference>()?;
    m.add_class::<PySpsa>()?;
    m.add_class::<PyAnnealer>()?;
    m.add_class::<PyAdam>()?;
    m.add_class::<PyAskTell>()?;
    m.add_class::<PyLeastSquares>()?;
    m.add_function(wrap_pyfunction!(_rust_reference_estimates, m)?)?;
    m.add_function(wrap_pyfunction!(_rust_reference_minimize, m)?)?;
    m.add_function(wrap_pyfunction!(_rust_reference_minimize_adaptive, m)?)?;
    m.add_function(wrap_pyfunction!(_rust_seconds_per_evaluation, m)?)?;
    m.add("PAPER_SIGMA_MIN", plateau_free::anneal::PAPER_SIGMA_MIN)?;
    m.add("PAPER_WARMUP", plateau_free::anneal::PAPER_WARMUP)?;
    m.add("STALL_WINDOW", plateau_free::run::STALL_WINDOW)?;
    m.add("DEFAULT_POLISH", plateau_free::run::DEFAULT_POLISH)?;
    m.add(
        "CHECKPOINT_SECONDS",
        plateau_free::lifecycle::CHECKPOINT_SECONDS,
    )?;
    m.add(
        "PROGRESS_SECONDS",
        plateau_free::lifecycle::PROGRESS_SECONDS,
    )?;
    m.add_function(wrap_pyfunction!(_replace_file, m)?)?;
    m.add_function(wrap_pyfunction!(drive::_drive, m)?)?;
    Ok(())
}
