//! The objective: a Python callable seen from Rust, with the GIL re-attached per call.

use super::*;

/// What an objective shares with the Python object that owns its estimator: the first
/// exception raised by `fun`, the count of evaluations, and the shape of `x`.
#[derive(Default)]
pub(crate) struct Shared {
    pub(crate) failed: AtomicBool,
    pub(crate) error: Mutex<Option<PyErr>>,
    pub(crate) evaluations: AtomicU64,
    /// The shape of the current `x` when it is not one-dimensional: points are handed to `fun`
    /// in that shape.
    pub(crate) shape: Mutex<Option<Vec<usize>>>,
    pub(crate) reshape: AtomicBool,
}

impl Shared {
    pub(crate) fn fail(&self, err: PyErr) {
        let mut slot = self.error.lock().unwrap_or_else(|p| p.into_inner());
        if slot.is_none() {
            *slot = Some(err);
        }
        self.failed.store(true, Ordering::Release);
    }

    pub(crate) fn failed(&self) -> bool {
        self.failed.load(Ordering::Acquire)
    }

    /// The stored exception, if any; clears it so that the estimator stays usable.
    pub(crate) fn take(&self) -> Option<PyErr> {
        if !self.failed() {
            return None;
        }
        self.failed.store(false, Ordering::Release);
        self.error.lock().unwrap_or_else(|p| p.into_inner()).take()
    }

    pub(crate) fn set_shape(&self, shape: &[usize]) {
        let reshape = shape.len() != 1;
        *self.shape.lock().unwrap_or_else(|p| p.into_inner()) = reshape.then(|| shape.to_vec());
        self.reshape.store(reshape, Ordering::Release);
    }

    /// The shape of one point, if it is not flat.
    pub(crate) fn point_shape(&self) -> Option<Vec<usize>> {
        if self.reshape.load(Ordering::Acquire) {
            self.shape.lock().unwrap_or_else(|p| p.into_inner()).clone()
        } else {
            None
        }
    }

    /// The Rust call's result, unless `fun` raised: then its exception.
    pub(crate) fn finish<T>(&self, result: Result<T, Error>) -> PyResult<T> {
        if let Some(err) = self.take() {
            return Err(err);
        }
        result.map_err(value_error)
    }
}

/// The library's error as a ValueError. The library checks the ranges of its options and
/// names each by its Rust name: where Python's keyword differs, the message names the keyword.
pub(crate) fn value_error(e: Error) -> PyErr {
    if let Error::InvalidParameter {
        name,
        value,
        reason,
    } = &e
    {
        if let Some((_, python)) = PYTHON_NAMES.iter().find(|(rust, _)| rust == name) {
            return PyValueError::new_err(format!("{python} = {value} is invalid: {reason}"));
        }
    }
    PyValueError::new_err(e.to_string())
}

/// `(Rust name, Python keyword)` of the library's options whose names differ: the one table of
/// them. A sequence `sigma0` is `Minimizer::sigma0_each`; `integrality` sets `Minimizer::steps`.
const PYTHON_NAMES: [(&str, &str); 2] = [("sigma0_each", "sigma0"), ("steps", "integrality")];

/// A Python callable as a [`plateau_free::Objective`].
pub(crate) struct PyObjective {
    pub(crate) fun: Py<PyAny>,
    pub(crate) batched: bool,
    pub(crate) seeded: bool,
    pub(crate) shared: Arc<Shared>,
}

impl PyObjective {
    pub(crate) fn new(fun: Py<PyAny>, batched: bool, seeded: bool) -> Self {
        PyObjective {
            fun,
            batched,
            seeded,
            shared: Arc::new(Shared::default()),
        }
    }

    /// [`PyObjective::new`] for a `fun` that the caller handed in: OptionTypeError (a
    /// ValueError and a TypeError) unless callable.
    pub(crate) fn callable(
        py: Python<'_>,
        fun: Py<PyAny>,
        batched: bool,
        seeded: bool,
    ) -> PyResult<Self> {
        if !fun.bind(py).is_callable() {
            return Err(option_type_error(
                py,
                format!("fun = {} must be callable", short_repr(fun.bind(py))),
            ));
        }
        Ok(PyObjective::new(fun, batched, seeded))
    }

    /// One point as a fresh numpy array shaped like `x`.
    pub(crate) fn point<'py>(&self, py: Python<'py>, point: &[f64]) -> PyResult<Bound<'py, PyAny>> {
        let array = PyArray1::from_slice(py, point);
        match self.shared.point_shape() {
            Some(shape) => Ok(array.reshape(shape)?.into_any()),
            None => Ok(array.into_any()),
        }
    }

    /// All points as one fresh `(N, *x.shape)` array: one copy of the whole buffer.
    pub(crate) fn points<'py>(
        &self,
        py: Python<'py>,
        points: Points<'_>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let array = PyArray1::from_slice(py, points.as_flat());
        let mut shape = vec![points.len()];
        match self.shared.point_shape() {
            Some(s) => shape.extend(s),
            None => shape.push(points.dim()),
        }
        Ok(array.reshape(shape)?.into_any())
    }

    pub(crate) fn call_one(&self, py: Python<'_>, point: &[f64], seed: u64) -> PyResult<f64> {
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

    pub(crate) fn call_batch(
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
pub(crate) fn to_f64(value: &Bound<'_, PyAny>) -> PyResult<f64> {
    if let Ok(f) = value.cast_exact::<PyFloat>() {
        return Ok(f.value());
    }
    // numpy's complex scalars convert to their real part (a float's `__float__`); refused.
    let complex = value
        .getattr("dtype")
        .and_then(|d| d.getattr("kind"))
        .is_ok_and(|k| k.extract::<String>().is_ok_and(|k| k == "c"));
    let extracted = if complex {
        Err(PyTypeError::new_err("a complex number is not real"))
    } else {
        value.extract::<f64>()
    };
    extracted.map_err(|e| {
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

pub(crate) fn short_repr(value: &Bound<'_, PyAny>) -> String {
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
pub(crate) fn read_values(
    py: Python<'_>,
    values: &Bound<'_, PyAny>,
    out: &mut [f64],
) -> PyResult<()> {
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
    let converted = (if values.is_none() {
        Err(PyTypeError::new_err("None is not an array"))
    } else {
        crate::convert::real_array(py, values)
    })
    .and_then(|array| numpy.call_method1("ascontiguousarray", (array,)))
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
