//! Baselines that show the plateau failure on the same objective and the same loop: a
//! small-step central finite difference (what a gradient sees without smoothing: zero on a
//! plateau) and SPSA (Spall, 1992).

use std::fmt;

use rand::RngExt;

use crate::check;
use crate::error::Error;
use crate::estimator::{mean, Bounds, Estimate, GradientEstimator};
use crate::objective::Objective;
use crate::seeding::{stream_rng, stream_seed};

mod ask_tell;

pub use ask_tell::{Baseline, BaselineAskTell};

/// Central finite differences `(f(theta + h e_i) - f(theta - h e_i)) / 2h` with a fixed
/// step `h`, `2n` evaluations per gradient. The spread handed in by the loop is ignored: this
/// is the unsmoothed gradient.
///
/// ```
/// use plateau_free::baseline::FiniteDifference;
/// use plateau_free::GradientEstimator;
/// let step = |x: &[f64]| if x[0] > 0.5 { 1.0 } else { 0.0 };
/// let mut fd = FiniteDifference::new(step, 1e-3)?;
/// // On the plateau the finite difference is exactly zero.
/// assert_eq!(fd.estimate(&[2.0], 0.5)?.gradient, vec![0.0]);
/// # Ok::<(), plateau_free::Error>(())
/// ```
pub struct FiniteDifference<F> {
    common: Common<F>,
    step: f64,
}

impl<F: Objective> FiniteDifference<F> {
    /// Central differences of step `step`.
    ///
    /// # Errors
    /// `step` not finite and positive.
    pub fn new(objective: F, step: f64) -> Result<Self, Error> {
        check::positive("step", step)?;
        Ok(FiniteDifference {
            common: Common::new(objective),
            step,
        })
    }

    setters! {
        /// The seed handed to a seeded objective (the same for both sides of a difference).
        seed(seed: u64) => common.seed = seed;
    }

    /// The input check: theta only (the spread is ignored).
    fn check(theta: &[f64], _sigma: f64) -> Result<(), Error> {
        check::theta(theta)
    }

    /// The gradient of estimate `index`, its input checked.
    ///
    /// With bounds ([`GradientEstimator::set_bounds`]), `theta +- h e_i` are clamped onto the
    /// box and the difference is divided by the distance between the clamped points: at a
    /// face the difference is one-sided (and zero across a box of zero width).
    fn gradient(&mut self, theta: &[f64], _sigma: f64, index: u64) -> Result<Estimate, Error> {
        let n = theta.len();
        let h = self.step;
        let bounds = self.common.bounds.as_ref();
        self.common.points.clear();
        self.common.points.extend_from_slice(theta);
        let mut gradient = vec![0.0; n];
        let mut mean_value = 0.0;
        let mut pair_means = Vec::with_capacity(n);
        for i in 0..n {
            let seed = stream_seed(self.common.seed, index, i as u64);
            let side = |x: f64, sample: usize, point: &mut Vec<f64>| {
                // theta near f64::MAX plus the step overflows: never evaluate f there.
                if !x.is_finite() {
                    return Err(Error::NonFinitePoint {
                        sample,
                        index: i,
                        value: x,
                    });
                }
                point[i] = x;
                evaluate_finite(&self.common.objective, point, seed, sample)
            };
            let (mut up, mut down) = (theta[i] + h, theta[i] - h);
            let clamped = match bounds {
                Some(b) if up.is_finite() && down.is_finite() => {
                    let (u, d) = (
                        up.clamp(b.lower[i], b.upper[i]),
                        down.clamp(b.lower[i], b.upper[i]),
                    );
                    let moved = (u, d) != (up, down);
                    (up, down) = (u, d);
                    moved
                }
                _ => false,
            };
            let plus = side(up, 2 * i, &mut self.common.points)?;
            let minus = side(down, 2 * i + 1, &mut self.common.points)?;
            self.common.points[i] = theta[i];
            gradient[i] = if !clamped {
                (0.5 * plus - 0.5 * minus) / h
            } else if up > down {
                (0.5 * plus - 0.5 * minus) / (0.5 * up - 0.5 * down)
            } else {
                0.0
            };
            mean_value += (plus + minus) / (2 * n) as f64;
            pair_means.push(0.5 * plus + 0.5 * minus);
        }
        check::gradient(&gradient)?;
        if !mean_value.is_finite() {
            // Values near +-f64::MAX overflow the running sum; their mean does not.
            mean_value = mean(&pair_means);
        }
        Ok(Estimate {
            resampled: 0,
            gradient,
            evaluations: 2 * n,
            mean_value,
        })
    }
}

/// Simultaneous-perturbation stochastic approximation: one Rademacher direction `delta`,
/// `g_i = (f(theta + c delta) - f(theta - c delta)) / (2 c delta_i)`, 2 evaluations per
/// gradient whatever the dimension. `c` is the spread handed in by the loop, so the annealer
/// plays the role of SPSA's decaying perturbation size.
///
/// ```
/// use plateau_free::baseline::Spsa;
/// use plateau_free::GradientEstimator;
/// let linear = |x: &[f64]| 3.0 * x[0] - x[1];
/// let g = Spsa::new(linear).estimate(&[0.0, 0.0], 0.1)?.gradient;
/// // Exact on a linear function up to the cross terms: each coordinate is 3 +- 1 or -1 +- 3.
/// assert!((g[0] - 2.0).abs() < 1e-12 || (g[0] - 4.0).abs() < 1e-12);
/// # Ok::<(), plateau_free::Error>(())
/// ```
pub struct Spsa<F> {
    common: Common<F>,
}

impl<F: Objective> Spsa<F> {
    /// SPSA on `objective`.
    #[must_use]
    pub fn new(objective: F) -> Self {
        Spsa {
            common: Common::new(objective),
        }
    }

    setters! {
        /// The seed of the directions and of the objective's seeds.
        seed(seed: u64) => common.seed = seed;
    }

    /// The input check: the spread, then theta.
    fn check(theta: &[f64], sigma: f64) -> Result<(), Error> {
        check::sigma(sigma)?;
        check::theta(theta)
    }

    /// The gradient of estimate `index`, its input checked.
    fn gradient(&mut self, theta: &[f64], sigma: f64, index: u64) -> Result<Estimate, Error> {
        let n = theta.len();
        let mut rng = stream_rng(self.common.seed, index, 0);
        let delta: Vec<f64> = (0..n)
            .map(|_| if rng.random::<bool>() { 1.0 } else { -1.0 })
            .collect();
        self.common.points.clear();
        self.common
            .points
            .extend(theta.iter().zip(&delta).map(|(t, d)| t + sigma * d));
        self.common
            .points
            .extend(theta.iter().zip(&delta).map(|(t, d)| t - sigma * d));
        check::points(&self.common.points, n)?;
        if let Some(bounds) = &self.common.bounds {
            // SPSA of `f` composed with the projection, as the plateau-free estimator's.
            bounds.project(&mut self.common.points);
        }
        let seed = stream_seed(self.common.seed, index, 1);
        let mut values = [0.0; 2];
        for (k, v) in values.iter_mut().enumerate() {
            *v = evaluate_finite(
                &self.common.objective,
                &self.common.points[k * n..(k + 1) * n],
                seed,
                k,
            )?;
        }
        let half_diff = 0.5 * values[0] - 0.5 * values[1];
        let gradient: Vec<f64> = delta.iter().map(|d| half_diff / (sigma * d)).collect();
        check::gradient(&gradient)?;
        Ok(Estimate {
            resampled: 0,
            gradient,
            evaluations: 2,
            mean_value: 0.5 * values[0] + 0.5 * values[1],
        })
    }
}

/// What both baselines hold: the objective; the seed and the count of estimates, which name
/// each estimate's random streams (the count is the stream position that an
/// [`crate::run::OptimizerState`] records); scratch space for the points evaluated.
struct Common<F> {
    objective: F,
    seed: u64,
    estimates: u64,
    points: Vec<f64>,
    /// The box the evaluated points are kept in ([`GradientEstimator::set_bounds`]).
    bounds: Option<Bounds>,
}

impl<F> Common<F> {
    /// Seed 0, no estimate drawn yet.
    fn new(objective: F) -> Self {
        Common {
            objective,
            seed: 0,
            estimates: 0,
            points: Vec::new(),
            bounds: None,
        }
    }
}

/// [`GradientEstimator`] for the baselines, written once: the stream position is the count
/// of estimates, and an estimate is the type's `check` of its input (a bad input spends no
/// index), the next index, then the type's `gradient` (an estimate that fails there has
/// spent its index, as the plateau-free estimator's does).
macro_rules! baseline_estimator {
    ($($baseline:ident),*) => {$(
        impl<F: Objective> GradientEstimator for $baseline<F> {
            fn stream_position(&self) -> Option<u64> {
                Some(self.common.estimates)
            }

            fn set_stream_position(&mut self, position: u64) {
                self.common.estimates = position;
            }

            fn set_bounds(&mut self, lower: &[f64], upper: &[f64]) -> Result<(), Error> {
                self.common.bounds = Some(Bounds::new(lower, upper)?);
                Ok(())
            }

            fn estimate(&mut self, theta: &[f64], sigma: f64) -> Result<Estimate, Error> {
                Self::check(theta, sigma)?;
                if let Some(bounds) = &self.common.bounds {
                    bounds.check_dim(theta.len())?;
                }
                let index = self.common.estimates;
                self.common.estimates += 1;
                self.gradient(theta, sigma, index)
            }
        }
    )*};
}

baseline_estimator!(FiniteDifference, Spsa);

/// `f(point)`, or the error that names evaluation `sample` and its point.
fn evaluate_finite<F: Objective>(
    f: &F,
    point: &[f64],
    seed: u64,
    sample: usize,
) -> Result<f64, Error> {
    let value = f.evaluate(point, seed);
    check::values(&[value], point, point.len()).map_err(|e| match e {
        Error::NonFiniteValue { value, point, .. } => Error::NonFiniteValue {
            sample,
            value,
            point,
        },
        other => other,
    })?;
    Ok(value)
}

impl<F> fmt::Debug for FiniteDifference<F> {
    /// The configuration; the objective by its type's name (closures have no `Debug`).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("FiniteDifference")
            .field("objective", &std::any::type_name::<F>())
            .field("step", &self.step)
            .field("seed", &self.common.seed)
            .field("bounds", &self.common.bounds)
            .field("estimates", &self.common.estimates)
            .finish_non_exhaustive()
    }
}

impl<F> fmt::Debug for Spsa<F> {
    /// The configuration; the objective by its type's name (closures have no `Debug`).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Spsa")
            .field("objective", &std::any::type_name::<F>())
            .field("seed", &self.common.seed)
            .field("bounds", &self.common.bounds)
            .field("estimates", &self.common.estimates)
            .finish_non_exhaustive()
    }
}
