//! Ask and tell: the optimiser hands out each iteration's points and takes their values back.
//!
//! The ask-and-tell form and the callback form give each other's results for every form of
//! objective, with and without parallel evaluation, with the same seeds, the same failures,
//! the same resampling, the same stops; a paper loop stopped and continued from its state is
//! the whole run. (`ask_tell_pinned.rs` compares both with pinned results,
//! `ask_tell_errors.rs` checks the misuses.)

use std::cell::RefCell;

use plateau_free::{
    estimator::OnFailure, objective::Batch, objective::Seeded, run::FailurePolicy,
    run::OptimizerState, run::Strategy, Adam, Annealer, Error, Minimizer, Optimizer,
    PlateauFreeGradient, Stop,
};

mod common;
use common::ask_tell::*;

#[test]
fn minimize_ask_tell_equals_run_for_every_form_of_objective() {
    for seed in [0, 5, 17] {
        for strategy in [Strategy::Adaptive, PAPER] {
            let x0 = [0.3, -1.2, 2.0, 0.0];
            let told = drive(
                opts(Minimizer::without_objective(), seed, strategy)
                    .ask_tell(&x0)
                    .unwrap(),
                noisy,
            );
            let plain = opts(Minimizer::new(stairs), seed, strategy)
                .run(&x0)
                .unwrap();
            let seeded = opts(Minimizer::new(Seeded(noisy)), seed, strategy)
                .run(&x0)
                .unwrap();
            let batch = opts(Minimizer::new(Batch(noisy_batch)), seed, strategy)
                .run(&x0)
                .unwrap();
            assert_eq!(told, seeded, "seed {seed}, {strategy:?}");
            assert_eq!(told, batch, "seed {seed}, {strategy:?}");
            // Without the noise, the plain objective's run is the noiseless ask and tell's.
            let told_plain = drive(
                opts(Minimizer::without_objective(), seed, strategy)
                    .ask_tell(&x0)
                    .unwrap(),
                |x, _| stairs(x),
            );
            assert_eq!(told_plain, plain, "seed {seed}, {strategy:?}");
            // The objective a minimiser holds is not used by its ask and tell.
            let from_callback_minimizer = drive(
                opts(Minimizer::new(|_: &[f64]| f64::NAN), seed, strategy)
                    .ask_tell(&x0)
                    .unwrap(),
                noisy,
            );
            assert_eq!(from_callback_minimizer, told);
        }
    }
}

#[test]
fn paper_loop_ask_tell_equals_minimize_sequential_and_parallel() {
    for seed in [1, 2, 9] {
        for (_, sampling, antithetic, orthogonal) in LOOPS {
            let told = drive_paper(
                loop_optimizer()
                    .ask_tell(
                        loop_estimator(
                            PlateauFreeGradient::without_objective(),
                            seed,
                            sampling,
                            antithetic,
                            orthogonal,
                        ),
                        &LOOP_START,
                    )
                    .unwrap(),
                noisy,
            );
            let est = |f| {
                loop_estimator(
                    PlateauFreeGradient::new(f),
                    seed,
                    sampling,
                    antithetic,
                    orthogonal,
                )
            };
            let seq = loop_optimizer()
                .minimize(&mut est(Seeded(noisy)), &LOOP_START)
                .unwrap();
            let par = loop_optimizer()
                .minimize(&mut est(Seeded(noisy)).parallel(true), &LOOP_START)
                .unwrap();
            let batch = loop_optimizer()
                .minimize(
                    &mut loop_estimator(
                        PlateauFreeGradient::new(Batch(noisy_batch)),
                        seed,
                        sampling,
                        antithetic,
                        orthogonal,
                    ),
                    &LOOP_START,
                )
                .unwrap();
            assert_eq!(told, seq);
            assert_eq!(told, par);
            assert_eq!(told, batch);
        }
    }
}

#[test]
fn asked_seeds_are_the_seeds_the_callback_forms_receive() {
    for strategy in [Strategy::Adaptive, PAPER] {
        // The callback form's seeds, in the order of the calls.
        let log = RefCell::new(Vec::new());
        let logged = Seeded(|x: &[f64], seed: u64| {
            log.borrow_mut().push(seed);
            noisy(x, seed)
        });
        opts(Minimizer::new(logged), 4, strategy)
            .polish(0.0)
            .run(&[1.0, 2.0])
            .unwrap();
        let mut asked = Vec::new();
        let mut run = opts(Minimizer::without_objective(), 4, strategy)
            .polish(0.0)
            .ask_tell(&[1.0, 2.0])
            .unwrap();
        while let Some(ask) = run.ask().unwrap() {
            assert_eq!(ask.dim(), 2);
            assert_eq!(ask.points().len(), ask.len());
            asked.extend_from_slice(ask.seeds());
            let values = evaluate_elsewhere(ask, noisy);
            run.tell(&values).unwrap();
        }
        assert_eq!(asked, *log.borrow(), "{strategy:?}");
        assert_eq!(asked.len(), run.finish().unwrap().evaluations);
        // The start first, alone, with the run's seed. Then the adaptive search: one seed
        // per generation (the first generation's is the run's); the paper's loop: one per
        // pair, and the final evaluation's seed is the run's.
        assert_eq!(asked[0], 4);
        if strategy == PAPER {
            assert_eq!(asked[1], asked[2]);
            assert_ne!(asked[2], asked[3]);
            assert_eq!(*asked.last().unwrap(), 4);
        } else {
            assert!(asked[..7].iter().all(|&s| s == asked[0]));
        }
    }
}

#[test]
fn a_nan_fails_as_in_the_callback_form() {
    // f is NaN on part of the line: the callback form's error, and ask and tell's, agree.
    let f = |x: &[f64]| {
        if x[0] > 2.0 {
            f64::NAN
        } else {
            (x[0] - 3.0).powi(2)
        }
    };
    for strategy in [Strategy::Adaptive, PAPER] {
        let called = opts(Minimizer::new(f), 2, strategy)
            .on_failure(FailurePolicy::Raise)
            .run(&[0.0])
            .unwrap_err();
        let mut run = opts(Minimizer::without_objective(), 2, strategy)
            .on_failure(FailurePolicy::Raise)
            .ask_tell(&[0.0])
            .unwrap();
        let told = loop {
            let ask = run.ask().unwrap().expect("fails before the end");
            let values = evaluate_elsewhere(ask, |x, _| f(x));
            if let Err(e) = run.tell(&values) {
                break e;
            }
        };
        // (NaN != NaN: compared by the message, which names the evaluation and the point.)
        assert_eq!(told.to_string(), called.to_string(), "{strategy:?}");
        assert!(matches!(told, Error::NonFiniteValue { .. }), "{told}");
    }
}

#[test]
fn resampling_in_the_paper_loop_redraws_at_the_next_ask() {
    // NaN on a quarter of the line: estimates are redrawn until every value is finite.
    let f = |x: &[f64]| {
        if x[0].fract().abs() < 0.25 {
            f64::NAN
        } else {
            (x[0] - 2.0).abs()
        }
    };
    let policy = OnFailure::Resample { limit: 50 };
    let opt = || {
        Optimizer::new(
            Adam::new(0.1).unwrap(),
            Annealer::constant(0.4, 40).unwrap(),
        )
    };
    let called = opt()
        .minimize(
            &mut PlateauFreeGradient::new(f)
                .samples(4)
                .seed(8)
                .on_failure(policy),
            &[0.6],
        )
        .unwrap();
    let grad = PlateauFreeGradient::without_objective()
        .samples(4)
        .seed(8)
        .on_failure(policy);
    let mut run = opt().ask_tell(grad, &[0.6]).unwrap();
    let (mut asks, mut redraws) = (0, 0);
    loop {
        let iteration = run.iteration();
        let Some(ask) = run.ask().unwrap() else {
            break;
        };
        asks += 1;
        let values = evaluate_elsewhere(ask, |x, _| f(x));
        run.tell(&values).unwrap();
        if run.iteration() == iteration {
            redraws += 1;
            assert!(values.iter().any(|v| v.is_nan()));
        } else {
            assert_eq!(run.last_estimate().unwrap().resampled, redraws);
            redraws = 0;
        }
    }
    assert!(asks > 40, "some estimates were redrawn: {asks} asks");
    assert_eq!(run.finish(), called);
}

#[test]
fn a_paper_loop_stopped_and_continued_from_its_state_is_the_whole_run() {
    let grad = || PlateauFreeGradient::without_objective().samples(6).seed(21);
    let whole = drive_paper(
        loop_optimizer().ask_tell(grad(), &LOOP_START).unwrap(),
        noisy,
    );
    let mut run = loop_optimizer().ask_tell(grad(), &LOOP_START).unwrap();
    for _ in 0..25 {
        let ask = run.ask().unwrap().unwrap();
        let values = evaluate_elsewhere(ask, noisy);
        run.tell(&values).unwrap();
    }
    // An iteration in progress is repeated by the continued run.
    run.ask().unwrap();
    let saved: OptimizerState = run.state();
    assert_eq!(saved.iteration, 25);
    let early = run.finish();
    assert!(early.stopped_early);
    assert_eq!(early.iterations(), 25);
    // Continued by ask and tell, and by the callback form.
    let continued = loop_optimizer()
        .ask_tell_from(grad(), saved.clone())
        .unwrap();
    assert_eq!(drive_paper(continued, noisy), whole);
    let mut callback = PlateauFreeGradient::new(Seeded(noisy)).samples(6).seed(21);
    let state = loop_optimizer()
        .minimize_from(
            &mut callback,
            saved,
            |_| std::ops::ControlFlow::Continue(()),
        )
        .unwrap();
    assert_eq!(state.history, whole);
}

#[test]
fn a_paper_budget_too_small_for_an_iteration_asks_for_the_start_alone() {
    let mut run = Minimizer::without_objective()
        .budget(4)
        .strategy(PAPER)
        .target(1.0)
        .ask_tell(&[0.25, 0.5])
        .unwrap();
    let ask = run.ask().unwrap().unwrap();
    assert_eq!(ask.points().as_flat(), &[0.25, 0.5]);
    assert_eq!(ask.seeds(), &[0]);
    assert_eq!(
        run.tell(&[0.5, 0.5]),
        Err(Error::TellCount {
            expected: 1,
            got: 2
        })
    );
    run.tell(&[0.5]).unwrap();
    let best = run.finish().unwrap();
    assert_eq!((best.fun, best.evaluations, best.iterations), (0.5, 1, 0));
    assert_eq!(best.stop, Stop::Target);
    let called = Minimizer::new(|x: &[f64]| x[0] + x[1] - 0.25)
        .budget(4)
        .strategy(PAPER)
        .target(1.0)
        .run(&[0.25, 0.5])
        .unwrap();
    assert_eq!(called, best);
}

/// The paper's loop stops at its target as the adaptive search does: after the estimate whose
/// points first reach it, with no final evaluation and no polish; the callback form and ask
/// and tell stop at the same evaluation.
#[test]
fn the_paper_loop_stops_after_the_estimate_that_reaches_the_target() {
    let f = |x: &[f64]| (x[0] - 1.0).powi(2) + (x[1] + 0.5).powi(2);
    let target = 0.05;
    for polish in [0.0, 0.5] {
        let mut run = Minimizer::without_objective()
            .budget(2002)
            .seed(4)
            .strategy(PAPER)
            .polish(polish)
            .target(target)
            .ask_tell(&[0.0, 0.0])
            .unwrap();
        let mut first_reached = None;
        while let Some(ask) = run.ask().unwrap() {
            let values: Vec<f64> = ask.iter().map(|(x, _)| f(x)).collect();
            let reached = values.iter().any(|&v| v <= target);
            run.tell(&values).unwrap();
            if reached && first_reached.is_none() {
                first_reached = Some(run.evaluations());
                assert!(run.is_done(), "the run goes on past its target");
            }
        }
        let told = run.finish().unwrap();
        assert_eq!(told.stop, Stop::Target, "{told:?}");
        assert!(told.fun <= target, "{told:?}");
        assert_eq!(Some(told.evaluations), first_reached);
        // The start (f = 1.25, above the target), then whole estimates of 4 points.
        assert_eq!(told.evaluations, 1 + 4 * told.iterations, "{told:?}");
        assert!(told.evaluations < 2002 / 4, "{told:?}");
        assert_eq!(f(&told.x), told.fun);
        let called = Minimizer::new(f)
            .budget(2002)
            .seed(4)
            .strategy(PAPER)
            .polish(polish)
            .target(target)
            .run(&[0.0, 0.0]);
        assert_eq!(called.as_ref(), Ok(&told), "polish {polish}");
    }
}
