//! The paper's loop with a baseline estimator, asked and told ([`BaselineAskTell`]): bit for
//! bit the callback form for both baselines, seeded objectives and Adam's box; a refused
//! value changes nothing; saved through a checkpoint and resumed, the run left alone.

use plateau_free::baseline::{Baseline, BaselineAskTell, FiniteDifference, Spsa};
use plateau_free::{objective::Seeded, Adam, Annealer, Error, Optimizer};

/// A staircase with a seeded jitter: the seeds matter, and a plain gradient sees plateaus.
fn stairs(x: &[f64], seed: u64) -> f64 {
    let jitter = (seed % 1000) as f64 * 1e-6;
    x.iter()
        .enumerate()
        .map(|(i, v)| ((v * 4.0).round() / 4.0 - i as f64 * 0.3).powi(2))
        .sum::<f64>()
        + jitter
}

fn optimizer(bounded: bool) -> Optimizer {
    let adam = Adam::new(0.05).unwrap();
    let adam = match bounded {
        true => adam.bounds(vec![-1.0; 3], vec![0.4, 2.0, 2.0]).unwrap(),
        false => adam,
    };
    Optimizer::new(adam, Annealer::paper(0.5, 120).unwrap())
}

fn told(mut run: BaselineAskTell) -> plateau_free::run::History {
    while let Some(ask) = run.ask().unwrap() {
        let values: Vec<f64> = ask.iter().map(|(x, seed)| stairs(x, seed)).collect();
        run.tell(&values).unwrap();
    }
    run.finish()
}

#[test]
fn asked_and_told_equals_the_callback_form() {
    let x0 = [0.1, 0.2, -0.3];
    for bounded in [false, true] {
        for seed in [0, 9] {
            let fd = Baseline::FiniteDifference { step: 1e-3 };
            let called = optimizer(bounded)
                .minimize(
                    &mut FiniteDifference::new(Seeded(stairs), 1e-3)
                        .unwrap()
                        .seed(seed),
                    &x0,
                )
                .unwrap();
            let run = optimizer(bounded).ask_tell_baseline(fd, seed, &x0).unwrap();
            assert_eq!(told(run), called, "fd, bounded {bounded}, seed {seed}");
            let called = optimizer(bounded)
                .minimize(&mut Spsa::new(Seeded(stairs)).seed(seed), &x0)
                .unwrap();
            let run = optimizer(bounded)
                .ask_tell_baseline(Baseline::Spsa, seed, &x0)
                .unwrap();
            assert_eq!(told(run), called, "spsa, bounded {bounded}, seed {seed}");
        }
    }
}

#[test]
fn a_refused_value_changes_nothing_and_bad_settings_are_errors() {
    let mut run = optimizer(false)
        .ask_tell_baseline(Baseline::Spsa, 1, &[0.0, 0.0, 0.0])
        .unwrap();
    let first: Vec<f64> = run.ask().unwrap().unwrap().points().as_flat().to_vec();
    assert!(matches!(
        run.tell(&[1.0, f64::NAN]),
        Err(Error::NonFiniteValue { .. })
    ));
    assert!(matches!(run.tell(&[1.0]), Err(Error::TellCount { .. })));
    assert!(matches!(run.ask(), Err(Error::AskPending)));
    run.tell(&[1.0, 0.5]).unwrap();
    let second: Vec<f64> = run.ask().unwrap().unwrap().points().as_flat().to_vec();
    assert_ne!(first, second);
    assert_eq!(run.iteration(), 1);
    for step in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let bad =
            optimizer(false).ask_tell_baseline(Baseline::FiniteDifference { step }, 0, &[0.0]);
        assert!(
            matches!(bad, Err(Error::InvalidParameter { .. })),
            "step {step}"
        );
    }
    let outside = optimizer(true).ask_tell_baseline(Baseline::Spsa, 0, &[0.5, 0.0, 0.0]);
    assert!(
        matches!(outside, Err(Error::OutsideBounds { .. })),
        "{outside:?}"
    );
}

#[cfg(feature = "serde")]
mod checkpoint {
    use super::*;
    use plateau_free::lifecycle::{Checkpoint, Driver, Interrupt, Observer, Progress};

    struct StopAt(usize, Interrupt);

    impl Observer for StopAt {
        fn observe(&mut self, p: &Progress) {
            if p.iteration == self.0 {
                self.1.trigger();
            }
        }
    }

    #[test]
    fn interrupted_and_resumed_is_the_run_left_alone() {
        let x0 = [0.1, 0.2, -0.3];
        let f = |x: &[f64], seed: u64| stairs(x, seed);
        let path =
            std::env::temp_dir().join(format!("plateau-free-baseline-{}.json", std::process::id()));
        for baseline in [Baseline::FiniteDifference { step: 1e-2 }, Baseline::Spsa] {
            let fresh = || optimizer(true).ask_tell_baseline(baseline, 3, &x0).unwrap();
            let alone = told(fresh());
            let _ = std::fs::remove_file(&path);
            let stop = Interrupt::new();
            let first = Driver::new()
                .interrupt(stop.clone())
                .observe(StopAt(50, stop))
                .checkpoint(Checkpoint::new(&path))
                .run_objective(fresh(), &Seeded(f))
                .unwrap();
            assert!(first.stopped_early);
            let resumed = Driver::new()
                .checkpoint(Checkpoint::new(&path))
                .run_objective(fresh(), &Seeded(f))
                .unwrap();
            assert_eq!(resumed, alone, "{baseline:?}");
        }
        std::fs::remove_file(&path).unwrap();
    }
}
