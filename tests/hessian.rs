//! `smoothed_hessian` against analytic Gaussian-smoothed Hessians, within stated standard
//! errors (seeded: the same draws every run).

use plateau_free::{hessian::smoothed_hessian, Error};

/// Every entry within `k` standard errors of the analytic value, and the errors small.
fn check(est: &plateau_free::hessian::HessianEstimate, exact: &[f64], k: f64, max_se: f64) {
    for (idx, ((h, se), e)) in est
        .hessian
        .iter()
        .zip(&est.standard_error)
        .zip(exact)
        .enumerate()
    {
        assert!(
            (h - e).abs() <= k * se,
            "entry {idx}: {h} vs exact {e} (se {se})"
        );
        assert!(*se < max_se, "entry {idx}: se {se}");
    }
}

#[test]
fn quadratic_hessian_is_exact_in_expectation() {
    // f = 1/2 x^T A x + b.x + 7: grad^2 Q_sigma = A for every sigma.
    let a = [[4.0, 1.0, -2.0], [1.0, 3.0, 0.5], [-2.0, 0.5, 1.0]];
    let f = |x: &[f64]| {
        let mut q = 7.0 + x[0] - 2.0 * x[2];
        for i in 0..3 {
            for j in 0..3 {
                q += 0.5 * x[i] * a[i][j] * x[j];
            }
        }
        q
    };
    let exact: Vec<f64> = a.iter().flatten().copied().collect();
    for (sigma, seed) in [(0.1, 1), (1.0, 2), (10.0, 3)] {
        let est = smoothed_hessian(f, &[0.3, -1.0, 2.0], sigma, 20_000, seed).unwrap();
        assert_eq!(est.evaluations, 40_000);
        check(&est, &exact, 4.5, 0.2);
    }
}

#[test]
fn cubic_smoothed_hessian() {
    // f = x0^3 + x0 x1^2: Q_sigma = f + 4 sigma^2 x0 (linear), so grad^2 Q = [[6 x0, 2 x1], [2 x1, 2 x0]].
    let f = |x: &[f64]| x[0].powi(3) + x[0] * x[1] * x[1];
    let theta = [0.5, -1.0];
    let exact = [3.0, -2.0, -2.0, 1.0];
    let est = smoothed_hessian(f, &theta, 0.3, 20_000, 9).unwrap();
    check(&est, &exact, 4.5, 0.2);
}

#[test]
fn a_steps_smoothed_hessian_is_seen_from_its_plateau() {
    // f = 1[x > 0]: Q_sigma(x) = Phi(x / sigma), Q'' = -x / sigma^3 phi(x / sigma). At x = -0.3
    // the plain second derivative is 0 (a plateau); the smoothed one is not.
    let f = |x: &[f64]| if x[0] > 0.0 { 1.0 } else { 0.0 };
    let (x, sigma) = (-0.3f64, 0.5f64);
    let u = x / sigma;
    let phi = (-0.5 * u * u).exp() / (2.0 * std::f64::consts::PI).sqrt();
    let exact = -x / sigma.powi(3) * phi;
    assert!(exact > 0.5);
    let est = smoothed_hessian(f, &[x], sigma, 50_000, 4).unwrap();
    check(&est, &[exact], 4.5, 0.1);
}

#[test]
fn bad_input_is_an_error() {
    let f = |x: &[f64]| x[0];
    assert_eq!(
        smoothed_hessian(f, &[], 1.0, 10, 0).unwrap_err(),
        Error::EmptyTheta
    );
    assert_eq!(
        smoothed_hessian(f, &[0.0], 0.0, 10, 0).unwrap_err(),
        Error::InvalidSigma(0.0)
    );
    assert_eq!(
        smoothed_hessian(f, &[0.0], 1.0, 0, 0).unwrap_err(),
        Error::ZeroSamples
    );
    assert!(matches!(
        smoothed_hessian(f, &[0.0], 1.0, 1, 0).unwrap_err(),
        Error::InvalidParameter { name: "pairs", .. }
    ));
    let nan = |x: &[f64]| if x[0] > 0.0 { f64::NAN } else { 0.0 };
    assert!(matches!(
        smoothed_hessian(nan, &[0.0], 1.0, 10, 0).unwrap_err(),
        Error::NonFiniteValue { .. }
    ));
}

#[test]
fn the_control_variate_removes_the_mean_curvature() {
    // On the sphere `f = |x|^2` (H = 2 I) each pair's term of a diagonal entry is
    // `(|eps|^2 - n)(eps_i^2 - 1)`, of variance `E[(eps_i^2 - 1)^4] + 2 (n - 1) E[(eps_i^2 - 1)^2]
    // = 60 + 4 (n - 1)` (chi-squared moments). With `f(theta)` as the control variate it would be
    // `|eps|^2 (eps_i^2 - 1)`, of variance `2 n^2 + 20 n + 52`. At n = 50 with 4000 pairs a
    // diagonal entry's standard error is about 0.25 against 1.23. Each standard error is itself
    // an estimate from heavy-tailed terms (single entries reach 0.33), so the test takes the
    // median over the 50 entries, within 5 %, and every one below 0.5. Every entry is also within
    // 4.5 standard errors of H, at sigma 1e-3 and 1e3, and the evaluations are `2 pairs`.
    let n = 50;
    let f = |x: &[f64]| x.iter().map(|v| v * v).sum::<f64>();
    let pairs = 4000;
    let expected = ((60.0 + 4.0 * (n as f64 - 1.0)) / pairs as f64).sqrt();
    for (sigma, seed) in [(1e-3, 5), (1e3, 6)] {
        let est = smoothed_hessian(f, &vec![0.7; n], sigma, pairs, seed).unwrap();
        assert_eq!(est.evaluations, 2 * pairs);
        let exact: Vec<f64> = (0..n * n)
            .map(|k| if k % (n + 1) == 0 { 2.0 } else { 0.0 })
            .collect();
        check(&est, &exact, 4.5, 0.5);
        let mut diagonal: Vec<f64> = (0..n).map(|i| est.standard_error[i * n + i]).collect();
        diagonal.sort_by(f64::total_cmp);
        let median = diagonal[n / 2];
        assert!(
            (median / expected - 1.0).abs() < 0.05,
            "sigma {sigma}: median se {median}, expected {expected}"
        );
    }
}

#[test]
fn a_huge_constant_does_not_swamp_the_curvature() {
    // f = 1e12 + x0 x1: the first pair's value is subtracted before the sums, so the constant
    // costs no digits; the off-diagonal entry is 1.
    let f = |x: &[f64]| 1e12 + x[0] * x[1];
    let est = smoothed_hessian(f, &[0.2, 0.4], 0.1, 20_000, 8).unwrap();
    check(&est, &[0.0, 1.0, 1.0, 0.0], 4.5, 0.05);
}
