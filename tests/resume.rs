//! Saving an optimiser's state and continuing from it: an interrupted run, saved (through
//! JSON under the `serde` feature) and resumed, ends bit for bit where the uninterrupted run
//! ends; a bad state is refused whole.

use std::ops::ControlFlow;

use plateau_free::baseline::Spsa;
use plateau_free::{
    adam::AdamMoments, run::OptimizerState, Adam, Annealer, Error, GradientEstimator, Optimizer,
    PlateauFreeGradient,
};

mod common;
use common::{bits, tilted_2d};

fn optimizer(record: bool) -> Optimizer {
    Optimizer::new(Adam::new(0.02).unwrap(), Annealer::paper(0.5, 60).unwrap()).record_theta(record)
}

/// Through JSON when the feature is on, else a clone: what a checkpoint file would do.
fn save_and_load(state: &OptimizerState) -> OptimizerState {
    #[cfg(feature = "serde")]
    {
        let text = serde_json::to_string(state).unwrap();
        serde_json::from_str(&text).unwrap()
    }
    #[cfg(not(feature = "serde"))]
    {
        state.clone()
    }
}

/// Runs to the end, stopping at each iteration in `stops` and continuing from a saved copy
/// with a freshly built optimiser and estimator (as a new process would).
fn run_with_stops<G: GradientEstimator>(
    make: impl Fn() -> G,
    record: bool,
    stops: &[usize],
) -> OptimizerState {
    let mut state = OptimizerState::new(&[1.0, 1.0]).unwrap();
    for &stop in stops {
        let mut grad = make();
        state = optimizer(record)
            .minimize_from(&mut grad, save_and_load(&state), |s| {
                if s.iteration == stop {
                    ControlFlow::Break(())
                } else {
                    ControlFlow::Continue(())
                }
            })
            .unwrap();
        assert_eq!(state.iteration, stop + 1);
        assert!(state.history.stopped_early);
    }
    let mut grad = make();
    optimizer(record)
        .minimize_from(&mut grad, save_and_load(&state), |_| {
            ControlFlow::Continue(())
        })
        .unwrap()
}

#[test]
fn interrupted_saved_and_resumed_is_bit_identical() {
    let make = || PlateauFreeGradient::new(tilted_2d).samples(8).seed(11);
    for record in [false, true] {
        let whole = optimizer(record)
            .minimize(&mut make(), &[1.0, 1.0])
            .unwrap();
        let resumed = run_with_stops(make, record, &[0, 17, 18, 41]);
        assert_eq!(resumed.iteration, 60);
        assert_eq!(bits(&resumed.theta), bits(whole.last_theta().unwrap()));
        assert_eq!(resumed.history, whole);
        assert!(!resumed.history.stopped_early);
    }
}

#[test]
fn resume_works_for_the_baselines_too() {
    let make = || Spsa::new(tilted_2d).seed(5);
    let whole = optimizer(true).minimize(&mut make(), &[1.0, 1.0]).unwrap();
    let resumed = run_with_stops(make, true, &[9, 30]);
    assert_eq!(resumed.history, whole);
}

#[test]
fn a_finished_state_continues_as_a_no_op() {
    let mut grad = PlateauFreeGradient::new(tilted_2d).samples(4);
    let end = optimizer(false)
        .minimize_from(&mut grad, OptimizerState::new(&[1.0, 1.0]).unwrap(), |_| {
            ControlFlow::Continue(())
        })
        .unwrap();
    let again = optimizer(false)
        .minimize_from(&mut grad, end.clone(), |_| ControlFlow::Continue(()))
        .unwrap();
    assert_eq!(again, end);
}

/// A state after a few iterations, to be damaged.
fn some_state() -> OptimizerState {
    let mut grad = PlateauFreeGradient::new(tilted_2d).samples(4).seed(2);
    optimizer(true)
        .minimize_from(&mut grad, OptimizerState::new(&[0.2, 0.1]).unwrap(), |s| {
            if s.iteration == 4 {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        })
        .unwrap()
}

#[test]
fn bad_states_are_refused_whole() {
    type Damage = fn(&mut OptimizerState);
    let cases: [(Damage, &str); 7] = [
        (|s| s.theta.push(0.0), "adam.m"),
        (|s| s.theta[1] = f64::NAN, "theta"),
        (|s| s.adam.v[0] = -1.0, "adam.v"),
        (|s| s.adam.m[1] = f64::INFINITY, "adam.m"),
        (|s| s.adam.steps = 2, "adam.steps"),
        (|s| s.history.value.pop().map(drop).unwrap_or(()), "history"),
        (|s| s.history.theta[0] = vec![0.0; 3], "history.theta"),
    ];
    for (damage, field) in cases {
        let mut state = some_state();
        damage(&mut state);
        let mut opt = optimizer(true);
        let mut grad = PlateauFreeGradient::new(tilted_2d).samples(4).seed(2);
        let err = opt
            .minimize_from(&mut grad, state.clone(), |_| ControlFlow::Continue(()))
            .unwrap_err();
        match &err.error {
            Error::InvalidState { field: f, .. } => assert_eq!(*f, field, "{err}"),
            other => panic!("expected InvalidState for {field}, got {other:?}"),
        }
        // Nothing was used: the state comes back as given, the estimator and Adam untouched.
        // (Compared by their printed form: a NaN is not equal to itself.)
        assert_eq!(format!("{:?}", err.state), format!("{state:?}"));
        assert_eq!(grad.estimates_made(), 0);
        assert_eq!(opt.adam().steps(), 0);
        assert!(err.to_string().len() < 200, "{err}");
    }
    assert!(Adam::new(0.1)
        .unwrap()
        .set_moments(AdamMoments {
            m: vec![0.0],
            v: vec![0.0, 0.0],
            steps: 1
        })
        .is_err());
}

#[cfg(feature = "serde")]
#[test]
fn a_state_survives_json_exactly() {
    let state = some_state();
    let text = serde_json::to_string(&state).unwrap();
    let back: OptimizerState = serde_json::from_str(&text).unwrap();
    assert_eq!(back, state);
    assert_eq!(bits(&back.adam.v), bits(&state.adam.v));
}

/// `HistoryKeep::Last(k)`: a run hands back the last `k` iterations, bit for bit the tail of
/// the whole record, and counts the others; stopped, saved and continued, it is the run in
/// one go; asked and told, it is the callback form.
#[test]
fn a_bounded_history_keeps_the_tail_and_resumes_bit_for_bit() {
    use plateau_free::run::HistoryKeep;
    let run = |keep, record| {
        let mut grad = PlateauFreeGradient::new(tilted_2d).samples(4).seed(2);
        optimizer(record)
            .keep_history(keep)
            .minimize(&mut grad, &[1.0, 1.0])
            .unwrap()
    };
    let all = run(HistoryKeep::All, true);
    assert_eq!((all.sigma.len(), all.dropped), (60, 0));
    assert_eq!(
        all,
        run(HistoryKeep::default(), true),
        "short runs keep all"
    );
    for k in [0, 1, 7, 30, 59, 60, 100] {
        let last = run(HistoryKeep::Last(k), true);
        let kept = k.min(60);
        assert_eq!(last.iterations(), 60);
        assert_eq!(last.dropped, 60 - kept);
        assert_eq!(bits(&last.sigma), bits(&all.sigma[60 - kept..]), "k = {k}");
        assert_eq!(bits(&last.value), bits(&all.value[60 - kept..]), "k = {k}");
        assert_eq!(last.theta, all.theta[60 - kept.max(1)..], "k = {k}");
        assert_eq!(last.last_theta(), all.last_theta());
        assert_eq!(last.evaluations, all.evaluations);

        // Stopped every 13 iterations, saved and continued.
        let keep = HistoryKeep::Last(k);
        let mut state = OptimizerState::new(&[1.0, 1.0]).unwrap();
        while state.iteration < 60 {
            let mut grad = PlateauFreeGradient::new(tilted_2d).samples(4).seed(2);
            let stop = state.iteration + 13;
            state = optimizer(true)
                .keep_history(keep)
                .minimize_from(&mut grad, save_and_load(&state), |s| {
                    if s.iteration + 1 == stop {
                        ControlFlow::Break(())
                    } else {
                        ControlFlow::Continue(())
                    }
                })
                .unwrap();
            state.validate().unwrap();
        }
        assert_eq!(state.history.sigma, last.sigma, "k = {k}");
        assert_eq!(state.history.dropped, last.dropped, "k = {k}");
        assert_eq!(state.history.theta, last.theta, "k = {k}");

        // Asked and told.
        let grad = PlateauFreeGradient::without_objective().samples(4).seed(2);
        let mut asked = optimizer(true)
            .keep_history(keep)
            .ask_tell(grad, &[1.0, 1.0])
            .unwrap();
        while let Some(ask) = asked.ask().unwrap() {
            let values: Vec<f64> = ask.points().iter().map(tilted_2d).collect();
            asked.tell(&values).unwrap();
            assert!(asked.history().sigma.len() <= 2 * k.max(1));
        }
        assert_eq!(asked.finish(), last, "k = {k}");
    }
    // A history whose dropped count does not add up is refused.
    let mut state = OptimizerState::new(&[1.0]).unwrap();
    state.history.dropped = 3;
    assert!(matches!(
        state.validate(),
        Err(Error::InvalidState {
            field: "history",
            ..
        })
    ));
}
