//! Diagonal decoding of the full metric ([`crate::run::Metric::Decoded`]): the covariance is
//! `D C D`, a diagonal `D` learned at separable CMA-ES-like rates on top of the full `C`.
//!
//! The full metric's rates fall as `1 / n^2`: at n = 80 its rank-mu rate is about 3e-4 a
//! generation, and learning the scales of an axis-parallel ellipsoid of condition 1e6 (bbob
//! f2) takes more than the `1000 n` evaluations of bbob-largescale, which separable CMA-ES
//! solves within them. Diagonal decoding (Akimoto and Hansen, "Diagonal Acceleration for
//! Covariance Matrix Adaptation Evolution Strategies", Evolutionary Computation 28(3), 2020)
//! keeps the full `C` for rotated structure and learns the per-coordinate scales `D`
//! separately, at rates of order `1 / n^0.75`:
//!
//! - a draw is `y = D C^{1/2} z`; `C` learns as the full metric does, from the decoded offsets
//!   `D^{-1} y`, at the paper's rates for its `n (n + 1) / 2` parameters (below), which from
//!   about n = 20 on are faster than the plain full metric's (about 1.5 times at n = 80);
//! - `D` moves multiplicatively, `D_i <- D_i exp(delta_i / (2 beta))`, with `delta_i` the
//!   rank-one and rank-mu terms of the whitened offsets' squares minus their expectation
//!   (`z_i^2 - 1`), and `beta = max(1, sqrt(cond C) - 1)`: while `C` is far from a multiple of
//!   the identity, the two would learn the same stretch, so `D` slows down;
//! - at each eigendecomposition, `C`'s diagonal moves into `D` (`C` becomes a correlation
//!   matrix), so that `D` holds every coordinate's scale.
//!
//! The rates are the paper's for `m` parameters: `c1 = 1 / (2 (m / n + 1) (n + 1)^0.75 +
//! mueff / 2)` and `cmu = min(mu' c1, 1 - c1)` with `mu' = mueff + 1 / mueff - 2 + lambda / (2
//! (lambda + 5))`; `m = n` for `D`, whose path cumulates at `cc = sqrt(mueff c1) / 2`, and
//! `m = n (n + 1) / 2` for `C` (the active update's weights sized for them). `D` learns from
//! the positive weights only, as the diagonal metric does (with the negative ones as well, the
//! rotated discus at n = 80 ended higher). Implemented here from the published formulas; no
//! code is taken from any other project.

use nalgebra::{DMatrix, DVector};

use super::Params;

/// `D`, its evolution path and its rates.
#[derive(Debug, Clone)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub(crate) struct Decoding {
    /// The per-coordinate scales `D`.
    pub scale: DVector<f64>,
    /// `D`'s evolution path of the mean shifts (in the search's coordinates).
    path: DVector<f64>,
    /// The path's expected squared length per coordinate so far (0 at the start, 1 in the
    /// limit): the rank-one term subtracts it, so that a young path is not read as a shrink.
    gamma: f64,
    c1: f64,
    cmu: f64,
    cc: f64,
}

/// dd-CMA-ES's rank-one and rank-mu rates for `m` parameters learned from the population of
/// `p`: `c1 = 1 / (2 (m / n + 1) (n + 1)^0.75 + mueff / 2)` and `cmu = min(mu' c1, 1 - c1)`.
fn rates(p: &Params, n: usize, m: f64) -> (f64, f64) {
    let (nf, lambda) = (n as f64, p.lambda as f64);
    let c1 = 1.0 / (2.0 * (m / nf + 1.0) * (nf + 1.0).powf(0.75) + p.mueff / 2.0);
    let mu_prime = p.mueff + 1.0 / p.mueff - 2.0 + lambda / (2.0 * (lambda + 5.0));
    (c1, (mu_prime * c1).min(1.0 - c1).max(0.0))
}

/// The rates of `C` under the decoding: dd-CMA-ES's for its `n (n + 1) / 2` parameters, a
/// faster than the plain full metric's (Hansen 2016) from about n = 20 on.
pub(super) fn correlation_rates(p: &Params, n: usize) -> (f64, f64) {
    let nf = n as f64;
    rates(p, n, nf * (nf + 1.0) / 2.0)
}

impl Decoding {
    /// `D = scales` for the strategy parameters `p`.
    pub fn new(scales: &DVector<f64>, p: &Params) -> Decoding {
        let n = scales.len();
        let (c1, cmu) = rates(p, n, n as f64);
        Decoding {
            scale: scales.clone(),
            path: DVector::zeros(scales.len()),
            gamma: 0.0,
            c1,
            cmu,
            cc: (p.mueff * c1).sqrt() / 2.0,
        }
    }

    /// The path's length against the dimension, for checkpoints read back.
    #[cfg(feature = "serde")]
    pub fn check(&self, n: usize) -> Result<(), crate::error::Error> {
        crate::check::len("search decoding", self.scale.len(), n)?;
        crate::check::len("search decoding path", self.path.len(), n)
    }

    /// Clears the path (the mean moved elsewhere).
    pub fn clear_path(&mut self) {
        self.path.fill(0.0);
        self.gamma = 0.0;
    }

    /// Follows the mean shift `yw` (in units of sigma; `hs` 0 stalls the path as it stalls
    /// the full metric's).
    pub fn follow(&mut self, yw: &DVector<f64>, hs: f64, mueff: f64) {
        let cc = self.cc;
        self.path
            .axpy(hs * (cc * (2.0 - cc) * mueff).sqrt(), yw, 1.0 - cc);
        self.gamma = (1.0 - cc).powi(2) * self.gamma + hs * cc * (2.0 - cc);
    }

    /// The path (in the search's coordinates), for the caller to whiten.
    pub fn path(&self) -> &DVector<f64> {
        &self.path
    }

    /// Moves `D` from the whitened path `zpath` and the selected whitened draws `zs` with their
    /// positive weights; `cond_sqrt` is `sqrt(cond C)` (`beta`'s argument).
    pub fn update(&mut self, zpath: &DVector<f64>, zs: &[(f64, DVector<f64>)], cond_sqrt: f64) {
        let beta = (cond_sqrt - 1.0).max(1.0);
        let mut delta = zpath.map(|z| self.c1 * (z * z - self.gamma));
        for (w, z) in zs {
            delta.zip_apply(z, |d, z| *d += self.cmu * w * (z * z - 1.0));
        }
        self.scale
            .zip_apply(&delta, |s, d| *s *= (d / (2.0 * beta)).exp());
    }

    /// Moves `C`'s diagonal into `D`: `C` becomes a correlation matrix.
    pub fn absorb(&mut self, cov: &mut DMatrix<f64>) {
        let s = cov.diagonal().map(|v| v.max(f64::MIN_POSITIVE).sqrt());
        let n = s.len();
        for i in 0..n {
            for j in 0..n {
                cov[(i, j)] /= s[i] * s[j];
            }
        }
        self.scale.component_mul_assign(&s);
    }
}
