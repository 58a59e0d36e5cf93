//! The limited-memory part of the low-rank-plus-diagonal metric ([`crate::run::Metric::LowRank`]):
//! `m` direction vectors that stretch the draws along the search's recent progress, in
//! `O(m n)` memory and time per sample.
//!
//! The draw is `y = D M z` with `z ~ N(0, I)`, `D` the diagonal metric's scales and
//! `M = F_m ... F_1`, `F_j = (1 - cd_j) I + cd_j v_j v_j^T`: the limited-memory matrix
//! adaptation of LM-MA-ES (Loshchilov, Glasmachers and Beyer, "Large Scale Black-Box
//! Optimization by Limited-Memory Matrix Adaptation", IEEE TEVC 23(2), 2019), whose vectors
//! `v_j` are evolution paths of the selected `z` at rates `cc_j = lambda / (4^(j-1) n)`, with
//! `cd_j = 1 / (1.5^(j-1) n)` and `m = 4 + floor(3 ln n)`. Each `F_j` is a rank-one change of a
//! multiple of the identity, so `M^{-1}` is as cheap as `M` (Sherman-Morrison), which maps a
//! point repaired onto the bounds back to its `z`. The diagonal learns, from the `D z`, what
//! the directions leave.
//!
//! Implemented here from the published formulas; no code is taken from any other project.

use nalgebra::DVector;

/// The direction vectors and their rates.
#[derive(Debug, Clone)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub(crate) struct LowRank {
    /// The paths `v_j`, `j = 1..m` (all zero before the first update).
    v: Vec<DVector<f64>>,
    /// `cd_j`: how much `F_j` moves a draw towards `v_j`.
    cd: Vec<f64>,
    /// `cc_j`: the learning rate of `v_j`.
    cc: Vec<f64>,
    /// Updates so far: `F_j` applies once `j <= updates` (a zero path is no direction).
    updates: usize,
}

impl LowRank {
    /// The directions for dimension `n` and population `lambda`, LM-MA-ES's `m` and rates.
    pub fn new(n: usize, lambda: usize) -> LowRank {
        let nf = n as f64;
        let m = 4 + (3.0 * nf.ln().max(0.0)).floor() as usize;
        let cd = (0..m).map(|j| 1.0 / (1.5f64.powi(j as i32) * nf)).collect();
        let cc = (0..m)
            .map(|j| (lambda as f64 / (4f64.powi(j as i32) * nf)).min(1.0))
            .collect();
        LowRank {
            v: vec![DVector::zeros(n); m],
            cd,
            cc,
            updates: 0,
        }
    }

    /// The number of factors in use.
    fn active(&self) -> usize {
        self.updates.min(self.v.len())
    }

    /// `u <- M u`.
    pub fn apply(&self, u: &mut DVector<f64>) {
        for j in 0..self.active() {
            let (c, v) = (self.cd[j], &self.v[j]);
            let along = c * v.dot(u);
            *u *= 1.0 - c;
            u.axpy(along, v, 1.0);
        }
    }

    /// `u <- M^{-1} u`: `F_j^{-1} = (I - a v v^T) / (1 - c)`, `a = c / (1 - c + c |v|^2)`.
    pub fn apply_inverse(&self, u: &mut DVector<f64>) {
        for j in (0..self.active()).rev() {
            let (c, v) = (self.cd[j], &self.v[j]);
            let a = c / (1.0 - c + c * v.norm_squared());
            let along = -a * v.dot(u);
            u.axpy(along, v, 1.0);
            *u /= 1.0 - c;
        }
    }

    /// Moves every path towards the generation's weighted mean `zw` of the selected `z`
    /// (`mueff` its effective number of points).
    pub fn update(&mut self, zw: &DVector<f64>, mueff: f64) {
        for (v, &c) in self.v.iter_mut().zip(&self.cc) {
            v.axpy((mueff * c * (2.0 - c)).sqrt(), zw, 1.0 - c);
        }
        self.updates += 1;
    }

    /// A read-back part's sizes against the dimension `n`.
    #[cfg(feature = "serde")]
    pub fn check(&self, n: usize) -> Result<(), crate::error::Error> {
        use crate::check::len;
        len("low-rank rates", self.cd.len(), self.v.len())?;
        len("low-rank rates", self.cc.len(), self.v.len())?;
        for v in &self.v {
            len("low-rank direction", v.len(), n)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_inverse_undoes_the_map() {
        let n = 7;
        let mut lr = LowRank::new(n, 10);
        for k in 0..12 {
            let zw = DVector::from_fn(n, |i, _| ((i * 3 + k) % 5) as f64 - 2.0);
            lr.update(&zw, 3.0);
        }
        let u0 = DVector::from_fn(n, |i, _| (i as f64).sin());
        let mut u = u0.clone();
        lr.apply(&mut u);
        assert!((&u - &u0).norm() > 1e-3);
        lr.apply_inverse(&mut u);
        assert!((&u - &u0).norm() < 1e-12 * u0.norm());
    }
}
