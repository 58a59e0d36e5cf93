//! Stop when done: the default adaptive run ends before its budget when restarts keep
//! converging back at the best point ([`Stop::Done`], a success), a flat region at the
//! optimum does not grow the spread, and multimodal functions still restart.

use plateau_free::{Minimizer, Stop};

/// The README's staircase: the squared distance of the rounded point to (1, 2, 3).
fn staircase(x: &[f64]) -> f64 {
    let t = [1.0, 2.0, 3.0];
    x.iter().zip(t).map(|(v, t)| (v.round() - t).powi(2)).sum()
}

fn sphere(x: &[f64]) -> f64 {
    x.iter().map(|v| (v - 0.3).powi(2)).sum()
}

fn rastrigin(x: &[f64]) -> f64 {
    let tau = std::f64::consts::TAU;
    x.iter()
        .map(|v| v * v - 10.0 * (tau * v).cos() + 10.0)
        .sum()
}

#[test]
fn the_staircase_stops_at_its_optimum_well_before_the_budget() {
    for seed in 0..5 {
        let best = Minimizer::new(staircase)
            .budget(3000)
            .seed(seed)
            .run(&[0.0; 3])
            .unwrap();
        assert_eq!(best.fun, 0.0, "seed {seed}");
        assert_eq!(best.stop, Stop::Done, "seed {seed}: {best:?}");
        assert!(best.success());
        // The first restart searches again from x0; the two more runs asked for on ties start
        // at the point it found again: about half the budget.
        assert!(best.evaluations < 1500, "seed {seed}: {best:?}");
        assert!(best.sigma < 100.0, "seed {seed}: {best:?}");
    }
}

#[test]
fn a_sphere_and_its_huge_multiple_stop_with_success() {
    for scale in [1.0, 1e300, 1e-300] {
        for seed in 0..3 {
            let f = |x: &[f64]| scale * sphere(x);
            let best = Minimizer::new(f)
                .budget(5000)
                .seed(seed)
                .run(&[1.0; 5])
                .unwrap();
            assert_eq!(best.stop, Stop::Done, "{scale:e} seed {seed}: {best:?}");
            // Two runs: the first, and its restart from x0 (twice the population) that finds
            // the point again.
            assert!(best.evaluations < 4000, "{scale:e} seed {seed}: {best:?}");
            assert!(best.fun / scale < 1e-10, "{scale:e} seed {seed}: {best:?}");
        }
    }
}

#[test]
fn patience_zero_spends_the_budget() {
    let best = Minimizer::new(staircase)
        .budget(3000)
        .patience(0)
        .run(&[0.0; 3])
        .unwrap();
    assert_eq!(best.stop, Stop::Budget);
    assert_eq!(best.evaluations, 3000);
    assert_eq!(best.fun, 0.0);
    // Ties above the best level no longer grow the spread without bound.
    assert!(best.sigma < 1e3, "{best:?}");
}

#[test]
fn rastrigin_restarts_past_its_first_local_optimum() {
    for seed in 0..3 {
        let best = Minimizer::new(rastrigin)
            .budget(20_000)
            .seed(seed)
            .run(&[3.3; 5])
            .unwrap();
        assert!(best.restarts >= 2, "seed {seed}: {best:?}");
    }
}

/// The mean of a generation of mirrored pairs: the midpoint of its first pair.
fn mean_of(ask: &plateau_free::Ask<'_>) -> Vec<f64> {
    let mut points = ask.iter();
    let (a, _) = points.next().unwrap();
    let (b, _) = points.next().unwrap();
    a.iter().zip(b).map(|(a, b)| 0.5 * (a + b)).collect()
}

/// Where each restart of a `patience(3)` search of the sphere started, with the best point
/// seen when it did.
fn restart_starts(from_best: bool) -> Vec<(Vec<f64>, Vec<f64>)> {
    let mut run = Minimizer::without_objective()
        .budget(20_000)
        .seed(1)
        .patience(3)
        .restart_from_best(from_best)
        .ask_tell(&[1.0, 1.0])
        .unwrap();
    let mut starts = Vec::new();
    let mut restarts = 0;
    loop {
        let now = run.so_far().restarts;
        let best = run.best().map(|(x, _)| x.to_vec());
        let Some(ask) = run.ask().unwrap() else {
            break;
        };
        if now > restarts {
            restarts = now;
            starts.push((mean_of(&ask), best.unwrap()));
        }
        let values: Vec<f64> = ask.iter().map(|(x, _)| sphere(x)).collect();
        run.tell(&values).unwrap();
    }
    assert_eq!(run.finish().unwrap().stop, Stop::Done);
    starts
}

#[test]
fn a_restart_starts_from_x0_until_a_run_finds_the_best_point_again() {
    let close = |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(a, b)| (a - b).abs() < 1e-12);
    // Run 1 converges; restart 1 searches again from x0 and finds the point again; the
    // further runs that patience 3 asks for start at that point.
    let starts = restart_starts(false);
    assert_eq!(starts.len(), 3, "{starts:?}");
    assert!(close(&starts[0].0, &[1.0, 1.0]), "{starts:?}");
    for (start, best) in &starts[1..] {
        assert!(close(start, best), "{starts:?}");
        assert!(!close(start, &[1.0, 1.0]), "{starts:?}");
    }
    // `restart_from_best(true)`: every restart starts at the best point seen.
    let starts = restart_starts(true);
    assert!(!starts.is_empty());
    for (start, best) in &starts {
        assert!(close(start, best), "{starts:?}");
    }
}
