//! Bad input is an `Error` carrying the offending value, never a panic and never a silently
//! wrong number. Every variant of `Error` is reached here through the public API.

use std::sync::Mutex;

use plateau_free::baseline::{FiniteDifference, Spsa};
use plateau_free::{
    anneal::Schedule, objective::Batch, objective::Points, objective::Seeded, Adam, Annealer,
    Error, GradientEstimator, Optimizer, PlateauFreeGradient, Sampling,
};

fn linear(x: &[f64]) -> f64 {
    x.iter().sum()
}

#[test]
fn empty_theta() {
    let mut est = PlateauFreeGradient::new(linear);
    assert_eq!(est.estimate(&[], 1.0), Err(Error::EmptyTheta));
    assert_eq!(est.estimate_with_spreads(&[], &[]), Err(Error::EmptyTheta));
    let mut opt = Optimizer::new(Adam::new(0.1).unwrap(), Annealer::paper(0.5, 3).unwrap());
    assert_eq!(opt.minimize(&mut est, &[]).unwrap_err(), Error::EmptyTheta);
    let mut fd = FiniteDifference::new(linear, 1e-3).unwrap();
    assert_eq!(fd.estimate(&[], 1.0), Err(Error::EmptyTheta));
    assert_eq!(Spsa::new(linear).estimate(&[], 1.0), Err(Error::EmptyTheta));
    // Bad input does not consume an estimate: the count of estimates is unchanged.
    assert_eq!(est.estimates_made(), 0);
}

#[test]
fn non_finite_theta() {
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let theta = [0.0, 1.0, bad, 2.0];
        let mut est = PlateauFreeGradient::new(linear);
        let check = |e: Error| match e {
            Error::NonFiniteTheta { index, value } => {
                assert_eq!(index, 2);
                assert_eq!(value.to_bits(), bad.to_bits());
            }
            other => panic!("expected NonFiniteTheta, got {other:?}"),
        };
        check(est.estimate(&theta, 1.0).unwrap_err());
        check(est.estimate_with_spreads(&theta, &[1.0; 4]).unwrap_err());
        let mut opt = Optimizer::new(Adam::new(0.1).unwrap(), Annealer::paper(0.5, 3).unwrap());
        check(opt.minimize(&mut est, &theta).unwrap_err());
        check(
            FiniteDifference::new(linear, 1e-3)
                .unwrap()
                .estimate(&theta, 1.0)
                .unwrap_err(),
        );
        check(Spsa::new(linear).estimate(&theta, 1.0).unwrap_err());
    }
}

#[test]
fn invalid_sigma() {
    for bad in [0.0, -0.0, -1.0, f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let mut est = PlateauFreeGradient::new(linear);
        match est.estimate(&[1.0], bad).unwrap_err() {
            Error::InvalidSigma(v) => assert_eq!(v.to_bits(), bad.to_bits()),
            other => panic!("sigma {bad}: {other:?}"),
        }
        match Spsa::new(linear).estimate(&[1.0], bad).unwrap_err() {
            Error::InvalidSigma(v) => assert_eq!(v.to_bits(), bad.to_bits()),
            other => panic!("sigma {bad}: {other:?}"),
        }
    }
    // The smallest positive double is a valid (if useless) spread.
    assert!(PlateauFreeGradient::new(linear)
        .estimate(&[1.0], 5e-324)
        .is_ok());
}

#[test]
fn invalid_spreads() {
    for bad in [0.0, -2.0, f64::NAN, f64::INFINITY] {
        let mut est = PlateauFreeGradient::new(linear);
        match est
            .estimate_with_spreads(&[1.0, 2.0, 3.0], &[0.5, 0.5, bad])
            .unwrap_err()
        {
            Error::InvalidSpread { index, value } => {
                assert_eq!(index, 2);
                assert_eq!(value.to_bits(), bad.to_bits());
            }
            other => panic!("spread {bad}: {other:?}"),
        }
    }
}

#[test]
fn length_mismatches() {
    let mut est = PlateauFreeGradient::new(linear);
    assert_eq!(
        est.estimate_with_spreads(&[1.0, 2.0, 3.0], &[0.5, 0.5]),
        Err(Error::LengthMismatch {
            what: "spreads",
            expected: 3,
            got: 2
        })
    );
    let mut adam = Adam::new(0.1).unwrap();
    let mut theta = vec![0.0; 3];
    assert!(matches!(
        adam.step(&mut theta, &[1.0; 4]),
        Err(Error::LengthMismatch {
            expected: 3,
            got: 4,
            ..
        })
    ));
    assert!(matches!(
        Adam::new(0.1).unwrap().bounds(vec![0.0; 2], vec![1.0; 3]),
        Err(Error::LengthMismatch {
            expected: 2,
            got: 3,
            ..
        })
    ));
    // Bounds of one length, theta of another.
    let mut bounded = Adam::new(0.1)
        .unwrap()
        .bounds(vec![0.0; 2], vec![1.0; 2])
        .unwrap();
    assert!(matches!(
        bounded.step(&mut theta, &[1.0; 3]),
        Err(Error::LengthMismatch {
            expected: 3,
            got: 2,
            ..
        })
    ));
    // theta changing length between steps.
    let mut adam = Adam::new(0.1).unwrap();
    adam.step(&mut [0.0, 0.0], &[1.0, 1.0]).unwrap();
    assert!(matches!(
        adam.step(&mut [0.0; 3], &[1.0; 3]),
        Err(Error::LengthMismatch {
            expected: 2,
            got: 3,
            ..
        })
    ));
}

#[test]
fn sample_counts() {
    let mut est = PlateauFreeGradient::new(linear).samples(0);
    assert_eq!(est.estimate(&[1.0], 1.0), Err(Error::ZeroSamples));
    let mut est = PlateauFreeGradient::new(linear)
        .samples(0)
        .antithetic(false);
    assert_eq!(est.estimate(&[1.0], 1.0), Err(Error::ZeroSamples));
    for odd in [1, 3, 7, 1001] {
        let mut est = PlateauFreeGradient::new(linear).samples(odd);
        assert_eq!(est.estimate(&[1.0], 1.0), Err(Error::OddSamples(odd)));
        // Without pairs an odd count is fine.
        let mut est = PlateauFreeGradient::new(linear)
            .samples(odd)
            .antithetic(false);
        assert_eq!(est.estimate(&[1.0], 1.0).unwrap().evaluations, odd);
    }
    assert_eq!(
        PlateauFreeGradient::new(linear)
            .sampling(Sampling::PerCoordinate)
            .orthogonal(true)
            .estimate(&[1.0], 1.0),
        Err(Error::OrthogonalUnsupported(Sampling::PerCoordinate))
    );
}

/// An objective that returns NaN or an infinity: the error names the evaluation (its index
/// within the estimate) and the exact point at which f was called.
#[test]
fn objective_returning_nan_or_infinity_names_the_point() {
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        for sampling in [
            Sampling::Radial,
            Sampling::PerCoordinate,
            Sampling::Gaussian,
        ] {
            let seen = Mutex::new(Vec::new());
            // Bad only on the far side of x0 = 0.3: some evaluations are fine, the first bad
            // one must be reported.
            let f = |x: &[f64]| {
                seen.lock().unwrap().push(x.to_vec());
                if x[0] > 0.3 {
                    bad
                } else {
                    x[1]
                }
            };
            let mut est = PlateauFreeGradient::new(f)
                .sampling(sampling)
                .samples(16)
                .seed(1);
            let err = est.estimate(&[0.0, 0.5], 1.0).unwrap_err();
            let seen = seen.into_inner().unwrap();
            let first_bad = seen.iter().position(|p| p[0] > 0.3).unwrap();
            match &err {
                Error::NonFiniteValue {
                    sample,
                    value,
                    point,
                } => {
                    assert_eq!(*sample, first_bad);
                    assert_eq!(value.to_bits(), bad.to_bits());
                    assert_eq!(point, &seen[first_bad]);
                }
                other => panic!("{other:?}"),
            }
            let text = err.to_string();
            assert!(text.contains(&format!("evaluation {first_bad}")), "{text}");
            assert!(
                text.contains(&format!("{:?}", seen[first_bad][0])),
                "{text}"
            );
        }
    }
}

#[test]
fn seeded_batch_and_parallel_objectives_report_bad_values_too() {
    let nan_at_right = |x: &[f64]| if x[0] > 0.0 { f64::NAN } else { 0.0 };
    let seeded = Seeded(|x: &[f64], _seed: u64| nan_at_right(x));
    let batch = Batch(|points: Points<'_>, _: &[u64], out: &mut [f64]| {
        for (p, o) in points.iter().zip(out.iter_mut()) {
            *o = nan_at_right(p);
        }
    });
    let is_nan_error = |e: Error| matches!(e, Error::NonFiniteValue { value, ref point, .. } if value.is_nan() && point[0] > 0.0);
    assert!(is_nan_error(
        PlateauFreeGradient::new(seeded)
            .samples(8)
            .estimate(&[0.0], 1.0)
            .unwrap_err()
    ));
    assert!(is_nan_error(
        PlateauFreeGradient::new(batch)
            .samples(8)
            .estimate(&[0.0], 1.0)
            .unwrap_err()
    ));
    assert!(is_nan_error(
        PlateauFreeGradient::new(nan_at_right)
            .samples(8)
            .parallel(true)
            .estimate(&[0.0], 1.0)
            .unwrap_err()
    ));
    // The baselines too: the finite difference's first evaluation is theta + h e_0.
    match FiniteDifference::new(nan_at_right, 1e-3)
        .unwrap()
        .estimate(&[0.0, 0.0], 1.0)
        .unwrap_err()
    {
        Error::NonFiniteValue { sample, point, .. } => {
            assert_eq!(sample, 0);
            assert_eq!(point, vec![1e-3, 0.0]);
        }
        other => panic!("{other:?}"),
    }
    assert!(is_nan_error(
        Spsa::new(nan_at_right).estimate(&[0.0], 1.0).unwrap_err()
    ));
}

#[test]
fn the_loop_stops_at_the_first_bad_value() {
    // Fine until theta has moved below -0.5, then NaN: the run returns the error.
    let f = |x: &[f64]| if x[0] < -0.5 { f64::NAN } else { x[0] };
    let mut est = PlateauFreeGradient::new(f).samples(4).seed(2);
    let mut opt = Optimizer::new(
        Adam::new(0.1).unwrap(),
        Annealer::constant(0.01, 100).unwrap(),
    );
    let err = opt
        .run(&mut est, &[0.0], |_| std::ops::ControlFlow::Continue(()))
        .unwrap_err();
    assert!(
        matches!(err.error, Error::NonFiniteValue { ref point, .. } if point[0] < -0.5),
        "{err:?}"
    );
    // The good iterations are kept, and the state continues from the last good point.
    let kept = err.history().iterations();
    assert!(kept > 0 && kept < 100, "{kept}");
    assert_eq!(err.state.iteration, kept);
    assert_eq!(err.history().last_theta(), Some(&err.state.theta[..]));
}

#[test]
fn gradient_overflow() {
    let f = |x: &[f64]| if x[0] > 0.0 { 1e300 } else { -1e300 };
    match PlateauFreeGradient::new(f)
        .estimate(&[0.0, 0.0], 1e-12)
        .unwrap_err()
    {
        Error::NonFiniteGradient { value, .. } => assert!(value.is_infinite()),
        other => panic!("{other:?}"),
    }
    // SPSA and finite differences, same values: the difference over a tiny step overflows.
    assert!(matches!(
        Spsa::new(f).estimate(&[0.0], 1e-12),
        Err(Error::NonFiniteGradient { index: 0, .. })
    ));
    assert!(matches!(
        FiniteDifference::new(f, 1e-12)
            .unwrap()
            .estimate(&[0.0], 1.0),
        Err(Error::NonFiniteGradient { index: 0, .. })
    ));
    // Adam refuses a non-finite gradient and leaves theta alone.
    let mut adam = Adam::new(0.1).unwrap();
    let mut theta = vec![1.0, 2.0];
    assert!(matches!(
        adam.step(&mut theta, &[0.0, f64::INFINITY]),
        Err(Error::NonFiniteGradient { index: 1, .. })
    ));
    assert_eq!(theta, vec![1.0, 2.0]);
}

#[test]
fn perturbed_point_overflow() {
    match PlateauFreeGradient::new(linear)
        .estimate(&[0.0, f64::MAX], 1e308)
        .unwrap_err()
    {
        Error::NonFinitePoint {
            sample,
            index,
            value,
        } => {
            assert_eq!(index, 1);
            assert!(value.is_infinite());
            assert!(sample < 2);
        }
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        Spsa::new(linear).estimate(&[f64::MAX], 1e308),
        Err(Error::NonFinitePoint { index: 0, .. })
    ));
}

#[test]
fn invalid_configuration() {
    let name_and_value = |e: Error| match e {
        Error::InvalidParameter { name, value, .. } => (name, value.as_f64()),
        other => panic!("{other:?}"),
    };
    assert_eq!(name_and_value(Adam::new(0.0).unwrap_err()), ("lr", 0.0));
    assert_eq!(name_and_value(Adam::new(-1.0).unwrap_err()), ("lr", -1.0));
    assert!(name_and_value(Adam::new(f64::NAN).unwrap_err()).1.is_nan());
    let adam = Adam::new(0.1).unwrap();
    assert_eq!(
        name_and_value(adam.clone().betas(1.0, 0.9).unwrap_err()),
        ("beta1", 1.0)
    );
    assert_eq!(
        name_and_value(adam.clone().betas(0.9, -0.1).unwrap_err()),
        ("beta2", -0.1)
    );
    assert_eq!(
        name_and_value(adam.clone().epsilon(0.0).unwrap_err()),
        ("epsilon", 0.0)
    );
    assert_eq!(
        name_and_value(Annealer::paper(0.0, 10).unwrap_err()),
        ("sigma0", 0.0)
    );
    assert_eq!(
        name_and_value(Annealer::paper(0.5, 0).unwrap_err()),
        ("iterations", 0.0)
    );
    assert_eq!(
        name_and_value(Annealer::exponential(0.5, f64::INFINITY, 10).unwrap_err()),
        ("sigma_min", f64::INFINITY)
    );
    assert_eq!(
        name_and_value(
            Annealer::new(Schedule::WarmLinear { warmup: 1.0 }, 0.5, 0.01, 10).unwrap_err()
        ),
        ("warmup", 1.0)
    );
    assert_eq!(
        name_and_value(FiniteDifference::new(linear, 0.0).expect_err("zero step rejected")),
        ("step", 0.0)
    );
    match adam
        .clone()
        .bounds(vec![0.0, 2.0], vec![1.0, 1.0])
        .unwrap_err()
    {
        Error::InvalidBounds {
            index,
            lower,
            upper,
        } => assert_eq!((index, lower, upper), (1, 2.0, 1.0)),
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        adam.bounds(vec![f64::NAN], vec![1.0]),
        Err(Error::InvalidBounds { index: 0, .. })
    ));
}

#[test]
fn messages_name_the_values() {
    let cases: Vec<(Error, &str)> = vec![
        (Error::InvalidSigma(-2.5), "-2.5"),
        (
            Error::NonFiniteTheta {
                index: 4,
                value: f64::NAN,
            },
            "theta[4] = NaN",
        ),
        (Error::OddSamples(3), "got 3"),
        (
            Error::InvalidSpread {
                index: 1,
                value: 0.0,
            },
            "spreads[1] = 0",
        ),
    ];
    for (err, needle) in cases {
        assert!(err.to_string().contains(needle), "{err}");
    }
}

/// Every `InvalidParameter` names the option and shows its value as it was written: a count
/// as an integer (it printed `budget = 0e0`, `population = 1e0`), a real number as a real
/// number (`lr = -0.5`, not `-5e-1`).
#[test]
fn messages_show_values_as_written() {
    use plateau_free::{error::ParameterValue, run::Strategy, Minimizer};
    let f = |x: &[f64]| x[0];
    let message = |e: Error| e.to_string();
    let m = || Minimizer::new(f);
    assert_eq!(
        message(m().budget(0).run(&[1.0]).unwrap_err()),
        "budget = 0 is invalid: must be at least 1 evaluation"
    );
    assert_eq!(
        message(m().population(1).run(&[1.0]).unwrap_err()),
        "population = 1 is invalid: must be at least 2"
    );
    assert_eq!(
        message(Annealer::paper(0.5, 0).unwrap_err()),
        "iterations = 0 is invalid: must be at least 1"
    );
    assert_eq!(
        message(Adam::new(-0.5).unwrap_err()),
        "lr = -0.5 is invalid: must be finite and > 0"
    );
    assert_eq!(
        message(Adam::new(1e-320).unwrap().betas(1.0, 0.9).unwrap_err()),
        "beta1 = 1.0 is invalid: must be in [0, 1)"
    );
    assert_eq!(
        message(m().sigma0(f64::NAN).run(&[1.0]).unwrap_err()),
        "sigma0 = NaN is invalid: must be finite and > 0"
    );
    assert_eq!(
        message(m().sigma0(-1e-300).run(&[1.0]).unwrap_err()),
        "sigma0 = -1e-300 is invalid: must be finite and > 0"
    );
    assert_eq!(
        message(
            m().strategy(Strategy::Paper {
                samples: 2,
                lr: 0.1,
                sigma0: 1.0
            })
            .polish(1.0)
            .run(&[1.0])
            .unwrap_err()
        ),
        "polish = 1.0 is invalid: must be a fraction of the budget in [0, 1): the share the adaptive search gets after the paper's loop"
    );
    assert_eq!(
        message(m().stop_when_stalled(0.0).run(&[1.0]).unwrap_err()),
        "stop_when_stalled = 0.0 is invalid: must be a fraction of the budget in (0, 1]: the window over which the best value must improve (STALL_WINDOW = 0.2 is the tested choice)"
    );
    assert_eq!(
        Error::ZeroSamples.to_string(),
        "samples = 0 is invalid: must be at least 1 (evaluations of f per estimate)"
    );
    assert_eq!(
        message(FiniteDifference::new(f, f64::INFINITY).unwrap_err()),
        "step = inf is invalid: must be finite and > 0"
    );
    assert!(matches!(
        m().budget(0).run(&[1.0]).unwrap_err(),
        Error::InvalidParameter {
            name: "budget",
            value: ParameterValue::Integer(0),
            ..
        }
    ));
    assert_eq!(
        message(
            m().bounds(vec![0.0, -1.0], vec![1.0, 1.0])
                .run(&[0.5, 2.0])
                .unwrap_err()
        ),
        "x0[1] = 2.0 lies outside the bounds [-1.0, 1.0]"
    );
}

/// `Metric::Full` (and `Metric::Decoded`) above `FULL_METRIC_LIMIT` dimensions is refused before anything is
/// allocated (its n x n matrices would abort the process at n = 10^5), in a run and in
/// ask/tell; at the limit, and with the other metrics far above it, the options pass.
#[test]
fn the_full_metric_refuses_a_dimension_it_cannot_hold() {
    use plateau_free::{error::ParameterValue, run::Metric, run::FULL_METRIC_LIMIT, Minimizer};
    let f = |x: &[f64]| x.iter().sum::<f64>();
    let big = vec![0.0; 100_000];
    let e = Minimizer::new(f)
        .metric(Metric::Full)
        .budget(1)
        .run(&big)
        .unwrap_err();
    assert_eq!(
        e.to_string(),
        "dimension = 100000 is invalid: above 10000 is too large for Metric::Full and Metric::Decoded (they keep n x n matrices); use Metric::Diagonal or Metric::Auto"
    );
    assert!(e.to_string().contains(&FULL_METRIC_LIMIT.to_string()));
    let over = vec![0.0; FULL_METRIC_LIMIT + 1];
    for metric in [Metric::Full, Metric::Decoded] {
        assert!(matches!(
            Minimizer::new(f)
                .metric(metric)
                .ask_tell(&over)
                .unwrap_err(),
            Error::InvalidParameter {
                name: "dimension",
                value: ParameterValue::Integer(10_001),
                ..
            }
        ));
    }
    // The other metrics at n = 10^5, one evaluation: the start alone.
    for metric in [Metric::Auto, Metric::Diagonal] {
        let r = Minimizer::new(f)
            .metric(metric)
            .budget(1)
            .run(&big)
            .unwrap();
        assert_eq!(r.evaluations, 1);
    }
}

/// Every other variant shows its numbers as `InvalidParameter` does: counts as integers, real
/// numbers in the shortest text that reads back to the same bits (it printed `sigma = -2.5e0`,
/// `theta[0] = 1e300`, `lower 1e0 > upper 0e0`).
#[test]
fn every_variant_shows_its_numbers_as_written() {
    let rows: Vec<(Error, &str)> =
        vec![
        (
            Error::NonFiniteTheta {
                index: 2,
                value: f64::NEG_INFINITY,
            },
            "theta[2] = -inf is not finite",
        ),
        (
            Error::InvalidSigma(-2.5),
            "sigma = -2.5 must be finite and > 0",
        ),
        (Error::InvalidSigma(0.0), "sigma = 0.0 must be finite and > 0"),
        (
            Error::InvalidSpread {
                index: 1,
                value: 1e-320,
            },
            "spreads[1] = 1e-320 must be finite and > 0",
        ),
        (
            Error::NonFinitePoint {
                sample: 3,
                index: 0,
                value: f64::INFINITY,
            },
            "perturbed point 3 has coordinate 0 = inf (theta plus offset overflowed)",
        ),
        (
            Error::NonFiniteValue {
                sample: 7,
                value: f64::NAN,
                point: vec![0.1, 1.0, -1e300, 2.5, 9.0],
            },
            "f returned NaN at evaluation 7, point [0.1, 1.0, -1e300, 2.5, ... (5 coordinates)]",
        ),
        (
            Error::NonFiniteGradient {
                index: 0,
                value: f64::MAX,
            },
            "gradient coordinate 0 = 1.7976931348623157e308 is not finite: f's values are too \
             large for the spread; rescale f",
        ),
        (
            Error::StepOverflow {
                index: 1,
                theta: 1e308,
                value: f64::INFINITY,
            },
            "the step would overflow theta[1] = 1e308 to inf; reduce lr",
        ),
        (
            Error::InvalidBounds {
                index: 0,
                lower: 1.0,
                upper: 0.0,
            },
            "bounds[0]: lower 1.0 > upper 0.0 (or not a number)",
        ),
        (
            Error::OutsideBounds {
                what: "x0",
                index: 0,
                value: 0.3,
                lower: 0.5,
                upper: 1.0,
            },
            "x0[0] = 0.3 lies outside the bounds [0.5, 1.0]",
        ),
        (
            Error::TellCount {
                expected: 4,
                got: 0,
            },
            "tell got 0 values for 4 asked points",
        ),
        (
            Error::Unfinished {
                evaluations: 0,
                budget: 10,
            },
            "the run is not finished (0 of at most 10 evaluations told): ask and tell until ask \
             gives None",
        ),
        (
            Error::LengthMismatch {
                what: "spreads",
                expected: 3,
                got: 0,
            },
            "length mismatch: spreads has length 0, expected 3",
        ),
    ];
    for (error, text) in rows {
        assert_eq!(error.to_string(), text);
    }
    // Through the API: a bad start, a bad spread, a saved state with a bad moment.
    let mut est = PlateauFreeGradient::new(linear);
    assert_eq!(
        est.estimate(&[1e300, f64::NAN], 0.5)
            .unwrap_err()
            .to_string(),
        "theta[1] = NaN is not finite"
    );
    assert_eq!(
        est.estimate(&[1.0], 0.0).unwrap_err().to_string(),
        "sigma = 0.0 must be finite and > 0"
    );
}
