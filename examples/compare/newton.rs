//! Newton steps on the Gaussian-smoothed objective, in a trust region: the measurement of
//! whether the smoothed Hessian pays as a step's curvature (`docs/convergence.md`, table 9).
//! It is a method of this comparison, not of the library.
//!
//! Each iteration draws `P = max(n, 2)` antithetic pairs `x +- sigma B eps` (`eps ~ N(0, I)`,
//! `B` the metric below) and estimates from them, by Stein's identity in the whitened
//! coordinates `u` (`x + B u`), the smoothed gradient `1/P sum (f+ - f-) / (2 sigma) eps` and
//! the smoothed Hessian `1/(P - 1) sum (w_k - mean w) eps eps^T / sigma^2`, with
//! `w = (f+ + f-) / 2 - f(x)`: the estimator of `plateau_free::hessian`, whose control
//! variate is the batch's mean of `w`, here in the metric. Both are mapped back to `x`; the
//! Hessian is averaged over the last `max(10, n)` iterations.
//!
//! The step minimises `g^T d + d^T H d / 2` within the trust region `|B^-1 d| <= radius`
//! (exactly, in the whitened Hessian's eigenbasis) and is taken when `f` falls by at least a
//! tenth of the model's promise; the radius doubles after a good step on its boundary and
//! shrinks to a quarter of the step after a bad one. `sigma` is the radius: the model is
//! fitted at the scale where it is used. A flat model (a batch of equal values) or a step to
//! a point of equal value (both: a plateau of `f`) doubles the radius, and with it `sigma`.
//!
//! The metric `B` starts as the identity and is renewed once `max(10, n)` iterations have
//! sampled in it, from their Hessian in `u`: `B <- B Q diag(|mu| + nu)^(-1/2)` with `Q`, `mu`
//! its eigenvectors and eigenvalues and `nu` the size of its noise. Without the metric the
//! estimate's error follows the largest curvature and the smallest is never resolved.

use nalgebra::{DMatrix, DVector, SymmetricEigen};
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;

/// The first trust radius, which is also the first `sigma` (the library's default `sigma0`).
const RADIUS0: f64 = 0.5;
/// The smallest radius, relative to `1 + |x|`: below it steps are lost to rounding.
const RADIUS_MIN: f64 = 1e-15;

/// Runs the method on `f` from `x0`, spending at most `budget` evaluations.
pub(crate) fn run(f: impl Fn(&[f64]) -> f64, x0: &[f64], budget: usize, seed: u64) {
    let n = x0.len();
    let pairs = n.max(2);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut x = DVector::from_column_slice(x0);
    let mut fx = f(x.as_slice());
    let mut spent = 1;
    let mut radius = RADIUS0;
    let mut model = Model::new(n, 10.max(n));
    while spent + 2 * pairs < budget {
        let sigma = radius;
        model.fit(&f, &x, fx, sigma, pairs, &mut rng);
        spent += 2 * pairs;
        let (d, length) = model.step(radius);
        let promise = model.predict(&d);
        if model.window.count == model.memory * pairs {
            model.adapt();
        }
        if promise.is_nan() || promise >= 0.0 {
            radius *= 2.0;
            continue;
        }
        let y = &x + &d;
        let fy = f(y.as_slice());
        spent += 1;
        // A step to a point of equal value is on a plateau of `f`: it is taken and the radius
        // (with `sigma`) doubles, as a flat batch does, since only a wider spread sees past it.
        let rho = if fy == fx {
            f64::INFINITY
        } else {
            (fy - fx) / promise
        };
        if rho > 0.1 {
            x = y;
            fx = fy;
        }
        let floor = RADIUS_MIN * (1.0 + x.norm());
        radius = next_radius(radius, length, rho).max(floor);
    }
}

/// The trust radius after a step of length `step` whose decrease was `rho` times the promise.
fn next_radius(radius: f64, step: f64, rho: f64) -> f64 {
    if rho == f64::INFINITY {
        2.0 * radius
    } else if rho.is_nan() || rho < 0.25 {
        0.25 * step
    } else if rho > 0.75 && step > 0.9 * radius {
        2.0 * radius
    } else {
        radius
    }
}

/// The quadratic model: this iteration's gradient and the averaged Hessian, and the metric
/// `B` they are sampled in.
struct Model {
    gradient: DVector<f64>,
    hessian: DMatrix<f64>,
    metric: DMatrix<f64>,
    inverse: DMatrix<f64>,
    /// The Hessian's terms in the whitened coordinates since the metric last changed.
    window: Window,
    fits: usize,
    memory: usize,
}

/// Sums of the Hessian estimate's terms and of their squares, entry by entry.
struct Window {
    sum: DMatrix<f64>,
    squares: DMatrix<f64>,
    count: usize,
}

impl Window {
    fn new(n: usize) -> Self {
        Window {
            sum: DMatrix::zeros(n, n),
            squares: DMatrix::zeros(n, n),
            count: 0,
        }
    }

    fn add(&mut self, term: &DMatrix<f64>) {
        self.sum += term;
        self.squares += term.component_mul(term);
        self.count += 1;
    }

    /// The mean, and the spectral size of its noise: `2 sqrt(n)` times the entries' root mean
    /// square standard error (the largest eigenvalue of a symmetric matrix of independent
    /// entries of that spread).
    fn mean_and_noise(&self) -> (DMatrix<f64>, f64) {
        let k = self.count as f64;
        let mean = &self.sum / k;
        let variance = (&self.squares / k - mean.component_mul(&mean)) / (k - 1.0).max(1.0);
        let n = mean.nrows() as f64;
        let rms = (variance.map(|v| v.max(0.0)).sum() / (n * n)).sqrt();
        (mean, 2.0 * n.sqrt() * rms)
    }
}

impl Model {
    fn new(n: usize, memory: usize) -> Self {
        Model {
            gradient: DVector::zeros(n),
            hessian: DMatrix::zeros(n, n),
            metric: DMatrix::identity(n, n),
            inverse: DMatrix::identity(n, n),
            window: Window::new(n),
            fits: 0,
            memory,
        }
    }

    /// Estimates the gradient at `x` and adds a Hessian estimate to the average, from `pairs`
    /// antithetic pairs `x +- sigma B eps`: the estimates in the whitened `u` (`x = x + B u`),
    /// mapped back by `B^-1`.
    fn fit(
        &mut self,
        f: &impl Fn(&[f64]) -> f64,
        x: &DVector<f64>,
        fx: f64,
        sigma: f64,
        pairs: usize,
        rng: &mut Xoshiro256PlusPlus,
    ) {
        let n = x.len();
        let mut eps = Vec::with_capacity(pairs);
        let mut w = Vec::with_capacity(pairs);
        let mut gradient = DVector::zeros(n);
        for _ in 0..pairs {
            let e = DVector::from_fn(n, |_, _| StandardNormal.sample(rng));
            let step = sigma * (&self.metric * &e);
            let plus = f((x + &step).as_slice());
            let minus = f((x - &step).as_slice());
            gradient.axpy((plus - minus) / (2.0 * sigma * pairs as f64), &e, 1.0);
            w.push((plus + minus) / 2.0 - fx);
            eps.push(e);
        }
        let mean = w.iter().sum::<f64>() / pairs as f64;
        let mut batch = DMatrix::zeros(n, n);
        for (e, wk) in eps.iter().zip(&w) {
            // Each pair's term, scaled so that the terms' mean is the batch's estimate.
            let term = (e * e.transpose())
                * ((wk - mean) * pairs as f64 / ((pairs - 1) as f64 * sigma * sigma));
            self.window.add(&term);
            batch += term / pairs as f64;
        }
        let back = self.inverse.transpose();
        self.gradient = &back * gradient;
        let batch = &back * batch * &self.inverse;
        self.fits += 1;
        let share = 1.0 / self.fits.min(self.memory) as f64;
        self.hessian = (1.0 - share) * &self.hessian + share * batch;
    }

    /// The next metric, from the window's Hessian in the whitened coordinates: with its
    /// eigenvalues `mu` and the noise's size `nu`, `B <- B Q diag(|mu| + nu)^(-1/2)`, so that
    /// a curvature the samples have not resolved changes nothing; scaled so that `B`'s largest
    /// singular value is 1 (no sample or step goes further than `sigma` or the radius).
    fn adapt(&mut self) {
        let (mean, noise) = self.window.mean_and_noise();
        self.window = Window::new(mean.nrows());
        let eig = SymmetricEigen::new(mean);
        if !eig.eigenvalues.iter().all(|m| m.is_finite()) || !noise.is_finite() {
            return;
        }
        let top = eig.eigenvalues.amax() + noise;
        if top <= 0.0 {
            return;
        }
        let scale = eig
            .eigenvalues
            .map(|m| 1.0 / (m.abs() + noise).max(1e-12 * top).sqrt());
        let q = &eig.eigenvectors;
        let metric = &self.metric * q * DMatrix::from_diagonal(&scale);
        let largest = SymmetricEigen::new(&metric * metric.transpose())
            .eigenvalues
            .max()
            .sqrt();
        self.metric = metric / largest;
        self.inverse =
            DMatrix::from_diagonal(&scale.map(|s| largest / s)) * q.transpose() * &self.inverse;
    }

    /// The model's change `g^T d + d^T H d / 2` at the step `d`.
    fn predict(&self, d: &DVector<f64>) -> f64 {
        self.gradient.dot(d) + 0.5 * d.dot(&(&self.hessian * d))
    }

    /// The model's minimiser within `|B^-1 d| <= radius`, a trust region in the metric, and
    /// that length: in the whitened `u`, `u = -(H_u + lambda I)^-1 g_u` with the smallest
    /// `lambda >= max(0, -mu_min)` that keeps `u` inside (bisection on `lambda`), `d = B u`.
    fn step(&self, radius: f64) -> (DVector<f64>, f64) {
        let b = &self.metric;
        let g = b.transpose() * &self.gradient;
        let eig = SymmetricEigen::new(b.transpose() * &self.hessian * b);
        let gq = eig.eigenvectors.transpose() * &g;
        let mu = &eig.eigenvalues;
        let length = |lambda: f64| {
            gq.iter()
                .zip(mu.iter())
                .map(|(g, m)| (g / (m + lambda)).powi(2))
                .sum::<f64>()
                .sqrt()
        };
        let mu_min = mu.min();
        let mut lo = (-mu_min).max(0.0) * (1.0 + 1e-12) + f64::MIN_POSITIVE;
        let lambda = if mu_min > 0.0 && length(0.0) <= radius {
            0.0
        } else {
            let mut hi = mu_min.abs() + g.norm() / radius + f64::MIN_POSITIVE;
            for _ in 0..100 {
                let mid = 0.5 * (lo + hi);
                if length(mid) > radius {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            hi
        };
        let uq = DVector::from_fn(mu.len(), |i, _| -gq[i] / (mu[i] + lambda));
        (b * (&eig.eigenvectors * &uq), uq.norm())
    }
}
