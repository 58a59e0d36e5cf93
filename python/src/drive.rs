//! `_drive`: a `plateau_free.minimize` run (adaptive, polished, the paper's loop) or a
//! `plateau_free.least_squares` run driven by the library's [`Driver`], so that the run's
//! lifecycle (interrupt, progress line, history, checkpoint) is the library's, written once.
//! [`Driven`] holds either run through `driven_runs.rs`'s [`DrivenRun`].
//!
//! Python keeps what is Python's: the evaluator (`evaluate(points, seeds) -> values`: `args`,
//! workers and executors, exceptions counted as failures, `on_failure='raise'`), the callback's
//! arguments and the result's fields. The run is a copy of the `_AskTell`'s (or the
//! `_LeastSquares`'), put back at the end (also when the run fails), so the result is read
//! from that object as before.

use std::collections::HashSet;
use std::io::Write;
use std::sync::OnceLock;

use super::*;
use crate::driven_runs::DrivenRun;
use plateau_free::lifecycle::{
    AskAndTell, Checkpoint, Driver, Interrupt, Observer, Progress, ProgressLine, Trace, TraceRow,
};
use plateau_free::Ask;

/// What a driven run tells Python besides its end.
#[derive(Default)]
struct Side {
    /// Why the run ended early: `"interrupted"` (Ctrl-C), `"callback"` or `"raised"`.
    why: Option<&'static str>,
    /// The callback's exception.
    raised: Option<PyErr>,
    /// The iteration the checkpoint's run had reached, and whether it had ended.
    restored: Option<(usize, bool)>,
}

/// The run as the driver holds it: the `_AskTell`'s or `_LeastSquares`' run with its history
/// and the evaluator's failure counts (saved with it), the Python settings a checkpoint must
/// match, and the callback.
struct Driven<R> {
    run: R,
    shape: Vec<usize>,
    trace: Trace,
    settings: Vec<(&'static str, String)>,
    evaluator: Py<PyAny>,
    after: Option<Py<PyAny>>,
    interrupt: Interrupt,
    side: Arc<Mutex<Side>>,
}

/// The evaluator's counts that a resumed run goes on from (`_Evaluator`'s attributes).
#[derive(serde::Serialize, serde::Deserialize)]
struct Counts {
    failures: usize,
    exceptions: usize,
    first_error: Option<String>,
}

/// A checkpoint's state: the run, its history, the counts.
#[derive(serde::Serialize)]
struct SavedView<'a, R> {
    run: &'a R,
    trace: &'a Trace,
    counts: Counts,
}

#[derive(serde::Deserialize)]
struct Saved {
    run: serde_json::Value,
    trace: Trace,
    counts: Counts,
}

impl<R: DrivenRun> Driven<R> {
    fn side(&self) -> std::sync::MutexGuard<'_, Side> {
        self.side.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Ends the run at the next turn, for `why` (the first reason given stays).
    fn stop(&self, why: &'static str, error: Option<PyErr>) {
        let mut side = self.side();
        side.why.get_or_insert(why);
        if let Some(error) = error {
            side.raised.get_or_insert(error);
        }
        self.interrupt.trigger();
    }

    /// After an iteration: a pending Ctrl-C, then the callback (`after(nit, nfev, info)`,
    /// `info` the adaptive search's best `(x, fun)`, the paper loop's last step, or the
    /// least-squares run's current `(x, fun)`); a truthy return or an exception ends the
    /// run.
    fn after_iteration(&self, py: Python<'_>, iteration: usize) {
        if py.check_signals().is_err() {
            return self.stop("interrupted", None);
        }
        let Some(after) = &self.after else {
            return;
        };
        let called = self.run.info(py, &self.shape).and_then(|info| {
            after
                .call1(py, (iteration, self.run.evaluations(), info))
                .and_then(|r| r.bind(py).is_truthy())
        });
        match called {
            Ok(true) => self.stop("callback", None),
            Ok(false) => {}
            Err(error) => self.stop("raised", Some(error)),
        }
    }

    fn counts(&self, py: Python<'_>) -> PyResult<Counts> {
        let e = self.evaluator.bind(py);
        Ok(Counts {
            failures: e.getattr("failures")?.extract()?,
            exceptions: e.getattr("exceptions")?.extract()?,
            first_error: e.getattr("first_error_text")?.extract()?,
        })
    }

    fn set_counts(&self, py: Python<'_>, counts: &Counts) -> PyResult<()> {
        let e = self.evaluator.bind(py);
        e.setattr("failures", counts.failures)?;
        e.setattr("exceptions", counts.exceptions)?;
        e.setattr("first_error_text", counts.first_error.clone())
    }
}

/// A checkpoint error naming what Python refused.
pub(crate) fn state_error(reason: impl std::fmt::Display) -> Error {
    Error::Checkpoint {
        path: String::new(),
        reason: reason.to_string(),
    }
}

/// A driven run's end: the run and its history.
struct Ended<R> {
    run: R,
    trace: Trace,
}

impl<R: DrivenRun> AskAndTell for Driven<R> {
    type Output = Ended<R>;

    fn ask(&mut self) -> Result<Option<Ask<'_>>, Error> {
        self.run.ask_points()
    }

    fn tell(&mut self, values: &[f64]) -> Result<(), Error> {
        let before = self.run.iteration();
        self.run.tell_values(values)?;
        let iteration = self.run.iteration();
        if iteration > before {
            self.trace.record(TraceRow {
                iteration,
                evaluations: self.run.evaluations(),
                best: self.run.best_value(),
                sigma: self.run.sigma(),
            });
            Python::attach(|py| self.after_iteration(py, iteration));
        } else if Python::attach(|py| py.check_signals().is_err()) {
            self.stop("interrupted", None);
        }
        Ok(())
    }

    fn values_per_point(&self) -> usize {
        self.run.values_per_point()
    }

    fn evaluations(&self) -> usize {
        self.run.evaluations()
    }

    fn budget(&self) -> Option<usize> {
        self.run.budget()
    }

    fn iteration(&self) -> usize {
        self.run.iteration()
    }

    fn sigma(&self) -> f64 {
        self.run.sigma()
    }

    fn best_value(&self) -> f64 {
        self.run.best_value()
    }

    fn failures(&self) -> usize {
        Python::attach(|py| self.counts(py).map_or(0, |c| c.failures))
    }

    fn finish(self) -> Result<Ended<R>, Error> {
        Ok(Ended {
            run: self.run,
            trace: self.trace,
        })
    }

    fn so_far(&self) -> Ended<R> {
        Ended {
            run: self.run.copy(),
            trace: self.trace.clone(),
        }
    }

    /// The Python settings first (`fun`'s name, the method, `x0` and its shape, the options),
    /// then the library's that they do not name.
    fn identity(&self) -> Vec<(&'static str, String)> {
        let mut identity = self.settings.clone();
        for (name, value) in self.run.identity() {
            if !identity.iter().any(|(n, _)| *n == name) {
                identity.push((name, value));
            }
        }
        identity
    }

    fn save(&self, out: &mut Vec<u8>) -> Result<(), Error> {
        let counts = Python::attach(|py| self.counts(py)).map_err(state_error)?;
        let view = SavedView {
            run: &self.run,
            trace: &self.trace,
            counts,
        };
        serde_json::to_writer(out, &view).map_err(|e| state_error(format!("not written: {e}")))
    }

    fn restore(&mut self, bytes: &[u8]) -> Result<(), Error> {
        let saved: Saved = serde_json::from_slice(bytes)
            .map_err(|e| state_error(format!("damaged state: {e}")))?;
        self.run.restore_state(saved.run)?;
        Python::attach(|py| self.set_counts(py, &saved.counts)).map_err(state_error)?;
        self.trace = saved.trace;
        self.side().restored = Some((self.run.iteration(), self.run.is_done()));
        Ok(())
    }
}

/// Python's `sys.stdout`, for the progress line (`disp=True` prints where `print` does).
struct Stdout;

impl Write for Stdout {
    fn write(&mut self, bytes: &[u8]) -> std::io::Result<usize> {
        let text = String::from_utf8_lossy(bytes);
        Python::attach(|py| {
            let out = py.import("sys")?.getattr("stdout")?;
            out.call_method1("write", (text.as_ref(),))?;
            Ok::<_, PyErr>(())
        })
        .map_err(std::io::Error::other)?;
        Ok(bytes.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Python::attach(|py| {
            py.import("sys")?
                .getattr("stdout")?
                .call_method0("flush")
                .map(drop)
        })
        .map_err(std::io::Error::other)
    }
}

/// A `RuntimeWarning` for a checkpoint that could not be written during the run (a full
/// disk, a folder removed): the run goes on, the file written last stays.
struct WarnNotSaved;

impl Observer for WarnNotSaved {
    fn observe(&mut self, _: &Progress) {}

    fn not_saved(&mut self, error: &plateau_free::Error) {
        Python::attach(|py| {
            let text = format!("{error}; the run goes on").replace('\0', " ");
            let message = std::ffi::CString::new(text).unwrap_or_default();
            let category = py.get_type::<pyo3::exceptions::PyRuntimeWarning>();
            // Warnings turned into errors cannot end the run from here: the next write
            // tries again, and the last one fails the run if the file still cannot be written.
            let _ = PyErr::warn(py, category.as_any(), &message, 1);
        });
    }
}

/// A setting's name for a checkpoint's identity, which takes static names: interned, each
/// name once per process (the names are `minimize`'s options, a fixed set).
fn interned(name: &str) -> &'static str {
    static NAMES: OnceLock<Mutex<HashSet<&'static str>>> = OnceLock::new();
    let mut names = NAMES
        .get_or_init(Default::default)
        .lock()
        .unwrap_or_else(|p| p.into_inner());
    if let Some(held) = names.get(name) {
        return held;
    }
    let held: &'static str = Box::leak(name.to_owned().into_boxed_str());
    names.insert(held);
    held
}

/// What ended a driven run with an error: the evaluator's exception (re-raised unchanged) or
/// the library's.
enum DriveError {
    Python(PyErr),
    Library(Error),
}

impl From<Error> for DriveError {
    fn from(error: Error) -> Self {
        DriveError::Library(error)
    }
}

/// The asked points' values from `evaluate(points, seeds)` (points shaped `(k, *x0.shape)`).
fn evaluate_ask(
    py: Python<'_>,
    evaluate: &Bound<'_, PyAny>,
    shape: &[usize],
    ask: Ask<'_>,
    out: &mut [f64],
) -> Result<(), DriveError> {
    let mut dims = vec![ask.len()];
    dims.extend(shape);
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
}

/// How a run is driven: `_drive`'s keywords.
struct Setup {
    disp: bool,
    keep: usize,
    checkpoint: Option<std::path::PathBuf>,
    checkpoint_every: Option<usize>,
    settings: Vec<(String, String)>,
    after: Option<Py<PyAny>>,
}

/// A driven run's end: the run, put back into its Python object, and the end's dict (or the
/// error, the run so far put back).
struct Outcome<R> {
    run: Option<R>,
    ended: PyResult<Py<PyDict>>,
}

/// Runs `run` (shaped `shape` for Python) to its end as `setup` says, with `evaluate` giving
/// the values.
fn drive_run<R: DrivenRun>(
    py: Python<'_>,
    run: R,
    shape: Vec<usize>,
    evaluate: &Bound<'_, PyAny>,
    setup: Setup,
) -> Outcome<R> {
    let interrupt = Interrupt::new();
    let side = Arc::new(Mutex::new(Side::default()));
    let driven = Driven {
        run,
        shape: shape.clone(),
        trace: Trace::new(setup.keep),
        settings: setup
            .settings
            .iter()
            .map(|(n, v)| (interned(n), v.clone()))
            .collect(),
        evaluator: evaluate.clone().unbind(),
        after: setup.after,
        interrupt: interrupt.clone(),
        side: side.clone(),
    };
    let mut driver = Driver::new().interrupt(interrupt);
    if setup.disp {
        driver = driver.observe(ProgressLine::new(Stdout));
    }
    if let Some(path) = setup.checkpoint {
        driver = driver.observe(WarnNotSaved);
        let saved = Checkpoint::new(path);
        driver = driver.checkpoint(match setup.checkpoint_every {
            Some(k) => saved.every_iterations(k),
            None => saved,
        });
    }
    let ended = driver.run(driven, |_, ask, out| {
        evaluate_ask(py, evaluate, &shape, ask, out)
    });
    let mut side = std::mem::take(&mut *side.lock().unwrap_or_else(|p| p.into_inner()));
    match ended {
        Ok(end) => Outcome {
            run: Some(end.run),
            ended: match side.raised.take() {
                Some(error) => Err(error),
                None => end_dict(py, &side, &end.trace),
            },
        },
        Err(failure) => {
            let run = failure.result.map(|end| end.run);
            let error = match failure.error {
                DriveError::Python(error) => error,
                DriveError::Library(error) => match &run {
                    Some(run) => run.python_error(error),
                    None => value_error(error),
                },
            };
            Outcome {
                run,
                ended: Err(error),
            }
        }
    }
}

/// The end of a run that finished or was stopped: `why`, `restored`, `rows`, `dropped` (see
/// [`_drive`]).
fn end_dict(py: Python<'_>, side: &Side, trace: &Trace) -> PyResult<Py<PyDict>> {
    let rows: Vec<(usize, f64, f64)> = trace
        .rows()
        .iter()
        .map(|r| (r.evaluations, r.best, r.sigma))
        .collect();
    let out = PyDict::new(py);
    out.set_item("why", side.why)?;
    out.set_item("restored", side.restored)?;
    out.set_item("dropped", trace.iterations_seen() - rows.len())?;
    out.set_item("rows", rows)?;
    Ok(out.unbind())
}

/// Runs `run` (an `_AskTell` or a `_LeastSquares`) to its end with the library's driver,
/// `evaluate` (an `_Evaluator`: callable on `(points, seeds)`, giving a value per point, or
/// a least-squares run's outputs per point, flat; with the attributes `failures`,
/// `exceptions` and `first_error_text` that a checkpoint keeps) giving the values. The
/// run's end is put back into `run`. Returns a dict: `why` (None for a run that ended by
/// itself, else `"interrupted"`, `"callback"`), `restored` (None, or `(iteration,
/// finished)` of a run resumed from `checkpoint`), `rows` (`(nfev, best, sigma)` of the
/// iterations the history kept, evenly thinned to between `keep` and `2 keep`) and
/// `dropped` (the iterations not kept).
///
/// `disp` prints the library's progress line on `sys.stdout`; `checkpoint` is the library's
/// [`Checkpoint`] (every `checkpoint_every` iterations, else on its timer), its identity
/// `settings` (name, value) first; `after(nit, nfev, info)` is called after every
/// iteration.
///
/// # Errors
/// The evaluator's or the callback's exception unchanged; the library's errors as
/// ValueError. The run so far is in `run` then.
#[pyfunction]
#[pyo3(signature = (run, evaluate, *, disp=false, keep=1_000_000, checkpoint=None, checkpoint_every=None, settings=Vec::new(), after=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn _drive<'py>(
    py: Python<'py>,
    run: Bound<'py, PyAny>,
    evaluate: Bound<'py, PyAny>,
    disp: bool,
    keep: usize,
    checkpoint: Option<std::path::PathBuf>,
    checkpoint_every: Option<usize>,
    settings: Vec<(String, String)>,
    after: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let setup = Setup {
        disp,
        keep,
        checkpoint,
        checkpoint_every,
        settings,
        after,
    };
    let ended = if let Ok(ask_tell) = run.cast::<PyAskTell>() {
        let ask_tell = ask_tell.borrow();
        let (held, shape) = ask_tell.copy_run(py)?;
        let outcome = drive_run(py, held, shape, &evaluate, setup);
        if let Some(end) = outcome.run {
            ask_tell.put_run(py, end)?;
        }
        outcome.ended
    } else {
        let vector = run.cast::<PyLeastSquares>()?.borrow();
        let held = vector.copy_run(py)?;
        let shape = vec![held.theta().len()];
        let outcome = drive_run(py, held, shape, &evaluate, setup);
        if let Some(end) = outcome.run {
            vector.put_run(py, end)?;
        }
        outcome.ended
    };
    ended.map(|dict| dict.into_bound(py))
}
