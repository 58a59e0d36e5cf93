//! `_drive`: an adaptive or polished `_AskTell` run driven by the library's
//! [`plateau_free::lifecycle::Driver`] with a Python evaluator, so that the run's lifecycle
//! (interrupt, progress line, trace, checkpoint) is the library's, not a second copy.
//!
//! The evaluator (`evaluate(points, seeds) -> values`) keeps the Python-side work: `args`,
//! workers and executors, exceptions counted as failures, `on_failure='raise'`. A truthy
//! return of `callback(iteration, evaluations, best, sigma)` or a pending Ctrl-C (checked
//! after every tell) triggers the driver's interrupt: the run ends at the next turn with
//! `Stop::Interrupted` and its best point so far.

use super::*;
use plateau_free::lifecycle::{
    Checkpoint, Driver, Interrupt, Observer, Progress, ProgressLine, Trace,
};

/// What ended a driven run early: an exception from Python (the evaluator's, re-raised
/// unchanged) or the library's error.
enum DriveError {
    Python(PyErr),
    Library(Error),
}

impl From<Error> for DriveError {
    fn from(error: Error) -> Self {
        DriveError::Library(error)
    }
}

impl DriveError {
    fn into_py(self) -> PyErr {
        match self {
            DriveError::Python(error) => error,
            DriveError::Library(error) => value_error(error),
        }
    }
}

/// After every tell: a pending Ctrl-C, or the Python callback's truthy return, triggers the
/// interrupt; the first exception (the signal's, the callback's) is kept to re-raise or
/// report.
struct Hooks {
    interrupt: Interrupt,
    callback: Option<Py<PyAny>>,
    /// Why the interrupt was triggered: `"interrupted"` (Ctrl-C) or `"callback"`.
    why: Arc<Mutex<Option<&'static str>>>,
    raised: Arc<Mutex<Option<PyErr>>>,
}

impl Hooks {
    fn stop(&self, why: &'static str) {
        let mut held = self.why.lock().unwrap_or_else(|p| p.into_inner());
        held.get_or_insert(why);
        self.interrupt.trigger();
    }
}

impl Observer for Hooks {
    fn observe(&mut self, p: &Progress) {
        Python::attach(|py| {
            if py.check_signals().is_err() {
                self.stop("interrupted");
                return;
            }
            let Some(callback) = &self.callback else {
                return;
            };
            let called = callback
                .call1(py, (p.iteration, p.evaluations, p.best, p.sigma))
                .and_then(|r| r.bind(py).is_truthy());
            match called {
                Ok(true) => self.stop("callback"),
                Ok(false) => {}
                Err(error) => {
                    self.raised
                        .lock()
                        .unwrap_or_else(|p| p.into_inner())
                        .get_or_insert(error);
                    self.stop("raised");
                }
            }
        });
    }
}

/// Runs the adaptive or polished `run` to its end with the library's driver and returns
/// `(result, why, trace)`: `result` the library's minimum as a dict (`x`, `fun`, `nit`,
/// `nfev`, `stop`), `why` None for a run that ended by itself, else `"interrupted"`,
/// `"callback"` or `"raised"`; `trace` the rows `(iteration, evaluations, best, sigma)` of
/// the library's [`Trace`] (`keep` rows at least). `disp` writes the library's progress line
/// on stderr; `checkpoint` is the library's [`Checkpoint`] (every `checkpoint_every`
/// iterations, else on its timer), checked against `identity` (the objective's name) too.
///
/// # Errors
/// The evaluator's exception unchanged; the library's errors as ValueError.
#[pyfunction]
#[pyo3(signature = (run, evaluate, *, disp=false, keep=1_000_000, checkpoint=None, checkpoint_every=None, callback=None))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
pub(crate) fn _drive<'py>(
    py: Python<'py>,
    run: PyRef<'py, PyAskTell>,
    evaluate: Bound<'py, PyAny>,
    disp: bool,
    keep: usize,
    checkpoint: Option<std::path::PathBuf>,
    checkpoint_every: Option<usize>,
    callback: Option<Py<PyAny>>,
) -> PyResult<(
    Bound<'py, PyDict>,
    Option<&'static str>,
    Vec<(usize, usize, f64, f64)>,
)> {
    let (method, shape) = run.take_adaptive(py)?;
    let interrupt = Interrupt::new();
    let hooks = Hooks {
        interrupt: interrupt.clone(),
        callback,
        why: Arc::default(),
        raised: Arc::default(),
    };
    let (why, raised) = (hooks.why.clone(), hooks.raised.clone());
    let mut trace = Trace::new(keep);
    let mut driver = Driver::new()
        .interrupt(interrupt)
        .observe(&mut trace)
        .observe(hooks);
    if disp {
        driver = driver.observe(ProgressLine::new(std::io::stderr()));
    }
    if let Some(path) = checkpoint {
        let saved = Checkpoint::new(path);
        driver = driver.checkpoint(match checkpoint_every {
            Some(k) => saved.every_iterations(k),
            None => saved,
        });
    }
    let driven = driver.run(method, |_workers, ask, out: &mut [f64]| {
        let mut dims = vec![ask.len()];
        dims.extend(&shape);
        let points = ask
            .points()
            .as_flat()
            .to_vec()
            .into_pyarray(py)
            .reshape(dims)
            .map_err(DriveError::Python)?;
        let seeds = ask.seeds().to_vec().into_pyarray(py);
        let values: Vec<f64> = evaluate
            .call1((points, seeds))
            .and_then(|v| v.extract())
            .map_err(DriveError::Python)?;
        if values.len() != out.len() {
            return Err(DriveError::Library(Error::TellCount {
                expected: out.len(),
                got: values.len(),
            }));
        }
        out.copy_from_slice(&values);
        Ok(())
    });
    let minimum = match driven {
        Ok(minimum) => minimum,
        Err(failure) => return Err(failure.error.into_py()),
    };
    if let Some(error) = raised.lock().unwrap_or_else(|p| p.into_inner()).take() {
        return Err(error);
    }
    let rows = trace
        .rows()
        .iter()
        .map(|r| (r.iteration, r.evaluations, r.best, r.sigma))
        .collect();
    let why = *why.lock().unwrap_or_else(|p| p.into_inner());
    Ok((minimum_dict(py, &minimum, &shape)?, why, rows))
}

/// The library's minimum as the dict `_adaptive_result` reads.
fn minimum_dict<'py>(
    py: Python<'py>,
    m: &RsMinimum,
    shape: &[usize],
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("x", array_like(py, m.x.clone(), shape)?)?;
    d.set_item("fun", m.fun)?;
    d.set_item("nit", m.iterations)?;
    d.set_item("nfev", m.evaluations)?;
    d.set_item("stop", format!("{:?}", m.stop))?;
    Ok(d)
}
