//! Failing objectives: NaN and infinite values (fail or resample) and panics (unwind or
//! caught), alone and inside an optimisation run.

use std::ops::ControlFlow;
use std::sync::atomic::{AtomicUsize, Ordering};

use plateau_free::{
    estimator::OnFailure, run::OptimizerState, Adam, Annealer, Error, Optimizer,
    PlateauFreeGradient,
};

mod common;
use common::{assert_repeats_sequential_and_parallel, bits, tilted_2d};

/// NaN on the bands where `x0 + x1` has a fractional part below 0.3: about a third of the
/// plane, so most estimates at sigma 0.5 meet it.
fn banded(x: &[f64]) -> f64 {
    let s = x[0] + x[1];
    if (s - s.floor()) < 0.3 {
        f64::NAN
    } else {
        (x[0] - 0.2).powi(2) + x[1].abs()
    }
}

#[test]
fn fail_is_the_default_and_names_value_and_point() {
    let mut grad = PlateauFreeGradient::new(banded).samples(8).seed(1);
    // Some estimates miss the bands; the first that meets one fails.
    let err = (0..50)
        .find_map(|_| grad.estimate(&[0.5, 0.6], 0.5).err())
        .expect("an estimate meets a NaN band");
    match &err {
        Error::NonFiniteValue { value, point, .. } => {
            assert!(value.is_nan());
            let s = point[0] + point[1];
            assert!(s - s.floor() < 0.3, "{point:?}");
        }
        other => panic!("expected NonFiniteValue, got {other:?}"),
    }
    assert!(err.to_string().contains("NaN"), "{err}");
}

#[test]
fn resample_redraws_until_finite_and_counts_it() {
    let make = || {
        PlateauFreeGradient::new(banded)
            .samples(8)
            .seed(1)
            .on_failure(OnFailure::Resample { limit: 100 })
    };
    let mut grad = make();
    let mut total_resampled = 0;
    for _ in 0..20 {
        let est = grad.estimate(&[0.5, 0.6], 0.5).unwrap();
        assert!(est.gradient.iter().all(|g| g.is_finite()));
        assert!(est.mean_value.is_finite());
        assert_eq!(est.evaluations, 8 * (est.resampled + 1));
        total_resampled += est.resampled;
    }
    // With 8 points per estimate and a third of the plane NaN, redraws are the rule.
    assert!(total_resampled > 10, "{total_resampled}");
}

#[test]
fn resampling_is_deterministic_and_parallel_matches_sequential() {
    assert_repeats_sequential_and_parallel(
        || {
            PlateauFreeGradient::new(banded)
                .samples(8)
                .seed(9)
                .on_failure(OnFailure::Resample { limit: 100 })
        },
        |grad| {
            (0..10)
                .map(|i| {
                    let e = grad.estimate(&[0.5 + 0.1 * i as f64, 0.6], 0.5).unwrap();
                    (bits(&e.gradient), e.resampled, e.mean_value.to_bits())
                })
                .collect::<Vec<_>>()
        },
    );
}

#[test]
fn resampling_changes_nothing_when_f_is_finite() {
    let f = |x: &[f64]| (x[0] - 1.0).abs() + x[1] * x[1];
    let mut plain = PlateauFreeGradient::new(f).samples(6).seed(4);
    let mut policy = PlateauFreeGradient::new(f)
        .samples(6)
        .seed(4)
        .on_failure(OnFailure::Resample { limit: 5 });
    for _ in 0..5 {
        let (a, b) = (
            plain.estimate(&[0.3, 0.1], 0.2).unwrap(),
            policy.estimate(&[0.3, 0.1], 0.2).unwrap(),
        );
        assert_eq!(a, b);
        assert_eq!(b.resampled, 0);
    }
}

#[test]
fn resampling_gives_up_at_the_limit() {
    let nan = |_: &[f64]| f64::NAN;
    for limit in [0, 3] {
        let mut grad = PlateauFreeGradient::new(nan).on_failure(OnFailure::Resample { limit });
        assert!(matches!(
            grad.estimate(&[0.0], 1.0),
            Err(Error::NonFiniteValue { .. })
        ));
        // One estimate spent however many redraws it took.
        assert_eq!(grad.estimates_made(), 1);
    }
}

#[test]
fn caught_panics_are_errors_sequential_and_parallel() {
    let f = |x: &[f64]| {
        if x[0] > 5.0 {
            panic!("out of range: {}", x[0])
        }
        x[0]
    };
    for parallel in [false, true] {
        let mut grad = PlateauFreeGradient::new(f)
            .samples(16)
            .parallel(parallel)
            .catch_panics(true);
        match grad.estimate(&[10.0], 0.1) {
            Err(Error::ObjectivePanicked { estimate, message }) => {
                assert_eq!(estimate, 0);
                assert!(message.starts_with("out of range: "), "{message}");
            }
            other => panic!("expected ObjectivePanicked, got {other:?}"),
        }
        // The estimator is intact and the panicked estimate is spent.
        assert_eq!(grad.estimates_made(), 1);
        let ok = grad.estimate(&[0.0], 0.1).unwrap();
        assert!(ok.gradient[0].is_finite());
    }
}

#[test]
fn uncaught_panics_unwind_as_before() {
    let f = |_: &[f64]| -> f64 { panic!("boom") };
    let mut grad = PlateauFreeGradient::new(f);
    let unwound = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let _ = grad.estimate(&[0.0], 1.0);
    }));
    assert!(unwound.is_err());
}

#[test]
fn a_panic_mid_run_keeps_the_state_and_the_run_resumes_bit_identical() {
    let calls = AtomicUsize::new(0);
    // The tilted step, except that its 57th call (iteration 7 with 8 samples) panics.
    let flaky = |x: &[f64]| {
        if calls.fetch_add(1, Ordering::SeqCst) == 56 {
            panic!("transient failure");
        }
        tilted_2d(x)
    };
    let opt = || {
        Optimizer::new(Adam::new(0.02).unwrap(), Annealer::paper(0.5, 40).unwrap())
            .record_theta(true)
    };
    let whole = opt()
        .minimize(
            &mut PlateauFreeGradient::new(tilted_2d).samples(8).seed(3),
            &[1.0, 1.0],
        )
        .unwrap();

    let mut grad = PlateauFreeGradient::new(flaky)
        .samples(8)
        .seed(3)
        .catch_panics(true);
    let err = opt()
        .run(&mut grad, &[1.0, 1.0], |_| ControlFlow::Continue(()))
        .unwrap_err();
    assert!(
        matches!(err.error, Error::ObjectivePanicked { estimate: 7, .. }),
        "{err}"
    );
    assert_eq!(err.history().iterations(), 7);
    assert_eq!(err.history().theta[..], whole.theta[..7]);
    assert_eq!(err.state.stream_position, Some(7));

    // Continued (the failure was transient) it ends where the uninterrupted run ended.
    let state: OptimizerState = *err.state;
    let done = opt()
        .minimize_from(&mut grad, state, |_| ControlFlow::Continue(()))
        .unwrap();
    assert_eq!(done.history, whole);
    assert_eq!(bits(&done.theta), bits(whole.last_theta().unwrap()));
}
