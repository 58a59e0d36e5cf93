//! Fuzzing a `Minimizer` with random configurations and inputs: each method (the adaptive
//! search with each metric, the paper's loop, the paper's loop polished), dimensions,
//! starts, bounds and budgets at the extremes, objectives whose values are huge, subnormal,
//! NaN or infinite; its callback form and its ask-and-tell forms. The contract checked:
//! never a panic, never a NaN or an infinity inside an `Ok`, at most the budget spent, every
//! point inside the bounds, every error message one short line.

use std::sync::atomic::{AtomicUsize, Ordering};

use plateau_free::{
    estimator::OnFailure, run::Metric, Adam, Annealer, Error, Minimizer, Minimum, Optimizer,
    PlateauFreeGradient, Stop,
};
use proptest::prelude::*;

mod common;
use common::fuzz::*;

/// A [`Minimizer`]'s method: the adaptive search with each metric, the paper's loop, the
/// paper's loop polished by the search.
#[derive(Debug, Clone, Copy)]
enum Method {
    Adaptive(Metric),
    Paper {
        samples: usize,
        lr: f64,
        sigma0: f64,
    },
    Polished {
        samples: usize,
        lr: f64,
        sigma0: f64,
    },
}

fn method() -> impl Strategy<Value = Method> {
    let paper = || (1usize..=4, extreme(), extreme());
    prop_oneof![
        Just(Method::Adaptive(Metric::Auto)),
        Just(Method::Adaptive(Metric::Full)),
        Just(Method::Adaptive(Metric::Decoded)),
        Just(Method::Adaptive(Metric::Diagonal)),
        paper().prop_map(|(k, lr, sigma0)| Method::Paper {
            samples: 2 * k,
            lr,
            sigma0
        }),
        paper().prop_map(|(k, lr, sigma0)| Method::Polished {
            samples: 2 * k,
            lr,
            sigma0
        }),
    ]
}

/// A run's setting: the method, the dimension, the start's magnitude, the options.
#[derive(Debug, Clone)]
struct Run {
    method: Method,
    n: usize,
    start: f64,
    budget: usize,
    seed: u64,
    sigma0: Option<f64>,
    /// The box's half width around the start.
    bounds: Option<f64>,
    target: Option<f64>,
}

fn run_setting() -> impl Strategy<Value = Run> {
    (
        method(),
        // 10^5 coordinates with budgets of 1 to 3: the start and at most one cheap ask.
        prop_oneof![
            6 => (1usize..=4, prop_oneof![1usize..=3, 4usize..=80]),
            1 => (Just(100_000usize), 1usize..=3),
        ],
        prop_oneof![signed_extreme(), Just(1e300), Just(-f64::MAX)],
        any::<u64>(),
        proptest::option::of(extreme()),
        proptest::option::of(extreme()),
        proptest::option::of(prop_oneof![signed_extreme(), Just(f64::NEG_INFINITY)]),
    )
        .prop_map(
            |(method, (n, budget), start, seed, sigma0, bounds, target)| Run {
                // A full metric needs n^2 numbers: fuzzed where that is cheap.
                method: match method {
                    Method::Adaptive(Metric::Full | Metric::Decoded) if n > 4 => {
                        Method::Adaptive(Metric::Auto)
                    }
                    m => m,
                },
                n,
                start,
                budget,
                seed,
                sigma0,
                bounds,
                target,
            },
        )
}

/// The objective values of a [`Minimizer`] run: no panics (a run does not catch them), and
/// sometimes 1e308 everywhere.
fn minimizer_values() -> impl Strategy<Value = Values> {
    prop_oneof![
        5 => values().prop_map(|v| if matches!(v, Values::Panic) { Values::Constant(1e308) } else { v }),
        1 => Just(Values::Constant(1e308)),
    ]
}

impl Run {
    fn minimizer<F>(&self, m: Minimizer<F>) -> Minimizer<F> {
        let mut m = m.budget(self.budget).seed(self.seed);
        m = match self.method {
            Method::Adaptive(metric) => m.metric(metric),
            Method::Paper {
                samples,
                lr,
                sigma0,
            } => m.strategy(plateau_free::run::Strategy::Paper {
                samples,
                lr,
                sigma0,
            }),
            Method::Polished {
                samples,
                lr,
                sigma0,
            } => m
                .strategy(plateau_free::run::Strategy::Paper {
                    samples,
                    lr,
                    sigma0,
                })
                .polish(0.5),
        };
        if let Some(s) = self.sigma0 {
            m = m.sigma0(s);
        }
        if let Some((lo, hi)) = self.bounds() {
            m = m.bounds(lo, hi);
        }
        if let Some(t) = self.target {
            m = m.target(t);
        }
        m
    }

    fn x0(&self) -> Vec<f64> {
        (0..self.n)
            .map(|i| {
                if i % 2 == 0 {
                    self.start
                } else {
                    -0.5 * self.start
                }
            })
            .collect()
    }

    /// A box of half width `w` around the start (its edges may overflow: an `Err`).
    fn bounds(&self) -> Option<(Vec<f64>, Vec<f64>)> {
        let w = self.bounds?;
        let x0 = self.x0();
        Some((
            x0.iter().map(|x| x - w).collect(),
            x0.iter().map(|x| x + w).collect(),
        ))
    }

    fn inside(&self, x: &[f64]) -> bool {
        match self.bounds() {
            Some((lo, hi)) => x
                .iter()
                .zip(lo.iter().zip(&hi))
                .all(|(v, (l, h))| l <= v && v <= h),
            None => true,
        }
    }

    /// The contract on a finished run's result: finite unless every evaluation failed (a
    /// failed point is never the best), evaluated, within the budget and the box, no worse
    /// than the start, at or below the target when it stopped there.
    fn check(&self, m: &Minimum, f: impl Fn(&[f64]) -> f64) -> Result<(), TestCaseError> {
        prop_assert!(m.failures <= m.evaluations);
        if m.fun.is_finite() {
            prop_assert_eq!(m.fun.to_bits(), f(&m.x).to_bits());
            let start = f(&self.x0());
            prop_assert!(!start.is_finite() || m.fun <= start);
        } else {
            prop_assert_eq!(m.fun, f64::INFINITY);
            prop_assert_eq!(m.failures, m.evaluations, "fun {}", m.fun);
        }
        prop_assert!(
            1 <= m.evaluations && m.evaluations <= self.budget,
            "{:?}",
            m.evaluations
        );
        prop_assert_eq!(m.x.len(), self.n);
        prop_assert!(all_finite(&m.x));
        prop_assert!(self.inside(&m.x));
        prop_assert!(m.sigma >= 0.0, "sigma {}", m.sigma);
        if m.stop == Stop::Target {
            prop_assert!(m.fun <= self.target.unwrap());
        }
        Ok(())
    }
}

/// An error's message: one short line.
fn check_error(e: &Error) -> Result<(), TestCaseError> {
    let text = e.to_string();
    prop_assert!(
        !text.is_empty() && text.len() < 400 && !text.contains('\n'),
        "{}",
        text
    );
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig {
        // Seeded, so that CI runs the same cases; `FUZZ_SEED=k FUZZ_CASES=5000` to hunt.
        cases: std::env::var("FUZZ_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(96),
        rng_seed: proptest::test_runner::RngSeed::Fixed(
            std::env::var("FUZZ_SEED").ok().and_then(|s| s.parse().ok()).unwrap_or(25),
        ),
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    #[test]
    fn minimizer_runs_keep_their_contract(r in run_setting(), kind in minimizer_values()) {
        let calls = AtomicUsize::new(0);
        let f = |x: &[f64]| {
            calls.fetch_add(1, Ordering::Relaxed);
            value(kind, x)
        };
        let outside = AtomicUsize::new(0);
        let watched = |x: &[f64]| {
            if !r.inside(x) {
                outside.fetch_add(1, Ordering::Relaxed);
            }
            f(x)
        };
        match r.minimizer(Minimizer::new(watched)).run(&r.x0()) {
            Ok(m) => {
                r.check(&m, |x| value(kind, x))?;
                prop_assert_eq!(calls.load(Ordering::Relaxed), m.evaluations);
            }
            Err(e) => {
                check_error(&e)?;
                prop_assert!(calls.load(Ordering::Relaxed) <= r.budget);
            }
        }
        prop_assert_eq!(outside.load(Ordering::Relaxed), 0);
    }

    #[test]
    fn minimizer_ask_tell_keeps_its_contract(
        r in run_setting(),
        kind in minimizer_values(),
        bad in proptest::collection::vec((0usize..4, prop_oneof![Just(f64::NAN), Just(f64::INFINITY), Just(f64::NEG_INFINITY), Just(1e308)]), 0..4),
    ) {
        let mut run = match r.minimizer(Minimizer::without_objective()).ask_tell(&r.x0()) {
            Ok(run) => run,
            Err(e) => return check_error(&e),
        };
        let mut bad = bad.into_iter();
        let mut told = 0;
        for _ in 0..(r.budget + 3) {
            let ask = match run.ask() {
                Ok(Some(ask)) => ask,
                Ok(None) => break,
                Err(e) => {
                    check_error(&e)?;
                    // A failed ask repeats or ends the run: either way, no panic on finish.
                    if let Err(e) = run.ask() {
                        check_error(&e)?;
                    }
                    break;
                }
            };
            prop_assert_eq!(ask.dim(), r.n);
            let mut values = Vec::with_capacity(ask.len());
            for (x, _) in ask.iter() {
                prop_assert!(all_finite(x) && r.inside(x));
                values.push(value(kind, x));
            }
            // Sometimes first a bad tell: a wrong count, or an injected value.
            if let Some((k, v)) = bad.next() {
                let mut wrong = values.clone();
                if k == 0 {
                    wrong.push(v);
                } else {
                    wrong[k % values.len()] = v;
                }
                if let Err(e) = run.tell(&wrong) {
                    check_error(&e)?;
                } else {
                    told += wrong.len();
                    continue;
                }
            }
            match run.tell(&values) {
                Ok(()) => told += values.len(),
                Err(e) => {
                    check_error(&e)?;
                    break;
                }
            }
            prop_assert_eq!(run.evaluations(), told);
            prop_assert!(told <= r.budget);
        }
        match run.finish() {
            Ok(m) => {
                let failed = m.fun == f64::INFINITY && m.failures == m.evaluations;
                prop_assert!(m.fun.is_finite() || failed, "{:?}", m);
                prop_assert!(m.evaluations <= r.budget, "{:?}", m);
                prop_assert!(all_finite(&m.x) && r.inside(&m.x));
            }
            Err(e) => check_error(&e)?,
        }
    }

    #[test]
    fn paper_ask_tell_keeps_its_contract(
        n in prop_oneof![4 => 1usize..=4, 1 => Just(100_000usize)],
        start in prop_oneof![signed_extreme(), Just(1e300)],
        samples in 1usize..=4,
        lr in extreme(),
        sigma0 in extreme(),
        iterations in 1usize..=3,
        width in proptest::option::of(extreme()),
        kind in values().prop_map(|v| if matches!(v, Values::Panic) { Values::Constant(f64::NAN) } else { v }),
        resample in proptest::option::of(0usize..=2),
        seed in any::<u64>(),
    ) {
        let iterations = if n > 4 { 1 } else { iterations };
        let x0: Vec<f64> = (0..n).map(|i| if i % 2 == 0 { start } else { -0.5 * start }).collect();
        let Ok(annealer) = Annealer::paper(sigma0, iterations) else { return Ok(()); };
        let Ok(mut adam) = Adam::new(lr) else { return Ok(()); };
        let bounds = width.map(|w| {
            (x0.iter().map(|x| x - w).collect::<Vec<_>>(), x0.iter().map(|x| x + w).collect::<Vec<_>>())
        });
        if let Some((lo, hi)) = &bounds {
            match adam.bounds(lo.clone(), hi.clone()) {
                Ok(a) => adam = a,
                Err(e) => return check_error(&e),
            }
        }
        let inside = |x: &[f64]| match &bounds {
            Some((lo, hi)) => x.iter().zip(lo.iter().zip(hi)).all(|(v, (l, h))| l <= v && v <= h),
            None => true,
        };
        let mut grad = PlateauFreeGradient::without_objective().samples(2 * samples).seed(seed);
        if let Some(limit) = resample {
            grad = grad.on_failure(OnFailure::Resample { limit });
        }
        let mut run = match Optimizer::new(adam, annealer).ask_tell(grad, &x0) {
            Ok(run) => run,
            Err(e) => return check_error(&e),
        };
        for _ in 0..(4 * iterations + 4) {
            let ask = match run.ask() {
                Ok(Some(ask)) => ask,
                Ok(None) => break,
                Err(e) => {
                    check_error(&e)?;
                    break;
                }
            };
            let mut values = Vec::with_capacity(ask.len());
            for (x, _) in ask.iter() {
                prop_assert!(all_finite(x) && inside(x));
                values.push(value(kind, x));
            }
            if let Err(e) = run.tell(&values) {
                check_error(&e)?;
                break;
            }
            prop_assert!(all_finite(run.theta()) && inside(run.theta()));
        }
        prop_assert!(run.iteration() <= iterations);
        let history = run.finish();
        prop_assert!(all_finite(&history.value), "values {:?}", history.value);
        prop_assert!(history.iterations() <= iterations);
        let last = history.last_theta().unwrap();
        prop_assert!(all_finite(last) && inside(last));
    }
}
