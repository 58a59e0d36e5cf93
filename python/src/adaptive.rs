//! The raw results of a `plateau_free::Minimizer` run (`plateau_free.minimize(fun, x0)`, run by
//! `plateau_free._drive` over `_AskTell`).

use super::*;

pub(crate) fn stop_name(stop: Stop) -> String {
    stop.to_string()
}

/// `(lower, upper)` for the Rust `Minimizer`.
pub(crate) type Bounds = (Vec<f64>, Vec<f64>);

pub(crate) fn minimum_dict(
    py: Python<'_>,
    out: &Bound<'_, PyDict>,
    best: RsMinimum,
    shape: &[usize],
) -> PyResult<()> {
    out.set_item("x", array_like(py, best.x, shape)?)?;
    out.set_item("fun", best.fun)?;
    out.set_item("nit", best.iterations)?;
    out.set_item("nfev", best.evaluations)?;
    out.set_item("restarts", best.restarts)?;
    out.set_item("sigma", best.sigma)?;
    out.set_item("stop", stop_name(best.stop))?;
    out.set_item("failures", best.failures)?;
    Ok(())
}
