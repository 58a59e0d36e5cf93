//! The vector (least-squares) method: the smoothed Jacobian's estimate against closed forms,
//! the sparsity patterns, the Gauss-Newton run, and every way an input can be wrong.

use plateau_free::kernel::normal_cdf;
use plateau_free::{
    run::FailurePolicy, vector::smoothed_jacobian, vector::Acceptance, vector::Sparsity, Error,
    LeastSquares,
};
use proptest::prelude::*;

/// The standard normal density.
fn phi(z: f64) -> f64 {
    (-0.5 * z * z).exp() / (2.0 * std::f64::consts::PI).sqrt()
}

/// The mean and the standard error of the mean of each entry over `count` seeded estimates.
fn mean_and_error<F>(count: u64, mut estimate: F) -> (Vec<f64>, Vec<f64>)
where
    F: FnMut(u64) -> Vec<f64>,
{
    let first = estimate(1000);
    let (mut sum, mut sq) = (vec![0.0; first.len()], vec![0.0; first.len()]);
    for seed in 0..count {
        for (k, v) in estimate(seed).into_iter().enumerate() {
            sum[k] += v;
            sq[k] += v * v;
        }
    }
    let c = count as f64;
    let mean: Vec<f64> = sum.iter().map(|s| s / c).collect();
    let se = mean
        .iter()
        .zip(&sq)
        .map(|(m, s2)| ((s2 / c - m * m) / (c - 1.0)).sqrt())
        .collect();
    (mean, se)
}

/// Asserts every entry within four standard errors of its exact value.
fn assert_unbiased(mean: &[f64], se: &[f64], exact: &[f64]) {
    for (k, ((m, s), e)) in mean.iter().zip(se).zip(exact).enumerate() {
        let z = (m - e) / s;
        assert!(
            z.abs() < 4.0,
            "entry {k}: mean {m} vs exact {e} (se {s}, z {z})"
        );
    }
}

/// Steps, whose smoothed Jacobian is known in closed form: `E 1[a.x + a.tau > b]` is
/// `Phi((a.x - b) / (sigma |a|))`, its derivative `a_j phi(.) / (sigma |a|)`.
#[test]
fn the_estimate_of_steps_is_unbiased() {
    let theta = [0.2, -0.1, 0.4];
    let sigma = 0.3;
    // r0 = 1[x0 > 0.3], r1 = 1[x0 + 2 x1 > 0.1], r2 = 1[x2 > 0.4] - 1[x1 > 0].
    let r = |x: &[f64], _: u64, out: &mut [f64]| {
        let step = |v: f64| if v > 0.0 { 1.0 } else { 0.0 };
        out[0] = step(x[0] - 0.3);
        out[1] = step(x[0] + 2.0 * x[1] - 0.1);
        out[2] = step(x[2] - 0.4) - step(x[1]);
    };
    let pattern = Sparsity::from_pairs(3, 3, &[(0, 0), (1, 0), (1, 1), (2, 1), (2, 2)]).unwrap();
    let norm = 5f64.sqrt();
    let z1 = (theta[0] + 2.0 * theta[1] - 0.1) / (sigma * norm);
    let exact = [
        phi((theta[0] - 0.3) / sigma) / sigma,
        phi(z1) / (sigma * norm),
        2.0 * phi(z1) / (sigma * norm),
        -phi(theta[1] / sigma) / sigma,
        phi((theta[2] - 0.4) / sigma) / sigma,
    ];
    let (mean, se) = mean_and_error(400, |seed| {
        smoothed_jacobian(r, &theta, sigma, 16, seed, &pattern)
            .unwrap()
            .values
    });
    assert_unbiased(&mean, &se, &exact);
    // And the smoothed residuals, from the same pairs.
    let exact_r = [
        normal_cdf((theta[0] - 0.3) / sigma),
        normal_cdf(z1),
        normal_cdf((theta[2] - 0.4) / sigma) - normal_cdf(theta[1] / sigma),
    ];
    let (mean, se) = mean_and_error(400, |seed| {
        smoothed_jacobian(r, &theta, sigma, 16, seed, &pattern)
            .unwrap()
            .residuals
    });
    assert_unbiased(&mean, &se, &exact_r);
}

/// A linear map `A x`: the smoothed Jacobian is `A` itself, dense.
#[test]
fn the_estimate_of_a_linear_map_is_unbiased_and_its_errors_are_honest() {
    let a = [[1.0, -2.0, 0.5, 0.0], [0.0, 3.0, -1.0, 2.0]];
    let r = |x: &[f64], _: u64, out: &mut [f64]| {
        for (o, row) in out.iter_mut().zip(&a) {
            *o = row.iter().zip(x).map(|(p, q)| p * q).sum();
        }
    };
    let pattern = Sparsity::dense(2, 4).unwrap();
    let exact: Vec<f64> = a.iter().flatten().copied().collect();
    let theta = [0.1, 0.2, -0.3, 1.0];
    let (mean, se) = mean_and_error(300, |seed| {
        smoothed_jacobian(r, &theta, 0.7, 8, seed, &pattern)
            .unwrap()
            .values
    });
    assert_unbiased(&mean, &se, &exact);
    // One estimate's own standard errors: the z of its entries has about unit spread.
    let one = smoothed_jacobian(r, &theta, 0.7, 2000, 3, &pattern).unwrap();
    let z2: f64 = one
        .values
        .iter()
        .zip(&one.standard_errors)
        .zip(&exact)
        .map(|((v, s), e)| ((v - e) / s).powi(2))
        .sum::<f64>()
        / exact.len() as f64;
    assert!(z2 > 0.1 && z2 < 4.0, "mean squared z {z2}");
}

/// With a pattern, the variance of an entry depends on its row alone, not on `n`: with a
/// diagonal map at n = 100,000, each entry is `mean(z^2)` over the pairs (mean 1, variance
/// 2 / pairs), whatever n.
#[test]
fn a_sparse_pattern_keeps_the_variance_independent_of_n() {
    let n = 100_000;
    let pattern = Sparsity::from_fn(n, n, |i, row| row.push(i)).unwrap();
    let r = |x: &[f64], _: u64, out: &mut [f64]| out.copy_from_slice(x);
    let pairs = 8;
    let j = smoothed_jacobian(r, &vec![0.5; n], 0.1, pairs, 5, &pattern).unwrap();
    assert_eq!(j.values.len(), n);
    let mean = j.values.iter().sum::<f64>() / n as f64;
    let var = j.values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
    let expected_var = 2.0 / pairs as f64;
    // The mean of n entries: standard error sqrt(2 / pairs / n).
    let se = (expected_var / n as f64).sqrt();
    assert!((mean - 1.0).abs() < 4.0 * se, "mean {mean}");
    // The sample variance of a mean of 8 chi-squared(1) / 8: within 5 %.
    assert!((var / expected_var - 1.0).abs() < 0.05, "variance {var}");
}

/// The same pattern from pairs, a closure and (for the full one) `dense`: the same
/// estimate, bit for bit.
#[test]
fn patterns_agree_however_they_are_given() {
    let r = |x: &[f64], _: u64, out: &mut [f64]| {
        out[0] = x[0] * x[1];
        out[1] = (x[1] - x[0]).sin();
    };
    let pairs: Vec<(usize, usize)> = vec![(1, 1), (0, 0), (0, 1), (1, 0), (0, 0)];
    let p1 = Sparsity::from_pairs(2, 2, &pairs).unwrap();
    let p2 = Sparsity::from_fn(2, 2, |_, row| row.extend([1, 0])).unwrap();
    let p3 = Sparsity::dense(2, 2).unwrap();
    assert_eq!(p1, p2);
    let e = |p: &Sparsity| smoothed_jacobian(r, &[0.3, 0.4], 0.2, 5, 9, p).unwrap();
    assert_eq!(e(&p1), e(&p3));
    assert!(!p1.is_dense() && p3.is_dense());
    assert_eq!(p1.max_row(), 2);
}

/// Tiny and huge spreads, one parameter and one output: finite, and right where the
/// closed form says.
#[test]
fn extreme_spreads_and_sizes() {
    let line = |x: &[f64], _: u64, out: &mut [f64]| out[0] = 3.0 * x[0];
    let p = Sparsity::dense(1, 1).unwrap();
    // At theta = 0 every spread is resolved (at 0.5, a spread below the spacing of doubles
    // there, 1e-16, moves no point and the estimate is 0: nothing can be seen).
    for sigma in [1e-200, 1e-8, 1.0, 1e8, 1e150] {
        let j = smoothed_jacobian(line, &[0.0], sigma, 200, 1, &p).unwrap();
        // 3 mean(z^2) over 200 pairs: 3 +- 3 sqrt(2 / 200) = 3 +- 0.3.
        assert!(
            (j.values[0] - 3.0).abs() < 1.2,
            "sigma {sigma}: {}",
            j.values[0]
        );
        assert!(j.standard_errors[0].is_finite());
    }
    // A step seen through a huge spread: the slope phi(0) / sigma, tiny but finite.
    let step = |x: &[f64], _: u64, out: &mut [f64]| out[0] = if x[0] > 0.0 { 1.0 } else { 0.0 };
    let (mean, se) = mean_and_error(200, |seed| {
        smoothed_jacobian(step, &[0.0], 1e6, 16, seed, &p)
            .unwrap()
            .values
    });
    assert_unbiased(&mean, &se, &[phi(0.0) / 1e6]);
}

#[test]
fn bad_inputs_are_errors_not_panics() {
    let p = Sparsity::dense(1, 2).unwrap();
    let ok = |x: &[f64], _: u64, out: &mut [f64]| out[0] = x[0];
    for sigma in [0.0, -1.0, f64::INFINITY, f64::NEG_INFINITY] {
        assert_eq!(
            smoothed_jacobian(ok, &[0.0, 0.0], sigma, 2, 0, &p),
            Err(Error::InvalidSigma(sigma))
        );
    }
    let e = smoothed_jacobian(ok, &[0.0, 0.0], f64::NAN, 2, 0, &p).unwrap_err();
    assert!(matches!(e, Error::InvalidSigma(s) if s.is_nan()));
    assert!(matches!(
        smoothed_jacobian(ok, &[0.0], 1.0, 2, 0, &p),
        Err(Error::LengthMismatch {
            what: "theta",
            expected: 2,
            got: 1
        })
    ));
    assert!(matches!(
        smoothed_jacobian(ok, &[0.0, f64::NAN], 1.0, 2, 0, &p),
        Err(Error::NonFiniteTheta { index: 1, .. })
    ));
    assert!(matches!(
        smoothed_jacobian(ok, &[0.0, 0.0], 1.0, 0, 0, &p),
        Err(Error::InvalidParameter { name: "pairs", .. })
    ));
    let nan = |_: &[f64], _: u64, out: &mut [f64]| out[0] = f64::NAN;
    let e = smoothed_jacobian(nan, &[0.0, 0.0], 1.0, 2, 0, &p).unwrap_err();
    assert!(matches!(e, Error::NonFiniteValue { sample: 0, .. }), "{e}");
    let huge = smoothed_jacobian(ok, &[f64::MAX, 0.0], 1e300, 2, 0, &p).unwrap_err();
    assert!(matches!(huge, Error::NonFinitePoint { .. }), "{huge}");
    // Patterns.
    assert!(matches!(
        Sparsity::from_pairs(2, 2, &[]),
        Err(Error::InvalidParameter {
            name: "sparsity entries",
            ..
        })
    ));
    assert!(matches!(
        Sparsity::from_pairs(2, 2, &[(0, 2)]),
        Err(Error::InvalidParameter {
            name: "sparsity parameter",
            ..
        })
    ));
    assert!(matches!(
        Sparsity::from_pairs(2, 2, &[(2, 0)]),
        Err(Error::InvalidParameter {
            name: "sparsity output",
            ..
        })
    ));
    assert!(Sparsity::dense(0, 3).is_err() && Sparsity::dense(3, 0).is_err());
    assert!(Sparsity::from_fn(3, 3, |_, _| {}).is_err());
}

#[test]
fn bad_options_of_the_run_are_errors() {
    let p = Sparsity::dense(1, 1).unwrap();
    let base = LeastSquares::new(p.clone());
    let e = |o: LeastSquares, x0: &[f64]| o.ask_tell(x0).unwrap_err().to_string();
    assert_eq!(
        e(base.clone().budget(0), &[0.0]),
        "budget = 0 is invalid: must be at least 1"
    );
    assert!(e(base.clone().sigma0(0.0), &[0.0]).contains("sigma0 = 0.0"));
    assert!(e(base.clone().sigma0(f64::INFINITY), &[0.0]).contains("sigma0 = inf"));
    assert!(e(base.clone().pairs(0), &[0.0]).contains("pairs = 0"));
    assert!(e(base.clone().memory(0), &[0.0]).contains("memory = 0"));
    assert!(e(base.clone().damping(-1.0), &[0.0]).contains("damping = -1.0"));
    assert!(e(base.clone().max_step(f64::NAN), &[0.0]).contains("max_step = NaN"));
    assert!(e(base.clone(), &[0.0, 1.0]).contains("x0 has length 2, expected 1"));
    assert!(e(base.clone(), &[]).contains("theta is empty"));
    assert!(e(base.clone().bounds(vec![0.0], vec![1.0]), &[2.0]).contains("outside the bounds"));
    // Ask and tell out of order, wrong counts, NaN (when raising): errors, and the run goes on.
    let raising = base.clone().on_failure(FailurePolicy::Raise);
    let mut run = raising.budget(50).ask_tell(&[0.5]).unwrap();
    assert_eq!(run.tell(&[1.0]), Err(Error::NothingAsked));
    assert!(matches!(run.finish(), Err(Error::Unfinished { .. })));
    assert_eq!(run.ask().unwrap().map(|a| a.len()), Some(1));
    assert!(matches!(run.ask(), Err(Error::AskPending)));
    assert!(matches!(
        run.tell(&[1.0, 2.0]),
        Err(Error::LengthMismatch { .. })
    ));
    assert!(matches!(
        run.tell(&[f64::NAN]),
        Err(Error::NonFiniteValue { sample: 0, .. })
    ));
    run.tell(&[0.5]).unwrap();
    // A closure returning the wrong length.
    let e = base
        .clone()
        .run_vec(|_| vec![1.0, 2.0], &[0.0])
        .unwrap_err();
    assert!(
        matches!(
            e,
            Error::LengthMismatch {
                what: "outputs",
                expected: 1,
                got: 2
            }
        ),
        "{e}"
    );
}

/// A linear least-squares problem with more outputs than parameters: the run ends at the
/// least-squares solution.
#[test]
fn a_linear_least_squares_problem_is_solved() {
    let a = [[1.0, 0.0], [1.0, 1.0], [1.0, 2.0], [1.0, 3.0]];
    let y = [1.0, 2.0, 2.0, 4.0];
    let r = |x: &[f64]| {
        a.iter()
            .zip(&y)
            .map(|(row, yi)| row[0] * x[0] + row[1] * x[1] - yi)
            .collect::<Vec<f64>>()
    };
    let best = LeastSquares::new(Sparsity::dense(4, 2).unwrap())
        .budget(300)
        .sigma0(0.5)
        .seed(2)
        .run_vec(r, &[0.0, 0.0])
        .unwrap();
    // The normal equations' solution: intercept 0.9, slope 0.9.
    assert!(
        (best.x[0] - 0.9).abs() < 1e-6 && (best.x[1] - 0.9).abs() < 1e-6,
        "{:?}",
        best.x
    );
    assert!((best.fun - 0.7).abs() < 1e-9, "{}", best.fun);
    assert!(best.nfev <= 300 && best.nit >= 1);
}

/// Residuals flat almost everywhere (each a rounded staircase of its parameter, 5,000 of
/// them) from a start where every small move changes nothing: the smoothed Jacobian sees
/// the steps, and the sum of squares falls by orders of magnitude within the budget.
#[test]
fn plateaus_do_not_stop_the_run() {
    let n = 5000;
    let target: Vec<f64> = (0..n).map(|i| (i % 10) as f64 / 10.0).collect();
    let r = |x: &[f64], _: u64, out: &mut [f64]| {
        for ((o, xi), t) in out.iter_mut().zip(x).zip(&target) {
            // Quantised to steps of 0.05: zero derivative everywhere but at the steps.
            *o = ((xi - t) * 20.0).round() / 20.0;
        }
    };
    let pattern = Sparsity::from_fn(n, n, |i, row| row.push(i)).unwrap();
    let x0 = vec![0.5; n];
    let mut start = vec![0.0; n];
    r(&x0, 0, &mut start);
    let f0: f64 = start.iter().map(|v| v * v).sum();
    let best = LeastSquares::new(pattern)
        .budget(600)
        .sigma0(0.2)
        .seed(4)
        .run(r, &x0)
        .unwrap();
    assert!(best.fun < 1e-3 * f0, "{} from {f0}", best.fun);
}

/// Ask and tell give the callback run's bits; every asked point lies in the box; the
/// evaluations stay within the budget; the same seed gives the same run.
#[test]
fn ask_tell_matches_the_callback_and_keeps_its_word() {
    let r = |x: &[f64]| vec![x[0] * x[0] - 0.25, x[0] + x[1] - 0.8, (x[1] - 0.3) * 2.0];
    let options =
        LeastSquares::new(Sparsity::from_pairs(3, 2, &[(0, 0), (1, 0), (1, 1), (2, 1)]).unwrap())
            .budget(157)
            .bounds(vec![0.0, 0.0], vec![1.0, 0.5])
            .seed(11);
    let mut run = options.ask_tell(&[1.0, 0.0]).unwrap();
    let mut asked = 0;
    while let Some(ask) = run.ask().unwrap() {
        asked += ask.len();
        let mut outputs = Vec::new();
        for (x, _) in ask.iter() {
            assert!(
                (0.0..=1.0).contains(&x[0]) && (0.0..=0.5).contains(&x[1]),
                "{x:?}"
            );
            outputs.extend(r(x));
        }
        run.tell(&outputs).unwrap();
    }
    assert!(run.ask().unwrap().is_none());
    let told = run.finish().unwrap();
    assert_eq!(told.nfev, asked);
    assert!(asked <= 157);
    assert_eq!(told, options.run_vec(r, &[1.0, 0.0]).unwrap());
    assert_eq!(told, options.run_vec(r, &[1.0, 0.0]).unwrap());
    assert!(told.fun < 1e-6, "{}", told.fun);
    // Acceptance::Always: every step taken, a result all the same.
    let always = options
        .clone()
        .acceptance(Acceptance::Always)
        .run_vec(r, &[1.0, 0.0])
        .unwrap();
    assert!(always.fun.is_finite() && always.nit >= 1);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Any pattern of any shape: one value per entry, finite, the row of each as given, and
    /// the same bits from the same seed.
    #[test]
    fn estimates_have_the_patterns_shape(
        m in 1usize..12,
        n in 1usize..12,
        entries in proptest::collection::vec((0usize..12, 0usize..12), 1..40),
        seed in any::<u64>(),
        sigma in 1e-6f64..1e3,
    ) {
        let pairs: Vec<(usize, usize)> = entries.iter().map(|&(i, j)| (i % m, j % n)).collect();
        let p = Sparsity::from_pairs(m, n, &pairs).unwrap();
        for &(i, j) in &pairs {
            prop_assert!(p.row(i).contains(&j));
        }
        let r = |x: &[f64], s: u64, out: &mut [f64]| {
            for (i, o) in out.iter_mut().enumerate() {
                *o = x.iter().enumerate().map(|(j, v)| ((i + 2 * j) as f64 * v).sin()).sum::<f64>()
                    + (s % 3) as f64;
            }
        };
        let theta: Vec<f64> = (0..n).map(|j| j as f64 * 0.1).collect();
        let a = smoothed_jacobian(r, &theta, sigma, 3, seed, &p).unwrap();
        prop_assert_eq!(a.values.len(), p.nnz());
        prop_assert_eq!(a.residuals.len(), m);
        prop_assert!(a.values.iter().chain(&a.standard_errors).all(|v| v.is_finite()));
        prop_assert_eq!(&a, &smoothed_jacobian(r, &theta, sigma, 3, seed, &p).unwrap());
    }
}
