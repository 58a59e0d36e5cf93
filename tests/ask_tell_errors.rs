//! Ask and tell's errors: asking twice, telling without asking, the wrong number of values,
//! non-finite values, a result taken too early, bad options.

use plateau_free::{
    run::FailurePolicy, run::Strategy, Adam, Annealer, Error, Minimizer, Optimizer,
    PlateauFreeGradient,
};

mod common;
use common::ask_tell::*;

#[test]
fn asking_twice_and_telling_without_asking_are_errors() {
    for strategy in [Strategy::Adaptive, PAPER] {
        let mut run = opts(Minimizer::without_objective(), 0, strategy)
            .ask_tell(&[0.5, 0.5])
            .unwrap();
        assert_eq!(run.tell(&[1.0]), Err(Error::NothingAsked));
        let first: Vec<f64> = run.ask().unwrap().unwrap().points().as_flat().to_vec();
        assert_eq!(run.ask().unwrap_err(), Error::AskPending);
        assert_eq!(
            Error::AskPending.to_string(),
            "ask called twice: the asked points still wait for their values (tell them first)"
        );
        let values: Vec<f64> = first.chunks(2).map(stairs).collect();
        run.tell(&values).unwrap();
        assert_eq!(run.tell(&values), Err(Error::NothingAsked), "told twice");
        // A paper loop on its own behaves the same.
        let grad = PlateauFreeGradient::without_objective().samples(4);
        let mut run = Optimizer::new(Adam::new(0.1).unwrap(), Annealer::constant(0.2, 3).unwrap())
            .ask_tell(grad, &[0.0])
            .unwrap();
        assert_eq!(run.tell(&[0.0; 4]), Err(Error::NothingAsked));
        run.ask().unwrap();
        assert_eq!(run.ask().unwrap_err(), Error::AskPending);
    }
}

#[test]
fn the_wrong_number_of_values_or_a_nan_changes_nothing() {
    for strategy in [Strategy::Adaptive, PAPER] {
        let clean = drive(
            opts(Minimizer::without_objective(), 3, strategy)
                .ask_tell(&[0.5, 0.5, 0.5])
                .unwrap(),
            noisy,
        );
        // The same run with mistakes in its third iteration, then corrected.
        let mut run = opts(Minimizer::without_objective(), 3, strategy)
            .on_failure(FailurePolicy::Raise)
            .ask_tell(&[0.5, 0.5, 0.5])
            .unwrap();
        let mut iteration = 0;
        while let Some(ask) = run.ask().unwrap() {
            let values = evaluate_elsewhere(ask, noisy);
            if iteration == 2 {
                let k = values.len();
                assert_eq!(
                    run.tell(&values[..k - 1]),
                    Err(Error::TellCount {
                        expected: k,
                        got: k - 1
                    })
                );
                assert_eq!(
                    Error::TellCount {
                        expected: 8,
                        got: 7
                    }
                    .to_string(),
                    "tell got 7 values for 8 asked points"
                );
                let mut bad = values.clone();
                bad[1] = f64::NAN;
                match run.tell(&bad) {
                    Err(Error::NonFiniteValue {
                        sample,
                        value,
                        point,
                    }) => {
                        assert!(value.is_nan());
                        // The adaptive search counts evaluations over the run, the paper's
                        // loop within the estimate (as their callback forms do).
                        let first = if strategy == PAPER {
                            0
                        } else {
                            run.evaluations()
                        };
                        assert_eq!(sample, first + 1);
                        assert_eq!(point.len(), 3);
                    }
                    other => panic!("{other:?}"),
                }
                bad[1] = f64::NEG_INFINITY;
                assert!(matches!(run.tell(&bad), Err(Error::NonFiniteValue { .. })));
            }
            run.tell(&values).unwrap();
            iteration += 1;
        }
        assert_eq!(run.finish().unwrap(), clean, "{strategy:?}");
    }
}

#[test]
fn results_come_at_the_end_and_bad_options_are_errors() {
    let mut run = Minimizer::without_objective()
        .budget(50)
        .ask_tell(&[1.0])
        .unwrap();
    assert_eq!(run.best(), None);
    assert_eq!(run.result(), None);
    let ask = run.ask().unwrap().unwrap();
    let values = evaluate_elsewhere(ask, |x, _| x[0] * x[0]);
    run.tell(&values).unwrap();
    let (x, fun) = run.best().unwrap();
    assert_eq!(fun, values.iter().copied().fold(f64::INFINITY, f64::min));
    assert_eq!(x[0] * x[0], fun);
    assert_eq!(
        run.finish(),
        Err(Error::Unfinished {
            evaluations: values.len(),
            budget: 50
        })
    );
    // The options are checked where the run is made, as `run` checks them.
    let m = Minimizer::without_objective;
    assert_eq!(m().ask_tell(&[]).unwrap_err(), Error::EmptyTheta);
    assert!(matches!(
        m().budget(0).ask_tell(&[1.0]),
        Err(Error::InvalidParameter { name: "budget", .. })
    ));
    assert_eq!(
        m().strategy(Strategy::Paper {
            samples: 3,
            lr: 0.1,
            sigma0: 1.0
        })
        .ask_tell(&[1.0])
        .unwrap_err(),
        Error::OddSamples(3)
    );
    let opt = || Optimizer::new(Adam::new(0.1).unwrap(), Annealer::constant(0.2, 3).unwrap());
    assert_eq!(
        opt()
            .ask_tell(PlateauFreeGradient::without_objective().samples(3), &[1.0])
            .unwrap_err(),
        Error::OddSamples(3)
    );
    assert!(matches!(
        opt().ask_tell(PlateauFreeGradient::without_objective(), &[f64::NAN]),
        Err(Error::NonFiniteTheta { index: 0, .. })
    ));
}
