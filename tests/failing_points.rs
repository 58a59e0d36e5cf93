//! Failures are data: `f` returning NaN or an infinity on a few per cent of points
//! (deterministic, by a hash of the point) under the default [`FailurePolicy::Continue`].
//! Every method ends near its clean run's value and counts the failures; a run whose every
//! point fails ends with `fun = inf` and `failures == evaluations`.

use plateau_free::{run::FailurePolicy, run::Strategy, vector::Sparsity, LeastSquares, Minimizer};

/// Whether `x` fails, and how: about 3 % of points, NaN, `+inf` and `-inf` in turn.
fn failure(x: &[f64]) -> Option<f64> {
    let mut h: u64 = 0x9E37_79B9_7F4A_7C15;
    for v in x {
        h = (h ^ v.to_bits()).wrapping_mul(0x0100_0000_01B3);
        h ^= h >> 29;
    }
    h = h.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    h ^= h >> 32;
    (h % 100 < 3).then(|| [f64::NAN, f64::INFINITY, f64::NEG_INFINITY][(h / 100 % 3) as usize])
}

fn sphere(x: &[f64]) -> f64 {
    x.iter().map(|v| (v - 0.3).powi(2)).sum()
}

fn rosenbrock(x: &[f64]) -> f64 {
    x.windows(2)
        .map(|w| 100.0 * (w[1] - w[0] * w[0]).powi(2) + (1.0 - w[0]).powi(2))
        .sum()
}

fn failing(f: fn(&[f64]) -> f64) -> impl Fn(&[f64]) -> f64 + Clone {
    move |x| failure(x).unwrap_or_else(|| f(x))
}

const PAPER: Strategy = Strategy::Paper {
    samples: 4,
    lr: 0.05,
    sigma0: 0.5,
};

/// The minimisers compared: the adaptive search, the paper's loop with its default polish,
/// and the loop alone.
fn minimizers<F>(f: F, n: usize, seed: u64) -> Vec<(&'static str, Minimizer<F>)>
where
    F: Fn(&[f64]) -> f64 + Clone,
{
    let budget = 1500 * n;
    vec![
        (
            "adaptive",
            Minimizer::new(f.clone()).budget(budget).seed(seed),
        ),
        (
            "paper+polish",
            Minimizer::new(f.clone())
                .budget(budget)
                .seed(seed)
                .strategy(PAPER),
        ),
        (
            "paper",
            Minimizer::new(f)
                .budget(budget)
                .seed(seed)
                .strategy(PAPER)
                .polish(0.0),
        ),
    ]
}

/// The median of five values.
fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// A failing run's value against the clean run's, as medians over seeds 0-4 (a single
/// run's final value varies by orders of magnitude from seed to seed for the loop alone):
/// within a factor 10, plus a floor far below every target for values at or near 0.
fn close(failed: f64, clean: f64) -> bool {
    failed <= 10.0 * clean + 1e-12
}

#[test]
fn every_scalar_method_goes_on_past_failures_and_counts_them() {
    for (name, f) in [
        ("sphere", sphere as fn(&[f64]) -> f64),
        ("rosenbrock", rosenbrock),
    ] {
        for n in [2, 5, 10] {
            let x0 = vec![-0.5; n];
            for (k, method) in ["adaptive", "paper+polish", "paper"]
                .into_iter()
                .enumerate()
            {
                let (mut clean, mut got) = (Vec::new(), Vec::new());
                for seed in 0..5 {
                    let c = minimizers(f, n, seed).swap_remove(k).1.run(&x0).unwrap();
                    let m = minimizers(failing(f), n, seed).swap_remove(k).1;
                    let g = m.run(&x0).unwrap();
                    assert_eq!(c.failures, 0);
                    assert!(g.failures > 0, "{name} {n} {method}: {g:?}");
                    assert!(g.fun.is_finite() && failure(&g.x).is_none());
                    clean.push(c.fun);
                    got.push(g.fun);
                }
                let (c, g) = (median(clean), median(got));
                assert!(
                    close(g, c),
                    "{name} {n} {method}: median {g:e} against {c:e}"
                );
            }
        }
    }
}

#[test]
fn least_squares_goes_on_past_failures_and_counts_them() {
    for n in [2, 5, 10] {
        // Rosenbrock's residuals: 10 (x_{i+1} - x_i^2) and 1 - x_i.
        let m = 2 * (n - 1);
        let residuals = |x: &[f64]| -> Vec<f64> {
            let mut r = Vec::with_capacity(m);
            for i in 0..n - 1 {
                r.push(10.0 * (x[i + 1] - x[i] * x[i]));
                r.push(1.0 - x[i]);
            }
            r
        };
        let with_failures = |x: &[f64]| match failure(x) {
            Some(bad) => vec![bad; m],
            None => residuals(x),
        };
        let pattern = Sparsity::from_fn(m, n, |i, row| {
            let k = i / 2;
            row.push(k);
            if i % 2 == 0 {
                row.push(k + 1);
            }
        })
        .unwrap();
        let options = |seed| {
            LeastSquares::new(pattern.clone())
                .budget(600 * n)
                .sigma0(0.3)
                .seed(seed)
        };
        let x0 = vec![-0.5; n];
        let (mut clean, mut got) = (Vec::new(), Vec::new());
        for seed in 0..5 {
            let c = options(seed).run_vec(residuals, &x0).unwrap();
            let g = options(seed).run_vec(with_failures, &x0).unwrap();
            assert_eq!(c.failures, 0);
            assert!(g.failures > 0);
            clean.push(c.fun);
            got.push(g.fun);
        }
        let (c, g) = (median(clean), median(got));
        assert!(close(g, c), "least squares {n}: median {g:e} against {c:e}");
        let raising = options(0).on_failure(FailurePolicy::Raise);
        assert!(raising.run_vec(with_failures, &x0).is_err());
    }
}

#[test]
fn a_run_whose_every_point_fails_ends_without_a_best_point() {
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let f = move |_: &[f64]| bad;
        for n in [1, 3] {
            let x0 = vec![0.5; n];
            for (method, m) in minimizers(f, n, 0) {
                let got = m.budget(300).run(&x0).unwrap();
                assert_eq!(got.fun, f64::INFINITY, "{method}: {got:?}");
                assert_eq!(got.failures, got.evaluations, "{method}: {got:?}");
                // The loop alone ends after its redraws; the others spend the budget.
                assert!(got.evaluations <= 300, "{method}: {got:?}");
                if method != "paper" {
                    assert_eq!(got.evaluations, 300, "{method}: {got:?}");
                }
                assert!(!got.success());
                assert_eq!(got.x, x0);
            }
            let pattern = Sparsity::dense(2, n).unwrap();
            let got = LeastSquares::new(pattern)
                .budget(100)
                .run_vec(|_| vec![bad; 2], &x0)
                .unwrap();
            assert_eq!(got.fun, f64::INFINITY);
            assert_eq!(got.failures, got.nfev);
            assert!(got.nfev > 90);
        }
    }
}

#[test]
fn raise_keeps_the_error() {
    let f = failing(rosenbrock);
    let err = Minimizer::new(f)
        .budget(3000)
        .on_failure(FailurePolicy::Raise)
        .run(&[-0.5; 3])
        .unwrap_err();
    assert!(
        matches!(err, plateau_free::Error::NonFiniteValue { .. }),
        "{err}"
    );
}
