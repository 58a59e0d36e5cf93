//! The Hessian of the Gaussian-smoothed objective, from values of `f` alone.
//!
//! With `Q_sigma(theta) = E_{eps ~ N(0, I)} f(theta + sigma eps)`, Stein's identity applied twice
//! gives
//!
//! ```text
//! grad^2 Q_sigma(theta) = E[ f(theta + sigma eps) (eps eps^T - I) ] / sigma^2.
//! ```
//!
//! The estimate pairs every `eps` with `-eps` (both have the same `eps eps^T`) and subtracts the
//! control variate `f(theta)` (`E[eps eps^T - I] = 0`, so the estimate stays unbiased while the
//! constant and the odd part of `f` cancel):
//!
//! ```text
//! H = 1/P sum_k [ (f(theta + sigma eps_k) + f(theta - sigma eps_k)) / 2 - f(theta) ] (eps_k eps_k^T - I) / sigma^2
//! ```
//!
//! `2P + 1` evaluations. It is exact in expectation for every `f`, a plateau included: for the
//! step `1[x > 0]`, `Q_sigma(x) = Phi(x / sigma)` and the estimate converges to its second
//! derivative `-x / sigma^3 phi(x / sigma)` (`tests/hessian.rs`). Storage is `n^2`.
//! No method of [`crate::minimize`] uses it: trust-region Newton steps built on this estimator
//! lost to the adaptive search on the comparison's suite (`docs/convergence.md`, table 9),
//! because a usable `n x n` estimate costs about `n^2` pairs.

use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;

use crate::check;
use crate::error::Error;

/// A Hessian estimate with its per-entry standard errors.
#[derive(Debug, Clone, PartialEq)]
pub struct HessianEstimate {
    /// `n x n`, row-major, symmetric.
    pub hessian: Vec<f64>,
    /// The standard error of each entry (the spread of the pairs' terms over `sqrt(P)`).
    pub standard_error: Vec<f64>,
    /// Evaluations of `f`: `2 pairs + 1`.
    pub evaluations: usize,
}

impl HessianEstimate {
    /// Entry `(i, j)`.
    pub fn get(&self, i: usize, j: usize) -> f64 {
        let n = (self.hessian.len() as f64).sqrt() as usize;
        self.hessian[i * n + j]
    }
}

/// Estimates `grad^2 Q_sigma(theta)` from `pairs` antithetic pairs (seeded).
///
/// ```
/// // f = x0^2 + 3 x0 x1: the smoothed Hessian of a quadratic is its Hessian, [[2, 3], [3, 0]].
/// let f = |x: &[f64]| x[0] * x[0] + 3.0 * x[0] * x[1];
/// let h = plateau_free::hessian::smoothed_hessian(f, &[0.5, -1.0], 0.3, 4000, 1)?;
/// assert!((h.get(0, 1) - 3.0).abs() < 5.0 * h.standard_error[1]);
/// # Ok::<(), plateau_free::Error>(())
/// ```
///
/// # Errors
/// An empty or non-finite `theta`, a bad `sigma`, zero pairs ([`Error::ZeroSamples`]), or `f`
/// returning NaN or an infinity ([`Error::NonFiniteValue`]).
pub fn smoothed_hessian<F: Fn(&[f64]) -> f64>(
    f: F,
    theta: &[f64],
    sigma: f64,
    pairs: usize,
    seed: u64,
) -> Result<HessianEstimate, Error> {
    check::theta(theta)?;
    check::sigma(sigma)?;
    if pairs == 0 {
        return Err(Error::ZeroSamples);
    }
    let n = theta.len();
    let mut evaluations = 0usize;
    let mut eval = |x: &[f64]| -> Result<f64, Error> {
        let v = f(x);
        evaluations += 1;
        if v.is_finite() {
            Ok(v)
        } else {
            Err(Error::NonFiniteValue {
                sample: evaluations - 1,
                value: v,
                point: x.to_vec(),
            })
        }
    };
    let f0 = eval(theta)?;
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut sum = vec![0.0; n * n];
    let mut sum_sq = vec![0.0; n * n];
    let mut eps = vec![0.0; n];
    let mut plus = vec![0.0; n];
    let mut minus = vec![0.0; n];
    let inv_s2 = 1.0 / (sigma * sigma);
    for _ in 0..pairs {
        for i in 0..n {
            eps[i] = StandardNormal.sample(&mut rng);
            plus[i] = theta[i] + sigma * eps[i];
            minus[i] = theta[i] - sigma * eps[i];
        }
        let d = 0.5 * (eval(&plus)? + eval(&minus)?) - f0;
        for i in 0..n {
            for j in i..n {
                let delta = if i == j { 1.0 } else { 0.0 };
                let t = d * (eps[i] * eps[j] - delta) * inv_s2;
                sum[i * n + j] += t;
                sum_sq[i * n + j] += t * t;
            }
        }
    }
    let p = pairs as f64;
    let mut hessian = vec![0.0; n * n];
    let mut standard_error = vec![0.0; n * n];
    for i in 0..n {
        for j in i..n {
            let mean = sum[i * n + j] / p;
            let var = if pairs > 1 {
                ((sum_sq[i * n + j] / p - mean * mean) * p / (p - 1.0)).max(0.0)
            } else {
                f64::INFINITY
            };
            let se = (var / p).sqrt();
            for (a, b) in [(i, j), (j, i)] {
                hessian[a * n + b] = mean;
                standard_error[a * n + b] = se;
            }
        }
    }
    Ok(HessianEstimate {
        hessian,
        standard_error,
        evaluations,
    })
}
