//! The stop rule ([`Stall`], `stop_when_stalled`): on synthetic loss sequences (a converged
//! noisy plateau stops one window after its last improvement, a decreasing loss never
//! stops, non-finite values never stop it, a window beyond the budget never fires), its
//! options' checks, and the methods that use it: the adaptive search, the polish after the
//! paper's loop (not the loop within its schedule), the paper's loop past its schedule, in
//! both the callback and the ask-and-tell forms.

use plateau_free::{
    run::Stall, run::Strategy, run::STALL_WINDOW, Adam, Annealer, Error, Minimizer, Optimizer,
    PlateauFreeGradient, Stop,
};

/// A deterministic noise in [0, 1) (SplitMix64 of `i`).
fn noise(i: u64) -> f64 {
    let mut z = i.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
}

/// The first iteration (from 0) at which the rule stops on `values`, `per` evaluations each.
fn first_stop(
    rule: &mut Stall,
    per: usize,
    values: impl IntoIterator<Item = f64>,
) -> Option<usize> {
    values.into_iter().position(|v| rule.observe(per, v))
}

#[test]
fn a_converged_noisy_plateau_stops_one_window_after_its_last_improvement() {
    // 50 iterations of descent to 1.0, then a noisy floor that never beats it (a loss
    // floor with noise above it): the best last improves at iteration 49.
    let descent = (0..50).map(|i| 1.0 + (50 - i) as f64 * 0.1 - 0.1);
    let floor = (0..1000u64).map(|i| 1.0 + 0.05 * noise(i));
    let mut rule = Stall::new(40, 0.0).unwrap();
    // 4 evaluations an iteration: the window of 40 is 10 iterations after iteration 49.
    assert_eq!(first_stop(&mut rule, 4, descent.chain(floor)), Some(59));
}

#[test]
fn a_tolerance_stops_a_creeping_improvement() {
    // Improvements of 1e-9 relative an iteration: below rtol = 1e-6 over a window of 10
    // iterations, so the rule stops after the first full window; with rtol = 0 it never does.
    let creep = |k: u64| (0..k).map(|i| 1.0 - 1e-9 * i as f64);
    let mut tolerant = Stall::new(10, 1e-6).unwrap();
    assert_eq!(first_stop(&mut tolerant, 1, creep(100)), Some(10));
    let mut strict = Stall::new(10, 0.0).unwrap();
    assert_eq!(first_stop(&mut strict, 1, creep(100)), None);
}

#[test]
fn a_decreasing_loss_never_stops() {
    // Noisy but decreasing: each iteration's smallest value beats the best of any window
    // ago (a trend of 1e-3 an iteration against noise of 1e-3).
    let mut rule = Stall::new(20, 0.0).unwrap();
    let values = (0..10_000u64).map(|i| 100.0 - 1e-3 * i as f64 + 1e-3 * noise(i));
    assert_eq!(first_stop(&mut rule, 2, values), None);
    // A geometric decrease towards zero, far below any absolute scale.
    let mut rule = Stall::new(5, 0.0).unwrap();
    assert_eq!(
        first_stop(&mut rule, 1, (0..1000).map(|i| 0.5f64.powi(i))),
        None
    );
}

#[test]
fn non_finite_values_never_stop_the_rule_nor_become_the_best() {
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let mut rule = Stall::new(3, 0.0).unwrap();
        assert_eq!(
            first_stop(&mut rule, 1, std::iter::repeat_n(bad, 100)),
            None,
            "{bad}"
        );
        // Among finite values they are skipped: the best stays the finite 1.0, reached at
        // iteration 1, so the rule stops 3 evaluations later, at iteration 4.
        let mut rule = Stall::new(3, 0.0).unwrap();
        let values = [2.0, 1.0, bad, 1.5, bad, bad, bad];
        assert_eq!(first_stop(&mut rule, 1, values), Some(4), "{bad}");
    }
}

#[test]
fn a_window_longer_than_the_budget_never_fires() {
    // The rule itself: a window of 100 evaluations, 99 of them observed, all equal.
    let mut rule = Stall::new(100, 0.0).unwrap();
    assert_eq!(first_stop(&mut rule, 1, std::iter::repeat_n(0.0, 99)), None);
    // A run whose budget is the window (fraction 1): the rule cannot judge before the
    // budget ends the run, which spends it all, as without the rule.
    let f = |x: &[f64]| (x[0].abs() - 1.0).max(0.0);
    let ruled = Minimizer::new(f)
        .budget(40)
        .seed(3)
        .stop_when_stalled(1.0)
        .run(&[5.0])
        .unwrap();
    let plain = Minimizer::new(f).budget(40).seed(3).run(&[5.0]).unwrap();
    assert_eq!(ruled.stop, Stop::Budget);
    assert_eq!(ruled, plain);
}

#[test]
fn bad_windows_and_tolerances_are_errors_naming_the_option() {
    for bad in [0.0, -0.1, 1.5, f64::NAN, f64::INFINITY] {
        let err = Minimizer::new(|x: &[f64]| x[0] * x[0])
            .stop_when_stalled(bad)
            .run(&[1.0])
            .unwrap_err();
        assert!(
            matches!(
                err,
                Error::InvalidParameter {
                    name: "stop_when_stalled",
                    ..
                }
            ),
            "{bad}: {err}"
        );
        let opt = Optimizer::new(Adam::new(0.1).unwrap(), Annealer::paper(0.5, 10).unwrap());
        assert!(opt.stop_when_stalled(bad).is_err(), "{bad}");
        assert!(Stall::of_budget(bad, 100).is_err(), "{bad}");
    }
    assert!(Stall::new(0, 0.0).is_err());
    for rtol in [-1e-3, f64::NAN, f64::INFINITY] {
        assert!(Stall::new(10, rtol).is_err(), "{rtol}");
    }
    assert_eq!(Stall::of_budget(0.1, 95).unwrap().window(), 10);
    assert_eq!(Stall::of_budget(1e-9, 95).unwrap().window(), 1);
}

/// A floor: every point with `|x_i| <= 1` is optimal (a converged search's values tie).
fn floor(x: &[f64]) -> f64 {
    x.iter().map(|v| (v.abs() - 1.0).max(0.0)).sum()
}

#[test]
fn the_adaptive_search_stops_on_a_floor_and_keeps_its_best() {
    // Without the patience rule, which would end these runs first: the stall rule alone.
    let x0 = [6.0, -4.0, 3.0];
    let plain = Minimizer::new(floor)
        .budget(6000)
        .seed(5)
        .patience(0)
        .run(&x0)
        .unwrap();
    let ruled = Minimizer::new(floor)
        .budget(6000)
        .seed(5)
        .patience(0)
        .stop_when_stalled(STALL_WINDOW)
        .run(&x0)
        .unwrap();
    assert_eq!(ruled.stop, Stop::Stalled);
    assert_eq!(ruled.fun, 0.0);
    assert_eq!(plain.fun, 0.0);
    assert!(ruled.evaluations < plain.evaluations, "{ruled:?}");
    // The same run, asked and told, stops at the same evaluation with the same result.
    let mut run = Minimizer::without_objective()
        .budget(6000)
        .seed(5)
        .patience(0)
        .stop_when_stalled(STALL_WINDOW)
        .ask_tell(&x0)
        .unwrap();
    while let Some(ask) = run.ask().unwrap() {
        let values: Vec<f64> = ask.iter().map(|(x, _)| floor(x)).collect();
        run.tell(&values).unwrap();
    }
    assert_eq!(run.finish().unwrap(), ruled);
}

#[test]
fn the_polish_is_judged_from_the_hand_over_not_the_loop() {
    let paper = Strategy::Paper {
        samples: 4,
        lr: 0.05,
        sigma0: 0.5,
    };
    let run = |window: Option<f64>| {
        let mut m = Minimizer::new(floor)
            .strategy(paper)
            .polish(0.25)
            .patience(0)
            .budget(4000)
            .seed(2);
        if let Some(w) = window {
            m = m.stop_when_stalled(w);
        }
        m.run(&[2.5, -2.0]).unwrap()
    };
    let plain = run(None);
    let ruled = run(Some(0.05));
    // The loop spends its three quarters (its schedule is not cut); the polish stops
    // a window (200 evaluations) after its last improvement.
    assert_eq!(ruled.stop, Stop::Stalled);
    assert!(
        ruled.evaluations > 3000 && ruled.evaluations < 4000,
        "{ruled:?}"
    );
    assert_eq!(ruled.fun, plain.fun);
}

#[test]
fn the_paper_loop_is_judged_past_its_schedule_only() {
    let new = |iterations: usize| {
        Optimizer::new(Adam::new(0.1).unwrap(), Annealer::paper(0.5, 100).unwrap())
            .iterations(iterations)
            .stop_when_stalled(0.05)
            .unwrap()
    };
    // Within the schedule: the whole schedule runs (the loss only falls as sigma anneals).
    let mut opt = new(100);
    let mut grad = PlateauFreeGradient::new(floor).samples(4).seed(1);
    let h = opt.minimize(&mut grad, &[3.0]).unwrap();
    assert_eq!(h.iterations(), 100);
    assert!(!opt.stalled());
    // Past it, on the floor, the rule ends the loop; ask and tell stops at the same step.
    let mut opt = new(2000);
    let mut grad = PlateauFreeGradient::new(floor).samples(4).seed(1);
    let called = opt.minimize(&mut grad, &[3.0]).unwrap();
    assert!(opt.stalled());
    assert!(
        called.iterations() > 100 && called.iterations() < 2000,
        "{}",
        called.iterations()
    );
    let grad = PlateauFreeGradient::without_objective().samples(4).seed(1);
    let mut run = new(2000).ask_tell(grad, &[3.0]).unwrap();
    while let Some(ask) = run.ask().unwrap() {
        let values: Vec<f64> = ask.points().iter().map(floor).collect();
        run.tell(&values).unwrap();
    }
    assert_eq!(run.finish(), called);
}
