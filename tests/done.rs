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
        assert!(best.evaluations < 1000, "seed {seed}: {best:?}");
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
            assert!(best.evaluations < 3500, "{scale:e} seed {seed}: {best:?}");
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
