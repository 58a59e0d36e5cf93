//! The paper's loop (`Optimizer`): `plateau.minimize(..., method="plateau")`.

use super::*;

/// Per-iteration records of a run.
#[derive(Default)]
pub(crate) struct Record {
    pub(crate) sigma: Vec<f64>,
    pub(crate) grad_norm: Vec<f64>,
    pub(crate) value: Vec<f64>,
    pub(crate) nfev: Vec<u64>,
    pub(crate) x: Vec<f64>,
    pub(crate) stopped_by_callback: bool,
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
pub(crate) fn _minimize<'py>(
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
    // The three estimator classes hold different Rust types: one `if let` arm each, the
    // same call in every arm.
    macro_rules! run_with_any_of {
        ($($class:ty),+) => {
            $(if let Ok(est) = estimator.cast::<$class>() {
                let mut est = est.try_borrow_mut()?;
                let est = &mut *est;
                run(py, &mut est.inner, &est.shared, &theta, &shape, optimizer, callback, record_x)?
            } else)+ {
                return Err(PyTypeError::new_err(format!(
                    "estimator must be a PlateauFreeGradient, FiniteDifference or Spsa, got {}",
                    short_repr(estimator)
                )));
            }
        };
    }
    let (x, nit, nfev, record) =
        run_with_any_of!(PyPlateauFreeGradient, PyFiniteDifference, PySpsa);
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
