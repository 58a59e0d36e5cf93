//! The paper's loop in its callback form (`Optimizer`), with any estimator: what
//! `plateau_free.minimize(..., method="fd")` and `"spsa"` run (the baselines have no ask-and-tell
//! form); and [`Record`], the per-iteration records of the paper's loop that
//! `plateau_free.minimize` returns as `history`, kept by this loop and by `_AskTell`.

use super::*;

/// Per-iteration records of a run: the last `keep_history` iterations (`minimize`'s option,
/// default [`HistoryKeep::DEFAULT_LAST`]), so that a run of any length has bounded memory.
#[derive(Default, Clone, serde::Serialize, serde::Deserialize)]
pub(crate) struct Record {
    pub(crate) sigma: Vec<f64>,
    pub(crate) grad_norm: Vec<f64>,
    pub(crate) value: Vec<f64>,
    pub(crate) nfev: Vec<u64>,
    pub(crate) x: Vec<f64>,
    pub(crate) stopped_by_callback: bool,
    /// Whether Ctrl-C (a `KeyboardInterrupt`) ended the run.
    #[serde(default)]
    pub(crate) interrupted: bool,
    /// The oldest iterations no longer held (a file without it has dropped none).
    #[serde(default)]
    pub(crate) dropped: usize,
}

impl Record {
    /// Appends one iteration's entry, then drops the oldest beyond the last `keep` once twice
    /// as many are held (O(1) an iteration on average, at most `2 keep` entries held).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn push(
        &mut self,
        sigma: f64,
        gradient: &[f64],
        value: f64,
        nfev: u64,
        theta: Option<&[f64]>,
        keep: usize,
    ) {
        self.sigma.push(sigma);
        self.grad_norm
            .push(gradient.iter().map(|v| v * v).sum::<f64>().sqrt());
        self.value.push(value);
        self.nfev.push(nfev);
        if let Some(theta) = theta {
            self.x.extend_from_slice(theta);
        }
        if self.sigma.len() > keep.saturating_mul(2).max(1) {
            self.trim(keep);
        }
    }

    /// Keeps exactly the last `keep` iterations' entries.
    pub(crate) fn trim(&mut self, keep: usize) {
        let held = self.sigma.len();
        if held <= keep {
            return;
        }
        let cut = held - keep;
        let dim = self.x.len() / held;
        self.sigma.drain(..cut);
        self.grad_norm.drain(..cut);
        self.value.drain(..cut);
        self.nfev.drain(..cut);
        self.x.drain(..cut * dim);
        self.dropped += cut;
    }

    /// Keeps the entries of the first `iterations` iterations (of `dim` coordinates each in
    /// `x`; the dropped ones count).
    fn truncate(&mut self, iterations: usize, dim: usize) {
        let held = iterations.saturating_sub(self.dropped);
        self.sigma.truncate(held);
        self.grad_norm.truncate(held);
        self.value.truncate(held);
        self.nfev.truncate(held);
        if !self.x.is_empty() {
            self.x.truncate(held * dim);
        }
    }

    /// The records into `out` (the raw results `plateau_free.minimize` reads), `x` shaped
    /// `(held, *shape)` when recorded.
    pub(crate) fn into_dict(
        self,
        py: Python<'_>,
        out: &Bound<'_, PyDict>,
        shape: &[usize],
        record_x: bool,
    ) -> PyResult<()> {
        let held = self.sigma.len();
        out.set_item("stopped_by_callback", self.stopped_by_callback)?;
        out.set_item("interrupted", self.interrupted)?;
        out.set_item("dropped", self.dropped)?;
        out.set_item("sigma", self.sigma.into_pyarray(py))?;
        out.set_item("grad_norm", self.grad_norm.into_pyarray(py))?;
        out.set_item("fun", self.value.into_pyarray(py))?;
        out.set_item("nfev_history", self.nfev.into_pyarray(py))?;
        if record_x {
            let mut full = vec![held];
            full.extend(shape);
            out.set_item("x_history", self.x.into_pyarray(py).reshape(full)?)?;
        }
        Ok(())
    }
}

/// The version of the checkpoint file's layout.
const CHECKPOINT_FORMAT: u32 = 1;

/// The contents of a `minimize(..., checkpoint=path)` file.
#[derive(serde::Serialize, serde::Deserialize)]
struct CheckpointFile {
    /// [`CHECKPOINT_FORMAT`].
    format: u32,
    /// The library's version.
    version: String,
    /// The run's settings, as Python describes them (a JSON object): compared key by key.
    settings: serde_json::Value,
    /// The loop's state (theta, Adam's moments, the iteration, the streams, the history).
    state: plateau_free::OptimizerState,
    /// The per-iteration records `minimize` returns.
    record: Record,
}

/// Where a run keeps its checkpoint, how often, and with which settings.
pub(crate) struct Checkpointing {
    path: std::path::PathBuf,
    /// Every this many iterations; `None`: about every
    /// [`plateau_free::lifecycle::CHECKPOINT_SECONDS`], the library's cadence; `Some(0)`:
    /// only at the end and when the run stops on an exception.
    every: Option<usize>,
    settings: serde_json::Value,
}

impl Checkpointing {
    /// Reads the file, if it exists: a damaged one, or one of other settings, is a
    /// ValueError naming the path and the difference (never half-used).
    fn load(&self, dim: usize) -> PyResult<Option<(plateau_free::OptimizerState, Record)>> {
        let path = self.path.display();
        let bytes = match std::fs::read(&self.path) {
            Ok(b) => b,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => {
                return Err(PyValueError::new_err(format!(
                    "checkpoint {path} cannot be read: {e}"
                )))
            }
        };
        let damaged =
            |why: String| PyValueError::new_err(format!("checkpoint {path} is damaged: {why}"));
        let file: CheckpointFile =
            serde_json::from_slice(&bytes).map_err(|e| damaged(e.to_string()))?;
        if file.format != CHECKPOINT_FORMAT {
            return Err(PyValueError::new_err(format!(
                "checkpoint {path} has format {}, this version reads {CHECKPOINT_FORMAT}",
                file.format
            )));
        }
        if file.version != env!("CARGO_PKG_VERSION") {
            return Err(PyValueError::new_err(format!(
                "checkpoint {path} was written by plateau-free {}, this is {}",
                file.version,
                env!("CARGO_PKG_VERSION")
            )));
        }
        if let (serde_json::Value::Object(found), serde_json::Value::Object(here)) =
            (&file.settings, &self.settings)
        {
            for (key, value) in here {
                let old = found.get(key).unwrap_or(&serde_json::Value::Null);
                if old != value {
                    return Err(PyValueError::new_err(format!(
                        "checkpoint: {key} is {old} in {path}, {value} here"
                    )));
                }
            }
        }
        file.state.validate().map_err(|e| damaged(e.to_string()))?;
        let n = file.state.iteration;
        let r = &file.record;
        let lengths = [
            r.sigma.len(),
            r.grad_norm.len(),
            r.value.len(),
            r.nfev.len(),
        ];
        let held = n.wrapping_sub(r.dropped);
        if file.state.theta.len() != dim
            || r.dropped > n
            || lengths.iter().any(|&l| l != held)
            || !(r.x.is_empty() || r.x.len() == held * dim)
        {
            return Err(damaged(format!(
                "its records do not fit {n} iterations of dimension {dim}"
            )));
        }
        Ok(Some((file.state, file.record)))
    }

    /// Writes the file atomically, with the library's `replace_file`.
    fn save(&self, state: &plateau_free::OptimizerState, record: &Record) -> PyResult<()> {
        let file = CheckpointFile {
            format: CHECKPOINT_FORMAT,
            version: env!("CARGO_PKG_VERSION").into(),
            settings: self.settings.clone(),
            state: state.clone(),
            record: record.clone(),
        };
        let bytes = serde_json::to_vec(&file).map_err(|e| PyValueError::new_err(e.to_string()))?;
        plateau_free::lifecycle::replace_file(&self.path, &bytes).map_err(|e| {
            pyo3::exceptions::PyOSError::new_err(format!(
                "checkpoint {} not written: {e}",
                self.path.display()
            ))
        })
    }
}

#[allow(clippy::too_many_arguments)]
pub(crate) fn run<G: GradientEstimator + Send + ?Sized>(
    py: Python<'_>,
    estimator: &mut G,
    shared: &Shared,
    theta: &[f64],
    shape: &[usize],
    mut optimizer: Optimizer,
    callback: Option<&Py<PyAny>>,
    record_x: bool,
    keep: usize,
    checkpoint: Option<&Checkpointing>,
) -> PyResult<(Vec<f64>, usize, usize, Record, usize)> {
    shared.set_shape(shape);
    let dim = theta.len();
    let loaded = match checkpoint {
        Some(c) => c.load(dim)?,
        None => None,
    };
    // The iterations read from the file (0: a fresh run).
    let restored = loaded.as_ref().map_or(0, |(state, _)| state.iteration);
    let (mut state, mut record) = match loaded {
        Some((state, mut record)) => {
            // A run the callback or Ctrl-C stopped goes on when called again.
            record.stopped_by_callback = false;
            record.interrupted = false;
            (state, record)
        }
        None => (
            plateau_free::OptimizerState::new(theta).map_err(value_error)?,
            Record::default(),
        ),
    };
    let save = |state: &plateau_free::OptimizerState, record: &Record| match checkpoint {
        Some(c) => c.save(state, record),
        None => Ok(()),
    };
    let started = std::time::Instant::now();
    let first_iteration = state.iteration;
    loop {
        // When the next checkpoint is due (iterations done), from the cadence and the cost.
        let done = state.iteration;
        let due = checkpoint.and_then(|c| match c.every {
            Some(0) => None,
            Some(k) => Some(done + k),
            None => {
                let ran = done - first_iteration;
                let per = started.elapsed().as_secs_f64() / ran.max(1) as f64;
                let k = if ran == 0 || per <= 0.0 {
                    1
                } else {
                    ((plateau_free::lifecycle::CHECKPOINT_SECONDS / per) as usize).max(1)
                };
                Some(done + k)
            }
        });
        let mut checkpoint_due = false;
        let callback_error: Mutex<Option<PyErr>> = Mutex::new(None);
        let mut nfev = state.history.evaluations as u64;
        let result = py.detach(|| {
            optimizer.minimize_from(estimator, state, |step| {
                let g = &step.estimate.gradient;
                nfev += step.estimate.evaluations as u64;
                record.push(
                    step.sigma,
                    g,
                    step.estimate.mean_value,
                    nfev,
                    record_x.then_some(step.theta),
                    keep,
                );
                let flow = Python::attach(|py| {
                    let outcome = (|| -> PyResult<bool> {
                        py.check_signals()?;
                        let Some(callback) = callback else {
                            return Ok(false);
                        };
                        let x = array_like(py, step.theta.to_vec(), shape)?;
                        let grad = array_like(py, g.clone(), shape)?;
                        let stop = callback.bind(py).call1((
                            step.iteration,
                            x,
                            step.sigma,
                            step.estimate.mean_value,
                            grad,
                            nfev,
                        ))?;
                        stop.is_truthy()
                    })();
                    match outcome {
                        Ok(true) => {
                            record.stopped_by_callback = true;
                            ControlFlow::Break(())
                        }
                        Ok(false) => ControlFlow::Continue(()),
                        Err(e) => {
                            *callback_error.lock().unwrap_or_else(|p| p.into_inner()) = Some(e);
                            ControlFlow::Break(())
                        }
                    }
                });
                if flow.is_continue() && due.is_some_and(|k| step.iteration + 1 >= k) {
                    checkpoint_due = true;
                    return ControlFlow::Break(());
                }
                flow
            })
        });
        let callback_error = callback_error
            .into_inner()
            .unwrap_or_else(|p| p.into_inner());
        state = match result {
            Ok(state) => state,
            Err(run_error) => {
                // `fun` raised (KeyboardInterrupt included) or a value was bad: the state
                // after the last good iteration is kept, to continue from.
                let state = *run_error.state;
                record.truncate(state.iteration, dim);
                save(&state, &record)?;
                let err = match shared.finish(Err::<(), _>(run_error.error)) {
                    Err(e) => e,
                    Ok(()) => PyValueError::new_err("the run failed"),
                };
                if !err.is_instance_of::<PyKeyboardInterrupt>(py) {
                    return Err(err);
                }
                // Ctrl-C: the run ends with the last completed iteration.
                record.interrupted = true;
                state
            }
        };
        if let Some(err) = callback_error {
            save(&state, &record)?;
            if !err.is_instance_of::<PyKeyboardInterrupt>(py) {
                return Err(err);
            }
            record.interrupted = true;
        }
        if checkpoint_due && !record.stopped_by_callback && !record.interrupted {
            save(&state, &record)?;
            continue;
        }
        break;
    }
    record.trim(keep);
    save(&state, &record)?;
    let history = shared.finish(Ok(state.history))?;
    let x = if history.theta.is_empty() {
        state.theta
    } else {
        history
            .last_theta()
            .map(<[f64]>::to_vec)
            .unwrap_or(state.theta)
    };
    Ok((
        x,
        history.iterations(),
        history.evaluations,
        record,
        restored,
    ))
}

/// The optimisation loop behind `plateau_free.minimize(method='fd' | 'spsa')`: `iterations`
/// Adam steps along the estimator's gradient with the annealer's sigma. `callback(iteration,
/// x, sigma, value, gradient, nfev)` runs after every iteration; a truthy return stops the run.
/// Ctrl-C (a `KeyboardInterrupt` from `fun`, the callback or the signal check) ends it after the
/// last completed iteration (`interrupted` in the raw results). Returns a dict of raw results
/// that `plateau_free.minimize` turns into an `OptimizeResult` (`restored`: the iterations read
/// from the checkpoint file, 0 for a fresh run).
#[pyfunction]
#[pyo3(signature = (estimator, x0, adam, annealer, iterations=None, callback=None, record_x=false, checkpoint=None, checkpoint_every=None, settings=None, keep_history=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn _minimize<'py>(
    py: Python<'py>,
    estimator: &Bound<'py, PyAny>,
    x0: &Bound<'py, PyAny>,
    adam: PyRef<'py, PyAdam>,
    annealer: PyRef<'py, PyAnnealer>,
    iterations: Option<usize>,
    callback: Option<Py<PyAny>>,
    record_x: bool,
    checkpoint: Option<std::path::PathBuf>,
    checkpoint_every: Option<usize>,
    settings: Option<String>,
    keep_history: Option<usize>,
) -> PyResult<Bound<'py, PyDict>> {
    let keep = keep_history.unwrap_or(HistoryKeep::DEFAULT_LAST);
    let (theta, shape) = to_vector(py, x0, "x0")?;
    let checkpointing = match checkpoint {
        Some(path) => Some(Checkpointing {
            path,
            every: checkpoint_every,
            settings: serde_json::from_str(settings.as_deref().unwrap_or("{}"))
                .map_err(|e| PyValueError::new_err(format!("settings: {e}")))?,
        }),
        None => None,
    };
    let mut optimizer = Optimizer::new(adam.inner.lock(py)?.clone(), annealer.inner)
        .record_theta(false)
        // The records are `Record`'s (of `keep` iterations): the library's own history
        // keeps the last iteration alone.
        .keep_history(HistoryKeep::Last(1));
    if let Some(iterations) = iterations {
        optimizer = optimizer.iterations(iterations);
    }
    let callback = callback.as_ref();
    // The three estimator classes hold different Rust types: one `if let` arm each, the
    // same call in every arm.
    macro_rules! run_with_any_of {
        ($($class:ty),+) => {
            $(if let Ok(est) = estimator.cast::<$class>() {
                let est = est.get();
                // Held for the whole run: another thread's calls on this estimator wait.
                let mut inner = est.inner.lock(py)?;
                run(py, &mut *inner, &est.shared, &theta, &shape, optimizer, callback, record_x, keep, checkpointing.as_ref())?
            } else)+ {
                return Err(PyTypeError::new_err(format!(
                    "estimator must be a PlateauFreeGradient, FiniteDifference or Spsa, got {}",
                    short_repr(estimator)
                )));
            }
        };
    }
    let (x, nit, nfev, record, restored) =
        run_with_any_of!(PyPlateauFreeGradient, PyFiniteDifference, PySpsa);
    let out = PyDict::new(py);
    out.set_item("x", array_like(py, x, &shape)?)?;
    out.set_item("nit", nit)?;
    out.set_item("nfev", nfev)?;
    out.set_item("restored", restored)?;
    record.into_dict(py, &out, &shape, record_x)?;
    Ok(out)
}
