//! Fuzzing the public API with random configurations, inputs and call sequences: dimensions
//! from 1 to 10^4 (10^5 for a [`Minimizer`]'s single cheap ask), spreads from 1e-300 to 1e300
//! (and the extremes of f64), starts up to f64::MAX, objectives whose values are huge,
//! subnormal, NaN or infinite (or that panic, with panics caught), budgets from 1. The
//! contract checked: never a panic, never a NaN or an infinity inside an `Ok`; a
//! [`Minimizer`] run spends at most its budget and stays inside its bounds.

use std::ops::ControlFlow;
use std::sync::atomic::{AtomicUsize, Ordering};

use plateau_free::baseline::{FiniteDifference, Spsa};
use plateau_free::{
    Adam, Annealer, Error, GradientEstimator, Metric, Minimizer, Minimum, OnFailure, Optimizer,
    OptimizerState, PlateauFreeGradient, Sampling, Schedule, Stop,
};
use proptest::prelude::*;

/// What the objective returns.
#[derive(Debug, Clone, Copy)]
enum Values {
    /// A steep linear function of the point times a scale (up to f64::MAX).
    Linear(f64),
    /// A step of height `scale` across `x0 = 0`.
    Step(f64),
    /// Pseudo-random values from the point's bits, each of them one of: huge, subnormal,
    /// zero, NaN, an infinity, ordinary.
    Chaos(u64),
    /// Always this value.
    Constant(f64),
    /// Panics on points with `x0 > 0`.
    Panic,
}

fn value(kind: Values, x: &[f64]) -> f64 {
    match kind {
        Values::Linear(scale) => scale * x.iter().take(4).sum::<f64>(),
        Values::Step(scale) => {
            if x[0] > 0.0 {
                scale
            } else {
                0.0
            }
        }
        Values::Chaos(salt) => {
            let h = plateau_free::seeding::mix(x[0].to_bits() ^ salt);
            match h % 8 {
                0 => f64::NAN,
                1 => f64::INFINITY,
                2 => -f64::MAX,
                3 => f64::MAX,
                4 => 5e-324,
                5 => 0.0,
                _ => (h >> 11) as f64 * 1e-10,
            }
        }
        Values::Constant(v) => v,
        Values::Panic => {
            if x[0] > 0.0 {
                panic!("fuzz: intended panic")
            }
            1.0
        }
    }
}

fn extreme() -> impl Strategy<Value = f64> {
    prop_oneof![
        (-300i32..=300, 1.0f64..10.0).prop_map(|(e, m)| m * 10f64.powi(e)),
        Just(f64::MAX),
        Just(f64::MIN_POSITIVE),
        Just(5e-324),
        Just(1e-300),
        Just(1e300),
        0.01f64..10.0,
    ]
}

fn signed_extreme() -> impl Strategy<Value = f64> {
    (extreme(), any::<bool>()).prop_map(|(x, neg)| if neg { -x } else { x })
}

fn values() -> impl Strategy<Value = Values> {
    prop_oneof![
        signed_extreme().prop_map(Values::Linear),
        signed_extreme().prop_map(Values::Step),
        any::<u64>().prop_map(Values::Chaos),
        prop_oneof![
            signed_extreme(),
            Just(f64::NAN),
            Just(f64::INFINITY),
            Just(0.0)
        ]
        .prop_map(Values::Constant),
        Just(Values::Panic),
    ]
}

fn dim() -> impl Strategy<Value = usize> {
    prop_oneof![4 => 1usize..=8, 1 => 9usize..=300, 1 => Just(10_000)]
}

#[derive(Debug, Clone)]
struct Config {
    samples: usize,
    sampling: Sampling,
    antithetic: bool,
    orthogonal: bool,
    parallel: bool,
    seed: u64,
    resample: Option<usize>,
}

fn config() -> impl Strategy<Value = Config> {
    (
        prop_oneof![1 => Just(0usize), 8 => 1usize..=9],
        prop_oneof![
            Just(Sampling::Radial),
            Just(Sampling::PerCoordinate),
            Just(Sampling::Gaussian)
        ],
        any::<bool>(),
        any::<bool>(),
        any::<bool>(),
        any::<u64>(),
        proptest::option::of(0usize..=4),
    )
        .prop_map(
            |(samples, sampling, antithetic, orthogonal, parallel, seed, resample)| Config {
                samples,
                sampling,
                antithetic,
                orthogonal,
                parallel,
                seed,
                resample,
            },
        )
}

#[derive(Debug, Clone)]
enum Op {
    Estimate(f64),
    Spreads(f64),
    Reset,
    AdamStep(f64),
}

fn ops() -> impl Strategy<Value = Vec<Op>> {
    proptest::collection::vec(
        prop_oneof![
            4 => extreme().prop_map(Op::Estimate),
            1 => (-1e300f64..1e300).prop_map(Op::Estimate),
            1 => extreme().prop_map(Op::Spreads),
            1 => Just(Op::Reset),
            2 => extreme().prop_map(Op::AdamStep),
        ],
        1..6,
    )
}

fn estimator(
    c: &Config,
    kind: Values,
) -> PlateauFreeGradient<impl Fn(&[f64]) -> f64 + Sync + Copy> {
    let mut g = PlateauFreeGradient::new(move |x: &[f64]| value(kind, x))
        .samples(c.samples)
        .sampling(c.sampling)
        .antithetic(c.antithetic)
        .orthogonal(c.orthogonal)
        .parallel(c.parallel)
        .seed(c.seed)
        // A panicking objective is only fuzzed with panics caught: uncaught, unwinding is
        // the documented behaviour.
        .catch_panics(true);
    if let Some(limit) = c.resample {
        g = g.on_failure(OnFailure::Resample { limit });
    }
    g
}

fn all_finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}

proptest! {
    // A few seconds in CI; `FUZZ_CASES=20000` for a longer hunt.
    #![proptest_config(ProptestConfig {
        cases: std::env::var("FUZZ_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(128),
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    #[test]
    fn estimates_and_steps_never_panic_nor_return_non_finite(
        c in config(),
        kind in values(),
        n in dim(),
        theta0 in signed_extreme(),
        ops in ops(),
        lr in extreme(),
    ) {
        let mut grad = estimator(&c, kind);
        let _ = grad.validate();
        let mut theta: Vec<f64> = (0..n).map(|i| if i % 2 == 0 { theta0 } else { -theta0 * 0.5 }).collect();
        let mut adam = Adam::new(lr).ok();
        for op in ops {
            match op {
                Op::Estimate(sigma) | Op::Spreads(sigma) => {
                    let r = if matches!(op, Op::Estimate(_)) {
                        grad.estimate(&theta, sigma)
                    } else {
                        grad.estimate_with_spreads(&theta, &vec![sigma; n])
                    };
                    if let Ok(e) = r {
                        prop_assert_eq!(e.gradient.len(), n);
                        prop_assert!(all_finite(&e.gradient), "gradient {:?}", &e.gradient[..n.min(4)]);
                        prop_assert!(e.mean_value.is_finite(), "mean {}", e.mean_value);
                        prop_assert!(e.evaluations >= c.samples);
                    }
                }
                Op::Reset => grad.reset(),
                Op::AdamStep(g) => {
                    if let Some(adam) = adam.as_mut() {
                        let gradient = vec![g; n];
                        let before = theta.clone();
                        if adam.step(&mut theta, &gradient).is_ok() {
                            prop_assert!(all_finite(&theta), "theta {:?}", &theta[..n.min(4)]);
                        } else {
                            prop_assert_eq!(&theta, &before);
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn runs_never_panic_nor_return_non_finite(
        c in config(),
        kind in values(),
        n in prop_oneof![1usize..=6, Just(1000)],
        start in signed_extreme(),
        sigma0 in extreme(),
        lr in extreme(),
        iterations in 0usize..6,
        stop in 0usize..6,
        record in any::<bool>(),
        schedule in prop_oneof![Just(Schedule::Constant), Just(Schedule::Exponential), Just(Schedule::Cosine)],
        baseline in 0u8..3,
    ) {
        let Ok(adam) = Adam::new(lr) else { return Ok(()); };
        let Ok(annealer) = Annealer::new(schedule, sigma0, sigma0 * 1e-3, iterations.max(1)) else { return Ok(()); };
        let mut opt = Optimizer::new(adam, annealer).iterations(iterations).record_theta(record);
        let f = move |x: &[f64]| value(kind, x);
        let mut est: Box<dyn GradientEstimator> = match baseline {
            0 => Box::new(estimator(&c, kind)),
            1 => match FiniteDifference::new(f, sigma0) { Ok(fd) => Box::new(fd), Err(_) => return Ok(()) },
            _ => Box::new(Spsa::new(f).seed(c.seed)),
        };
        if matches!(kind, Values::Panic) && baseline != 0 {
            // The baselines do not catch panics.
            return Ok(());
        }
        let start = vec![start; n];
        let check = |h: &plateau_free::History| -> Result<(), TestCaseError> {
            prop_assert!(all_finite(&h.value), "values {:?}", h.value);
            prop_assert!(h.theta.iter().all(|t| all_finite(t)));
            Ok(())
        };
        match opt.run(&mut *est, &start, |_| ControlFlow::Continue(())) {
            Ok(h) => {
                check(&h)?;
                prop_assert_eq!(h.iterations(), iterations);
                prop_assert!(h.last_theta().is_some());
            }
            Err(e) => {
                check(e.history())?;
                prop_assert!(e.to_string().len() < 400, "{}", e);
            }
        }
        // Interrupted and resumed: the same contract.
        if let Ok(state) = OptimizerState::new(&start) {
            let r = opt.minimize_from(&mut *est, state, |s| {
                if s.iteration == stop { ControlFlow::Break(()) } else { ControlFlow::Continue(()) }
            });
            let state = match r { Ok(s) => s, Err(e) => *e.state };
            prop_assert!(all_finite(&state.theta));
            if let Ok(end) = opt.minimize_from(&mut *est, state, |_| ControlFlow::Continue(())) {
                check(&end.history)?;
                prop_assert!(all_finite(&end.theta));
            }
        }
    }
}

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
                    Method::Adaptive(Metric::Full) if n > 4 => Method::Adaptive(Metric::Auto),
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
            } => m.strategy(plateau_free::Strategy::Paper {
                samples,
                lr,
                sigma0,
            }),
            Method::Polished {
                samples,
                lr,
                sigma0,
            } => m
                .strategy(plateau_free::Strategy::Paper {
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

// The cases the fuzz test found, kept as plain regression tests.

/// Adam with a huge learning rate at a huge theta stepped to -inf and returned Ok.
#[test]
fn found_adam_step_overflow_is_refused_unchanged() {
    let mut adam = Adam::new(1e308).unwrap();
    let mut theta = vec![-1e308, 1.0];
    let err = adam.step(&mut theta, &[1.0, 1.0]).unwrap_err();
    assert!(
        matches!(err, plateau_free::Error::StepOverflow { index: 0, .. }),
        "{err}"
    );
    assert!(err.to_string().contains("-1e308"), "{err}");
    assert_eq!(theta, vec![-1e308, 1.0]);
    assert_eq!(adam.steps(), 0);
    assert_eq!(adam.moments(), plateau_free::AdamMoments::default());
}

/// Nine values of f64::MAX / 9 (rounded) summed past f64::MAX: mean_value was infinite.
#[test]
fn found_mean_of_huge_values_stays_finite() {
    let f = |x: &[f64]| if x[0] > 0.0 { f64::MAX } else { 0.0 };
    let mut grad = PlateauFreeGradient::new(f).samples(9).antithetic(false);
    for _ in 0..20 {
        let e = grad.estimate(&[1.0], 1e300).unwrap();
        assert!(e.mean_value.is_finite() && e.mean_value >= 0.0, "{e:?}");
        assert!(e.mean_value <= f64::MAX);
    }
    let all_max = |_: &[f64]| f64::MAX;
    let e = PlateauFreeGradient::new(all_max)
        .samples(9)
        .antithetic(false)
        .estimate(&[1.0], 1.0)
        .unwrap();
    assert_eq!(e.mean_value, f64::MAX);
}

/// Finite differences summed f(theta + h) + f(theta - h) near f64::MAX to infinity, and
/// evaluated f at an overflowed point theta + h.
#[test]
fn found_finite_differences_at_the_end_of_the_range() {
    let huge = |_: &[f64]| f64::MAX;
    let e = FiniteDifference::new(huge, 1e-3)
        .unwrap()
        .estimate(&[0.0, 1.0], 0.1)
        .unwrap();
    assert_eq!(e.mean_value, f64::MAX);
    assert_eq!(e.gradient, vec![0.0, 0.0]);
    let seen_infinite = std::cell::Cell::new(false);
    let watch = |x: &[f64]| {
        seen_infinite.set(seen_infinite.get() || !x[0].is_finite());
        1.0
    };
    let err = FiniteDifference::new(watch, f64::MAX)
        .unwrap()
        .estimate(&[f64::MAX], 0.1)
        .unwrap_err();
    assert!(
        matches!(err, plateau_free::Error::NonFinitePoint { index: 0, .. }),
        "{err}"
    );
    assert!(!seen_infinite.get());
}
