//! Ask and tell from Python: `_AskTell`, which `plateau_free.ask_tell(x0, ...)`
//! (`python/plateau_free/_ask_tell.py`) wraps. Nothing here calls Python: the caller evaluates the
//! asked points wherever it likes and tells their values back.

use super::*;
use plateau_free::baseline::Baseline;
use plateau_free::lifecycle::AskAndTell;
use plateau_free::{objective::Points, Ask, AskTell as RsAskTell};

/// The run behind `plateau_free.AskTell`: `plateau_free::Minimizer`'s adaptive search, or the paper's
/// loop as `plateau_free.minimize(method='plateau')` runs it (its final evaluation included).
///
/// `ask()` gives `(X, seeds)`: `X` a float64 array of shape `(k, *x0.shape)`, `seeds` a uint64
/// array of length `k` (the seeds a seeded `fun` would receive), or None once the run has
/// ended. `tell(values)` takes `k` floats in the order of `X`. Asking twice, telling without
/// asking and telling the wrong number of values are ValueErrors, as are non-finite values
/// (which change nothing: tell again). Calls from several threads run one at a time.
#[pyclass(module = "plateau_free._native", name = "_AskTell", frozen)]
pub(crate) struct PyAskTell {
    run: Guarded<Run>,
    shape: Vec<usize>,
}

#[derive(serde::Serialize, serde::Deserialize)]
pub(crate) enum Run {
    Adaptive(Box<RsAskTell>),
    Paper(Box<Paper>),
}

/// The paper's loop, its per-iteration records and its final evaluation.
#[derive(serde::Serialize, serde::Deserialize)]
pub(crate) struct Paper {
    run: Loop,
    seed: u64,
    record_x: bool,
    /// The iterations `record` keeps (the last ones).
    keep: usize,
    final_evaluation: bool,
    record: Record,
    /// Whether the final evaluation is asked and awaits its value.
    pub(crate) final_asked: bool,
    final_value: Option<f64>,
    /// The final evaluation's point and seed while it is asked (what its `Ask` borrows).
    #[serde(default)]
    final_point: Vec<f64>,
    #[serde(default)]
    final_seed: [u64; 1],
}

impl Paper {
    /// The next points: the loop's, then the final evaluation (the last iterate with the
    /// run's seed, as `plateau_free.minimize`), then None.
    fn ask_points(&mut self) -> Result<Option<Ask<'_>>, Error> {
        if self.final_asked {
            return Err(Error::AskPending);
        }
        if !self.run.is_done() {
            return self.run.ask();
        }
        if !self.final_evaluation || self.final_value.is_some() {
            return Ok(None);
        }
        self.final_asked = true;
        self.final_point = self.run.theta().to_vec();
        self.final_seed = [self.seed];
        let points = Points::new(&self.final_point, self.final_point.len());
        Ask::try_new(points, &self.final_seed).map(Some)
    }

    fn tell(&mut self, values: &[f64]) -> Result<(), Error> {
        if self.final_asked {
            if values.len() != 1 {
                return Err(Error::TellCount {
                    expected: 1,
                    got: values.len(),
                });
            }
            // `result.fun` is this value: a NaN or an infinity is refused under every
            // failure policy (there is no other point to rank it against).
            if !values[0].is_finite() {
                return Err(Error::NonFiniteValue {
                    sample: self.run.history().evaluations,
                    value: values[0],
                    point: self.run.theta().to_vec(),
                });
            }
            self.final_value = Some(values[0]);
            self.final_asked = false;
            return Ok(());
        }
        let before = self.run.iteration();
        self.run.tell(values)?;
        if self.run.iteration() == before {
            return Ok(()); // a redraw: the iteration is not done
        }
        let history = self.run.history();
        if let (Some(&sigma), Some(estimate)) = (history.sigma.last(), self.run.last_estimate()) {
            self.record.push(
                sigma,
                &estimate.gradient,
                estimate.mean_value,
                history.evaluations as u64,
                self.record_x.then_some(self.run.theta()),
                self.keep,
            );
        }
        Ok(())
    }

    fn is_done(&self) -> bool {
        self.run.is_done()
            && !self.final_asked
            && (!self.final_evaluation || self.final_value.is_some())
    }
}

impl Run {
    /// The next points and their seeds; None once the run has ended.
    pub(crate) fn ask_points(&mut self) -> Result<Option<Ask<'_>>, Error> {
        match self {
            Run::Adaptive(run) => run.ask(),
            Run::Paper(p) => p.ask_points(),
        }
    }

    /// The values of the asked points, in their order.
    pub(crate) fn tell_values(&mut self, values: &[f64]) -> Result<(), Error> {
        match self {
            Run::Adaptive(run) => run.tell(values),
            Run::Paper(p) => p.tell(values),
        }
    }

    /// Evaluations told so far (the paper loop's final one included).
    pub(crate) fn evaluations(&self) -> usize {
        match self {
            Run::Adaptive(run) => run.evaluations(),
            Run::Paper(p) => p.run.history().evaluations + usize::from(p.final_value.is_some()),
        }
    }

    /// Iterations completed: generations, or the paper loop's steps.
    pub(crate) fn iteration(&self) -> usize {
        match self {
            Run::Adaptive(run) => run.iteration(),
            Run::Paper(p) => p.run.iteration(),
        }
    }

    /// The spread now: the adaptive search's, the paper loop's last step's (NaN before).
    pub(crate) fn sigma(&self) -> f64 {
        match self {
            Run::Adaptive(run) => run.sigma(),
            Run::Paper(p) => p.run.history().sigma.last().copied().unwrap_or(f64::NAN),
        }
    }

    /// The best value so far (the paper loop: its last estimate's mean value).
    pub(crate) fn best_value(&self) -> f64 {
        match self {
            Run::Adaptive(run) => AskAndTell::best_value(&**run),
            Run::Paper(p) => p
                .run
                .last_estimate()
                .map_or(f64::INFINITY, |e| e.mean_value),
        }
    }

    /// The budget of evaluations (the adaptive search's).
    pub(crate) fn budget(&self) -> Option<usize> {
        match self {
            Run::Adaptive(run) => Some(run.budget()),
            Run::Paper(_) => None,
        }
    }

    /// The library's settings of the run, for a checkpoint's identity.
    pub(crate) fn identity(&self) -> Vec<(&'static str, String)> {
        match self {
            Run::Adaptive(run) => AskAndTell::identity(&**run),
            Run::Paper(p) => p.run.identity(),
        }
    }

    /// Whether the run has ended.
    pub(crate) fn is_done(&self) -> bool {
        match self {
            Run::Adaptive(run) => run.is_done(),
            Run::Paper(p) => p.is_done(),
        }
    }
}

/// What pickling keeps: the run (the library's serde state) and the shape of `x0`.
#[derive(serde::Serialize, serde::Deserialize)]
struct Saved {
    run: Run,
    shape: Vec<usize>,
}

impl PyAskTell {
    /// A copy of the run this object holds (bit for bit, through its serde state), for the
    /// library's driver, and the shape of `x0`.
    pub(crate) fn copy_run(&self, py: Python<'_>) -> PyResult<(Run, Vec<usize>)> {
        let held = self.run.lock(py)?;
        Ok((copy_of(&held)?, self.shape.clone()))
    }

    /// Replaces the run this object holds (with the driven run's end).
    pub(crate) fn put_run(&self, py: Python<'_>, run: Run) -> PyResult<()> {
        *self.run.lock(py)? = run;
        Ok(())
    }
}

/// A bit-exact copy of `run`, through its serde state.
pub(crate) fn copy_of(run: &Run) -> PyResult<Run> {
    let fail = |e: serde_json::Error| PyValueError::new_err(format!("cannot copy the run: {e}"));
    serde_json::from_str(&serde_json::to_string(run).map_err(fail)?).map_err(fail)
}

#[pymethods]
impl PyAskTell {
    /// The run as a JSON string (the library's serde state, no objective): pickled, and read
    /// back by `_from_state`, it goes on bit for bit.
    fn _state(&self, py: Python<'_>) -> PyResult<String> {
        let run = self.run.lock(py)?;
        // `Saved` owns its run: serialise a borrowed view of the same fields instead.
        #[derive(serde::Serialize)]
        struct View<'a> {
            run: &'a Run,
            shape: &'a [usize],
        }
        serde_json::to_string(&View {
            run: &run,
            shape: &self.shape,
        })
        .map_err(|e| PyValueError::new_err(format!("cannot save the run: {e}")))
    }

    /// The run that `_state` wrote.
    #[staticmethod]
    fn _from_state(state: &str) -> PyResult<Self> {
        let saved: Saved = serde_json::from_str(state)
            .map_err(|e| PyValueError::new_err(format!("not a saved ask-and-tell run: {e}")))?;
        Ok(PyAskTell {
            run: Guarded::new(saved.run),
            shape: saved.shape,
        })
    }

    /// Pickling (and `copy.deepcopy`): `_from_state(_state())`.
    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, (String,))> {
        let from_state = slf.get_type().getattr("_from_state")?;
        Ok((from_state, (slf.get()._state(py)?,)))
    }

    /// The adaptive search (`plateau_free.minimize`'s default method) from `x0`.
    #[staticmethod]
    fn adaptive(py: Python<'_>, x0: &Bound<'_, PyAny>, options: AdaptiveOptions) -> PyResult<Self> {
        let (theta, shape) = to_vector(py, x0, "x0")?;
        let minimizer = options.apply(RsMinimizer::without_objective());
        let run = minimizer.ask_tell(&theta).map_err(value_error)?;
        Ok(PyAskTell {
            run: Guarded::new(Run::Adaptive(Box::new(run))),
            shape,
        })
    }

    /// The paper's loop (`plateau_free.minimize(method='plateau')`) from `x0`.
    #[staticmethod]
    #[pyo3(signature = (x0, adam, annealer, iterations, samples=2, sampling="radial", antithetic=true, orthogonal=false, seed=0, record_x=false, final_evaluation=true, keep_history=None, on_failure="raise"))]
    #[allow(clippy::too_many_arguments)]
    fn paper(
        py: Python<'_>,
        x0: &Bound<'_, PyAny>,
        adam: PyRef<'_, PyAdam>,
        annealer: PyRef<'_, PyAnnealer>,
        iterations: usize,
        samples: usize,
        sampling: &str,
        antithetic: bool,
        orthogonal: bool,
        seed: u64,
        record_x: bool,
        final_evaluation: bool,
        keep_history: Option<usize>,
        on_failure: &str,
    ) -> PyResult<Self> {
        let (theta, shape) = to_vector(py, x0, "x0")?;
        let grad = RsPlateauFreeGradient::without_objective()
            .samples(samples)
            .sampling(parse_sampling(sampling)?)
            .antithetic(antithetic)
            .orthogonal(orthogonal)
            .seed(seed)
            .on_failure(estimate_on_failure(on_failure)?);
        let optimizer = paper_optimizer(py, &adam, &annealer, iterations)?;
        let run = optimizer.ask_tell(grad, &theta).map_err(value_error)?;
        let ends = Ends::new(seed, record_x, final_evaluation, keep_history);
        Ok(PyAskTell::paper_run(
            Loop::Gaussian(Box::new(run)),
            ends,
            shape,
        ))
    }

    /// The paper's loop with a baseline estimator (`plateau_free.minimize(method='fd')`,
    /// `'spsa'`) from `x0`: `baseline` is `'fd'` (central differences of `step`) or `'spsa'`.
    #[staticmethod]
    #[pyo3(signature = (x0, adam, annealer, iterations, baseline, step=1e-3, seed=0, record_x=false, final_evaluation=true, keep_history=None))]
    #[allow(clippy::too_many_arguments)]
    fn baseline(
        py: Python<'_>,
        x0: &Bound<'_, PyAny>,
        adam: PyRef<'_, PyAdam>,
        annealer: PyRef<'_, PyAnnealer>,
        iterations: usize,
        baseline: &str,
        step: f64,
        seed: u64,
        record_x: bool,
        final_evaluation: bool,
        keep_history: Option<usize>,
    ) -> PyResult<Self> {
        let kind = match baseline {
            "fd" => Baseline::FiniteDifference { step },
            "spsa" => Baseline::Spsa,
            _ => {
                return Err(PyValueError::new_err(format!(
                    "baseline = '{baseline}' is not one: use 'fd' or 'spsa'"
                )))
            }
        };
        let (theta, shape) = to_vector(py, x0, "x0")?;
        let optimizer = paper_optimizer(py, &adam, &annealer, iterations)?;
        let run = optimizer
            .ask_tell_baseline(kind, seed, &theta)
            .map_err(value_error)?;
        let ends = Ends::new(seed, record_x, final_evaluation, keep_history);
        Ok(PyAskTell::paper_run(
            Loop::Baseline(Box::new(run)),
            ends,
            shape,
        ))
    }

    /// `(X, seeds)`: the next points, shape `(k, *x0.shape)`, and their uint64 seeds; None
    /// once the run has ended.
    #[allow(clippy::type_complexity)]
    fn ask<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<Option<(Bound<'py, PyAny>, Bound<'py, PyArray1<u64>>)>> {
        let asked = self
            .run
            .lock(py)?
            .ask_points()
            .map_err(value_error)?
            .map(|a| (a.points().as_flat().to_vec(), a.seeds().to_vec()));
        let Some((points, seeds)) = asked else {
            return Ok(None);
        };
        let mut shape = vec![seeds.len()];
        shape.extend(&self.shape);
        let points = points.into_pyarray(py).reshape(shape)?.into_any();
        Ok(Some((points, seeds.into_pyarray(py))))
    }

    /// Tells the values of the asked points, in their order.
    fn tell(&self, py: Python<'_>, values: Vec<f64>) -> PyResult<()> {
        let mut run = self.run.lock(py)?;
        let final_asked = matches!(&*run, Run::Paper(p) if p.final_asked);
        run.tell_values(&values).map_err(|e| match e {
            Error::NonFiniteValue { .. } if final_asked => PyValueError::new_err(format!(
                "{e}: tell finite values (the final evaluation must be finite)"
            )),
            e => value_error(e),
        })
    }

    /// Whether the run has ended.
    #[getter]
    fn done(&self, py: Python<'_>) -> PyResult<bool> {
        Ok(self.run.lock(py)?.is_done())
    }

    /// Whether the asked point is the paper loop's final evaluation (its value is
    /// `result.fun`, and must be finite).
    #[getter]
    fn final_asked(&self, py: Python<'_>) -> PyResult<bool> {
        Ok(matches!(&*self.run.lock(py)?, Run::Paper(p) if p.final_asked))
    }

    /// Iterations completed: generations of the adaptive search, steps of the paper's loop.
    #[getter]
    fn nit(&self, py: Python<'_>) -> PyResult<usize> {
        Ok(self.run.lock(py)?.iteration())
    }

    /// Evaluations told so far.
    #[getter]
    fn nfev(&self, py: Python<'_>) -> PyResult<usize> {
        Ok(self.run.lock(py)?.evaluations())
    }

    /// `(x, fun)`: the best point told so far and its value (the adaptive search), or None.
    fn best<'py>(&self, py: Python<'py>) -> PyResult<Option<(Bound<'py, PyAny>, f64)>> {
        best_of(py, &*self.run.lock(py)?, &self.shape)
    }

    /// The adaptive search's overall spread now (NaN for the paper's loop).
    fn sigma(&self, py: Python<'_>) -> PyResult<f64> {
        Ok(match &*self.run.lock(py)? {
            Run::Adaptive(run) => run.sigma(),
            Run::Paper(_) => f64::NAN,
        })
    }

    /// The paper loop's last iteration: `(iterations done, x, sigma, mean value, gradient,
    /// evaluations)`; None before the first and for the adaptive search.
    fn last_step<'py>(&self, py: Python<'py>) -> PyResult<Option<Step<'py>>> {
        last_step_of(py, &*self.run.lock(py)?, &self.shape)
    }

    /// The paper loop's raw results so far, as [`PyAskTell::result`] gives them at the end
    /// (the run need not have ended); None for the adaptive search.
    fn partial<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        match &*self.run.lock(py)? {
            Run::Paper(p) => Ok(Some(paper_dict(py, p, &self.shape)?)),
            Run::Adaptive(_) => Ok(None),
        }
    }

    /// The raw results of the ended run (the dict that `_minimize_adaptive` or `_minimize`
    /// returns, plus the paper loop's final value), or None before the end.
    fn result<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let out = PyDict::new(py);
        match &*self.run.lock(py)? {
            Run::Adaptive(run) => {
                let Some(best) = run.result() else {
                    return Ok(None);
                };
                minimum_dict(py, &out, best.clone(), &self.shape)?;
            }
            Run::Paper(p) => {
                if !p.is_done() {
                    return Ok(None);
                }
                return Ok(Some(paper_dict(py, p, &self.shape)?));
            }
        }
        Ok(Some(out))
    }
}

/// The paper loop's optimiser for `_AskTell`: its records are `Record`'s (of `keep`
/// iterations), so the library's own history keeps the last iteration alone.
fn paper_optimizer(
    py: Python<'_>,
    adam: &PyAdam,
    annealer: &PyAnnealer,
    iterations: usize,
) -> PyResult<Optimizer> {
    Ok(Optimizer::new(adam.inner.lock(py)?.clone(), annealer.inner)
        .record_theta(false)
        .keep_history(HistoryKeep::Last(1))
        .iterations(iterations))
}

/// What a paper loop's run does around the loop: its seed (of the final evaluation), the
/// records it keeps, whether `fun` is evaluated once more at the end.
struct Ends {
    seed: u64,
    record_x: bool,
    keep: usize,
    final_evaluation: bool,
}

impl Ends {
    fn new(seed: u64, record_x: bool, final_evaluation: bool, keep: Option<usize>) -> Ends {
        Ends {
            seed,
            record_x,
            keep: keep.unwrap_or(HistoryKeep::DEFAULT_LAST),
            final_evaluation,
        }
    }
}

impl PyAskTell {
    fn paper_run(run: Loop, ends: Ends, shape: Vec<usize>) -> PyAskTell {
        PyAskTell {
            run: Guarded::new(Run::Paper(Box::new(Paper {
                run,
                seed: ends.seed,
                record_x: ends.record_x,
                keep: ends.keep,
                final_evaluation: ends.final_evaluation,
                record: Record::default(),
                final_asked: false,
                final_value: None,
                final_point: Vec::new(),
                final_seed: [ends.seed],
            }))),
            shape,
        }
    }
}

/// `(x, fun)`: the adaptive search's best point so far and its value; None before any
/// value and for the paper's loop.
pub(crate) fn best_of<'py>(
    py: Python<'py>,
    run: &Run,
    shape: &[usize],
) -> PyResult<Option<(Bound<'py, PyAny>, f64)>> {
    match run {
        Run::Adaptive(run) => match run.best() {
            Some((x, fun)) => Ok(Some((array_like(py, x.to_vec(), shape)?, fun))),
            None => Ok(None),
        },
        Run::Paper(_) => Ok(None),
    }
}

/// The paper loop's last iteration: `(iterations done, x, sigma, mean value, gradient,
/// evaluations)`.
pub(crate) type Step<'py> = (usize, Bound<'py, PyAny>, f64, f64, Bound<'py, PyAny>, usize);

/// The paper loop's last iteration; None before the first and for the adaptive search.
pub(crate) fn last_step_of<'py>(
    py: Python<'py>,
    run: &Run,
    shape: &[usize],
) -> PyResult<Option<Step<'py>>> {
    let Run::Paper(p) = run else {
        return Ok(None);
    };
    let (Some(&sigma), Some(estimate)) = (p.run.history().sigma.last(), p.run.last_estimate())
    else {
        return Ok(None);
    };
    Ok(Some((
        p.run.iteration(),
        array_like(py, p.run.theta().to_vec(), shape)?,
        sigma,
        estimate.mean_value,
        array_like(py, estimate.gradient.clone(), shape)?,
        p.run.history().evaluations,
    )))
}

/// The paper loop's raw results: `x`, `nit`, `nfev`, the final value and the records.
fn paper_dict<'py>(py: Python<'py>, p: &Paper, shape: &[usize]) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    out.set_item("x", array_like(py, p.run.theta().to_vec(), shape)?)?;
    out.set_item("nit", p.run.iteration())?;
    out.set_item("nfev", p.run.history().evaluations)?;
    out.set_item("final_value", p.final_value)?;
    let mut record = p.record.clone();
    record.trim(p.keep);
    record.into_dict(py, &out, shape, p.record_x)?;
    Ok(out)
}

/// `on_failure` for the paper loop's estimator: `'continue'` redraws an estimate with a
/// failed point (up to [`FAILURE_REDRAWS`] times), `'raise'` ends the run.
fn estimate_on_failure(policy: &str) -> PyResult<plateau_free::estimator::OnFailure> {
    match policy {
        "continue" => Ok(plateau_free::estimator::OnFailure::Resample {
            limit: FAILURE_REDRAWS,
        }),
        "raise" => Ok(plateau_free::estimator::OnFailure::Fail),
        _ => Err(PyValueError::new_err(format!(
            "on_failure = '{policy}' is not a policy: use 'continue' or 'raise'"
        ))),
    }
}

/// The redraws of one estimate that the paper's loop makes under `on_failure='continue'`:
/// as many as `method='polished'`'s loop makes.
const FAILURE_REDRAWS: usize = 10;
