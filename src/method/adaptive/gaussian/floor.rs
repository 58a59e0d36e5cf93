//! The floor on the spread along a discrete coordinate ([`crate::Minimizer::steps`]).
//!
//! Along a coordinate of step `s` the objective is a staircase whose treads are `s` wide.
//! Smoothed by a Gaussian of standard deviation `sd` along it, the staircase becomes a smooth
//! function only while `sd` is not small next to `s`: below, the smoothed function is flat
//! across the tread the mean stands on (its gradient is the jumps at the tread's edges
//! weighted by the kernel there, `exp(-(s / 2)^2 / (2 sd^2))` at the centre), every draw
//! rounds to the same value, and ranks no longer tell directions apart. The covariance
//! update then shrinks the coordinate further (its selected steps are no longer than the
//! others'), and the coordinate is frozen where it stands for the rest of the run.
//!
//! The floor keeps the probability that a draw leaves the mean's tread, from its centre,
//! at least `alpha = 1 / (n lambda)`: the margin of CMA-ES with margin (Hamano, Saito,
//! Nomura and Shirakawa, GECCO 2022), one coordinate's change in about every `n`
//! generations. From the centre a draw leaves when `|N(0, sd^2)| > s / 2`, so
//! `sd >= s / (2 Phi^{-1}(1 - alpha / 2))`: about `0.2 s` for the usual populations, the
//! bound pycma's integer handling also settles on (Marty, Semet, Auger, Hansen and Tran,
//! 2024). A coordinate whose spread fell below its floor has its row and column of the
//! covariance scaled up to it; the others keep theirs.

use nalgebra::DMatrix;

use super::SearchGaussian;
use crate::kernel::normal_cdf;

/// The floors of a run of `lambda` draws in dimension `n` for the steps `steps` (0 for a
/// continuous coordinate, whose floor is 0).
pub(crate) fn floors(steps: &[f64], lambda: usize) -> Vec<f64> {
    let alpha = 1.0 / (steps.len() * lambda.max(1)) as f64;
    let z = upper_quantile(alpha / 2.0);
    steps.iter().map(|s| s / (2.0 * z)).collect()
}

/// `Phi^{-1}(1 - p)` for `p` in `(0, 1/2]`, by bisection on [`normal_cdf`] (once per run).
fn upper_quantile(p: f64) -> f64 {
    let (mut lo, mut hi) = (0.0, 40.0);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if normal_cdf(-mid) > p {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

impl SearchGaussian {
    /// Raises every coordinate's standard deviation `sigma sqrt(C_ii)` to its floor (see
    /// the module), scaling the covariance's rows and columns; the full metric is then
    /// decomposed again.
    pub(super) fn apply_floors(&mut self) {
        if self.floors.is_empty() {
            return;
        }
        let mut scale = vec![1.0; self.n];
        let mut raised = false;
        for (i, &floor) in self.floors.iter().enumerate() {
            let sd = self.sigma * self.variance(i).sqrt();
            if floor > 0.0 && sd < floor && sd > 0.0 {
                scale[i] = floor / sd;
                raised = true;
            }
        }
        if !raised {
            return;
        }
        match (&mut self.full, &mut self.decoding) {
            (Some(_), Some(decoding)) => decoding
                .scale
                .iter_mut()
                .zip(&scale)
                .for_each(|(d, s)| *d *= s),
            (Some((cov, _)), None) => {
                let d = DMatrix::from_diagonal(&nalgebra::DVector::from_vec(scale));
                *cov = &d * &*cov * &d;
                self.decompose();
            }
            (None, _) => self.d.iter_mut().zip(&scale).for_each(|(d, s)| *d *= s),
        }
    }

    /// The covariance's condition number that [`super::RunEnd::Condition`] tests against
    /// `limit`. The floors raise the discrete coordinates' variances in `C` on purpose, so
    /// with floors and at least two continuous coordinates it is the condition of the
    /// continuous coordinates' block (a block of one coordinate has none: the whole matrix
    /// is tested then); the block is computed only when the whole matrix passes `limit`.
    pub(super) fn condition(&self, limit: f64) -> f64 {
        // With diagonal decoding, cond(D C D) <= cond(D) cond(C): a bound, not the value.
        let (hi, lo) = self.decoding_range();
        let whole = (self.d.max() / self.d.min() * hi / lo).powi(2);
        if whole <= limit || self.floors.is_empty() {
            return whole;
        }
        let continuous: Vec<usize> = (0..self.n).filter(|&i| self.floors[i] <= 0.0).collect();
        if continuous.len() < 2 {
            return whole;
        }
        let (largest, smallest) = match &self.full {
            Some((cov, _)) => {
                let k = continuous.len();
                let scale = |i: usize| self.decoding.as_ref().map_or(1.0, |dd| dd.scale[i]);
                let block = DMatrix::from_fn(k, k, |a, b| {
                    let (i, j) = (continuous[a], continuous[b]);
                    scale(i) * cov[(i, j)] * scale(j)
                });
                let e = block.symmetric_eigenvalues();
                (e.max(), e.min())
            }
            None => {
                let d = continuous.iter().map(|&i| self.d[i] * self.d[i]);
                d.fold((0.0f64, f64::INFINITY), |(hi, lo), v| {
                    (hi.max(v), lo.min(v))
                })
            }
        };
        largest / smallest.max(f64::MIN_POSITIVE)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_floor_keeps_the_margin_of_leaving_the_tread() {
        assert!((upper_quantile(0.025) - 1.959_964).abs() < 1e-5);
        let f = floors(&[0.0, 1.0, 2.0], 10);
        assert_eq!(f[0], 0.0);
        // A draw from the tread's centre leaves it with probability 1 / (n lambda).
        let leave = 2.0 * normal_cdf(-0.5 / f[1]);
        assert!((leave - 1.0 / 30.0).abs() < 1e-9, "{leave}");
        assert_eq!(f[2], 2.0 * f[1]);
    }

    #[test]
    fn the_condition_leaves_out_the_raised_discrete_coordinates() {
        // A discrete coordinate raised far above the others: condition 1e16 over the whole.
        for full in [true, false] {
            let mut run = SearchGaussian::new(&[0.0; 3], 1.0, &[1.0, 1e8, 2.0], 6, full);
            assert_eq!(run.condition(1e14), 1e16);
            run.floors = vec![0.0, 0.5, 0.0];
            // The continuous block diag(1, 4).
            assert!((run.condition(1e14) - 4.0).abs() < 1e-9, "{full}");
            // Below the limit the whole matrix is the answer (a block's is never larger).
            assert_eq!(run.condition(1e17), 1e16);
            // One continuous coordinate: no block to judge, the whole matrix is tested.
            run.floors = vec![0.5, 0.5, 0.0];
            assert_eq!(run.condition(1e14), 1e16);
        }
        // A rotated block: the condition of its eigenvalues, not of its diagonal.
        let mut run = SearchGaussian::new(&[0.0; 3], 1.0, &[1.0, 1e8, 2.0], 6, true);
        run.floors = vec![0.0, 0.5, 0.0];
        let (cov, _) = run.full.as_mut().unwrap();
        cov[(0, 2)] = 1.5;
        cov[(2, 0)] = 1.5;
        // [[1, 1.5], [1.5, 4]]: eigenvalues (5 +- sqrt(18)) / 2.
        let root = 18f64.sqrt();
        let expected = (5.0 + root) / (5.0 - root);
        assert!((run.condition(1e14) - expected).abs() < 1e-9 * expected);
    }
}
