//! The conventions users bring: a starting spread per coordinate, one-sided and infinite
//! bounds, and one polish default for the paper's loop.

use std::cell::Cell;

use plateau_free::{run::Strategy, run::DEFAULT_POLISH, Error, Minimizer};

const PAPER: Strategy = Strategy::Paper {
    samples: 4,
    lr: 0.05,
    sigma0: 0.5,
};

#[test]
fn a_spread_per_coordinate_fits_coordinates_of_different_scales() {
    // One coordinate in thousandths, one in thousands.
    let f = |x: &[f64]| ((x[0] - 3e-4) / 1e-3).powi(2) + ((x[1] - 300.0) / 1e3).powi(2);
    let best = Minimizer::new(f)
        .budget(3000)
        .sigma0_each(vec![1e-3, 1e3])
        .run(&[0.0, 0.0])
        .unwrap();
    assert!(best.fun < 1e-12, "{best:?}");
    // Wrong length, a non-positive spread, or both spreads set: errors.
    let e = |m: Minimizer<_>| m.run(&[0.0, 0.0]).unwrap_err();
    let m = || Minimizer::new(f).budget(10);
    assert!(matches!(
        e(m().sigma0_each(vec![1.0])),
        Error::LengthMismatch { .. }
    ));
    assert!(matches!(
        e(m().sigma0_each(vec![1.0, 0.0])),
        Error::InvalidParameter {
            name: "sigma0_each",
            ..
        }
    ));
    assert!(matches!(
        e(m().sigma0_each(vec![1.0, 1.0]).sigma0(1.0)),
        Error::InvalidParameter {
            name: "sigma0_each",
            ..
        }
    ));
}

#[test]
fn one_sided_bounds_project_on_their_finite_side_only() {
    let below = Cell::new(0usize);
    // The optimum, x = -3, lies below the lower bound 0: the answer is the bound.
    let f = |x: &[f64]| {
        if x[0] < 0.0 {
            below.set(below.get() + 1);
        }
        (x[0] + 3.0).powi(2) + (x[1] - 7.0).powi(2)
    };
    let best = Minimizer::new(f)
        .budget(2000)
        .bounds(
            vec![0.0, f64::NEG_INFINITY],
            vec![f64::INFINITY, f64::INFINITY],
        )
        .run(&[5.0, 0.0])
        .unwrap();
    assert_eq!(below.get(), 0);
    assert_eq!(best.x[0], 0.0, "{best:?}");
    assert!((best.x[1] - 7.0).abs() < 1e-6, "{best:?}");
    // The paper's loop (and its polish) keep the same box.
    let best = Minimizer::new(f)
        .budget(2000)
        .strategy(PAPER)
        .bounds(vec![0.0, f64::NEG_INFINITY], vec![f64::INFINITY, 2.0])
        .run(&[5.0, 0.0])
        .unwrap();
    assert_eq!(below.get(), 0);
    assert!(best.x[0] >= 0.0 && best.x[1] <= 2.0, "{best:?}");
    // Crossed or NaN bounds, or a start outside the open box: errors.
    let err = |lo: f64, hi: f64, x0: f64| {
        Minimizer::new(f)
            .bounds(vec![lo, f64::NEG_INFINITY], vec![hi, f64::INFINITY])
            .run(&[x0, 0.0])
            .unwrap_err()
    };
    assert!(matches!(
        err(f64::NAN, 1.0, 0.0),
        Error::InvalidBounds { .. }
    ));
    assert!(matches!(
        err(f64::INFINITY, f64::INFINITY, 0.0),
        Error::OutsideBounds { .. }
    ));
    assert!(matches!(
        err(0.0, f64::INFINITY, -1.0),
        Error::OutsideBounds { .. }
    ));
}

#[test]
fn the_paper_strategy_polishes_half_its_budget_by_default() {
    assert_eq!(DEFAULT_POLISH, 0.5);
    let f = |x: &[f64]| ((x[0] - 0.3).powi(2) + (x[1] + 0.2).powi(2)).sqrt();
    let run = |m: Minimizer<_>| {
        m.budget(800)
            .seed(3)
            .strategy(PAPER)
            .run(&[1.0, 1.0])
            .unwrap()
    };
    let default = run(Minimizer::new(f));
    assert_eq!(default, run(Minimizer::new(f).polish(DEFAULT_POLISH)));
    assert_ne!(default, run(Minimizer::new(f).polish(0.0)));
    // The adaptive strategy has nothing to polish: no default, and a set polish is an error.
    assert!(Minimizer::new(f).budget(100).run(&[1.0, 1.0]).is_ok());
    assert!(Minimizer::new(f).polish(0.5).run(&[1.0, 1.0]).is_err());
}
