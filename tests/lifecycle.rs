//! The run's lifecycle (`plateau_free::lifecycle`) for every method: interrupt, errors that
//! carry the result, progress and trace, workers bit-identical to one, checkpoints that
//! resume bit for bit and refuse another run's file, and the extreme dimensions.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;

use plateau_free::lifecycle::{AskAndTell, Driver, Interrupt, ProgressLine, Trace};
use plateau_free::{
    run::FailurePolicy, run::Metric, run::Strategy, vector::Sparsity, Adam, Annealer, Ask, Error,
    LeastSquares, Minimizer, Optimizer, PlateauFreeGradient, Stop,
};

mod common;
use common::StopAt;

/// A plain objective, as a function pointer (one type for every run of a test).
type Plain = fn(&[f64]) -> f64;

const PAPER: Strategy = Strategy::Paper {
    samples: 4,
    lr: 0.05,
    sigma0: 0.5,
};

/// Rosenbrock in any dimension.
fn rosenbrock(x: &[f64]) -> f64 {
    x.windows(2)
        .map(|w| 100.0 * (w[1] - w[0] * w[0]).powi(2) + (1.0 - w[0]).powi(2))
        .sum()
}

/// The three strategies of a `Minimizer` run on `f`: adaptive, the paper's loop, and the
/// loop polished by the adaptive search; failures raise.
fn strategies_of<F: plateau_free::Objective + Clone>(f: F, seed: u64) -> [Minimizer<F>; 3] {
    let m = || {
        Minimizer::new(f.clone())
            .budget(3000)
            .seed(seed)
            .on_failure(FailurePolicy::Raise)
    };
    [m(), m().strategy(PAPER), m().strategy(PAPER).polish(0.5)]
}

/// [`strategies_of`] Rosenbrock.
fn strategies(seed: u64) -> [Minimizer<Plain>; 3] {
    strategies_of(rosenbrock as Plain, seed)
}

#[test]
fn an_interrupt_from_another_thread_returns_the_best_point_so_far() {
    // Call 300 of f waits until the other thread, which watches the count, has triggered
    // the interrupt: the run ends after that generation, wherever the threads' timing.
    let calls = AtomicUsize::new(0);
    let stop = Interrupt::new();
    let f = |x: &[f64]| {
        if calls.fetch_add(1, Ordering::SeqCst) + 1 == 300 {
            while !stop.is_triggered() {
                std::thread::yield_now();
            }
        }
        rosenbrock(x)
    };
    let x0 = [-1.0, 2.0, 0.5];
    let best = std::thread::scope(|s| {
        let trigger = stop.clone();
        let calls = &calls;
        s.spawn(move || {
            while calls.load(Ordering::SeqCst) < 300 {
                std::thread::yield_now();
            }
            trigger.trigger();
        });
        Minimizer::new(f)
            .budget(10_000_000)
            .run_with(&x0, Driver::new().interrupt(stop.clone()))
    })
    .unwrap();
    assert_eq!(best.stop, Stop::Interrupted);
    assert!(!best.success());
    assert!(
        best.evaluations >= 300 && best.evaluations < 400,
        "{best:?}"
    );
    assert!(best.fun < rosenbrock(&x0), "{best:?}");
    assert_eq!(best.fun, rosenbrock(&best.x));
}

#[test]
fn an_interrupt_ends_the_paper_loop_with_its_history_so_far() {
    let f = |x: &[f64]| rosenbrock(x);
    let grad = PlateauFreeGradient::without_objective().samples(4).seed(1);
    let opt = Optimizer::new(Adam::new(0.01).unwrap(), Annealer::paper(0.3, 500).unwrap());
    let run = opt.ask_tell(grad, &[0.0, 0.0]).unwrap();
    let stop = Interrupt::new();
    let driver = Driver::new()
        .interrupt(stop.clone())
        .observe(StopAt(25, stop));
    let history = driver.run_objective(run, &f).unwrap();
    assert!(history.stopped_early);
    assert_eq!(history.iterations(), 25);
    assert_eq!(history.evaluations, 100);
}

/// `f` with NaN from call `from` on (the count shared by the clones).
fn failing_from(from: usize) -> impl Fn(&[f64]) -> f64 + Sync + Clone {
    let calls = std::sync::Arc::new(AtomicUsize::new(0));
    move |x: &[f64]| {
        if calls.fetch_add(1, Ordering::SeqCst) >= from {
            f64::NAN
        } else {
            rosenbrock(x)
        }
    }
}

#[test]
fn an_error_carries_the_result_so_far() {
    let x0 = [-1.0, 2.0];
    for k in 0..3 {
        // A fresh count of calls for each strategy.
        let m = strategies_of(failing_from(200), 0)
            .into_iter()
            .nth(k)
            .unwrap();
        let failure = m.run_with(&x0, Driver::new()).unwrap_err();
        assert!(
            matches!(failure.error, Error::NonFiniteValue { .. }),
            "{failure}"
        );
        let so_far = failure.result.expect("the run began");
        assert_eq!(so_far.stop, Stop::Interrupted);
        assert!(
            so_far.evaluations <= 200 && so_far.evaluations > 150,
            "{k}: {so_far:?}"
        );
        assert!(so_far.fun < rosenbrock(&x0));
        assert_eq!(so_far.fun, rosenbrock(&so_far.x));
    }
    // The adaptive search, and the error as `Error` through `?`.
    let failure = Minimizer::new(failing_from(100))
        .budget(3000)
        .on_failure(FailurePolicy::Raise)
        .run_with(&x0, Driver::new())
        .unwrap_err();
    let so_far = failure.result.clone().unwrap();
    assert!(so_far.evaluations <= 100 && so_far.fun < rosenbrock(&x0));
    let as_error: Error = failure.into();
    assert!(matches!(
        as_error,
        Error::NonFiniteValue { sample: 100, .. }
    ));
    // Bad options: the run never began.
    let failure = Minimizer::new(rosenbrock)
        .budget(0)
        .run_with(&x0, Driver::new())
        .unwrap_err();
    assert!(failure.result.is_none());
    assert!(matches!(
        failure.error,
        Error::InvalidParameter { name: "budget", .. }
    ));
}

#[test]
fn an_error_of_the_evaluation_carries_the_result_so_far() {
    /// The evaluation's own error type, as the Python bindings carry an exception.
    #[derive(Debug)]
    #[allow(dead_code)] // The library's error is carried, not read.
    enum Mine {
        Raised(usize),
        Library(Error),
    }
    impl From<Error> for Mine {
        fn from(e: Error) -> Mine {
            Mine::Library(e)
        }
    }
    let run = Minimizer::without_objective()
        .budget(1000)
        .ask_tell(&[3.0, 3.0])
        .unwrap();
    let mut turns = 0;
    let failure = Driver::new()
        .run(run, |_, ask: Ask<'_>, out: &mut [f64]| {
            turns += 1;
            if turns == 10 {
                return Err(Mine::Raised(turns));
            }
            for ((x, _), o) in ask.iter().zip(out.iter_mut()) {
                *o = rosenbrock(x);
            }
            Ok(())
        })
        .unwrap_err();
    assert!(matches!(failure.error, Mine::Raised(10)));
    let so_far = failure.result.unwrap();
    assert_eq!(so_far.iterations, 8); // the start's turn, then 8 generations
    assert!(so_far.fun < rosenbrock(&[3.0, 3.0]));
}

#[test]
fn the_progress_line_writes_lines() {
    let mut out = Vec::new();
    let line = ProgressLine::new(&mut out).every(Duration::ZERO);
    let best = Minimizer::new(rosenbrock)
        .budget(300)
        .run_with(&[0.0, 0.0], Driver::new().observe(line))
        .unwrap();
    let text = String::from_utf8(out).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), best.iterations + 2, "{text}");
    assert!(lines[0].starts_with("iteration 0  evaluations 1/300  best 1.000e0  sigma"));
    let end = format!("end: iteration {}  evaluations 300/300", best.iterations);
    assert!(lines.last().unwrap().starts_with(&end), "{text}");
    // The default writes the first line and the end within its 5 seconds.
    let mut out = Vec::new();
    Minimizer::new(rosenbrock)
        .budget(300)
        .run_with(
            &[0.0, 0.0],
            Driver::new().observe(ProgressLine::new(&mut out)),
        )
        .unwrap();
    assert_eq!(String::from_utf8(out).unwrap().lines().count(), 2);
    // Failed evaluations are counted on the line.
    let mut out = Vec::new();
    let holes = |x: &[f64]| if x[0] > 0.3 { f64::NAN } else { rosenbrock(x) };
    let best = Minimizer::new(holes)
        .budget(300)
        .run_with(
            &[0.0, 0.0],
            Driver::new().observe(ProgressLine::new(&mut out)),
        )
        .unwrap();
    assert!(best.failures > 0);
    let text = String::from_utf8(out).unwrap();
    let end = text.lines().last().unwrap();
    assert!(
        end.ends_with(&format!("  failed {}", best.failures)),
        "{text}"
    );
}

/// A method of one point an ask for `iterations` iterations: long runs, cheaply.
struct Walk {
    x: Vec<f64>,
    iterations: usize,
    done: usize,
    best: f64,
    seeds: [u64; 1],
}

impl Walk {
    /// At 0, for `iterations` iterations.
    fn new(iterations: usize) -> Walk {
        Walk {
            x: vec![0.0],
            iterations,
            done: 0,
            best: f64::INFINITY,
            seeds: [0],
        }
    }
}

impl AskAndTell for Walk {
    type Output = f64;
    fn ask(&mut self) -> Result<Option<Ask<'_>>, Error> {
        if self.done == self.iterations {
            return Ok(None);
        }
        self.x[0] = 1.0 / (1.0 + self.done as f64);
        Ask::try_new(
            plateau_free::objective::Points::new(&self.x, 1),
            &self.seeds,
        )
        .map(Some)
    }
    fn tell(&mut self, values: &[f64]) -> Result<(), Error> {
        self.best = self.best.min(values[0]);
        self.done += 1;
        Ok(())
    }
    fn evaluations(&self) -> usize {
        self.done
    }
    fn iteration(&self) -> usize {
        self.done
    }
    fn sigma(&self) -> f64 {
        f64::NAN
    }
    fn best_value(&self) -> f64 {
        self.best
    }
    fn finish(self) -> Result<f64, Error> {
        Ok(self.best)
    }
    fn so_far(&self) -> f64 {
        self.best
    }
}

#[test]
fn the_trace_stays_bounded() {
    let keep = 100;
    let mut trace = Trace::new(keep);
    let walk = Walk::new(100_000);
    let best = Driver::new()
        .observe(&mut trace)
        .run(walk, |_, ask, out| {
            out[0] = ask.points().get(0)[0];
            Ok::<(), Error>(())
        })
        .unwrap();
    let rows = trace.rows();
    assert!(
        rows.len() >= keep && rows.len() <= 2 * keep,
        "{}",
        rows.len()
    );
    assert_eq!(trace.iterations_seen(), 100_000);
    assert_eq!(rows[0].iteration, 1);
    assert_eq!(rows.last().unwrap().iteration, 100_000);
    assert_eq!(rows.last().unwrap().best, best);
    // Evenly spread: every kept row but the latest is `stride` iterations after the last.
    let stride = trace.stride();
    assert!(rows[..rows.len() - 1]
        .windows(2)
        .all(|w| w[1].iteration - w[0].iteration == stride));
}

#[test]
fn workers_give_the_bits_of_one() {
    let x0 = [-1.2, 1.0, 0.5, -0.3, 0.8];
    for seed in 0..3 {
        for m in strategies(seed) {
            let one = m.run(&x0).unwrap();
            let four = m.run_with(&x0, Driver::new().workers(4)).unwrap();
            assert_eq!(one, four, "seed {seed}");
            assert_eq!(one.fun.to_bits(), four.fun.to_bits());
        }
        // The paper's loop alone, and least squares.
        let opt = || Optimizer::new(Adam::new(0.02).unwrap(), Annealer::paper(0.4, 100).unwrap());
        let grad = || {
            PlateauFreeGradient::without_objective()
                .samples(6)
                .seed(seed)
        };
        let f = |x: &[f64]| rosenbrock(x);
        let one = Driver::new()
            .run_objective(opt().ask_tell(grad(), &x0).unwrap(), &f)
            .unwrap();
        let four = Driver::new()
            .workers(4)
            .run_objective(opt().ask_tell(grad(), &x0).unwrap(), &f)
            .unwrap();
        assert_eq!(one, four);
        let r = |x: &[f64], _: u64, out: &mut [f64]| {
            for (i, w) in x.windows(2).enumerate() {
                out[2 * i] = 10.0 * (w[1] - w[0] * w[0]);
                out[2 * i + 1] = 1.0 - w[0];
            }
        };
        let ls = LeastSquares::new(Sparsity::dense(8, 5).unwrap())
            .budget(400)
            .seed(seed);
        let four = Driver::new()
            .workers(4)
            .run(ls.ask_tell(&x0).unwrap(), |w, ask, out| {
                w.evaluate_rows(&r, ask, 8, out)
            })
            .unwrap();
        assert_eq!(four, ls.run(r, &x0).unwrap());
    }
}

#[test]
fn dimension_one_and_a_huge_dimension() {
    let f = |x: &[f64]| (x[0] - 0.25).powi(2);
    let best = Minimizer::new(f)
        .budget(500)
        .target(1e-12)
        .run_with(&[3.0], Driver::new().workers(2))
        .unwrap();
    assert_eq!(best.stop, Stop::Target);
    let n = 1_000_000;
    let sphere = |x: &[f64]| x.iter().map(|v| v * v).sum::<f64>();
    let x0 = vec![1.0; n];
    let mut trace = Trace::new(4);
    let best = Minimizer::new(sphere)
        .budget(9)
        .population(4)
        .metric(Metric::Diagonal)
        .run_with(&x0, Driver::new().workers(2).observe(&mut trace))
        .unwrap();
    assert_eq!(best.evaluations, 9);
    assert_eq!(best.x.len(), n);
    assert!(best.fun <= n as f64);
    assert_eq!(trace.rows().len(), 3);
}

#[cfg(feature = "serde")]
mod checkpoints {
    use super::*;
    use plateau_free::lifecycle::Checkpoint;
    use plateau_free::Minimum;

    /// A fresh file name in the temporary directory.
    fn path(name: &str) -> std::path::PathBuf {
        let dir =
            std::env::temp_dir().join(format!("plateau-free-lifecycle-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(name);
        let _ = std::fs::remove_file(&path);
        path
    }

    /// `m` from `x0` interrupted after `at` iterations with a checkpoint at `path`, then
    /// resumed from it to the end.
    fn interrupted_and_resumed(
        m: &Minimizer<Plain>,
        x0: &[f64],
        at: usize,
        path: &std::path::Path,
    ) -> Minimum {
        let stop = Interrupt::new();
        let driver = Driver::new()
            .interrupt(stop.clone())
            .observe(StopAt(at, stop))
            .checkpoint(Checkpoint::new(path).every_iterations(7));
        let first = m.run_with(x0, driver).unwrap();
        assert_eq!(first.stop, Stop::Interrupted);
        assert_eq!(first.iterations, at);
        let resumed = Driver::new().checkpoint(Checkpoint::new(path));
        m.run_with(x0, resumed).unwrap()
    }

    #[test]
    fn a_resumed_run_is_the_run_left_alone() {
        let x0 = [-1.2, 1.0, 0.5];
        for (k, m) in strategies(1).iter().enumerate() {
            let alone = m.run(&x0).unwrap();
            assert!(alone.iterations > 150, "{k}: {alone:?}");
            for at in [1, 40, 150, 400]
                .into_iter()
                .filter(|&at| at < alone.iterations)
            {
                let path = path(&format!("resume-{k}-{at}.json"));
                let resumed = interrupted_and_resumed(m, &x0, at, &path);
                assert_eq!(resumed, alone, "strategy {k}, interrupted at {at}");
                assert_eq!(resumed.fun.to_bits(), alone.fun.to_bits());
            }
        }
    }

    #[test]
    fn a_run_that_never_saw_a_finite_value_resumes() {
        // Its result's value is infinite: the state must keep it (JSON has no infinity).
        let nan = |_: &[f64]| f64::NAN;
        let m = Minimizer::new(nan).budget(60).seed(1);
        let path = path("never-finite.json");
        let first = m
            .run_with(
                &[0.0, 0.0],
                Driver::new().checkpoint(Checkpoint::new(&path)),
            )
            .unwrap();
        assert!(first.fun.is_infinite() && first.failures == 60);
        let again = m
            .run_with(
                &[0.0, 0.0],
                Driver::new().checkpoint(Checkpoint::new(&path)),
            )
            .unwrap();
        assert_eq!(again, first);
        // Half the space fails: generations whose median is infinite, saved mid-run.
        let holes = |x: &[f64]| if x[0] > 0.9 { f64::NAN } else { rosenbrock(x) };
        let m = Minimizer::new(holes).budget(400).seed(1);
        let alone = m.run(&[0.0, 0.0]).unwrap();
        assert!(alone.failures > 0);
        let path = path.with_extension("holes");
        let stop = Interrupt::new();
        let driver = Driver::new()
            .interrupt(stop.clone())
            .observe(StopAt(30, stop));
        m.run_with(&[0.0, 0.0], driver.checkpoint(Checkpoint::new(&path)))
            .unwrap();
        let resumed = m
            .run_with(
                &[0.0, 0.0],
                Driver::new().checkpoint(Checkpoint::new(&path)),
            )
            .unwrap();
        assert_eq!(resumed, alone);
    }

    #[test]
    fn an_error_inside_an_evaluation_leaves_the_last_turn_to_resume_from() {
        // The evaluation of turn 30 fails (Ctrl-C inside an evaluation, an error): the file
        // holds the end of turn 29, written although no timer was due, and the resumed run
        // redoes turn 30 and is the run left alone.
        let x0 = [-1.2, 1.0, 0.5];
        let m = Minimizer::new(rosenbrock as Plain).budget(2000).seed(5);
        let alone = m.run(&x0).unwrap();
        let path = path("inside.json");
        let mut turn = 0;
        let failure = Driver::new()
            .checkpoint(Checkpoint::new(&path))
            .run(m.ask_tell(&x0).unwrap(), |w, ask, out| {
                turn += 1;
                if turn == 30 {
                    return Err(Error::Unfinished {
                        evaluations: 0,
                        budget: 0,
                    });
                }
                w.evaluate(&(rosenbrock as Plain), ask, out)
            })
            .unwrap_err();
        assert!(matches!(failure.error, Error::Unfinished { .. }));
        let resumed = m
            .run_with(&x0, Driver::new().checkpoint(Checkpoint::new(&path)))
            .unwrap();
        assert_eq!(resumed, alone);
    }

    #[test]
    fn the_paper_loop_resumes_bit_for_bit() {
        let f = |x: &[f64]| rosenbrock(x);
        let opt = || Optimizer::new(Adam::new(0.02).unwrap(), Annealer::paper(0.4, 300).unwrap());
        let fresh = || {
            let grad = PlateauFreeGradient::without_objective().samples(4).seed(3);
            opt().ask_tell(grad, &[0.0, 0.5]).unwrap()
        };
        let alone = Driver::new().run_objective(fresh(), &f).unwrap();
        let path = path("paper.json");
        let stop = Interrupt::new();
        let first = Driver::new()
            .interrupt(stop.clone())
            .observe(StopAt(120, stop))
            .checkpoint(Checkpoint::new(&path))
            .run_objective(fresh(), &f)
            .unwrap();
        assert!(first.stopped_early);
        let resumed = Driver::new()
            .checkpoint(Checkpoint::new(&path))
            .run_objective(fresh(), &f)
            .unwrap();
        assert_eq!(resumed, alone);
    }

    #[test]
    fn another_runs_checkpoint_is_a_clear_error() {
        let x0 = [0.5, 0.5];
        let m = Minimizer::new(rosenbrock as Plain).budget(500).seed(1);
        let path = path("other.json");
        m.run_with(&x0, Driver::new().checkpoint(Checkpoint::new(&path)))
            .unwrap();
        let mismatch = |m: &Minimizer<Plain>, x0: &[f64]| {
            let failure = m
                .run_with(x0, Driver::new().checkpoint(Checkpoint::new(&path)))
                .unwrap_err();
            assert!(failure.result.is_none());
            match failure.error {
                Error::CheckpointMismatch {
                    field,
                    saved,
                    given,
                    ..
                } => (field, saved, given),
                e => panic!("{e}"),
            }
        };
        let seed_2 = Minimizer::new(rosenbrock as Plain).budget(500).seed(2);
        let (field, saved, given) = mismatch(&seed_2, &x0);
        assert_eq!(
            (field.as_str(), saved.as_str(), given.as_str()),
            ("seed", "1", "2")
        );
        let (field, ..) = mismatch(&m, &[0.5, 0.6]);
        assert_eq!(field, "x0");
        let other = Minimizer::new(rosenbrock as Plain).budget(600).seed(1);
        assert_eq!(mismatch(&other, &x0).0, "budget");
        let message = other
            .run_with(&x0, Driver::new().checkpoint(Checkpoint::new(&path)))
            .unwrap_err()
            .to_string();
        assert!(
            message.contains("budget is 500 there, 600 here"),
            "{message}"
        );
        // A state changed after it was written, still valid JSON: refused by its checksum.
        m.run_with(
            &x0,
            Driver::new().checkpoint(Checkpoint::new(path.with_extension("ok"))),
        )
        .unwrap();
        let text = std::fs::read_to_string(path.with_extension("ok")).unwrap();
        let at = text.find("\"evaluations\":").unwrap() + "\"evaluations\":".len();
        let damaged = format!("{}1{}", &text[..at], &text[at..]);
        std::fs::write(&path, damaged).unwrap();
        let failure = m
            .run_with(&x0, Driver::new().checkpoint(Checkpoint::new(&path)))
            .unwrap_err();
        assert!(
            failure.error.to_string().contains("checksum"),
            "{}",
            failure.error
        );
        // A damaged file.
        std::fs::write(&path, b"{\"format\":2,\"version\"").unwrap();
        let failure = m
            .run_with(&x0, Driver::new().checkpoint(Checkpoint::new(&path)))
            .unwrap_err();
        assert!(
            matches!(failure.error, Error::Checkpoint { .. }),
            "{}",
            failure.error
        );
        // A method with no saved form is refused before it begins.
        let walk = Walk::new(10);
        let failure = Driver::new()
            .checkpoint(Checkpoint::new(path.with_extension("walk")))
            .run(walk, |_, _, out| {
                out[0] = 1.0;
                Ok::<(), Error>(())
            })
            .unwrap_err();
        assert!(failure.result.is_none());
        assert!(
            failure.error.to_string().contains("cannot be saved"),
            "{}",
            failure.error
        );
        // A finished run's file resumes to its result at once.
        std::fs::remove_file(&path).unwrap();
        let done = m
            .run_with(&x0, Driver::new().checkpoint(Checkpoint::new(&path)))
            .unwrap();
        let again = m
            .run_with(&x0, Driver::new().checkpoint(Checkpoint::new(&path)))
            .unwrap();
        assert_eq!(done, again);
    }
}
