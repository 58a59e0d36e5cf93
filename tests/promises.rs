//! What every method promises, checked over random boxes, starts, seeds and small
//! budgets, for every method: the paper's loop (`Optimizer` with `PlateauFreeGradient` and each
//! sampler, finite differences, SPSA), `Minimizer` with the adaptive search, `Strategy::Paper`
//! and the polished loop; each in its callback form and (where it has one) asked and told.
//!
//! - **Bounds are a promise**: with bounds, `f` is called only inside the box, the result lies
//!   inside, and a start outside is an error (before anything is evaluated).
//! - **The start counts**: a method that returns the best point seen is never worse than
//!   `f(x0)`.
//! - **The budget is a ceiling**: `evaluations <= budget`, for every budget (1, 2, 3, smaller
//!   than a population or than the samples of an estimate).
//!
//! `PROMISES_CASES` sets the number of cases per property (default 256).

use std::cell::RefCell;

use plateau_free::baseline::{FiniteDifference, Spsa};
use plateau_free::{
    run::History, run::Strategy as Method, Adam, Annealer, Error, GradientEstimator, Minimizer,
    Minimum, Optimizer, PaperAskTell, PlateauFreeGradient, Sampling,
};
use proptest::prelude::*;

/// A box, a start inside it, a seed and a budget.
#[derive(Debug, Clone)]
struct Case {
    lower: Vec<f64>,
    upper: Vec<f64>,
    x0: Vec<f64>,
    seed: u64,
    budget: usize,
}

impl Case {
    fn inside(&self, x: &[f64]) -> bool {
        x.len() == self.lower.len()
            && x.iter()
                .zip(&self.lower)
                .zip(&self.upper)
                .all(|((v, l), u)| l <= v && v <= u)
    }

    /// The start moved outside the box in coordinate `k`.
    fn outside(&self, k: usize) -> Vec<f64> {
        let mut x = self.x0.clone();
        let k = k % x.len();
        x[k] = if k % 2 == 0 {
            self.upper[k] + 0.5
        } else {
            self.lower[k] - 1e-9
        };
        x
    }

    /// The objective: a bowl centred outside the box (so that every method pushes against
    /// its faces) plus a staircase (plateaus).
    fn value(&self, x: &[f64]) -> f64 {
        x.iter()
            .enumerate()
            .map(|(i, v)| {
                let centre = if i % 2 == 0 {
                    self.upper[i] + 1.0
                } else {
                    self.lower[i] - 1.0
                };
                (v - centre).powi(2) + 0.1 * (2.0 * v).floor()
            })
            .sum()
    }
}

fn case() -> impl Strategy<Value = Case> {
    let coordinate = (
        -3.0..3.0f64,
        prop_oneof![6 => 0.01..3.0f64, 1 => Just(0.0)],
        prop_oneof![Just(0.0), Just(1.0), 0.0..=1.0f64],
    );
    (
        prop::collection::vec(coordinate, 1..=4),
        any::<u64>(),
        prop_oneof![1usize..=3, 1usize..=80],
    )
        .prop_map(|(coordinates, seed, budget)| {
            let lower: Vec<f64> = coordinates.iter().map(|c| c.0).collect();
            let upper: Vec<f64> = coordinates.iter().map(|c| c.0 + c.1).collect();
            let x0 = coordinates
                .iter()
                .map(|c| (c.0 + c.2 * c.1).clamp(c.0, c.0 + c.1))
                .collect();
            Case {
                lower,
                upper,
                x0,
                seed,
                budget,
            }
        })
}

fn cases() -> ProptestConfig {
    let cases = std::env::var("PROMISES_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(256);
    ProptestConfig::with_cases(cases)
}

/// The configurations of the plateau-free estimator the paper's loop is run with: every
/// sampler, with and without antithetic pairs, and orthogonal directions.
const ESTIMATORS: [(Sampling, bool, bool, usize); 6] = [
    (Sampling::Radial, true, false, 2),
    (Sampling::Radial, false, true, 3),
    (Sampling::PerCoordinate, true, false, 4),
    (Sampling::PerCoordinate, false, false, 1),
    (Sampling::Gaussian, true, false, 2),
    (Sampling::Gaussian, false, true, 3),
];

fn configure<F>(
    grad: PlateauFreeGradient<F>,
    (sampling, antithetic, orthogonal, samples): (Sampling, bool, bool, usize),
    seed: u64,
) -> PlateauFreeGradient<F> {
    grad.sampling(sampling)
        .antithetic(antithetic)
        .orthogonal(orthogonal)
        .samples(samples)
        .seed(seed)
}

/// The paper's loop of a case: Adam with a large step (it runs into the faces), bounded by
/// the box, under the paper's schedule from a spread as large as the box.
fn optimizer(c: &Case) -> Optimizer {
    let adam = Adam::new(0.5)
        .unwrap()
        .bounds(c.lower.clone(), c.upper.clone())
        .unwrap();
    Optimizer::new(adam, Annealer::paper(1.5, 1 + c.budget % 12).unwrap())
}

/// The `Minimizer` methods of a case, on the objective `f`.
fn methods<F: Fn(&[f64]) -> f64 + Copy>(c: &Case, f: F) -> Vec<(&'static str, Minimizer<F>)> {
    let paper = |samples| Method::Paper {
        samples,
        lr: 0.4,
        sigma0: 1.5,
    };
    let m = || {
        Minimizer::new(f)
            .budget(c.budget)
            .seed(c.seed)
            .bounds(c.lower.clone(), c.upper.clone())
    };
    vec![
        ("adaptive", m()),
        ("adaptive pop", m().population(2 + c.budget % 20)),
        ("paper", m().strategy(paper(2))),
        ("paper N8", m().strategy(paper(8))),
        ("polished", m().strategy(paper(2)).polish(0.3)),
    ]
}

/// Runs an ask-and-tell paper loop to its end with `f`.
fn drive_paper(mut run: PaperAskTell, f: impl Fn(&[f64]) -> f64) -> History {
    while let Some(ask) = run.ask().unwrap() {
        let values: Vec<f64> = ask.points().iter().map(&f).collect();
        run.tell(&values).unwrap();
    }
    run.finish()
}

/// Checks the points a run evaluated and the point it returned.
fn check_points(
    c: &Case,
    what: &str,
    seen: &[Vec<f64>],
    result: &[f64],
) -> Result<(), TestCaseError> {
    if let Some(p) = seen.iter().find(|p| !c.inside(p)) {
        return Err(TestCaseError::fail(format!(
            "{what}: f called outside the box at {p:?}"
        )));
    }
    prop_assert!(c.inside(result), "{what}: the result {result:?} is outside");
    Ok(())
}

/// Checks a `Minimizer` result against the promises.
fn check_minimum(
    c: &Case,
    what: &str,
    seen: &[Vec<f64>],
    m: &Minimum,
) -> Result<(), TestCaseError> {
    check_points(c, what, seen, &m.x)?;
    prop_assert_eq!(m.evaluations, seen.len(), "{}", what);
    prop_assert!(m.evaluations <= c.budget, "{}: {:?}", what, m);
    prop_assert!(
        m.fun <= c.value(&c.x0),
        "{}: worse than the start: {:?}",
        what,
        m
    );
    prop_assert_eq!(m.fun, c.value(&m.x), "{}", what);
    Ok(())
}

/// A start outside the box is an error, and nothing is evaluated.
fn refuses<T: std::fmt::Debug>(
    what: &str,
    seen: &RefCell<Vec<Vec<f64>>>,
    result: Result<T, Error>,
) -> Result<(), TestCaseError> {
    prop_assert!(
        matches!(result, Err(Error::OutsideBounds { .. })),
        "{}: a start outside the box gave {:?}",
        what,
        result
    );
    prop_assert!(seen.borrow().is_empty(), "{}: evaluated", what);
    Ok(())
}

proptest! {
    #![proptest_config(cases())]

    #[test]
    fn the_papers_loop_evaluates_only_inside_the_box(c in case(), k in 0usize..4) {
        let seen = RefCell::new(Vec::new());
        let f = |x: &[f64]| {
            seen.borrow_mut().push(x.to_vec());
            c.value(x)
        };
        for config in ESTIMATORS {
            let what = format!("loop {config:?}");
            seen.borrow_mut().clear();
            let mut grad = configure(PlateauFreeGradient::new(f), config, c.seed);
            let called = optimizer(&c).minimize(&mut grad, &c.x0).unwrap();
            check_points(&c, &what, &seen.borrow(), called.last_theta().unwrap())?;
            prop_assert_eq!(called.evaluations, seen.borrow().len());

            // Asked and told: the same points, the same history, bit for bit.
            let asked = RefCell::new(Vec::new());
            let grad = configure(PlateauFreeGradient::without_objective(), config, c.seed);
            let run = optimizer(&c).ask_tell(grad, &c.x0).unwrap();
            let told = drive_paper(run, |x| {
                asked.borrow_mut().push(x.to_vec());
                c.value(x)
            });
            prop_assert_eq!(&*asked.borrow(), &*seen.borrow(), "{}", what);
            prop_assert_eq!(&told, &called, "{}", what);

            // A start outside the box.
            seen.borrow_mut().clear();
            let mut grad = configure(PlateauFreeGradient::new(f), config, c.seed);
            refuses(&what, &seen, optimizer(&c).minimize(&mut grad, &c.outside(k)))?;
            let grad = configure(PlateauFreeGradient::without_objective(), config, c.seed);
            refuses(&what, &seen, optimizer(&c).ask_tell(grad, &c.outside(k)))?;
        }

        // The baselines on the same loop (they have no ask-and-tell form).
        let baselines: [(&str, Box<dyn GradientEstimator + '_>); 2] = [
            ("finite differences", Box::new(FiniteDifference::new(f, 0.7).unwrap().seed(c.seed))),
            ("spsa", Box::new(Spsa::new(f).seed(c.seed))),
        ];
        for (what, mut estimator) in baselines {
            seen.borrow_mut().clear();
            let h = optimizer(&c).minimize(&mut *estimator, &c.x0).unwrap();
            check_points(&c, what, &seen.borrow(), h.last_theta().unwrap())?;
            prop_assert_eq!(h.evaluations, seen.borrow().len());
            seen.borrow_mut().clear();
            refuses(what, &seen, optimizer(&c).minimize(&mut *estimator, &c.outside(k)))?;
        }
    }

    #[test]
    fn minimize_keeps_its_promises(c in case(), k in 0usize..4) {
        let seen = RefCell::new(Vec::new());
        let f = |x: &[f64]| {
            seen.borrow_mut().push(x.to_vec());
            c.value(x)
        };
        for (what, minimizer) in methods(&c, f) {
            seen.borrow_mut().clear();
            let mut run = minimizer.ask_tell(&c.x0).unwrap();
            while let Some(ask) = run.ask().unwrap() {
                let values: Vec<f64> = ask.points().iter().map(f).collect();
                run.tell(&values).unwrap();
            }
            let told = run.finish().unwrap();
            check_minimum(&c, what, &seen.borrow(), &told)?;
            let asked = seen.replace(Vec::new());

            // The callback form: the same points and the same result, bit for bit.
            let called = minimizer.run(&c.x0).unwrap();
            prop_assert_eq!(&*seen.borrow(), &asked, "{}", what);
            prop_assert_eq!(&called, &told, "{}", what);

            seen.borrow_mut().clear();
            refuses(what, &seen, minimizer.ask_tell(&c.outside(k)))?;
            refuses(what, &seen, minimizer.run(&c.outside(k)))?;
        }
    }

    #[test]
    fn the_budget_is_a_ceiling_and_the_start_counts(
        budget in prop_oneof![1usize..=3, 1usize..=40],
        population in 2usize..=24,
        samples in 1usize..=8,
        polish in prop_oneof![Just(0.0), 0.0..0.9f64],
        seed in any::<u64>(),
        n in 1usize..=5,
    ) {
        let count = RefCell::new(0usize);
        let f = |x: &[f64]| {
            *count.borrow_mut() += 1;
            x.iter().map(|v| (v - 0.3).abs().floor() + v * v).sum::<f64>()
        };
        let x0 = vec![0.25; n];
        let paper = Method::Paper { samples: 2 * samples, lr: 0.1, sigma0: 0.5 };
        let runs = [
            Minimizer::new(f).budget(budget).seed(seed),
            Minimizer::new(f).budget(budget).seed(seed).population(population),
            Minimizer::new(f).budget(budget).seed(seed).strategy(paper),
            Minimizer::new(f).budget(budget).seed(seed).strategy(paper).polish(polish),
        ];
        for m in runs {
            *count.borrow_mut() = 0;
            let best = m.run(&x0).unwrap();
            prop_assert!(best.evaluations <= budget, "{:?}", best);
            prop_assert_eq!(best.evaluations, *count.borrow());
            prop_assert!(best.fun <= f(&x0), "{:?}", best);
        }
    }
}

/// The case: in 10^4 dimensions, with 2000 evaluations, the adaptive search never
/// evaluated `x0` and returned 22,861 (24,510 here) where `f(x0)` = 20,000.
#[test]
fn the_start_counts_in_ten_thousand_dimensions() {
    let n = 10_000;
    let x0 = vec![2f64.sqrt(); n];
    let f = |x: &[f64]| x.iter().map(|v| v * v).sum::<f64>();
    let f0 = f(&x0);
    assert!((f0 - 20_000.0).abs() < 1e-6);
    let best = Minimizer::new(f).budget(2000).run(&x0).unwrap();
    assert!(best.fun <= f0, "{} > f(x0) = {f0}", best.fun);
    assert_eq!(best.evaluations, 2000);
    let paper = Method::Paper {
        samples: 2,
        lr: 0.01,
        sigma0: 0.5,
    };
    let best = Minimizer::new(f)
        .strategy(paper)
        .budget(2000)
        .run(&x0)
        .unwrap();
    assert!(best.fun <= f0, "{} > f(x0) = {f0}", best.fun);
}

/// `Strategy::Paper` without polish spends the start, `N` per iteration and the final
/// evaluation: `(budget - 2) / N` iterations, or the start alone when no iteration fits.
#[test]
fn the_papers_budget_counts_the_start_and_the_final_evaluation() {
    let f = |x: &[f64]| (x[0] - 0.2).abs();
    for samples in [2, 4, 6] {
        for budget in 1..40 {
            let m = Minimizer::new(f)
                .strategy(Method::Paper {
                    samples,
                    lr: 0.05,
                    sigma0: 0.3,
                })
                .polish(0.0)
                .budget(budget)
                .run(&[1.0])
                .unwrap();
            let iterations = budget.saturating_sub(2) / samples;
            assert_eq!(m.iterations, iterations, "{budget} {samples}");
            let spent = if iterations > 0 {
                2 + samples * iterations
            } else {
                1
            };
            assert_eq!(m.evaluations, spent, "{budget} {samples}");
            assert!(m.fun <= f(&[1.0]));
        }
    }
}

/// An estimator of one's own that does not implement `set_bounds`.
struct Unbounded;

impl GradientEstimator for Unbounded {
    fn estimate(&mut self, theta: &[f64], _sigma: f64) -> Result<plateau_free::Estimate, Error> {
        Ok(plateau_free::Estimate::new(vec![1.0; theta.len()], 0, 0.0))
    }
}

#[test]
fn an_estimator_that_cannot_keep_the_bounds_refuses_to_start() {
    let adam = Adam::new(0.1)
        .unwrap()
        .bounds(vec![0.0], vec![1.0])
        .unwrap();
    let mut opt = Optimizer::new(adam, Annealer::constant(0.1, 5).unwrap());
    let err = opt.run(&mut Unbounded, &[0.5], |_| {
        std::ops::ControlFlow::Continue(())
    });
    let err = err.unwrap_err();
    assert!(
        matches!(err.error, Error::BoundsUnsupported { estimator } if estimator.ends_with("Unbounded")),
        "{err}"
    );
    assert_eq!(err.state.iteration, 0);
    assert!(err.to_string().contains("set_bounds"), "{err}");
    // Without bounds it runs.
    let mut opt = Optimizer::new(Adam::new(0.1).unwrap(), Annealer::constant(0.1, 5).unwrap());
    assert_eq!(
        opt.minimize(&mut Unbounded, &[0.5]).unwrap().iterations(),
        5
    );
}

/// With bounds, the estimate is the estimate of `f` composed with the projection onto the
/// box: bit for bit, for every sampler (the same draws, the same weights, the values of the
/// projected points).
#[test]
fn a_bounded_estimate_is_that_of_f_composed_with_the_projection() {
    let (lower, upper) = (vec![-0.5, 0.0, 0.2], vec![0.5, 2.0, 0.2]);
    let f = |x: &[f64]| (x[0] - 1.0).powi(2) + (3.0 * x[1]).sin() + x[2] * x[0];
    let projected = |x: &[f64]| {
        let p: Vec<f64> = x
            .iter()
            .zip(&lower)
            .zip(&upper)
            .map(|((v, l), u)| v.clamp(*l, *u))
            .collect();
        f(&p)
    };
    let theta = [0.5, 0.1, 0.2];
    for config in ESTIMATORS {
        let mut bounded =
            configure(PlateauFreeGradient::new(f), config, 9).bounds(lower.clone(), upper.clone());
        let mut composed = configure(PlateauFreeGradient::new(projected), config, 9);
        for _ in 0..3 {
            let a = bounded.estimate(&theta, 0.7).unwrap();
            let b = composed.estimate(&theta, 0.7).unwrap();
            assert_eq!(a, b, "{config:?}");
        }
        let spreads = [0.3, 1.0, 0.1];
        let a = bounded.estimate_with_spreads(&theta, &spreads).unwrap();
        let b = composed.estimate_with_spreads(&theta, &spreads).unwrap();
        assert_eq!(a, b, "{config:?}");
    }
    // SPSA likewise.
    let mut bounded = Spsa::new(f).seed(4);
    bounded.set_bounds(&lower, &upper).unwrap();
    let mut composed = Spsa::new(projected).seed(4);
    for _ in 0..5 {
        assert_eq!(
            bounded.estimate(&theta, 0.7).unwrap(),
            composed.estimate(&theta, 0.7).unwrap()
        );
    }
    // Finite differences are one-sided at a face, and zero across a box of zero width.
    let mut fd = FiniteDifference::new(|x: &[f64]| 3.0 * x[0] + 2.0 * x[1] - x[2], 0.25).unwrap();
    fd.set_bounds(&lower, &upper).unwrap();
    let g = fd.estimate(&theta, 1.0).unwrap().gradient;
    assert!(
        (g[0] - 3.0).abs() < 1e-12 && (g[1] - 2.0).abs() < 1e-12,
        "{g:?}"
    );
    assert_eq!(g[2], 0.0);
    // A box of another dimension is refused.
    let mut grad = PlateauFreeGradient::new(f).bounds(vec![0.0], vec![1.0]);
    assert!(matches!(
        grad.estimate(&theta, 0.5),
        Err(Error::LengthMismatch { what: "bounds", .. })
    ));
    assert!(matches!(
        PlateauFreeGradient::new(f)
            .bounds(vec![1.0], vec![0.0])
            .validate(),
        Err(Error::InvalidBounds { index: 0, .. })
    ));
}

/// At a face, the half of the kernel beyond it sees the face's value: for `f(x) = x` on
/// `[0, inf)` at `theta = 0` the estimate is that of `max(x, 0)`, whose smoothed slope at 0
/// is 1/2 (the unbounded slope is 1).
#[test]
fn at_a_face_the_normal_component_is_damped() {
    let mut grad = PlateauFreeGradient::new(|x: &[f64]| x[0])
        .samples(20_000)
        .seed(3)
        .bounds(vec![0.0], vec![f64::INFINITY]);
    let g = grad.estimate(&[0.0], 0.4).unwrap().gradient[0];
    assert!((g - 0.5).abs() < 0.02, "{g}");
    let mut free = PlateauFreeGradient::new(|x: &[f64]| x[0])
        .samples(20_000)
        .seed(3);
    let g = free.estimate(&[0.0], 0.4).unwrap().gradient[0];
    assert!((g - 1.0).abs() < 0.03, "{g}");
}

/// A saved state outside the box is refused by every way of continuing it.
#[test]
fn a_saved_state_outside_the_box_is_refused() {
    let adam = || {
        Adam::new(0.1)
            .unwrap()
            .bounds(vec![0.0; 2], vec![1.0; 2])
            .unwrap()
    };
    let opt = || Optimizer::new(adam(), Annealer::constant(0.1, 4).unwrap());
    let f = |x: &[f64]| x[0] + x[1];
    let mut state = opt()
        .minimize_from(
            &mut PlateauFreeGradient::new(f),
            plateau_free::run::OptimizerState::new(&[0.5, 0.5]).unwrap(),
            |s| {
                if s.iteration == 1 {
                    std::ops::ControlFlow::Break(())
                } else {
                    std::ops::ControlFlow::Continue(())
                }
            },
        )
        .unwrap();
    state.theta[1] = 1.5;
    let err = opt()
        .minimize_from(&mut PlateauFreeGradient::new(f), state.clone(), |_| {
            std::ops::ControlFlow::Continue(())
        })
        .unwrap_err();
    assert_eq!(
        err.error,
        Error::OutsideBounds {
            what: "theta",
            index: 1,
            value: 1.5,
            lower: 0.0,
            upper: 1.0
        }
    );
    assert_eq!(*err.state, state, "the state comes back unused");
    let err = opt()
        .ask_tell_from(PlateauFreeGradient::without_objective(), state)
        .unwrap_err();
    assert!(matches!(
        err.error,
        Error::OutsideBounds { what: "theta", .. }
    ));
    // A start outside, and bounds of another dimension.
    let mut grad = PlateauFreeGradient::new(f);
    assert_eq!(
        opt()
            .minimize(&mut grad, &[-0.1, 0.5])
            .unwrap_err()
            .to_string(),
        "start[0] = -0.1 lies outside the bounds [0.0, 1.0]"
    );
    assert!(matches!(
        opt().minimize(&mut grad, &[0.5]),
        Err(Error::LengthMismatch { what: "bounds", .. })
    ));
    assert_eq!(grad.estimates_made(), 0);
}
