//! Conversions between numpy/Python values and the Rust types.

use super::*;

/// `x` as a flat vector and its shape; ValueError naming `name` and showing the value for
/// anything but a non-empty array of finite numbers.
pub(crate) fn to_vector(
    py: Python<'_>,
    x: &Bound<'_, PyAny>,
    name: &str,
) -> PyResult<(Vec<f64>, Vec<usize>)> {
    let not_numbers = |why: String| {
        option_type_error(
            py,
            format!("{name} = {} is not an array of numbers{why}", short_repr(x)),
        )
    };
    if x.is_none() || x.is_instance_of::<PyString>() || x.is_instance_of::<PyBytes>() {
        return Err(not_numbers(String::new()));
    }
    let numpy = py.import("numpy")?;
    let array = real_array(py, x).map_err(|e| not_numbers(format!(": {}", e.value(py))))?;
    let shape = array.cast::<PyUntypedArray>()?.shape().to_vec();
    // `ascontiguousarray` makes a 0-d array 1-d: the shape is taken before.
    let array = numpy.call_method1("ascontiguousarray", (array,))?;
    let values = array.cast::<PyArrayDyn<f64>>()?.to_vec()?;
    if values.is_empty() {
        return Err(PyValueError::new_err(format!(
            "{name} = {} is empty (shape {shape:?}): the objective needs at least one parameter",
            short_repr(x)
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

/// `plateau_free.OptionTypeError`, made when the module is imported.
pub(crate) static OPTION_TYPE_ERROR: pyo3::sync::PyOnceLock<Py<PyType>> =
    pyo3::sync::PyOnceLock::new();

/// `plateau_free.OptionTypeError`: a subclass of both ValueError and TypeError, for an option
/// of the wrong type (`type(name, (ValueError, TypeError), ...)`, as Rust cannot declare a
/// class of two bases).
pub(crate) fn option_type_error_class(py: Python<'_>) -> PyResult<&Py<PyType>> {
    OPTION_TYPE_ERROR.get_or_try_init(py, || {
        let bases = PyTuple::new(
            py,
            [py.get_type::<PyValueError>(), py.get_type::<PyTypeError>()],
        )?;
        let namespace = PyDict::new(py);
        namespace.set_item("__module__", "plateau_free")?;
        namespace.set_item(
            "__doc__",
            "An option of the wrong type (a string for a number, None for a seed, ...): a \
             ValueError, as every bad option of plateau_free, and a TypeError, as Python's \
             convention has it. The message names the option and shows its value.",
        )?;
        let class =
            py.import("builtins")?
                .getattr("type")?
                .call1(("OptionTypeError", bases, namespace))?;
        Ok(class.cast_into::<PyType>()?.unbind())
    })
}

pub(crate) fn option_type_error(py: Python<'_>, message: String) -> PyErr {
    match option_type_error_class(py) {
        Ok(class) => PyErr::from_type(class.bind(py).clone(), message),
        Err(e) => e,
    }
}

/// Whether `value` is a bool (Python's or numpy's).
fn is_bool(value: &Bound<'_, PyAny>) -> bool {
    value.is_instance_of::<PyBool>()
        || value
            .get_type()
            .qualname()
            .is_ok_and(|n| n == "bool" || n == "bool_")
}

/// A whole-number option from `lowest` to 2**64 - 1: an int (numpy's included) or a float of
/// whole value; OptionTypeError for what is not a number, ValueError for another number.
pub(crate) fn whole(value: &Bound<'_, PyAny>, name: &str, lowest: u64) -> PyResult<u64> {
    let py = value.py();
    let must = || {
        format!(
            "{name} = {} must be a whole number from {lowest} to 2**64 - 1",
            short_repr(value)
        )
    };
    if is_bool(value) || value.is_instance_of::<PyString>() {
        return Err(option_type_error(py, must()));
    }
    if let Ok(v) = value.extract::<u64>() {
        return if v >= lowest {
            Ok(v)
        } else {
            Err(PyValueError::new_err(must()))
        };
    }
    if value.hasattr("__index__")? {
        return Err(PyValueError::new_err(must())); // an integer out of range
    }
    match value.extract::<f64>() {
        Ok(v) if v.is_finite() && v.fract() == 0.0 && v >= lowest as f64 && v < 2f64.powi(64) => {
            Ok(v as u64)
        }
        Ok(_) => Err(PyValueError::new_err(must())),
        Err(_) => Err(option_type_error(py, must())),
    }
}

/// [`whole`] as a count (usize).
pub(crate) fn count(value: &Bound<'_, PyAny>, name: &str, lowest: u64) -> PyResult<usize> {
    usize::try_from(whole(value, name, lowest)?).map_err(|_| {
        PyValueError::new_err(format!(
            "{name} = {} is too large for this platform",
            short_repr(value)
        ))
    })
}

/// A number option (its range is the Rust side's check): OptionTypeError for what is not a
/// number.
pub(crate) fn real(value: &Bound<'_, PyAny>, name: &str) -> PyResult<f64> {
    let wrong = || {
        option_type_error(
            value.py(),
            format!("{name} = {} must be a number", short_repr(value)),
        )
    };
    if is_bool(value) || value.is_instance_of::<PyString>() {
        return Err(wrong());
    }
    value.extract::<f64>().map_err(|_| wrong())
}

/// A True/False option.
pub(crate) fn flag(value: &Bound<'_, PyAny>, name: &str) -> PyResult<bool> {
    if is_bool(value) {
        return value.is_truthy();
    }
    Err(option_type_error(
        value.py(),
        format!("{name} = {} must be True or False", short_repr(value)),
    ))
}

/// A name option (a str, or a str enum such as `plateau_free.Sampling`).
pub(crate) fn text(value: &Bound<'_, PyAny>, name: &str) -> PyResult<String> {
    match value.cast::<PyString>() {
        Ok(s) => s.extract::<String>(),
        Err(_) => Err(option_type_error(
            value.py(),
            format!("{name} = {} must be a name (a str)", short_repr(value)),
        )),
    }
}

/// The extraction functions of the constructors' and methods' arguments
/// (`#[pyo3(from_py_with = ...)]`): each names its option in its errors.
macro_rules! option_arguments {
    ($($function:ident($name:literal) -> $ty:ty = $check:ident $(, $lowest:literal)?;)*) => {$(
        pub(crate) fn $function(value: &Bound<'_, PyAny>) -> PyResult<$ty> {
            $check(value, $name $(, $lowest)?)
        }
    )*};
}

option_arguments! {
    seed_arg("seed") -> u64 = whole, 0;
    samples_arg("samples") -> usize = count, 1;
    iterations_arg("iterations") -> usize = count, 1;
    iteration_arg("iteration") -> usize = count, 0;
    sampling_arg("sampling") -> String = text;
    schedule_arg("schedule") -> String = text;
    antithetic_arg("antithetic") -> bool = flag;
    batched_arg("batched") -> bool = flag;
    seeded_arg("seeded") -> bool = flag;
    orthogonal_arg("orthogonal") -> bool = flag;
    parallel_arg("parallel") -> bool = flag;
    step_arg("step") -> f64 = real;
    sigma_arg("sigma") -> f64 = real;
    sigma0_arg("sigma0") -> f64 = real;
    sigma_min_arg("sigma_min") -> f64 = real;
    warmup_arg("warmup") -> f64 = real;
    lr_arg("lr") -> f64 = real;
    beta1_arg("beta1") -> f64 = real;
    beta2_arg("beta2") -> f64 = real;
    epsilon_arg("epsilon") -> f64 = real;
}

/// Adam's `bounds`: None, or `(lower, upper)`, two sequences of numbers.
pub(crate) fn adam_bounds_arg(value: &Bound<'_, PyAny>) -> PyResult<Option<Bounds>> {
    if value.is_none() {
        return Ok(None);
    }
    value.extract::<Bounds>().map(Some).map_err(|_| {
        option_type_error(
            value.py(),
            format!(
                "bounds = {} must be (lower, upper): two sequences of numbers, one per coordinate",
                short_repr(value)
            ),
        )
    })
}

/// `builder` with `set` applied when a value is given: an option that Python passes as None
/// keeps the builder's default.
pub(crate) fn maybe<B, V>(builder: B, value: Option<V>, set: impl FnOnce(B, V) -> B) -> B {
    match value {
        Some(v) => set(builder, v),
        None => builder,
    }
}

/// The options of a `plateau_free::Minimizer` run, the same for `plateau_free.minimize` and
/// `plateau_free.ask_tell` with `method='adaptive'` or `'polished'`: the dict that
/// `plateau_free._options._adaptive_options` makes (a missing key is a TypeError naming it).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
pub(crate) struct AdaptiveOptions {
    budget: Option<usize>,
    seed: u64,
    sigma0: Option<f64>,
    /// One spread per coordinate: `Minimizer::sigma0_each`.
    sigma0_each: Option<Vec<f64>>,
    bounds: Option<Bounds>,
    target: Option<f64>,
    population: Option<usize>,
    /// `Minimizer::metric`: `'auto'`, `'full'`, `'decoded'`, `'diagonal'` or `'low_rank'`.
    metric: PyMetric,
    restarts: bool,
    /// `method='polished'`: `Strategy::Paper`'s `(samples, lr, sigma0)`; None for the
    /// adaptive search alone.
    paper: Option<(usize, f64, f64)>,
    /// `method='polished'`: `Minimizer::polish`'s fraction of the budget.
    polish: Option<f64>,
    /// `Minimizer::stop_when_stalled`'s window, a fraction of the budget; None: off.
    stall: Option<f64>,
    /// `'continue'` or `'raise'`: `Minimizer::on_failure`.
    on_failure: String,
    /// `Minimizer::patience`: converged restarts back at the best point that end the run.
    patience: Option<usize>,
    /// `Minimizer::steps` (from `integrality=`: 1.0 an integer, 0.0 continuous).
    steps: Option<Vec<f64>>,
}

impl AdaptiveOptions {
    /// `minimizer` with these options; those given as None keep the Minimizer's defaults.
    pub(crate) fn apply<F>(self, minimizer: RsMinimizer<F>) -> RsMinimizer<F> {
        let policy = if self.on_failure == "raise" {
            FailurePolicy::Raise
        } else {
            FailurePolicy::Continue
        };
        let minimizer = minimizer
            .seed(self.seed)
            .metric(self.metric.0)
            .restarts(self.restarts)
            .on_failure(policy);
        let minimizer = maybe(minimizer, self.budget, RsMinimizer::budget);
        let minimizer = maybe(minimizer, self.sigma0, RsMinimizer::sigma0);
        let minimizer = maybe(minimizer, self.sigma0_each, RsMinimizer::sigma0_each);
        let minimizer = maybe(minimizer, self.patience, RsMinimizer::patience);
        let minimizer = maybe(minimizer, self.steps, RsMinimizer::steps);
        let minimizer = maybe(minimizer, self.bounds, |m, (lower, upper)| {
            m.bounds(lower, upper)
        });
        let minimizer = maybe(minimizer, self.target, RsMinimizer::target);
        let minimizer = maybe(minimizer, self.population, RsMinimizer::population);
        let minimizer = maybe(minimizer, self.paper, |m, (samples, lr, sigma0)| {
            m.strategy(Strategy::Paper {
                samples,
                lr,
                sigma0,
            })
        });
        let minimizer = maybe(minimizer, self.polish, RsMinimizer::polish);
        maybe(minimizer, self.stall, RsMinimizer::stop_when_stalled)
    }
}

/// A [`Metric`] by its Python name (`plateau_free._checks._metric` spells it).
pub(crate) struct PyMetric(Metric);

impl FromPyObject<'_, '_> for PyMetric {
    type Error = PyErr;

    fn extract(value: Borrowed<'_, '_, PyAny>) -> PyResult<Self> {
        let name: String = value.extract()?;
        match name.as_str() {
            "auto" => Ok(PyMetric(Metric::Auto)),
            "full" => Ok(PyMetric(Metric::Full)),
            "decoded" => Ok(PyMetric(Metric::Decoded)),
            "diagonal" => Ok(PyMetric(Metric::Diagonal)),
            "low_rank" => Ok(PyMetric(Metric::LowRank)),
            _ => Err(PyValueError::new_err(format!(
                "metric = '{name}' is not a metric: use 'auto', 'full', 'decoded', 'diagonal' or 'low_rank'"
            ))),
        }
    }
}

/// A spread: one number, or one per coordinate.
pub(crate) enum Spread {
    Scalar(f64),
    PerCoordinate(Vec<f64>),
}

pub(crate) fn to_spread(py: Python<'_>, sigma: &Bound<'_, PyAny>) -> PyResult<Spread> {
    if sigma.is_instance_of::<PyFloat>() || sigma.is_instance_of::<PyInt>() {
        return Ok(Spread::Scalar(real(sigma, "sigma")?));
    }
    let wrong = |why: String| {
        option_type_error(
            py,
            format!(
                "sigma = {} must be a number, or one per element of x{why}",
                short_repr(sigma)
            ),
        )
    };
    if sigma.is_none() || is_bool(sigma) || sigma.is_instance_of::<PyString>() {
        return Err(wrong(String::new()));
    }
    let numpy = py.import("numpy")?;
    let array = real_array(py, sigma).map_err(|e| wrong(format!(": {}", e.value(py))))?;
    if array.cast::<PyUntypedArray>()?.ndim() == 0 {
        return Ok(Spread::Scalar(array.extract()?));
    }
    let array = numpy.call_method1("ascontiguousarray", (array,))?;
    Ok(Spread::PerCoordinate(
        array.cast::<PyArrayDyn<f64>>()?.to_vec()?,
    ))
}

pub(crate) fn parse_sampling(name: &str) -> PyResult<Sampling> {
    match name.to_ascii_lowercase().replace(['-', ' '], "_").as_str() {
        "radial" => Ok(Sampling::Radial),
        "per_coordinate" | "percoordinate" => Ok(Sampling::PerCoordinate),
        "gaussian" => Ok(Sampling::Gaussian),
        _ => Err(PyValueError::new_err(format!(
            "sampling = '{name}' is not a sampler: use 'radial', 'per_coordinate' or 'gaussian'"
        ))),
    }
}

pub(crate) fn sampling_name(sampling: Sampling) -> &'static str {
    match sampling {
        Sampling::Radial => "radial",
        Sampling::PerCoordinate => "per_coordinate",
        Sampling::Gaussian => "gaussian",
    }
}

pub(crate) fn array_like<'py>(
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
pub(crate) fn py_float(v: f64) -> String {
    if v.is_nan() {
        "nan".into()
    } else if v.is_infinite() {
        if v > 0.0 { "inf" } else { "-inf" }.into()
    } else {
        format!("{v:?}")
    }
}

pub(crate) fn py_bool(b: bool) -> &'static str {
    if b {
        "True"
    } else {
        "False"
    }
}

/// `x` as a float64 array when its numbers are real (bool, int, float, or objects that convert);
/// complex numbers, strings and dates are refused rather than cast (numpy's cast to float64
/// keeps a complex number's real part with a mere warning).
pub(crate) fn real_array<'py>(
    py: Python<'py>,
    x: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    let numpy = py.import("numpy")?;
    let array = numpy.call_method1("asarray", (x,))?;
    let kind: String = array.getattr("dtype")?.getattr("kind")?.extract()?;
    if !"biufO".contains(kind.as_str()) {
        let name: String = array.getattr("dtype")?.str()?.extract()?;
        return Err(PyTypeError::new_err(format!(
            "it holds {name} values, not real numbers"
        )));
    }
    numpy.call_method1("asarray", (array, "float64"))
}
