//! The Gaussian-smoothed Jacobian of a vector objective, by Stein's identity on antithetic
//! pairs, estimated only on a [`Sparsity`] pattern.

use rand_distr::{Distribution, StandardNormal};

use super::Sparsity;
use crate::check;
use crate::error::Error;
use crate::seeding::{stream_rng, stream_seed, OBJECTIVE_STREAM};

/// An estimate of the smoothed Jacobian `J_ij = d/dtheta_j E[r_i(theta + tau)]`,
/// `tau ~ N(0, sigma^2 I)`, on the entries of a [`Sparsity`] pattern, with the smoothed
/// residuals `E[r(theta + tau)]` from the same evaluations.
#[derive(Debug, Clone, PartialEq)]
pub struct JacobianEstimate {
    /// The entries, in the pattern's order (row by row, each row's parameters ascending).
    pub values: Vec<f64>,
    /// The standard error of every entry (from the spread of the pairs; infinite with one
    /// pair).
    pub standard_errors: Vec<f64>,
    /// The smoothed residuals, one per output: the mean of `(r(theta + tau) + r(theta -
    /// tau)) / 2` over the pairs.
    pub residuals: Vec<f64>,
    /// The number of antithetic pairs (evaluations / 2).
    pub pairs: usize,
}

/// Sums the pairs' contributions: Stein's identity with antithetic pairs,
/// `J_ij = E[(r_i(theta + tau) - r_i(theta - tau)) tau_j] / (2 sigma^2)`.
#[derive(Debug, Clone)]
pub(crate) struct Accumulator {
    pub(crate) sum: Vec<f64>,
    sum_sq: Option<Vec<f64>>,
    pub(crate) residual_sum: Vec<f64>,
    pub(crate) pairs: usize,
}

impl Accumulator {
    /// Zero sums for `sparsity`; `errors`: also the sums of squares (for standard errors).
    pub(crate) fn new(sparsity: &Sparsity, errors: bool) -> Self {
        let nnz = sparsity.nnz();
        Accumulator {
            sum: vec![0.0; nnz],
            sum_sq: errors.then(|| vec![0.0; nnz]),
            residual_sum: vec![0.0; sparsity.outputs()],
            pairs: 0,
        }
    }

    /// Adds the pair `(theta + tau, theta - tau)` with outputs `plus` and `minus`.
    pub(crate) fn add(
        &mut self,
        sparsity: &Sparsity,
        tau: &[f64],
        sigma: f64,
        plus: &[f64],
        minus: &[f64],
    ) {
        // Divided in two steps: sigma^2 alone underflows for sigma = 1e-200.
        let scale = 0.5 / sigma;
        for (i, (&p, &q)) in plus.iter().zip(minus).enumerate() {
            self.residual_sum[i] += 0.5 * (p + q);
            let d = (p - q) * scale;
            if d == 0.0 {
                continue;
            }
            match &mut self.sum_sq {
                None => sparsity.for_row(i, |k, j| self.sum[k] += d * (tau[j] / sigma)),
                Some(sq) => sparsity.for_row(i, |k, j| {
                    let x = d * (tau[j] / sigma);
                    self.sum[k] += x;
                    sq[k] += x * x;
                }),
            }
        }
        self.pairs += 1;
    }

    /// The mean of the pairs, the standard errors (if summed) and the smoothed residuals.
    pub(crate) fn finish(self) -> JacobianEstimate {
        let p = self.pairs.max(1) as f64;
        let values: Vec<f64> = self.sum.iter().map(|s| s / p).collect();
        let standard_errors = match &self.sum_sq {
            Some(sq) if self.pairs > 1 => values
                .iter()
                .zip(sq)
                .map(|(m, s2)| ((s2 / p - m * m).max(0.0) / (p - 1.0)).sqrt())
                .collect(),
            _ => vec![f64::INFINITY; values.len()],
        };
        JacobianEstimate {
            values,
            standard_errors,
            residuals: self.residual_sum.iter().map(|s| s / p).collect(),
            pairs: self.pairs,
        }
    }
}

/// Perturbation `k` of estimate `estimate`: `tau = sigma z`, `z` standard normal from the
/// stream `(seed, estimate, k)` of [`crate::seeding`].
pub(crate) fn draw(seed: u64, estimate: u64, k: usize, sigma: f64, tau: &mut [f64]) {
    let mut rng = stream_rng(seed, estimate, k as u64);
    for t in tau.iter_mut() {
        let z: f64 = StandardNormal.sample(&mut rng);
        *t = sigma * z;
    }
}

/// The objective's seed of pair `k` of estimate `estimate` (both members share it: common
/// random numbers).
pub(crate) fn pair_seed(seed: u64, estimate: u64, k: usize) -> u64 {
    stream_seed(seed, estimate, OBJECTIVE_STREAM ^ k as u64)
}

/// The first non-finite output of `outputs` (rows of `m`, the points' outputs), as the
/// error that names it; `first` is the count of evaluations before these.
pub(crate) fn check_outputs(
    outputs: &[f64],
    m: usize,
    point: impl Fn(usize) -> Vec<f64>,
    first: usize,
) -> Result<(), Error> {
    match outputs.iter().position(|v| !v.is_finite()) {
        Some(at) => Err(Error::NonFiniteValue {
            sample: first + at / m,
            value: outputs[at],
            point: point(at / m),
        }),
        None => Ok(()),
    }
}

/// The Gaussian-smoothed Jacobian of `r` at `theta` on the entries of `sparsity`, from
/// `pairs` antithetic pairs (2 `pairs` evaluations): Stein's identity
/// `J_ij = E[(r_i(theta + tau) - r_i(theta - tau)) tau_j] / (2 sigma^2)`,
/// `tau ~ N(0, sigma^2 I)`. Unbiased for every `r` with finite smoothed moments; the
/// variance of entry `(i, j)` is about `sum_{l in S_i} J_il^2 / pairs` plus the curvature's
/// share, so with a sparse pattern it does not grow with the number of parameters.
///
/// `r(x, seed, out)` writes the `m` outputs at `x` into `out` (no allocation per call); both
/// members of a pair get the same seed (common random numbers). The estimate is a function
/// of `seed` alone.
///
/// The pattern is an assumption, not checked: an output that moves with a parameter outside
/// its row leaves that dependence out of the estimate (unbiased on the pattern's entries all
/// the same).
///
/// ```
/// use plateau_free::{vector::smoothed_jacobian, vector::Sparsity};
/// // r(x) = (2 x0, x0 - 3 x1): linear, so the smoothed Jacobian is the matrix itself.
/// let r = |x: &[f64], _seed: u64, out: &mut [f64]| {
///     out[0] = 2.0 * x[0];
///     out[1] = x[0] - 3.0 * x[1];
/// };
/// let pattern = Sparsity::from_pairs(2, 2, &[(0, 0), (1, 0), (1, 1)])?;
/// let j = smoothed_jacobian(r, &[0.3, -1.0], 0.5, 4000, 7, &pattern)?;
/// for (value, exact) in j.values.iter().zip([2.0, 1.0, -3.0]) {
///     assert!((value - exact).abs() < 0.2, "{value} vs {exact}");
/// }
/// // Within a few standard errors (each from the spread of the pairs).
/// assert!((j.values[2] + 3.0).abs() < 4.0 * j.standard_errors[2]);
/// # Ok::<(), plateau_free::Error>(())
/// ```
///
/// # Errors
/// An empty or non-finite `theta`, a `theta` whose length is not the pattern's parameter
/// count, `sigma` not finite and positive, zero pairs, a non-finite output
/// ([`Error::NonFiniteValue`], naming the point), a perturbed point that overflows.
pub fn smoothed_jacobian<F>(
    mut r: F,
    theta: &[f64],
    sigma: f64,
    pairs: usize,
    seed: u64,
    sparsity: &Sparsity,
) -> Result<JacobianEstimate, Error>
where
    F: FnMut(&[f64], u64, &mut [f64]),
{
    check::theta(theta)?;
    check::len("theta", theta.len(), sparsity.params())?;
    check::sigma(sigma)?;
    check::at_least_one("pairs", pairs)?;
    let (n, m) = (theta.len(), sparsity.outputs());
    let mut acc = Accumulator::new(sparsity, true);
    let (mut tau, mut point) = (vec![0.0; n], vec![0.0; n]);
    let (mut plus, mut minus) = (vec![0.0; m], vec![0.0; m]);
    for k in 0..pairs {
        draw(seed, 0, k, sigma, &mut tau);
        let s = pair_seed(seed, 0, k);
        for (sign, out) in [(1.0, &mut plus), (-1.0, &mut minus)] {
            for ((p, &t), &x) in point.iter_mut().zip(&tau).zip(theta) {
                *p = x + sign * t;
            }
            if let Some(index) = point.iter().position(|v| !v.is_finite()) {
                return Err(Error::NonFinitePoint {
                    sample: 2 * k,
                    index,
                    value: point[index],
                });
            }
            r(&point, s, out);
            let sample = 2 * k + usize::from(sign < 0.0);
            check_outputs(out, m, |_| point.clone(), sample)?;
        }
        acc.add(sparsity, &tau, sigma, &plus, &minus);
    }
    Ok(acc.finish())
}
