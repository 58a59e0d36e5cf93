//! Fuzzing the gradient estimators (the plateau-free estimator, finite differences, SPSA)
//! and the optimiser's loop with random configurations, inputs and call sequences:
//! dimensions from 1 to 10^4, spreads from 1e-300 to 1e300 (and the extremes of f64), starts
//! up to f64::MAX, objectives whose values are huge, subnormal, NaN or infinite (or that
//! panic, with panics caught). The contract checked: never a panic, never a NaN or an
//! infinity inside an `Ok`. The cases the fuzzing found are kept as plain regression tests
//! at the end; `fuzz_minimizer.rs` fuzzes a `Minimizer` the same way.

use std::ops::ControlFlow;

use plateau_free::baseline::{FiniteDifference, Spsa};
use plateau_free::{
    anneal::Schedule, estimator::OnFailure, run::OptimizerState, Adam, Annealer, GradientEstimator,
    Optimizer, PlateauFreeGradient, Sampling,
};
use proptest::prelude::*;

mod common;
use common::fuzz::*;

#[derive(Debug, Clone)]
struct Config {
    samples: usize,
    sampling: Sampling,
    antithetic: bool,
    orthogonal: bool,
    parallel: bool,
    seed: u64,
    resample: Option<usize>,
}

fn config() -> impl Strategy<Value = Config> {
    (
        prop_oneof![1 => Just(0usize), 8 => 1usize..=9],
        prop_oneof![
            Just(Sampling::Radial),
            Just(Sampling::PerCoordinate),
            Just(Sampling::Gaussian)
        ],
        any::<bool>(),
        any::<bool>(),
        any::<bool>(),
        any::<u64>(),
        proptest::option::of(0usize..=4),
    )
        .prop_map(
            |(samples, sampling, antithetic, orthogonal, parallel, seed, resample)| Config {
                samples,
                sampling,
                antithetic,
                orthogonal,
                parallel,
                seed,
                resample,
            },
        )
}

#[derive(Debug, Clone)]
enum Op {
    Estimate(f64),
    Spreads(f64),
    Reset,
    AdamStep(f64),
}

fn ops() -> impl Strategy<Value = Vec<Op>> {
    proptest::collection::vec(
        prop_oneof![
            4 => extreme().prop_map(Op::Estimate),
            1 => (-1e300f64..1e300).prop_map(Op::Estimate),
            1 => extreme().prop_map(Op::Spreads),
            1 => Just(Op::Reset),
            2 => extreme().prop_map(Op::AdamStep),
        ],
        1..6,
    )
}

fn estimator(
    c: &Config,
    kind: Values,
) -> PlateauFreeGradient<impl Fn(&[f64]) -> f64 + Sync + Copy> {
    let mut g = PlateauFreeGradient::new(move |x: &[f64]| value(kind, x))
        .samples(c.samples)
        .sampling(c.sampling)
        .antithetic(c.antithetic)
        .orthogonal(c.orthogonal)
        .parallel(c.parallel)
        .seed(c.seed)
        // A panicking objective is only fuzzed with panics caught: uncaught, unwinding is
        // the documented behaviour.
        .catch_panics(true);
    if let Some(limit) = c.resample {
        g = g.on_failure(OnFailure::Resample { limit });
    }
    g
}

proptest! {
    // A few seconds in CI; `FUZZ_CASES=20000` for a longer hunt.
    #![proptest_config(ProptestConfig {
        cases: std::env::var("FUZZ_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(128),
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    #[test]
    fn estimates_and_steps_never_panic_nor_return_non_finite(
        c in config(),
        kind in values(),
        n in dim(),
        theta0 in signed_extreme(),
        ops in ops(),
        lr in extreme(),
    ) {
        let mut grad = estimator(&c, kind);
        let _ = grad.validate();
        let mut theta: Vec<f64> = (0..n).map(|i| if i % 2 == 0 { theta0 } else { -theta0 * 0.5 }).collect();
        let mut adam = Adam::new(lr).ok();
        for op in ops {
            match op {
                Op::Estimate(sigma) | Op::Spreads(sigma) => {
                    let r = if matches!(op, Op::Estimate(_)) {
                        grad.estimate(&theta, sigma)
                    } else {
                        grad.estimate_with_spreads(&theta, &vec![sigma; n])
                    };
                    if let Ok(e) = r {
                        prop_assert_eq!(e.gradient.len(), n);
                        prop_assert!(all_finite(&e.gradient), "gradient {:?}", &e.gradient[..n.min(4)]);
                        prop_assert!(e.mean_value.is_finite(), "mean {}", e.mean_value);
                        prop_assert!(e.evaluations >= c.samples);
                    }
                }
                Op::Reset => grad.reset(),
                Op::AdamStep(g) => {
                    if let Some(adam) = adam.as_mut() {
                        let gradient = vec![g; n];
                        let before = theta.clone();
                        if adam.step(&mut theta, &gradient).is_ok() {
                            prop_assert!(all_finite(&theta), "theta {:?}", &theta[..n.min(4)]);
                        } else {
                            prop_assert_eq!(&theta, &before);
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn runs_never_panic_nor_return_non_finite(
        c in config(),
        kind in values(),
        n in prop_oneof![1usize..=6, Just(1000)],
        start in signed_extreme(),
        sigma0 in extreme(),
        lr in extreme(),
        iterations in 0usize..6,
        stop in 0usize..6,
        record in any::<bool>(),
        schedule in prop_oneof![Just(Schedule::Constant), Just(Schedule::Exponential), Just(Schedule::Cosine)],
        baseline in 0u8..3,
    ) {
        let Ok(adam) = Adam::new(lr) else { return Ok(()); };
        let Ok(annealer) = Annealer::new(schedule, sigma0, sigma0 * 1e-3, iterations.max(1)) else { return Ok(()); };
        let mut opt = Optimizer::new(adam, annealer).iterations(iterations).record_theta(record);
        let f = move |x: &[f64]| value(kind, x);
        let mut est: Box<dyn GradientEstimator> = match baseline {
            0 => Box::new(estimator(&c, kind)),
            1 => match FiniteDifference::new(f, sigma0) { Ok(fd) => Box::new(fd), Err(_) => return Ok(()) },
            _ => Box::new(Spsa::new(f).seed(c.seed)),
        };
        if matches!(kind, Values::Panic) && baseline != 0 {
            // The baselines do not catch panics.
            return Ok(());
        }
        let start = vec![start; n];
        let check = |h: &plateau_free::run::History| -> Result<(), TestCaseError> {
            prop_assert!(all_finite(&h.value), "values {:?}", h.value);
            prop_assert!(h.theta.iter().all(|t| all_finite(t)));
            Ok(())
        };
        match opt.run(&mut *est, &start, |_| ControlFlow::Continue(())) {
            Ok(h) => {
                check(&h)?;
                prop_assert_eq!(h.iterations(), iterations);
                prop_assert!(h.last_theta().is_some());
            }
            Err(e) => {
                check(e.history())?;
                prop_assert!(e.to_string().len() < 400, "{}", e);
            }
        }
        // Interrupted and resumed: the same contract.
        if let Ok(state) = OptimizerState::new(&start) {
            let r = opt.minimize_from(&mut *est, state, |s| {
                if s.iteration == stop { ControlFlow::Break(()) } else { ControlFlow::Continue(()) }
            });
            let state = match r { Ok(s) => s, Err(e) => *e.state };
            prop_assert!(all_finite(&state.theta));
            if let Ok(end) = opt.minimize_from(&mut *est, state, |_| ControlFlow::Continue(())) {
                check(&end.history)?;
                prop_assert!(all_finite(&end.theta));
            }
        }
    }
}

// The cases the fuzz test found, kept as plain regression tests.

/// Adam with a huge learning rate at a huge theta stepped to -inf and returned Ok.
#[test]
fn found_adam_step_overflow_is_refused_unchanged() {
    let mut adam = Adam::new(1e308).unwrap();
    let mut theta = vec![-1e308, 1.0];
    let err = adam.step(&mut theta, &[1.0, 1.0]).unwrap_err();
    assert!(
        matches!(err, plateau_free::Error::StepOverflow { index: 0, .. }),
        "{err}"
    );
    assert!(err.to_string().contains("-1e308"), "{err}");
    assert_eq!(theta, vec![-1e308, 1.0]);
    assert_eq!(adam.steps(), 0);
    assert_eq!(adam.moments(), plateau_free::adam::AdamMoments::default());
}

/// Nine values of f64::MAX / 9 (rounded) summed past f64::MAX: mean_value was infinite.
#[test]
fn found_mean_of_huge_values_stays_finite() {
    let f = |x: &[f64]| if x[0] > 0.0 { f64::MAX } else { 0.0 };
    let mut grad = PlateauFreeGradient::new(f).samples(9).antithetic(false);
    for _ in 0..20 {
        let e = grad.estimate(&[1.0], 1e300).unwrap();
        assert!(e.mean_value.is_finite() && e.mean_value >= 0.0, "{e:?}");
        assert!(e.mean_value <= f64::MAX);
    }
    let all_max = |_: &[f64]| f64::MAX;
    let e = PlateauFreeGradient::new(all_max)
        .samples(9)
        .antithetic(false)
        .estimate(&[1.0], 1.0)
        .unwrap();
    assert_eq!(e.mean_value, f64::MAX);
}

/// Finite differences summed f(theta + h) + f(theta - h) near f64::MAX to infinity, and
/// evaluated f at an overflowed point theta + h.
#[test]
fn found_finite_differences_at_the_end_of_the_range() {
    let huge = |_: &[f64]| f64::MAX;
    let e = FiniteDifference::new(huge, 1e-3)
        .unwrap()
        .estimate(&[0.0, 1.0], 0.1)
        .unwrap();
    assert_eq!(e.mean_value, f64::MAX);
    assert_eq!(e.gradient, vec![0.0, 0.0]);
    let seen_infinite = std::cell::Cell::new(false);
    let watch = |x: &[f64]| {
        seen_infinite.set(seen_infinite.get() || !x[0].is_finite());
        1.0
    };
    let err = FiniteDifference::new(watch, f64::MAX)
        .unwrap()
        .estimate(&[f64::MAX], 0.1)
        .unwrap_err();
    assert!(
        matches!(err, plateau_free::Error::NonFinitePoint { index: 0, .. }),
        "{err}"
    );
    assert!(!seen_infinite.get());
}
