//! Python bindings of `plateau`: the extension module `plateau._plateau`, re-exported (with
//! `minimize`, `Sampling` and the result types) by the Python package `plateau`
//! (`python/plateau/__init__.py`).
//!
//! How a Python objective runs: every estimate is computed with the GIL released
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
    Adam as RsAdam, Annealer as RsAnnealer, Error, GradientEstimator, Objective, Optimizer,
    PlateauFreeGradient as RsPlateauFreeGradient, Points, Sampling, Schedule,
};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyFloat, PyInt};

// ---------------------------------------------------------------------------------------------
// The objective: a Python callable seen from Rust.

/// What an objective shares with the Python object that owns its estimator: the first
/// exception raised by `fun`, the count of evaluations, and the shape of `x`.
#[derive(Default)]
struct Shared {
    failed: AtomicBool,
    error: Mutex<Option<PyErr>>,
    evaluations: AtomicU64,
    /// The shape of the current `x` when it is not one-dimensional: points are handed to `fun`
    /// in that shape.
    shape: Mutex<Option<Vec<usize>>>,
    reshape: AtomicBool,
}

impl Shared {
    fn fail(&self, err: PyErr) {
        let mut slot = self.error.lock().unwrap_or_else(|p| p.into_inner());
        if slot.is_none() {
            *slot = Some(err);
        }
        self.failed.store(true, Ordering::Release);
    }

    fn failed(&self) -> bool {
        self.failed.load(Ordering::Acquire)
    }

    /// The stored exception, if any; clears it so that the estimator stays usable.
    fn take(&self) -> Option<PyErr> {
        if !self.failed() {
            return None;
        }
        self.failed.store(false, Ordering::Release);
        self.error.lock().unwrap_or_else(|p| p.into_inner()).take()
    }

    fn set_shape(&self, shape: &[usize]) {
        let reshape = shape.len() != 1;
        *self.shape.lock().unwrap_or_else(|p| p.into_inner()) = reshape.then(|| shape.to_vec());
        self.reshape.store(reshape, Ordering::Release);
    }

    /// The shape of one point, if it is not flat.
    fn point_shape(&self) -> Option<Vec<usize>> {
        if self.reshape.load(Ordering::Acquire) {
            self.shape.lock().unwrap_or_else(|p| p.into_inner()).clone()
        } else {
            None
        }
    }

    /// The Rust call's result, unless `fun` raised: then its exception.
    fn finish<T>(&self, result: Result<T, Error>) -> PyResult<T> {
        if let Some(err) = self.take() {
            return Err(err);
        }
        result.map_err(value_error)
    }
}

fn value_error(e: Error) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// A Python callable as a [`plateau::Objective`].
struct PyObjective {
    fun: Py<PyAny>,
    batched: bool,
    seeded: bool,
    shared: Arc<Shared>,
}

impl PyObjective {
    fn new(fun: Py<PyAny>, batched: bool, seeded: bool) -> Self {
        PyObjective {
            fun,
            batched,
            seeded,
            shared: Arc::new(Shared::default()),
        }
    }

    /// One point as a fresh numpy array shaped like `x`.
    fn point<'py>(&self, py: Python<'py>, point: &[f64]) -> PyResult<Bound<'py, PyAny>> {
        let array = PyArray1::from_slice(py, point);
        match self.shared.point_shape() {
            Some(shape) => Ok(array.reshape(shape)?.into_any()),
            None => Ok(array.into_any()),
        }
    }

    /// All points as one fresh `(N, *x.shape)` array: one copy of the whole buffer.
    fn points<'py>(&self, py: Python<'py>, points: Points<'_>) -> PyResult<Bound<'py, PyAny>> {
        let array = PyArray1::from_slice(py, points.as_flat());
        let mut shape = vec![points.len()];
        match self.shared.point_shape() {
            Some(s) => shape.extend(s),
            None => shape.push(points.dim()),
        }
        Ok(array.reshape(shape)?.into_any())
    }

    fn call_one(&self, py: Python<'_>, point: &[f64], seed: u64) -> PyResult<f64> {
        py.check_signals()?;
        self.shared.evaluations.fetch_add(1, Ordering::Relaxed);
        let fun = self.fun.bind(py);
        let x = self.point(py, point)?;
        let value = if self.seeded {
            fun.call1((x, seed))?
        } else {
            fun.call1((x,))?
        };
        to_f64(&value)
    }

    fn call_batch(
        &self,
        py: Python<'_>,
        points: Points<'_>,
        seeds: &[u64],
        out: &mut [f64],
    ) -> PyResult<()> {
        py.check_signals()?;
        self.shared
            .evaluations
            .fetch_add(points.len() as u64, Ordering::Relaxed);
        let fun = self.fun.bind(py);
        let x = self.points(py, points)?;
        let values = if self.seeded {
            fun.call1((x, PyArray1::from_slice(py, seeds)))?
        } else {
            fun.call1((x,))?
        };
        read_values(py, &values, out)
    }
}

/// A value returned by `fun` as a float: Python floats, ints, numpy scalars, anything with
/// `__float__`.
fn to_f64(value: &Bound<'_, PyAny>) -> PyResult<f64> {
    if let Ok(f) = value.cast_exact::<PyFloat>() {
        return Ok(f.value());
    }
    value.extract::<f64>().map_err(|e| {
        let kind = value
            .get_type()
            .name()
            .map(|n| n.to_string())
            .unwrap_or_else(|_| "?".into());
        let err = PyTypeError::new_err(format!(
            "fun must return a real number, it returned {kind}: {}",
            short_repr(value)
        ));
        err.set_cause(value.py(), Some(e));
        err
    })
}

fn short_repr(value: &Bound<'_, PyAny>) -> String {
    let text = value
        .repr()
        .map(|r| r.to_string())
        .unwrap_or_else(|_| "<no repr>".into());
    if text.chars().count() > 80 {
        let cut: String = text.chars().take(77).collect();
        format!("{cut}...")
    } else {
        text
    }
}

/// The `N` values a batched `fun` returned, into `out`.
fn read_values(py: Python<'_>, values: &Bound<'_, PyAny>, out: &mut [f64]) -> PyResult<()> {
    let wrong_length = |shape: &[usize]| {
        PyValueError::new_err(format!(
            "batched fun must return {} values (one per row of its argument), it returned an array of shape {:?}",
            out.len(),
            shape
        ))
    };
    // The usual case: a contiguous float64 vector, read in one copy.
    if let Ok(array) = values.cast::<PyArray1<f64>>() {
        if let Ok(readonly) = array.try_readonly() {
            if let Ok(slice) = readonly.as_slice() {
                if slice.len() != out.len() {
                    return Err(wrong_length(&[slice.len()]));
                }
                out.copy_from_slice(slice);
                return Ok(());
            }
        }
    }
    let numpy = py.import("numpy")?;
    let converted = numpy
        .call_method1("ascontiguousarray", (values, "float64"))
        .map_err(|e| {
            let err = PyTypeError::new_err(format!(
                "batched fun must return {} real numbers, it returned {}",
                out.len(),
                short_repr(values)
            ));
            err.set_cause(py, Some(e));
            err
        })?;
    let untyped = converted.cast::<PyUntypedArray>()?;
    if untyped.ndim() != 1 || untyped.len() != out.len() {
        return Err(wrong_length(untyped.shape()));
    }
    let array = converted.cast::<PyArray1<f64>>()?;
    out.copy_from_slice(array.readonly().as_slice()?);
    Ok(())
}

impl Objective for PyObjective {
    fn evaluate(&self, point: &[f64], seed: u64) -> f64 {
        if self.shared.failed() {
            return f64::NAN;
        }
        Python::attach(|py| {
            let result = if self.batched {
                let mut out = [0.0];
                self.call_batch(py, Points::new(point, point.len()), &[seed], &mut out)
                    .map(|()| out[0])
            } else {
                self.call_one(py, point, seed)
            };
            result.unwrap_or_else(|e| {
                self.shared.fail(e);
                f64::NAN
            })
        })
    }

    fn evaluate_batch(&self, points: Points<'_>, seeds: &[u64], out: &mut [f64]) {
        if self.batched {
            if self.shared.failed() {
                out.fill(f64::NAN);
                return;
            }
            Python::attach(|py| {
                if let Err(e) = self.call_batch(py, points, seeds, out) {
                    self.shared.fail(e);
                    out.fill(f64::NAN);
                }
            });
            return;
        }
        for (i, o) in out.iter_mut().enumerate() {
            if self.shared.failed() {
                *o = f64::NAN;
                continue;
            }
            *o = self.evaluate(points.get(i), seeds[i]);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Conversions.

/// `x` as a flat vector and its shape; ValueError naming `name` for an empty or non-finite `x`.
fn to_vector(py: Python<'_>, x: &Bound<'_, PyAny>, name: &str) -> PyResult<(Vec<f64>, Vec<usize>)> {
    let numpy = py.import("numpy")?;
    let array = numpy.call_method1("asarray", (x, "float64"))?;
    let shape = array.cast::<PyUntypedArray>()?.shape().to_vec();
    // `ascontiguousarray` makes a 0-d array 1-d: the shape is taken before.
    let array = numpy.call_method1("ascontiguousarray", (array,))?;
    let values = array.cast::<PyArrayDyn<f64>>()?.to_vec()?;
    if values.is_empty() {
        return Err(PyValueError::new_err(format!(
            "{name} is empty (shape {shape:?}): the objective needs at least one parameter"
        )));
    }
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        let at = if shape.len() == 1 {
            format!("{name}[{i}]")
        } else {
            format!("{name}.flat[{i}]")
        };
        return Err(PyValueError::new_err(format!(
            "{at} = {} is not finite",
            py_float(values[i])
        )));
    }
    Ok((values, shape))
}

/// A spread: one number, or one per coordinate.
enum Spread {
    Scalar(f64),
    PerCoordinate(Vec<f64>),
}

fn to_spread(py: Python<'_>, sigma: &Bound<'_, PyAny>) -> PyResult<Spread> {
    if sigma.is_instance_of::<PyFloat>() || sigma.is_instance_of::<PyInt>() {
        return Ok(Spread::Scalar(sigma.extract()?));
    }
    let numpy = py.import("numpy")?;
    let array = numpy.call_method1("asarray", (sigma, "float64"))?;
    if array.cast::<PyUntypedArray>()?.ndim() == 0 {
        return Ok(Spread::Scalar(array.extract()?));
    }
    let array = numpy.call_method1("ascontiguousarray", (array,))?;
    Ok(Spread::PerCoordinate(
        array.cast::<PyArrayDyn<f64>>()?.to_vec()?,
    ))
}

fn parse_sampling(name: &str) -> PyResult<Sampling> {
    match name.to_ascii_lowercase().replace(['-', ' '], "_").as_str() {
        "radial" => Ok(Sampling::Radial),
        "per_coordinate" | "percoordinate" => Ok(Sampling::PerCoordinate),
        "gaussian" => Ok(Sampling::Gaussian),
        _ => Err(PyValueError::new_err(format!(
            "sampling = '{name}' is not a sampler: use 'radial', 'per_coordinate' or 'gaussian'"
        ))),
    }
}

fn sampling_name(sampling: Sampling) -> &'static str {
    match sampling {
        Sampling::Radial => "radial",
        Sampling::PerCoordinate => "per_coordinate",
        Sampling::Gaussian => "gaussian",
    }
}

fn array_like<'py>(
    py: Python<'py>,
    values: Vec<f64>,
    shape: &[usize],
) -> PyResult<Bound<'py, PyAny>> {
    let array = values.into_pyarray(py);
    if shape.len() == 1 {
        Ok(array.into_any())
    } else {
        Ok(array.reshape(shape.to_vec())?.into_any())
    }
}

/// A float as Python prints it: `nan`, `inf`, `-inf`, `0.5`, `1.0`.
fn py_float(v: f64) -> String {
    if v.is_nan() {
        "nan".into()
    } else if v.is_infinite() {
        if v > 0.0 { "inf" } else { "-inf" }.into()
    } else {
        format!("{v:?}")
    }
}

fn py_bool(b: bool) -> &'static str {
    if b {
        "True"
    } else {
        "False"
    }
}

// ---------------------------------------------------------------------------------------------
// The estimators.

/// The plateau-free gradient of `fun`: the gradient of `fun` smoothed by a Gaussian of spread
/// `sigma` in parameter space, estimated from `samples` evaluations of `fun` per estimate.
///
/// fun: `fun(x) -> float`, `x` a float64 array shaped like the `x` of `estimate`. With
///     `seeded=True`, `fun(x, seed)`: both members of an antithetic pair get the same seed
///     (common random numbers for a noisy renderer). With `batched=True`, `fun(X) -> N values`
///     once per estimate, `X` of shape `(N, *x.shape)`; both: `fun(X, seeds)`, `seeds` a uint64
///     array of length N.
/// samples: evaluations of `fun` per estimate (even with antithetic pairs).
/// sampling: 'radial' (default; exact in every dimension), 'per_coordinate' (the paper's;
///     biased for non-separable fun), 'gaussian' (plain evolution strategies).
/// antithetic: pair every perturbation with its opposite.
/// seed: estimate `e` draws from `(seed, e)` alone: the numbers of the Rust API.
/// orthogonal: mutually orthogonal directions within one estimate ('radial', 'gaussian').
/// parallel: evaluate the points of one estimate on several threads (for a `fun` that releases
///     the GIL); the results are those of the sequential run.
///
/// The estimate runs in Rust with the GIL released; an exception raised by `fun` stops it and
/// comes out of `estimate` unchanged.
#[pyclass(module = "plateau", name = "PlateauFreeGradient")]
struct PyPlateauFreeGradient {
    inner: RsPlateauFreeGradient<PyObjective>,
    shared: Arc<Shared>,
    fun: Py<PyAny>,
    samples: usize,
    sampling: Sampling,
    antithetic: bool,
    seed: u64,
    batched: bool,
    seeded: bool,
    orthogonal: bool,
    parallel: bool,
}

#[pymethods]
impl PyPlateauFreeGradient {
    #[new]
    #[pyo3(signature = (fun, samples=2, sampling="radial", antithetic=true, seed=0, batched=false, seeded=false, orthogonal=false, parallel=false))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        fun: Py<PyAny>,
        samples: usize,
        sampling: &str,
        antithetic: bool,
        seed: u64,
        batched: bool,
        seeded: bool,
        orthogonal: bool,
        parallel: bool,
    ) -> PyResult<Self> {
        if !fun.bind(py).is_callable() {
            return Err(PyTypeError::new_err(format!(
                "fun must be callable, got {}",
                short_repr(fun.bind(py))
            )));
        }
        let sampling = parse_sampling(sampling)?;
        if samples == 0 {
            return Err(value_error(Error::ZeroSamples));
        }
        if antithetic && samples % 2 == 1 {
            return Err(PyValueError::new_err(format!(
                "samples = {samples}: antithetic pairs need an even number of samples; use an even count or antithetic=False"
            )));
        }
        if orthogonal && sampling == Sampling::PerCoordinate {
            return Err(value_error(Error::OrthogonalUnsupported(sampling)));
        }
        let objective = PyObjective::new(fun.clone_ref(py), batched, seeded);
        let shared = objective.shared.clone();
        let inner = RsPlateauFreeGradient::new(objective)
            .samples(samples)
            .sampling(sampling)
            .antithetic(antithetic)
            .orthogonal(orthogonal)
            .seed(seed)
            .parallel(parallel);
        Ok(PyPlateauFreeGradient {
            inner,
            shared,
            fun,
            samples,
            sampling,
            antithetic,
            seed,
            batched,
            seeded,
            orthogonal,
            parallel,
        })
    }

    /// The gradient of `fun` smoothed by N(0, sigma^2 I) at `x`, as a float64 array shaped like
    /// `x`. `sigma` is a positive float, or an array of per-coordinate spreads (one per element
    /// of `x`).
    fn estimate<'py>(
        &mut self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
        sigma: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let (theta, shape) = to_vector(py, x, "x")?;
        let spread = to_spread(py, sigma)?;
        self.shared.set_shape(&shape);
        let inner = &mut self.inner;
        let result = py.detach(|| match &spread {
            Spread::Scalar(s) => inner.estimate(&theta, *s),
            Spread::PerCoordinate(s) => inner.estimate_with_spreads(&theta, s),
        });
        let estimate = self.shared.finish(result)?;
        array_like(py, estimate.gradient, &shape)
    }

    /// Restarts the count of estimates: the next estimate repeats the first one's draws.
    fn reset(&mut self) {
        self.inner.reset();
    }

    /// The objective.
    #[getter]
    fn fun(&self, py: Python<'_>) -> Py<PyAny> {
        self.fun.clone_ref(py)
    }
    /// Evaluations of `fun` per estimate.
    #[getter]
    fn samples(&self) -> usize {
        self.samples
    }
    /// The sampler: 'radial', 'per_coordinate' or 'gaussian'.
    #[getter]
    fn sampling(&self) -> &'static str {
        sampling_name(self.sampling)
    }
    /// Whether perturbations come in antithetic pairs.
    #[getter]
    fn antithetic(&self) -> bool {
        self.antithetic
    }
    /// The seed.
    #[getter]
    fn seed(&self) -> u64 {
        self.seed
    }
    /// Whether `fun` takes a whole batch.
    #[getter]
    fn batched(&self) -> bool {
        self.batched
    }
    /// Whether `fun` takes a seed.
    #[getter]
    fn seeded(&self) -> bool {
        self.seeded
    }
    /// Whether the directions of one estimate are orthogonal.
    #[getter]
    fn orthogonal(&self) -> bool {
        self.orthogonal
    }
    /// Whether the evaluations of one estimate run on several threads.
    #[getter]
    fn parallel(&self) -> bool {
        self.parallel
    }
    /// Estimates made since construction or the last `reset()`.
    #[getter]
    fn estimates(&self) -> u64 {
        self.inner.estimates_made()
    }
    /// Evaluations of `fun` since construction.
    #[getter]
    fn nfev(&self) -> u64 {
        self.shared.evaluations.load(Ordering::Relaxed)
    }

    fn __repr__(&self) -> String {
        format!(
            "PlateauFreeGradient(samples={}, sampling='{}', antithetic={}, seed={}, batched={}, seeded={}, orthogonal={}, parallel={})",
            self.samples,
            sampling_name(self.sampling),
            py_bool(self.antithetic),
            self.seed,
            py_bool(self.batched),
            py_bool(self.seeded),
            py_bool(self.orthogonal),
            py_bool(self.parallel),
        )
    }
}

/// Central finite differences with a fixed step: the unsmoothed gradient (zero on a plateau).
#[pyclass(module = "plateau", name = "FiniteDifference")]
struct PyFiniteDifference {
    inner: RsFiniteDifference<PyObjective>,
    shared: Arc<Shared>,
    step: f64,
    seed: u64,
}

#[pymethods]
impl PyFiniteDifference {
    #[new]
    #[pyo3(signature = (fun, step=1e-3, seed=0, batched=false, seeded=false))]
    fn new(
        py: Python<'_>,
        fun: Py<PyAny>,
        step: f64,
        seed: u64,
        batched: bool,
        seeded: bool,
    ) -> PyResult<Self> {
        if !fun.bind(py).is_callable() {
            return Err(PyTypeError::new_err("fun must be callable"));
        }
        let objective = PyObjective::new(fun, batched, seeded);
        let shared = objective.shared.clone();
        let inner = RsFiniteDifference::new(objective, step)
            .map_err(value_error)?
            .seed(seed);
        Ok(PyFiniteDifference {
            inner,
            shared,
            step,
            seed,
        })
    }

    /// `(f(x + h e_i) - f(x - h e_i)) / 2h` for every coordinate: `2 n` evaluations. `sigma` is
    /// accepted for symmetry with the other estimators and ignored.
    #[pyo3(signature = (x, sigma=None))]
    fn estimate<'py>(
        &mut self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
        sigma: Option<f64>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let _ = sigma;
        let (theta, shape) = to_vector(py, x, "x")?;
        self.shared.set_shape(&shape);
        let inner = &mut self.inner;
        let result = py.detach(|| inner.estimate(&theta, 1.0));
        let estimate = self.shared.finish(result)?;
        array_like(py, estimate.gradient, &shape)
    }

    /// The step h.
    #[getter]
    fn step(&self) -> f64 {
        self.step
    }
    /// The seed handed to a seeded `fun`.
    #[getter]
    fn seed(&self) -> u64 {
        self.seed
    }
    /// Evaluations of `fun` since construction.
    #[getter]
    fn nfev(&self) -> u64 {
        self.shared.evaluations.load(Ordering::Relaxed)
    }

    fn __repr__(&self) -> String {
        format!("FiniteDifference(step={:?}, seed={})", self.step, self.seed)
    }
}

/// SPSA: one Rademacher direction per estimate, 2 evaluations whatever the dimension.
#[pyclass(module = "plateau", name = "Spsa")]
struct PySpsa {
    inner: RsSpsa<PyObjective>,
    shared: Arc<Shared>,
    seed: u64,
}

#[pymethods]
impl PySpsa {
    #[new]
    #[pyo3(signature = (fun, seed=0, batched=false, seeded=false))]
    fn new(
        py: Python<'_>,
        fun: Py<PyAny>,
        seed: u64,
        batched: bool,
        seeded: bool,
    ) -> PyResult<Self> {
        if !fun.bind(py).is_callable() {
            return Err(PyTypeError::new_err("fun must be callable"));
        }
        let objective = PyObjective::new(fun, batched, seeded);
        let shared = objective.shared.clone();
        Ok(PySpsa {
            inner: RsSpsa::new(objective).seed(seed),
            shared,
            seed,
        })
    }

    /// `g_i = (f(x + c d) - f(x - c d)) / (2 c d_i)` with `c = sigma`.
    fn estimate<'py>(
        &mut self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
        sigma: f64,
    ) -> PyResult<Bound<'py, PyAny>> {
        let (theta, shape) = to_vector(py, x, "x")?;
        self.shared.set_shape(&shape);
        let inner = &mut self.inner;
        let result = py.detach(|| inner.estimate(&theta, sigma));
        let estimate = self.shared.finish(result)?;
        array_like(py, estimate.gradient, &shape)
    }

    /// The seed.
    #[getter]
    fn seed(&self) -> u64 {
        self.seed
    }
    /// Evaluations of `fun` since construction.
    #[getter]
    fn nfev(&self) -> u64 {
        self.shared.evaluations.load(Ordering::Relaxed)
    }

    fn __repr__(&self) -> String {
        format!("Spsa(seed={})", self.seed)
    }
}

// ---------------------------------------------------------------------------------------------
// Annealer and Adam.

/// The spread sigma as a function of the iteration.
#[pyclass(module = "plateau", name = "Annealer", frozen)]
#[derive(Clone)]
struct PyAnnealer {
    inner: RsAnnealer,
}

fn schedule_name(schedule: Schedule) -> &'static str {
    match schedule {
        Schedule::Constant => "constant",
        Schedule::WarmLinear { .. } => "paper",
        Schedule::Exponential => "exponential",
        Schedule::Cosine => "cosine",
    }
}

#[pymethods]
impl PyAnnealer {
    /// A schedule of any shape: 'paper' (warm start for `warmup` of the run, then linear),
    /// 'constant', 'exponential' or 'cosine'.
    #[new]
    #[pyo3(signature = (schedule="paper", sigma0=0.5, sigma_min=0.01, iterations=400, warmup=0.5))]
    fn new(
        schedule: &str,
        sigma0: f64,
        sigma_min: f64,
        iterations: usize,
        warmup: f64,
    ) -> PyResult<Self> {
        let shape = match schedule.to_ascii_lowercase().as_str() {
            "paper" | "warm_linear" | "warmlinear" => Schedule::WarmLinear { warmup },
            "constant" => Schedule::Constant,
            "exponential" => Schedule::Exponential,
            "cosine" => Schedule::Cosine,
            _ => {
                return Err(PyValueError::new_err(format!(
                    "annealer = '{schedule}' is not a schedule: use 'paper', 'constant', 'exponential' or 'cosine'"
                )))
            }
        };
        let sigma_min = if shape == Schedule::Constant {
            sigma0
        } else {
            sigma_min
        };
        Ok(PyAnnealer {
            inner: RsAnnealer::new(shape, sigma0, sigma_min, iterations).map_err(value_error)?,
        })
    }

    /// The paper's schedule: `sigma0` for half the run, then linear to 0.01 at the last
    /// iteration.
    #[staticmethod]
    #[pyo3(signature = (sigma0=0.5, iterations=400))]
    fn paper(sigma0: f64, iterations: usize) -> PyResult<Self> {
        Ok(PyAnnealer {
            inner: RsAnnealer::paper(sigma0, iterations).map_err(value_error)?,
        })
    }

    /// A constant spread.
    #[staticmethod]
    #[pyo3(signature = (sigma=0.5, iterations=400))]
    fn constant(sigma: f64, iterations: usize) -> PyResult<Self> {
        Ok(PyAnnealer {
            inner: RsAnnealer::constant(sigma, iterations).map_err(value_error)?,
        })
    }

    /// Geometric decay from `sigma0` to `sigma_min`.
    #[staticmethod]
    #[pyo3(signature = (sigma0=0.5, sigma_min=0.01, iterations=400))]
    fn exponential(sigma0: f64, sigma_min: f64, iterations: usize) -> PyResult<Self> {
        Ok(PyAnnealer {
            inner: RsAnnealer::exponential(sigma0, sigma_min, iterations).map_err(value_error)?,
        })
    }

    /// Half a cosine from `sigma0` down to `sigma_min`.
    #[staticmethod]
    #[pyo3(signature = (sigma0=0.5, sigma_min=0.01, iterations=400))]
    fn cosine(sigma0: f64, sigma_min: f64, iterations: usize) -> PyResult<Self> {
        Ok(PyAnnealer {
            inner: RsAnnealer::cosine(sigma0, sigma_min, iterations).map_err(value_error)?,
        })
    }

    /// Sigma at `iteration` (counted from 0; past the end, the final value).
    fn sigma(&self, iteration: usize) -> f64 {
        self.inner.sigma(iteration)
    }

    /// Sigma at every iteration of the run, as an array.
    fn sigmas<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        (0..self.inner.iterations())
            .map(|i| self.inner.sigma(i))
            .collect::<Vec<_>>()
            .into_pyarray(py)
    }

    /// The spread at the start.
    #[getter]
    fn sigma0(&self) -> f64 {
        self.inner.sigma0()
    }
    /// The floor.
    #[getter]
    fn sigma_min(&self) -> f64 {
        self.inner.sigma_min()
    }
    /// The length of the run the schedule spans.
    #[getter]
    fn iterations(&self) -> usize {
        self.inner.iterations()
    }
    /// 'paper', 'constant', 'exponential' or 'cosine'.
    #[getter]
    fn schedule(&self) -> &'static str {
        schedule_name(self.inner.schedule())
    }
    /// The warm-start fraction of the paper's schedule (None for the others).
    #[getter]
    fn warmup(&self) -> Option<f64> {
        match self.inner.schedule() {
            Schedule::WarmLinear { warmup } => Some(warmup),
            _ => None,
        }
    }

    fn __repr__(&self) -> String {
        format!(
            "Annealer(schedule='{}', sigma0={:?}, sigma_min={:?}, iterations={})",
            self.schedule(),
            self.inner.sigma0(),
            self.inner.sigma_min(),
            self.inner.iterations()
        )
    }
}

type ArrayPair<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>);

/// Adam with bias correction and optional box bounds (projection after every step).
#[pyclass(module = "plateau", name = "Adam")]
struct PyAdam {
    inner: RsAdam,
    bounds: Option<(Vec<f64>, Vec<f64>)>,
}

#[pymethods]
impl PyAdam {
    /// `bounds`: None, or `(lower, upper)`, two arrays as long as x (infinite entries allowed).
    #[new]
    #[pyo3(signature = (lr=0.02, beta1=0.9, beta2=0.999, epsilon=1e-8, bounds=None))]
    fn new(
        lr: f64,
        beta1: f64,
        beta2: f64,
        epsilon: f64,
        bounds: Option<(Vec<f64>, Vec<f64>)>,
    ) -> PyResult<Self> {
        let mut inner = RsAdam::new(lr)
            .and_then(|a| a.betas(beta1, beta2))
            .and_then(|a| a.epsilon(epsilon))
            .map_err(value_error)?;
        if let Some((lower, upper)) = &bounds {
            inner = inner
                .bounds(lower.clone(), upper.clone())
                .map_err(value_error)?;
        }
        Ok(PyAdam { inner, bounds })
    }

    /// One step downhill from `x` along `gradient`; returns the new x (a new array).
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
        gradient: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let (mut theta, shape) = to_vector(py, x, "x")?;
        let (g, _) = to_vector(py, gradient, "gradient")?;
        self.inner.step(&mut theta, &g).map_err(value_error)?;
        array_like(py, theta, &shape)
    }

    /// Forgets the moment estimates.
    fn reset(&mut self) {
        self.inner.reset();
    }

    /// The learning rate.
    #[getter]
    fn lr(&self) -> f64 {
        self.inner.lr()
    }
    /// Steps taken since construction or the last reset.
    #[getter]
    fn steps(&self) -> usize {
        self.inner.steps()
    }
    /// `(lower, upper)` or None.
    #[getter]
    fn bounds<'py>(&self, py: Python<'py>) -> Option<ArrayPair<'py>> {
        self.bounds
            .as_ref()
            .map(|(l, u)| (PyArray1::from_slice(py, l), PyArray1::from_slice(py, u)))
    }

    fn __repr__(&self) -> String {
        format!(
            "Adam(lr={:?}, bounds={})",
            self.inner.lr(),
            if self.bounds.is_some() {
                "(...)"
            } else {
                "None"
            }
        )
    }
}

// ---------------------------------------------------------------------------------------------
// The loop.

/// Per-iteration records of a run.
#[derive(Default)]
struct Record {
    sigma: Vec<f64>,
    grad_norm: Vec<f64>,
    value: Vec<f64>,
    nfev: Vec<u64>,
    x: Vec<f64>,
    stopped_by_callback: bool,
}

#[allow(clippy::too_many_arguments)]
fn run<G: GradientEstimator + Send + ?Sized>(
    py: Python<'_>,
    estimator: &mut G,
    shared: &Shared,
    theta: &[f64],
    shape: &[usize],
    mut optimizer: Optimizer,
    callback: Option<&Py<PyAny>>,
    record_x: bool,
) -> PyResult<(Vec<f64>, usize, usize, Record)> {
    shared.set_shape(shape);
    let mut record = Record::default();
    let callback_error: Mutex<Option<PyErr>> = Mutex::new(None);
    let result = py.detach(|| {
        let mut nfev = 0u64;
        optimizer.minimize_with(estimator, theta, |step| {
            let g = &step.estimate.gradient;
            nfev += step.estimate.evaluations as u64;
            record.sigma.push(step.sigma);
            record
                .grad_norm
                .push(g.iter().map(|v| v * v).sum::<f64>().sqrt());
            record.value.push(step.estimate.mean_value);
            record.nfev.push(nfev);
            if record_x {
                record.x.extend_from_slice(step.theta);
            }
            Python::attach(|py| {
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
            })
        })
    });
    if let Some(err) = callback_error
        .into_inner()
        .unwrap_or_else(|p| p.into_inner())
    {
        return Err(err);
    }
    let history = shared.finish(result)?;
    let x = history
        .last_theta()
        .map(<[f64]>::to_vec)
        .unwrap_or_else(|| theta.to_vec());
    Ok((x, history.iterations(), history.evaluations, record))
}

/// The optimisation loop behind `plateau.minimize`: `iterations` Adam steps along the
/// estimator's gradient with the annealer's sigma. `callback(iteration, x, sigma, value,
/// gradient, nfev)` runs after every iteration; a truthy return stops the run. Returns a dict
/// of raw results that `plateau.minimize` turns into an `OptimizeResult`.
#[pyfunction]
#[pyo3(signature = (estimator, x0, adam, annealer, iterations=None, callback=None, record_x=false))]
#[allow(clippy::too_many_arguments)]
fn _minimize<'py>(
    py: Python<'py>,
    estimator: &Bound<'py, PyAny>,
    x0: &Bound<'py, PyAny>,
    adam: PyRef<'py, PyAdam>,
    annealer: PyRef<'py, PyAnnealer>,
    iterations: Option<usize>,
    callback: Option<Py<PyAny>>,
    record_x: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let (theta, shape) = to_vector(py, x0, "x0")?;
    let mut optimizer = Optimizer::new(adam.inner.clone(), annealer.inner).record_theta(false);
    if let Some(iterations) = iterations {
        optimizer = optimizer.iterations(iterations);
    }
    let callback = callback.as_ref();
    let (x, nit, nfev, record) = if let Ok(est) = estimator.cast::<PyPlateauFreeGradient>() {
        let mut est = est.try_borrow_mut()?;
        let est = &mut *est;
        run(
            py,
            &mut est.inner,
            &est.shared,
            &theta,
            &shape,
            optimizer,
            callback,
            record_x,
        )?
    } else if let Ok(est) = estimator.cast::<PyFiniteDifference>() {
        let mut est = est.try_borrow_mut()?;
        let est = &mut *est;
        run(
            py,
            &mut est.inner,
            &est.shared,
            &theta,
            &shape,
            optimizer,
            callback,
            record_x,
        )?
    } else if let Ok(est) = estimator.cast::<PySpsa>() {
        let mut est = est.try_borrow_mut()?;
        let est = &mut *est;
        run(
            py,
            &mut est.inner,
            &est.shared,
            &theta,
            &shape,
            optimizer,
            callback,
            record_x,
        )?
    } else {
        return Err(PyTypeError::new_err(format!(
            "estimator must be a PlateauFreeGradient, FiniteDifference or Spsa, got {}",
            short_repr(estimator)
        )));
    };
    let out = PyDict::new(py);
    out.set_item("x", array_like(py, x, &shape)?)?;
    out.set_item("nit", nit)?;
    out.set_item("nfev", nfev)?;
    out.set_item("stopped_by_callback", record.stopped_by_callback)?;
    out.set_item("sigma", record.sigma.into_pyarray(py))?;
    out.set_item("grad_norm", record.grad_norm.into_pyarray(py))?;
    out.set_item("fun", record.value.into_pyarray(py))?;
    out.set_item("nfev_history", record.nfev.into_pyarray(py))?;
    if record_x {
        let mut full = vec![nit];
        full.extend(&shape);
        out.set_item("x_history", record.x.into_pyarray(py).reshape(full)?)?;
    }
    Ok(out)
}

// ---------------------------------------------------------------------------------------------
// Cross-language determinism: the same functions written in Rust, run through the Rust API.

/// A test function with a plateau and a step; the same arithmetic, in the same order, as
/// `bumpy` in `python/tests/test_determinism.py`.
fn bumpy(x: &[f64]) -> f64 {
    let mut total = 0.0;
    for (i, v) in x.iter().enumerate() {
        let d = v - 0.1 * i as f64;
        total += (i as f64 + 1.0) * d * d;
    }
    if x[0] + 2.0 * x[x.len() - 1] > 0.3 {
        total += 1.0;
    }
    total
}

fn bumpy_seeded(x: &[f64], seed: u64) -> f64 {
    bumpy(x) + (seed % 1000) as f64 * 1e-3
}

/// `count` gradient estimates of the reference function `bumpy` (or `bumpy(x) + (seed % 1000)
/// * 1e-3` when `seeded`) computed by the Rust API alone, one row each: the numbers the Python
/// binding must reproduce bit for bit.
#[pyfunction]
#[pyo3(signature = (x, sigma, samples=2, sampling="radial", antithetic=true, seed=0, count=1, seeded=false, orthogonal=false))]
#[allow(clippy::too_many_arguments)]
fn _rust_reference_estimates<'py>(
    py: Python<'py>,
    x: Vec<f64>,
    sigma: f64,
    samples: usize,
    sampling: &str,
    antithetic: bool,
    seed: u64,
    count: usize,
    seeded: bool,
    orthogonal: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let sampling = parse_sampling(sampling)?;
    let mut rows = Vec::with_capacity(count * x.len());
    macro_rules! estimates {
        ($objective:expr) => {{
            let mut g = RsPlateauFreeGradient::new($objective)
                .samples(samples)
                .sampling(sampling)
                .antithetic(antithetic)
                .orthogonal(orthogonal)
                .seed(seed);
            for _ in 0..count {
                rows.extend(g.estimate(&x, sigma).map_err(value_error)?.gradient);
            }
        }};
    }
    if seeded {
        estimates!(plateau::Seeded(bumpy_seeded));
    } else {
        estimates!(bumpy);
    }
    Ok(rows.into_pyarray(py).reshape([count, x.len()])?.into_any())
}

/// The final x of a Rust `Optimizer` run on `bumpy` (paper annealer, Adam): what
/// `plateau.minimize` must reproduce bit for bit.
#[pyfunction]
#[pyo3(signature = (x0, sigma0=0.5, iterations=50, lr=0.02, samples=2, seed=0))]
fn _rust_reference_minimize<'py>(
    py: Python<'py>,
    x0: Vec<f64>,
    sigma0: f64,
    iterations: usize,
    lr: f64,
    samples: usize,
    seed: u64,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let mut g = RsPlateauFreeGradient::new(bumpy)
        .samples(samples)
        .seed(seed);
    let adam = RsAdam::new(lr).map_err(value_error)?;
    let annealer = RsAnnealer::paper(sigma0, iterations).map_err(value_error)?;
    let history = Optimizer::new(adam, annealer)
        .minimize(&mut g, &x0)
        .map_err(value_error)?;
    Ok(PyArray1::from_slice(
        py,
        history.last_theta().unwrap_or(&x0),
    ))
}

/// Evaluations per second of a trivial Rust closure through the same estimator (for the
/// overhead benchmark's baseline): returns seconds per evaluation.
#[pyfunction]
#[pyo3(signature = (dim=10, samples=10_000, repeats=5))]
fn _rust_seconds_per_evaluation(
    py: Python<'_>,
    dim: usize,
    samples: usize,
    repeats: usize,
) -> PyResult<f64> {
    py.detach(|| {
        let mut g = RsPlateauFreeGradient::new(|x: &[f64]| x[0]).samples(samples);
        let x = vec![0.5; dim];
        let mut best = f64::INFINITY;
        for _ in 0..repeats.max(1) {
            let start = std::time::Instant::now();
            g.estimate(&x, 0.1).map_err(value_error)?;
            best = best.min(start.elapsed().as_secs_f64() / samples as f64);
        }
        Ok(best)
    })
}

/// The Rust extension of the Python package `plateau`; use `import plateau`.
#[pymodule]
fn _plateau(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyPlateauFreeGradient>()?;
    m.add_class::<PyFiniteDifference>()?;
    m.add_class::<PySpsa>()?;
    m.add_class::<PyAnnealer>()?;
    m.add_class::<PyAdam>()?;
    m.add_function(wrap_pyfunction!(_minimize, m)?)?;
    m.add_function(wrap_pyfunction!(_rust_reference_estimates, m)?)?;
    m.add_function(wrap_pyfunction!(_rust_reference_minimize, m)?)?;
    m.add_function(wrap_pyfunction!(_rust_seconds_per_evaluation, m)?)?;
    m.add("PAPER_SIGMA_MIN", plateau::PAPER_SIGMA_MIN)?;
    m.add("PAPER_WARMUP", plateau::PAPER_WARMUP)?;
    Ok(())
}
