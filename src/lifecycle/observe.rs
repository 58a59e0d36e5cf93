//! What a run shows while it runs: [`Observer`], called after every iteration with the
//! [`Progress`], and [`ProgressLine`], a plain line every few seconds.

use std::io::Write;
use std::time::{Duration, Instant};

use crate::Error;

/// Where a run stands after an iteration: what an [`Observer`] sees.
///
/// ```
/// use plateau_free::lifecycle::{Driver, Observer, Progress};
/// use plateau_free::Minimizer;
///
/// struct Last(Option<Progress>);
/// impl Observer for Last {
///     fn observe(&mut self, p: &Progress) {
///         self.0 = Some(*p);
///     }
/// }
/// let mut last = Last(None);
/// let best = Minimizer::new(|x: &[f64]| x[0] * x[0])
///     .budget(80)
///     .run_with(&[1.0], Driver::new().observe(&mut last))?;
/// let p = last.0.unwrap();
/// assert_eq!((p.iteration, p.evaluations, p.budget), (best.iterations, 80, Some(80)));
/// assert_eq!((p.best, p.sigma), (best.fun, best.sigma));
/// # Ok::<(), plateau_free::lifecycle::Failure<plateau_free::Minimum>>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct Progress {
    /// Iterations completed (the method's count: generations, gradient steps).
    pub iteration: usize,
    /// Evaluations told so far.
    pub evaluations: usize,
    /// The budget of evaluations, if the method has one.
    pub budget: Option<usize>,
    /// The best value so far (for the paper's loop, the mean value of its last estimate).
    pub best: f64,
    /// The current spread (NaN for a method with none).
    pub sigma: f64,
    /// Time since the run began (since this driver's run began, for a resumed run).
    pub elapsed: Duration,
    /// Evaluations that failed so far ([`crate::lifecycle::AskAndTell::failures`]).
    pub failures: usize,
}

/// Shown every iteration of a [`crate::lifecycle::Driver`]'s run. To stop the run from an
/// observer, hold an [`crate::lifecycle::Interrupt`] and trigger it.
///
/// ```
/// use plateau_free::lifecycle::{Driver, Observer, Progress};
/// use plateau_free::Minimizer;
///
/// struct Count(usize);
/// impl Observer for Count {
///     fn observe(&mut self, _progress: &Progress) {
///         self.0 += 1;
///     }
/// }
/// let mut count = Count(0);
/// let best = Minimizer::new(|x: &[f64]| x[0].abs())
///     .budget(100)
///     .run_with(&[1.0], Driver::new().observe(&mut count))?;
/// assert_eq!(count.0, best.iterations + 1); // the start's ask, then every generation
/// # Ok::<(), plateau_free::lifecycle::Failure<plateau_free::Minimum>>(())
/// ```
pub trait Observer {
    /// After every tell.
    fn observe(&mut self, progress: &Progress);

    /// Once, when the run ends (done, interrupted or failed), with where it ended.
    fn end(&mut self, progress: &Progress) {
        let _ = progress;
    }

    /// When a checkpoint due during the run could not be written (a full disk, a folder
    /// removed): the run goes on, the file written last stays the one to resume from, and
    /// the next write tries again. A run ends on this only at its end, when the last write
    /// fails.
    fn not_saved(&mut self, error: &Error) {
        let _ = error;
    }
}

impl<O: Observer + ?Sized> Observer for &mut O {
    fn observe(&mut self, progress: &Progress) {
        (**self).observe(progress);
    }

    fn end(&mut self, progress: &Progress) {
        (**self).end(progress);
    }

    fn not_saved(&mut self, error: &Error) {
        (**self).not_saved(error);
    }
}

/// How often [`ProgressLine`] writes by default, in seconds.
///
/// ```
/// assert_eq!(plateau_free::lifecycle::PROGRESS_SECONDS, 5.0);
/// ```
pub const PROGRESS_SECONDS: f64 = 5.0;

/// A plain progress line to any writer (a terminal, a log file, a pipe): one every few
/// seconds ([`PROGRESS_SECONDS`] by default) and one at the end. A writer that fails is
/// ignored: a progress display never ends a run.
///
/// ```
/// use plateau_free::lifecycle::{Driver, ProgressLine};
/// use plateau_free::Minimizer;
///
/// let mut out = Vec::new();
/// let every_iteration = ProgressLine::new(&mut out).every(std::time::Duration::ZERO);
/// Minimizer::new(|x: &[f64]| x[0] * x[0])
///     .budget(60)
///     .run_with(&[1.0], Driver::new().observe(every_iteration))?;
/// let text = String::from_utf8(out).unwrap();
/// assert!(text.starts_with("iteration 0  evaluations 1/60  best 1.000e0"));
/// assert!(text.lines().last().unwrap().starts_with("end: iteration"));
/// # Ok::<(), plateau_free::lifecycle::Failure<plateau_free::Minimum>>(())
/// ```
#[derive(Debug)]
pub struct ProgressLine<W: Write> {
    out: W,
    every: Duration,
    last: Option<Instant>,
}

impl<W: Write> ProgressLine<W> {
    /// Lines to `out`, every [`PROGRESS_SECONDS`].
    pub fn new(out: W) -> ProgressLine<W> {
        ProgressLine {
            out,
            every: Duration::from_secs_f64(PROGRESS_SECONDS),
            last: None,
        }
    }

    /// Writes at most once per `every` (the first iteration's line and the end's always).
    #[must_use]
    pub fn every(mut self, every: Duration) -> ProgressLine<W> {
        self.every = every;
        self
    }

    /// The writer back.
    pub fn into_inner(self) -> W {
        self.out
    }

    fn write(&mut self, prefix: &str, p: &Progress) {
        let budget = p.budget.map(|b| format!("/{b}")).unwrap_or_default();
        let failed = match p.failures {
            0 => String::new(),
            n => format!("  failed {n}"),
        };
        let _ = writeln!(
            self.out,
            "{prefix}iteration {}  evaluations {}{budget}  best {:.3e}  sigma {:.3e}  elapsed {:.1} s{failed}",
            p.iteration,
            p.evaluations,
            p.best,
            p.sigma,
            p.elapsed.as_secs_f64()
        );
        let _ = self.out.flush();
    }
}

impl<W: Write> Observer for ProgressLine<W> {
    fn observe(&mut self, progress: &Progress) {
        let now = Instant::now();
        if self.last.is_none_or(|last| now - last >= self.every) {
            self.last = Some(now);
            self.write("", progress);
        }
    }

    fn end(&mut self, progress: &Progress) {
        self.write("end: ", progress);
    }

    fn not_saved(&mut self, error: &Error) {
        let _ = writeln!(self.out, "warning: {error}; the run goes on");
        let _ = self.out.flush();
    }
}
