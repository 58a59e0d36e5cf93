//! The Hessian of the Gaussian-smoothed objective, from values of `f` alone.
//!
//! With `Q_sigma(theta) = E_{eps ~ N(0, I)} f(theta + sigma eps)`, Stein's identity applied twice
//! gives
//!
//! ```text
//! grad^2 Q_sigma(theta) = E[ f(theta + sigma eps) (eps eps^T - I) ] / sigma^2.
//! ```
//!
//! The estimate pairs every `eps` with `-eps` (both have the same `eps eps^T`) and takes as
//! control variate the mean of the other pairs' values (`E[eps eps^T - I] = 0` and the pairs
//! are independent, so the estimate stays unbiased), with `w_k = (f(theta + sigma eps_k) +
//! f(theta - sigma eps_k)) / 2`:
//!
//! ```text
//! H = 1/P sum_k (w_k - mean_{j != k} w_j) (eps_k eps_k^T - I) / sigma^2
//!   = 1/(P - 1) sum_k (w_k - mean w) eps_k eps_k^T / sigma^2
//! ```
//!
//! `2P` evaluations, `P >= 2`. The odd part of `f` cancels within a pair, and its constant and
//! its mean curvature `sigma^2 tr(H) / 2` across pairs: a control variate of `f(theta)` alone
//! leaves the latter in every term, whose spread then grows with `n` (on the sphere about
//! `sqrt(2) n` per term against `sqrt(4 n)`, `tests/hessian.rs`). It is exact in expectation for
//! every `f`, a plateau included: for the
//! step `1[x > 0]`, `Q_sigma(x) = Phi(x / sigma)` and the estimate converges to its second
//! derivative `-x / sigma^3 phi(x / sigma)` (`tests/hessian.rs`). Storage is `5 n^2`.
//! No method of [`crate::minimize`] uses it: trust-region Newton steps built on this estimator
//! lost to the adaptive search on the comparison's suite (`docs/convergence.md`, table 9),
//! because a usable `n x n` estimate costs about `n^2` pairs.

use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;

use crate::check;
use crate::error::{Error, ParameterValue};

/// A Hessian estimate with its per-entry standard errors.
#[derive(Debug, Clone, PartialEq)]
pub struct HessianEstimate {
    /// `n x n`, row-major, symmetric.
    pub hessian: Vec<f64>,
    /// The standard error of each entry (the spread of the pairs' terms over `sqrt(P)`).
    pub standard_error: Vec<f64>,
    /// Evaluations of `f`: `2 pairs`.
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
/// assert_eq!(h.evaluations, 8000);
/// # Ok::<(), plateau_free::Error>(())
/// ```
///
/// # Errors
/// An empty or non-finite `theta`, a bad `sigma`, zero pairs ([`Error::ZeroSamples`]) or one
/// ([`Error::InvalidParameter`]: the control variate needs another pair), or `f` returning NaN
/// or an infinity ([`Error::NonFiniteValue`]).
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
    if pairs == 1 {
        return Err(Error::InvalidParameter {
            name: "pairs",
            value: ParameterValue::Integer(1),
            reason: "must be at least 2: each pair's control variate is the others' mean",
        });
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
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut sums = Sums::new(n);
    let (mut eps, mut plus, mut minus) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    // The first pair's value is subtracted from every pair's: the control variate removes any
    // constant, and a huge `f` keeps its small differences.
    let mut shift = None;
    for _ in 0..pairs {
        for i in 0..n {
            eps[i] = StandardNormal.sample(&mut rng);
            plus[i] = theta[i] + sigma * eps[i];
            minus[i] = theta[i] - sigma * eps[i];
        }
        let w = 0.5 * eval(&plus)? + 0.5 * eval(&minus)?;
        let shift = *shift.get_or_insert(w);
        sums.add(w - shift, &eps);
    }
    let (hessian, standard_error) = sums.estimate(sigma);
    Ok(HessianEstimate {
        hessian,
        standard_error,
        evaluations,
    })
}

/// Per upper-triangle entry `(i, j)`, with `e = eps_i eps_j - delta_ij` (centred, so that the
/// terms' spread is the estimate's: the `delta` itself sums to nothing against `w - mean w`)
/// and `w` a pair's value: the sums
/// of `w e`, `e`, `w^2 e^2`, `w e^2` and `e^2` over the pairs (one pass, `O(n^2)` memory
/// whatever the number of pairs), and of `w`.
struct Sums {
    n: usize,
    pairs: usize,
    w: f64,
    we: Vec<f64>,
    e: Vec<f64>,
    wwee: Vec<f64>,
    wee: Vec<f64>,
    ee: Vec<f64>,
}

impl Sums {
    fn new(n: usize) -> Self {
        let zeros = vec![0.0; n * n];
        Sums {
            n,
            pairs: 0,
            w: 0.0,
            we: zeros.clone(),
            e: zeros.clone(),
            wwee: zeros.clone(),
            wee: zeros.clone(),
            ee: zeros,
        }
    }

    fn add(&mut self, w: f64, eps: &[f64]) {
        let n = self.n;
        self.pairs += 1;
        self.w += w;
        for i in 0..n {
            for j in i..n {
                let k = i * n + j;
                let e = eps[i] * eps[j] - if i == j { 1.0 } else { 0.0 };
                self.we[k] += w * e;
                self.e[k] += e;
                self.wwee[k] += w * w * e * e;
                self.wee[k] += w * e * e;
                self.ee[k] += e * e;
            }
        }
    }

    /// The estimate and its standard errors: the terms are `t_k = P / (P - 1) (w_k - mean w)
    /// e_k / sigma^2`, whose mean is the estimate; their spread comes from the sums.
    fn estimate(&self, sigma: f64) -> (Vec<f64>, Vec<f64>) {
        let (n, p) = (self.n, self.pairs as f64);
        let mean_w = self.w / p;
        let scale = p / ((p - 1.0) * sigma * sigma);
        let mut hessian = vec![0.0; n * n];
        let mut standard_error = vec![0.0; n * n];
        for i in 0..n {
            for j in i..n {
                let k = i * n + j;
                let mean = (self.we[k] - mean_w * self.e[k]) * scale / p;
                let squares = (self.wwee[k] - 2.0 * mean_w * self.wee[k]
                    + mean_w * mean_w * self.ee[k])
                    * scale
                    * scale;
                let var = ((squares / p - mean * mean) * p / (p - 1.0)).max(0.0);
                let se = (var / p).sqrt();
                for (a, b) in [(i, j), (j, i)] {
                    hessian[a * n + b] = mean;
                    standard_error[a * n + b] = se;
                }
            }
        }
        (hessian, standard_error)
    }
}
