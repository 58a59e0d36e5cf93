//! Cross-language determinism: the same functions written in Rust, run through the Rust API.

use super::*;

/// A test function with a plateau and a step; the same arithmetic, in the same order, as
/// `bumpy` in `python/tests/test_determinism.py`.
pub(crate) fn bumpy(x: &[f64]) -> f64 {
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

pub(crate) fn bumpy_seeded(x: &[f64], seed: u64) -> f64 {
    bumpy(x) + (seed % 1000) as f64 * 1e-3
}

/// `count` gradient estimates of the reference function `bumpy` (or `bumpy(x) + (seed % 1000)
/// * 1e-3` when `seeded`) computed by the Rust API alone, one row each: the numbers the Python
/// binding must reproduce bit for bit.
#[pyfunction]
#[pyo3(signature = (x, sigma, samples=2, sampling="radial", antithetic=true, seed=0, count=1, seeded=false, orthogonal=false))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn _rust_reference_estimates<'py>(
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
        estimates!(plateau_free::objective::Seeded(bumpy_seeded));
    } else {
        estimates!(bumpy);
    }
    Ok(rows.into_pyarray(py).reshape([count, x.len()])?.into_any())
}

/// The final x of a Rust `Optimizer` run on `bumpy` (paper annealer, Adam): what
/// `plateau_free.minimize` must reproduce bit for bit.
#[pyfunction]
#[pyo3(signature = (x0, sigma0=0.5, iterations=50, lr=0.02, samples=2, seed=0))]
pub(crate) fn _rust_reference_minimize<'py>(
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

/// The staircase of the `minimize` tests: the squared distance of the rounded point to the
/// integer target `(1, -2, 3, 1, -2, 3, ...)`; the same arithmetic, in the same order, as
/// `staircase` in `python/tests/test_adaptive.py` (rounding is `floor(v + 0.5)` on both sides).
pub(crate) fn staircase(x: &[f64]) -> f64 {
    const TARGET: [f64; 3] = [1.0, -2.0, 3.0];
    let mut total = 0.0;
    for (i, v) in x.iter().enumerate() {
        let d = (v + 0.5).floor() - TARGET[i % 3];
        total += d * d;
    }
    total
}

pub(crate) fn staircase_seeded(x: &[f64], seed: u64) -> f64 {
    staircase(x) + (seed % 1000) as f64 * 1e-3
}

/// A Rust `Minimizer` run on `staircase` (or `staircase(x) + (seed % 1000) * 1e-3` when
/// `seeded`): the result `plateau_free.minimize(..., budget=...)` must reproduce bit for bit.
/// With `paper = (samples, lr, sigma0)` and `polish`: `Strategy::Paper` and
/// `Minimizer::polish`, what `method='polished'` must reproduce.
#[pyfunction]
#[pyo3(signature = (x0, budget=None, seed=0, sigma0=None, bounds=None, seeded=false, paper=None, polish=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn _rust_reference_minimize_adaptive<'py>(
    py: Python<'py>,
    x0: Vec<f64>,
    budget: Option<usize>,
    seed: u64,
    sigma0: Option<f64>,
    bounds: Option<Bounds>,
    seeded: bool,
    paper: Option<(usize, f64, f64)>,
    polish: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    macro_rules! run {
        ($objective:expr) => {{
            let m = RsMinimizer::new($objective).seed(seed);
            let m = maybe(m, budget, RsMinimizer::budget);
            let m = maybe(m, sigma0, RsMinimizer::sigma0);
            let m = maybe(m, bounds, |m, (lower, upper)| m.bounds(lower, upper));
            let m = maybe(m, paper, |m, (samples, lr, sigma0)| {
                m.strategy(Strategy::Paper {
                    samples,
                    lr,
                    sigma0,
                })
            });
            let m = maybe(m, polish, RsMinimizer::polish);
            m.run(&x0).map_err(value_error)?
        }};
    }
    let best = if seeded {
        run!(plateau_free::objective::Seeded(staircase_seeded))
    } else {
        run!(staircase)
    };
    let out = PyDict::new(py);
    minimum_dict(py, &out, best, &[x0.len()])?;
    Ok(out)
}

/// Evaluations per second of a trivial Rust closure through the same estimator (for the
/// overhead benchmark's baseline): returns seconds per evaluation.
#[pyfunction]
#[pyo3(signature = (dim=10, samples=10_000, repeats=5))]
pub(crate) fn _rust_seconds_per_evaluation(
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
