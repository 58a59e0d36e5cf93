//! `plateau_free::argmin` (feature `argmin`): the adapter's gradient is the estimator's, bit
//! for bit; its mean is the smoothed gradient; argmin's solvers leave plateaus with it.
#![cfg(feature = "argmin")]

mod common;

use argmin::core::{CostFunction, Executor, Gradient, State};
use argmin::solver::gradientdescent::SteepestDescent;
use argmin::solver::linesearch::{condition::ArmijoCondition, BacktrackingLineSearch};
use argmin::solver::quasinewton::LBFGS;
use common::{bits, mean_and_standard_error, tilted_2d};
use plateau_free::argmin::{ArgminProblem, Cost, Spread};
use plateau_free::kernel::{gaussian, normal_cdf};
use plateau_free::{Annealer, Error, PlateauFreeGradient, Sampling};

fn step(x: &[f64]) -> f64 {
    if x[0] > 0.3 {
        1.0
    } else {
        0.0
    }
}

fn staircase(x: &[f64]) -> f64 {
    x[0].floor()
}

/// `draws` gradients of the adapter at `theta` (coordinate 0), over `seeds` seeds.
fn adapter_draws(
    f: fn(&[f64]) -> f64,
    theta: f64,
    sigma: f64,
    seeds: u64,
    per_seed: usize,
) -> Vec<f64> {
    let mut draws = Vec::new();
    for seed in 0..seeds {
        let estimator = PlateauFreeGradient::new(f).samples(4).seed(seed);
        let problem = ArgminProblem::new(estimator, Spread::Fixed(sigma)).unwrap();
        for _ in 0..per_seed {
            draws.push(problem.gradient(&vec![theta]).unwrap()[0]);
        }
    }
    draws
}

/// The mean over 20 seeds of 500 gradients each lies within 4 standard errors of the
/// analytic smoothed gradient (a false alarm about once in 16,000 runs).
fn assert_unbiased(f: fn(&[f64]) -> f64, theta: f64, sigma: f64, exact: f64) {
    let (mean, se) = mean_and_standard_error(&adapter_draws(f, theta, sigma, 20, 500));
    assert!(se > 0.0 && se < 0.05 * exact.abs().max(0.1), "se {se}");
    // (At the step's edge the radial sampler is exact: a standard error of rounding alone.)
    assert!(
        (mean - exact).abs() < 4.0 * se + 1e-12 * exact.abs(),
        "theta {theta} sigma {sigma}: mean {mean} +- {se}, exact {exact}"
    );
}

#[test]
fn the_mean_gradient_of_a_step_is_the_smoothed_gradient() {
    // d/dtheta Phi((theta - a) / sigma) = phi((theta - a) / sigma) / sigma.
    for (theta, sigma) in [(0.0, 0.5), (1.0, 0.4), (0.3, 0.05), (-2.0, 2.0)] {
        assert_unbiased(step, theta, sigma, gaussian(theta - 0.3, sigma));
    }
}

#[test]
fn the_mean_gradient_of_a_staircase_is_the_smoothed_gradient() {
    // floor(x) smoothed: the sum of the steps at every integer k.
    for (theta, sigma) in [(0.5, 0.3), (2.2, 0.7), (-1.0, 1.5)] {
        let exact: f64 = (-30..=30)
            .map(|k| gaussian(theta - f64::from(k), sigma))
            .sum();
        assert_unbiased(staircase, theta, sigma, exact);
    }
}

#[test]
fn the_mean_smoothed_cost_of_a_step_is_the_smoothed_step() {
    // E over seeds of the common-random-numbers cost = Phi((theta - a) / sigma).
    let (theta, sigma) = (0.1, 0.4);
    let costs: Vec<f64> = (0..2000)
        .map(|seed| {
            let estimator = PlateauFreeGradient::new(step as fn(&[f64]) -> f64).seed(seed);
            let problem = ArgminProblem::new(estimator, Spread::Fixed(sigma)).unwrap();
            problem.cost(&vec![theta]).unwrap()
        })
        .collect();
    let (mean, se) = mean_and_standard_error(&costs);
    let exact = normal_cdf((theta - 0.3) / sigma);
    assert!((mean - exact).abs() < 4.0 * se, "{mean} +- {se} vs {exact}");
}

#[test]
fn every_gradient_is_the_estimators_estimate_bit_for_bit() {
    let make = || {
        PlateauFreeGradient::new(tilted_2d)
            .samples(6)
            .sampling(Sampling::PerCoordinate)
            .seed(11)
    };
    let annealer = Annealer::paper(0.5, 10).unwrap();
    for spread in [Spread::Fixed(0.3), Spread::Annealed(annealer)] {
        let problem = ArgminProblem::new(make(), spread).unwrap();
        let mut direct = make();
        for k in 0..15 {
            let theta = vec![0.1 * k as f64, -0.2];
            let sigma = match &spread {
                Spread::Fixed(s) => *s,
                Spread::Annealed(a) => a.sigma(k),
            };
            assert_eq!(problem.sigma(), sigma);
            let expected = direct.estimate(&theta, sigma).unwrap().gradient;
            assert_eq!(bits(&problem.gradient(&theta).unwrap()), bits(&expected));
        }
        assert_eq!(problem.gradient_calls(), 15);
        assert_eq!(problem.into_estimator().estimates_made(), 15);
    }
}

#[test]
fn the_cost_repeats_at_the_same_point_and_is_f_for_cost_objective() {
    let make = || PlateauFreeGradient::new(tilted_2d).seed(5);
    let problem = ArgminProblem::new(make(), Spread::Fixed(1.0)).unwrap();
    let theta = vec![0.2, 0.1];
    let first = problem.cost(&theta).unwrap();
    assert_eq!(first.to_bits(), problem.cost(&theta).unwrap().to_bits());
    // 8 pairs of a 0/1 function straddling the edge: a multiple of 1/16, not 0 or 1.
    assert!(
        first > 0.0 && first < 1.0 && (first * 16.0).fract() == 0.0,
        "{first}"
    );
    let exact = ArgminProblem::new(make(), Spread::Fixed(1.0))
        .unwrap()
        .with_cost(Cost::Objective)
        .unwrap();
    assert_eq!(exact.cost(&theta).unwrap(), tilted_2d(&theta));
    assert_eq!(exact.cost_calls(), 1);
}

fn steepest_descent(
    problem: ArgminProblem<fn(&[f64]) -> f64>,
    start: Vec<f64>,
    iters: u64,
) -> Vec<f64> {
    let line_search = BacktrackingLineSearch::new(ArmijoCondition::new(1e-4).unwrap());
    let run = Executor::new(problem, SteepestDescent::new(line_search))
        .configure(|s| s.param(start).max_iters(iters))
        .run()
        .unwrap();
    run.state().get_best_param().unwrap().clone()
}

fn lbfgs(problem: ArgminProblem<fn(&[f64]) -> f64>, start: Vec<f64>, iters: u64) -> Vec<f64> {
    let line_search = BacktrackingLineSearch::new(ArmijoCondition::new(1e-4).unwrap());
    let solver = LBFGS::new(line_search, 5).with_tolerance_grad(0.0).unwrap();
    let run = Executor::new(problem, solver)
        .configure(|s| s.param(start).max_iters(iters))
        .run()
        .unwrap();
    run.state().get_best_param().unwrap().clone()
}

fn terraces(x: &[f64]) -> f64 {
    (4.0 * (x[0] * x[0] + x[1] * x[1])).floor() / 4.0
}

#[test]
fn steepest_descent_leaves_the_plateau_of_a_step() {
    let estimator = PlateauFreeGradient::new(tilted_2d as fn(&[f64]) -> f64)
        .samples(16)
        .seed(1);
    let problem = ArgminProblem::new(estimator, Spread::Fixed(1.0)).unwrap();
    let x = steepest_descent(problem, vec![1.0, 1.0], 30);
    assert_eq!(tilted_2d(&x), 0.0, "{x:?}");
}

#[test]
fn both_solvers_descend_the_terraces_with_an_annealed_spread() {
    let start = vec![1.2, -0.9];
    assert_eq!(terraces(&start), 2.25);
    for seed in 0..5 {
        let problem = || {
            let estimator = PlateauFreeGradient::new(terraces as fn(&[f64]) -> f64)
                .samples(16)
                .seed(seed);
            ArgminProblem::new(
                estimator,
                Spread::Annealed(Annealer::paper(0.5, 60).unwrap()),
            )
            .unwrap()
        };
        let sd = steepest_descent(problem(), start.clone(), 60);
        assert_eq!(terraces(&sd), 0.0, "steepest descent, seed {seed}: {sd:?}");
        let lb = lbfgs(problem(), start.clone(), 60);
        assert_eq!(terraces(&lb), 0.0, "L-BFGS, seed {seed}: {lb:?}");
        // Same seed, same run.
        assert_eq!(bits(&lbfgs(problem(), start.clone(), 60)), bits(&lb));
    }
}

#[test]
fn bad_input_is_an_error_naming_it() {
    let make = || PlateauFreeGradient::new(step as fn(&[f64]) -> f64);
    for sigma in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let e = ArgminProblem::new(make(), Spread::Fixed(sigma)).unwrap_err();
        assert!(matches!(e, Error::InvalidSigma(_)), "{e}");
    }
    let e = ArgminProblem::new(make().samples(3), Spread::Fixed(1.0)).unwrap_err();
    assert_eq!(e, Error::OddSamples(3));
    let problem = ArgminProblem::new(make(), Spread::Fixed(1.0)).unwrap();
    for theta in [vec![f64::NAN], vec![], vec![f64::INFINITY]] {
        let e = problem.gradient(&theta).unwrap_err();
        let e = e
            .downcast::<Error>()
            .expect("the crate's error inside argmin's");
        assert!(
            matches!(e, Error::NonFiniteTheta { .. } | Error::EmptyTheta),
            "{e}"
        );
        let e = problem
            .cost(&theta)
            .unwrap_err()
            .downcast::<Error>()
            .unwrap();
        assert!(
            matches!(e, Error::NonFiniteTheta { .. } | Error::EmptyTheta),
            "{e}"
        );
    }
    // A NaN of f: the estimator's error, and the cost's.
    let nan = |x: &[f64]| if x[0] > 0.0 { f64::NAN } else { 0.0 };
    let problem = ArgminProblem::new(PlateauFreeGradient::new(nan), Spread::Fixed(1.0)).unwrap();
    let e = problem
        .gradient(&vec![0.0])
        .unwrap_err()
        .downcast::<Error>()
        .unwrap();
    assert!(matches!(e, Error::NonFiniteValue { .. }), "{e}");
    let e = problem
        .cost(&vec![0.0])
        .unwrap_err()
        .downcast::<Error>()
        .unwrap();
    assert!(matches!(e, Error::NonFiniteValue { .. }), "{e}");
}

#[test]
fn extreme_spreads_and_dimensions_give_finite_answers() {
    for sigma in [1e-12, 1e6] {
        let make = || PlateauFreeGradient::new(|x: &[f64]| x[0]).samples(4);
        let problem = ArgminProblem::new(make(), Spread::Fixed(sigma)).unwrap();
        let g = problem.gradient(&vec![0.0]).unwrap();
        let direct = make().estimate(&[0.0], sigma).unwrap().gradient;
        assert_eq!(bits(&g), bits(&direct), "sigma {sigma}");
        assert!(g[0].is_finite() && g[0] > 0.0, "sigma {sigma}: {g:?}");
        // A linear f: the antithetic pairs' mean is f(0) = 0 up to rounding.
        assert!(problem.cost(&vec![0.0]).unwrap().abs() < 1e-9 * sigma);
    }
    let n = 200;
    let estimator = PlateauFreeGradient::new(|x: &[f64]| x.iter().sum::<f64>()).samples(4);
    let problem = ArgminProblem::new(estimator, Spread::Fixed(0.1)).unwrap();
    let g = problem.gradient(&vec![0.0; n]).unwrap();
    assert_eq!(g.len(), n);
    assert!(g.iter().all(|gi| gi.is_finite()));
    assert!((problem.cost(&vec![0.0; n]).unwrap()).abs() < 1e-9);
}

#[test]
fn the_cost_keeps_its_points_inside_the_estimators_box() {
    let f = |x: &[f64]| {
        assert!((0.0..=1.0).contains(&x[0]), "outside the box: {x:?}");
        x[0]
    };
    let estimator = PlateauFreeGradient::new(f).bounds(vec![0.0], vec![1.0]);
    let problem = ArgminProblem::new(estimator, Spread::Fixed(5.0)).unwrap();
    assert!(problem.cost(&vec![0.0]).unwrap() >= 0.0);
    assert!(problem.gradient(&vec![0.0]).unwrap()[0] > 0.0);
}
