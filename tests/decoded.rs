//! The diagonally decoded full metric ([`Metric::Decoded`]) learns axis-parallel scales at
//! rates of order `n^-0.75`: on an axis-parallel ellipsoid of condition 1e6 at n = 40 it
//! reaches 1e-8 within `1000 n` evaluations, where the full metric, whose rates fall as
//! `n^-2`, is still far above; and on a rotated ellipsoid, which the diagonal cannot help
//! with, it learns the rotation as the full metric does. Seeded runs.

use plateau_free::{run::Metric, Minimizer, Minimum};

mod common;
use common::{dot, orthonormal};

/// `sum_i 10^(6 i / (n - 1)) z_i^2` of `z = R (x - 1)`, `R` a rotation (the identity for
/// `rotated` false).
fn ellipsoid(n: usize, rotated: bool) -> impl Fn(&[f64]) -> f64 + Clone {
    let axes = if rotated { rotation(n) } else { Vec::new() };
    move |x: &[f64]| {
        let shifted: Vec<f64> = x.iter().map(|v| v - 1.0).collect();
        let z: Vec<f64> = if rotated {
            axes.iter().map(|row| dot(row, &shifted)).collect()
        } else {
            shifted
        };
        z.iter()
            .enumerate()
            .map(|(i, v)| 1e6f64.powf(i as f64 / (n - 1) as f64) * v * v)
            .sum()
    }
}

/// An orthonormal basis of dense vectors (a fixed sequence, Gram-Schmidt).
fn rotation(n: usize) -> Vec<Vec<f64>> {
    orthonormal((0..n).map(|k| {
        (0..n)
            .map(|i| {
                let diagonal = if i == k { 40.0 } else { 0.0 };
                (((i + 1) * (k + 2) * 7919) % 31) as f64 - 15.0 + diagonal
            })
            .collect()
    }))
}

/// The decoded and the full metric from the same start and seed, `1000 n` evaluations.
fn both(f: impl Fn(&[f64]) -> f64 + Clone, n: usize, seed: u64) -> (Minimum, Minimum) {
    let run = |metric| {
        Minimizer::new(f.clone())
            .metric(metric)
            .budget(1000 * n)
            .target(1e-8)
            .sigma0(2.0)
            .seed(seed)
            .run(&vec![0.0; n])
            .unwrap()
    };
    (run(Metric::Decoded), run(Metric::Full))
}

#[test]
fn decoding_learns_an_axis_parallel_ellipsoid_the_full_metric_does_not() {
    let n = 40;
    for seed in 0..2 {
        let (decoded, full) = both(ellipsoid(n, false), n, seed);
        assert!(decoded.fun <= 1e-8, "seed {seed}: decoded {decoded:?}");
        // Within about a third of the budget (the full metric needs more than all of it).
        assert!(
            decoded.evaluations < 1000 * n / 3,
            "seed {seed}: {decoded:?}"
        );
        assert!(full.fun > 1e-4, "seed {seed}: full {}", full.fun);
    }
}

#[test]
fn decoding_keeps_the_full_metric_on_a_rotated_ellipsoid() {
    let n = 10;
    for seed in 0..2 {
        let (decoded, full) = both(ellipsoid(n, true), n, seed);
        assert!(decoded.fun <= 1e-8, "seed {seed}: decoded {decoded:?}");
        assert!(full.fun <= 1e-8, "seed {seed}: full {full:?}");
        // The decoding slows while the correlations are far from learned, so it costs
        // little here: within a quarter more evaluations than the full metric's.
        let (d, f) = (decoded.evaluations, full.evaluations);
        assert!(4 * d <= 5 * f, "seed {seed}: decoded {d}, full {f}");
    }
}
