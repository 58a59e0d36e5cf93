//! Helpers shared by the integration tests (`mod common;` in each test file that needs them).
//!
//! Each file under `tests/` is its own crate and uses only some of these, so the unused ones
//! would warn in the others.
#![allow(dead_code)]

pub mod ask_tell;
pub mod fuzz;

use std::fmt::Debug;

use plateau_free::lifecycle::{Interrupt, Observer, Progress};
use plateau_free::{GradientEstimator, Objective, PlateauFreeGradient};

/// The 2-D tilted step `1[x + 2y > 0.3]`: from (1, 1) the edge is 2.7 away along `x + 2y`,
/// a plateau for any local method.
pub fn tilted_2d(x: &[f64]) -> f64 {
    if x[0] + 2.0 * x[1] > 0.3 {
        1.0
    } else {
        0.0
    }
}

/// `a . b`.
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// `vectors` made orthonormal in their order (Gram-Schmidt): dense axes for rotated test
/// functions, the same for every run.
pub fn orthonormal(vectors: impl IntoIterator<Item = Vec<f64>>) -> Vec<Vec<f64>> {
    let mut axes: Vec<Vec<f64>> = Vec::new();
    for mut v in vectors {
        for a in &axes {
            let d = dot(&v, a);
            v.iter_mut().zip(a).for_each(|(x, y)| *x -= d * y);
        }
        let norm = dot(&v, &v).sqrt();
        v.iter_mut().for_each(|x| *x /= norm);
        axes.push(v);
    }
    axes
}

/// The exact bit patterns of `v`, for comparisons that must hold bit for bit (`-0.0` and
/// `0.0` differ, and a NaN equals itself).
pub fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// The mean of `k` draws and its standard error (the sample standard deviation over
/// `sqrt(k)`), two-pass.
pub fn mean_and_standard_error(draws: &[f64]) -> (f64, f64) {
    let k = draws.len() as f64;
    let mean = draws.iter().sum::<f64>() / k;
    let sd = (draws.iter().map(|g| (g - mean).powi(2)).sum::<f64>() / (k - 1.0)).sqrt();
    (mean, sd / k.sqrt())
}

/// The gradients of `k` consecutive estimates at `theta` with spread `sigma`, coordinate by
/// coordinate: `draws[i][j]` is coordinate `i` of estimate `j`.
pub fn gradient_draws<G: GradientEstimator>(
    est: &mut G,
    theta: &[f64],
    sigma: f64,
    k: usize,
) -> Vec<Vec<f64>> {
    let mut draws = vec![Vec::with_capacity(k); theta.len()];
    for _ in 0..k {
        let g = est.estimate(theta, sigma).expect("valid input").gradient;
        for (coordinate, gi) in draws.iter_mut().zip(g) {
            coordinate.push(gi);
        }
    }
    draws
}

/// Runs `run` on the estimator `make` builds, with sequential evaluation twice and then with
/// parallel evaluation, and asserts that all three give the same result: a run repeats
/// exactly, and parallel evaluation does not change it.
pub fn assert_repeats_sequential_and_parallel<F, T>(
    make: impl Fn() -> PlateauFreeGradient<F>,
    run: impl Fn(&mut PlateauFreeGradient<F>) -> T,
) where
    F: Objective + Sync,
    T: PartialEq + Debug,
{
    let go = |parallel: bool| run(&mut make().parallel(parallel));
    let first = go(false);
    assert_eq!(first, go(false), "a second sequential run");
    assert_eq!(first, go(true), "parallel evaluation");
}

/// Triggers `interrupt` once the run has completed `at` iterations.
pub struct StopAt(pub usize, pub Interrupt);

impl Observer for StopAt {
    fn observe(&mut self, p: &Progress) {
        if p.iteration >= self.0 {
            self.1.trigger();
        }
    }
}
