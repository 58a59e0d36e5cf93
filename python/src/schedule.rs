//! Annealer and Adam.

use super::*;

/// The spread sigma as a function of the iteration.
#[pyclass(module = "plateau_free", name = "Annealer", frozen)]
#[derive(Clone)]
pub(crate) struct PyAnnealer {
    pub(crate) inner: RsAnnealer,
}

pub(crate) fn schedule_name(schedule: Schedule) -> &'static str {
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
    #[pyo3(signature = (schedule="paper".into(), sigma0=0.5, sigma_min=0.01, iterations=400, warmup=0.5),
        text_signature = "(schedule='paper', sigma0=0.5, sigma_min=0.01, iterations=400, warmup=0.5)")]
    pub(crate) fn new(
        #[pyo3(from_py_with = schedule_arg)] schedule: String,
        #[pyo3(from_py_with = sigma0_arg)] sigma0: f64,
        #[pyo3(from_py_with = sigma_min_arg)] sigma_min: f64,
        #[pyo3(from_py_with = iterations_arg)] iterations: usize,
        #[pyo3(from_py_with = warmup_arg)] warmup: f64,
    ) -> PyResult<Self> {
        let shape = match schedule.to_ascii_lowercase().as_str() {
            "paper" | "warm_linear" | "warmlinear" => Schedule::WarmLinear { warmup },
            "constant" => Schedule::Constant,
            "exponential" => Schedule::Exponential,
            "cosine" => Schedule::Cosine,
            _ => {
                return Err(PyValueError::new_err(format!(
                    "schedule = '{schedule}' is not a schedule: use 'paper', 'constant', 'exponential' or 'cosine'"
                )))
            }
        };
        let sigma_min = if shape == Schedule::Constant {
            // A constant schedule never reaches `sigma_min`; a bad value is still refused,
            // by the library's check.
            RsAnnealer::new(shape, sigma0, sigma_min, iterations).map_err(value_error)?;
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
    pub(crate) fn paper(
        #[pyo3(from_py_with = sigma0_arg)] sigma0: f64,
        #[pyo3(from_py_with = iterations_arg)] iterations: usize,
    ) -> PyResult<Self> {
        Ok(PyAnnealer {
            inner: RsAnnealer::paper(sigma0, iterations).map_err(value_error)?,
        })
    }

    /// A constant spread.
    #[staticmethod]
    #[pyo3(signature = (sigma=0.5, iterations=400))]
    pub(crate) fn constant(
        #[pyo3(from_py_with = sigma_arg)] sigma: f64,
        #[pyo3(from_py_with = iterations_arg)] iterations: usize,
    ) -> PyResult<Self> {
        Ok(PyAnnealer {
            inner: RsAnnealer::constant(sigma, iterations).map_err(value_error)?,
        })
    }

    /// Geometric decay from `sigma0` to `sigma_min`.
    #[staticmethod]
    #[pyo3(signature = (sigma0=0.5, sigma_min=0.01, iterations=400))]
    pub(crate) fn exponential(
        #[pyo3(from_py_with = sigma0_arg)] sigma0: f64,
        #[pyo3(from_py_with = sigma_min_arg)] sigma_min: f64,
        #[pyo3(from_py_with = iterations_arg)] iterations: usize,
    ) -> PyResult<Self> {
        Ok(PyAnnealer {
            inner: RsAnnealer::exponential(sigma0, sigma_min, iterations).map_err(value_error)?,
        })
    }

    /// Half a cosine from `sigma0` down to `sigma_min`.
    #[staticmethod]
    #[pyo3(signature = (sigma0=0.5, sigma_min=0.01, iterations=400))]
    pub(crate) fn cosine(
        #[pyo3(from_py_with = sigma0_arg)] sigma0: f64,
        #[pyo3(from_py_with = sigma_min_arg)] sigma_min: f64,
        #[pyo3(from_py_with = iterations_arg)] iterations: usize,
    ) -> PyResult<Self> {
        Ok(PyAnnealer {
            inner: RsAnnealer::cosine(sigma0, sigma_min, iterations).map_err(value_error)?,
        })
    }

    /// Sigma at `iteration` (counted from 0; past the end, the final value).
    pub(crate) fn sigma(&self, #[pyo3(from_py_with = iteration_arg)] iteration: usize) -> f64 {
        self.inner.sigma(iteration)
    }

    /// Sigma at every iteration of the run, as an array.
    pub(crate) fn sigmas<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let iterations = self.inner.iterations();
        let mut sigmas = Vec::new();
        // Reserved first: a schedule too long for memory is an error, not an abort.
        sigmas.try_reserve_exact(iterations).map_err(|_| {
            PyValueError::new_err(format!(
                "iterations = {iterations}: one sigma per iteration is more memory than can be allocated; use sigma(i)"
            ))
        })?;
        sigmas.extend((0..iterations).map(|i| self.inner.sigma(i)));
        Ok(sigmas.into_pyarray(py))
    }

    /// The spread at the start.
    #[getter]
    pub(crate) fn sigma0(&self) -> f64 {
        self.inner.sigma0()
    }
    /// The floor.
    #[getter]
    pub(crate) fn sigma_min(&self) -> f64 {
        self.inner.sigma_min()
    }
    /// The length of the run the schedule spans.
    #[getter]
    pub(crate) fn iterations(&self) -> usize {
        self.inner.iterations()
    }
    /// 'paper', 'constant', 'exponential' or 'cosine'.
    #[getter]
    pub(crate) fn schedule(&self) -> &'static str {
        schedule_name(self.inner.schedule())
    }
    /// The warm-start fraction of the paper's schedule (None for the others).
    #[getter]
    pub(crate) fn warmup(&self) -> Option<f64> {
        match self.inner.schedule() {
            Schedule::WarmLinear { warmup } => Some(warmup),
            _ => None,
        }
    }

    pub(crate) fn __repr__(&self) -> String {
        format!(
            "Annealer(schedule='{}', sigma0={:?}, sigma_min={:?}, iterations={})",
            self.schedule(),
            self.inner.sigma0(),
            self.inner.sigma_min(),
            self.inner.iterations()
        )
    }
}

pub(crate) type ArrayPair<'py> = (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>);

/// Adam with bias correction and optional box bounds (projection after every step). May be
/// shared by threads: their steps run one at a time.
#[pyclass(module = "plateau_free", name = "Adam", frozen)]
pub(crate) struct PyAdam {
    pub(crate) inner: Guarded<RsAdam>,
    pub(crate) bounds: Option<(Vec<f64>, Vec<f64>)>,
}

#[pymethods]
impl PyAdam {
    /// `bounds`: None, or `(lower, upper)`, two arrays as long as x (infinite entries allowed).
    #[new]
    #[pyo3(signature = (lr=0.02, beta1=0.9, beta2=0.999, epsilon=1e-8, bounds=None))]
    pub(crate) fn new(
        #[pyo3(from_py_with = lr_arg)] lr: f64,
        #[pyo3(from_py_with = beta1_arg)] beta1: f64,
        #[pyo3(from_py_with = beta2_arg)] beta2: f64,
        #[pyo3(from_py_with = epsilon_arg)] epsilon: f64,
        #[pyo3(from_py_with = adam_bounds_arg)] bounds: Option<(Vec<f64>, Vec<f64>)>,
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
        Ok(PyAdam {
            inner: Guarded::new(inner),
            bounds,
        })
    }

    /// One step downhill from `x` along `gradient`; returns the new x (a new array).
    pub(crate) fn step<'py>(
        &self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
        gradient: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let (mut theta, shape) = to_vector(py, x, "x")?;
        let (g, _) = to_vector(py, gradient, "gradient")?;
        self.inner
            .lock(py)?
            .step(&mut theta, &g)
            .map_err(value_error)?;
        array_like(py, theta, &shape)
    }

    /// Forgets the moment estimates.
    pub(crate) fn reset(&self, py: Python<'_>) -> PyResult<()> {
        self.inner.lock(py)?.reset();
        Ok(())
    }

    /// The learning rate.
    #[getter]
    pub(crate) fn lr(&self, py: Python<'_>) -> PyResult<f64> {
        Ok(self.inner.lock(py)?.lr())
    }
    /// Steps taken since construction or the last reset.
    #[getter]
    pub(crate) fn steps(&self, py: Python<'_>) -> PyResult<usize> {
        Ok(self.inner.lock(py)?.steps())
    }
    /// `(lower, upper)` or None.
    #[getter]
    pub(crate) fn bounds<'py>(&self, py: Python<'py>) -> Option<ArrayPair<'py>> {
        self.bounds
            .as_ref()
            .map(|(l, u)| (PyArray1::from_slice(py, l), PyArray1::from_slice(py, u)))
    }

    pub(crate) fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        Ok(format!(
            "Adam(lr={:?}, bounds={})",
            self.lr(py)?,
            if self.bounds.is_some() {
                "(...)"
            } else {
                "None"
            }
        ))
    }
}
