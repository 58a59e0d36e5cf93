//! [`Driver`]: the run's lifecycle, written once: interrupt, ask, evaluate, tell, observe,
//! checkpoint; and [`Failure`], the error that ends a run with its result so far.

use std::fmt;
use std::time::Instant;

#[cfg(feature = "serde")]
use super::checkpoint::Checkpoint;
use super::interrupt::Interrupt;
use super::method::AskAndTell;
use super::observe::{Observer, Progress};
use super::workers::Workers;
use crate::error::Error;
use crate::objective::Objective;
use crate::run::Ask;

/// An error that ended a run, with the run's result so far: its best point is never lost.
///
/// `result` is `None` only when the run never began (bad options or start, a checkpoint
/// that could not be read): then nothing was evaluated. Otherwise it is what the method
/// had when the error came ([`AskAndTell::so_far`]: for a [`crate::Minimum`], the best
/// point told so far, with [`crate::Stop::Interrupted`]).
///
/// ```
/// use plateau_free::lifecycle::Driver;
/// use plateau_free::{Error, run::FailurePolicy, Minimizer};
///
/// // f gives NaN from its 30th call on, and the policy raises.
/// let calls = std::sync::atomic::AtomicUsize::new(0);
/// let f = |x: &[f64]| match calls.fetch_add(1, std::sync::atomic::Ordering::Relaxed) {
///     0..29 => x[0] * x[0],
///     _ => f64::NAN,
/// };
/// let m = Minimizer::new(f).budget(500).on_failure(FailurePolicy::Raise);
/// let failure = m.run_with(&[2.0], Driver::new()).unwrap_err();
/// assert!(matches!(failure.error, Error::NonFiniteValue { .. }));
/// let so_far = failure.result.unwrap();
/// assert!(so_far.fun < 4.0 && so_far.evaluations < 30);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Failure<R, E = Error> {
    /// What ended the run.
    pub error: E,
    /// The result so far (`None`: the run never began), boxed so that a `Result` with a
    /// failure stays small.
    pub result: Option<Box<R>>,
}

impl<R, E: fmt::Display> fmt::Display for Failure<R, E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.error.fmt(f)
    }
}

impl<R: fmt::Debug, E: std::error::Error + 'static> std::error::Error for Failure<R, E> {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        Some(&self.error)
    }
}

impl<R> From<Failure<R, Error>> for Error {
    /// The error alone.
    fn from(failure: Failure<R, Error>) -> Error {
        failure.error
    }
}

/// Runs any [`AskAndTell`] method with an objective, after argmin's executor: each turn it
/// checks the [`Interrupt`], asks, evaluates the points on the [`Workers`], tells, shows
/// every [`Observer`] the [`Progress`] and, with the `serde` feature, writes the
/// [`crate::lifecycle::Checkpoint`] when it is due. It ends when the method is done, when
/// the interrupt is triggered ([`crate::Stop::Interrupted`], the best point so far), or on
/// an error, which comes back as a [`Failure`] with the result so far.
///
/// ```
/// use plateau_free::lifecycle::{Driver, ProgressLine, Trace};
/// use plateau_free::{Adam, Annealer, Optimizer, PlateauFreeGradient};
///
/// // The paper's loop, driven: the same bits as its callback form.
/// let f = |x: &[f64]| if x[0] + 2.0 * x[1] > 0.3 { 1.0 } else { 0.0 };
/// let opt = || Optimizer::new(Adam::new(0.02).unwrap(), Annealer::paper(0.5, 200).unwrap());
/// let run = opt().ask_tell(PlateauFreeGradient::without_objective().samples(8).seed(7), &[1.0, 1.0])?;
/// let mut trace = Trace::new(50);
/// let driven = Driver::new()
///     .observe(&mut trace)
///     .observe(ProgressLine::new(std::io::sink()))
///     .run_objective(run, &f)?;
/// let called = opt().minimize(&mut PlateauFreeGradient::new(f).samples(8).seed(7), &[1.0, 1.0])?;
/// assert_eq!(driven, called);
/// assert_eq!(trace.rows().last().unwrap().iteration, 200);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct Driver<'a> {
    interrupt: Option<Interrupt>,
    observers: Vec<Box<dyn Observer + Send + 'a>>,
    workers: Workers,
    #[cfg(feature = "serde")]
    checkpoint: Option<Checkpoint>,
}

impl fmt::Debug for Driver<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut d = f.debug_struct("Driver");
        d.field("interrupt", &self.interrupt)
            .field("observers", &self.observers.len())
            .field("workers", &self.workers.threads());
        #[cfg(feature = "serde")]
        d.field("checkpoint", &self.checkpoint);
        d.finish()
    }
}

/// A driver can be moved to another thread.
const _: fn() = || {
    fn send<T: Send>() {}
    send::<Driver<'static>>();
};

impl Default for Driver<'_> {
    fn default() -> Self {
        Driver::new()
    }
}

impl<'a> Driver<'a> {
    /// A driver with no interrupt, no observer, one worker and no checkpoint.
    pub fn new() -> Self {
        Driver {
            interrupt: None,
            observers: Vec::new(),
            workers: Workers::default(),
            #[cfg(feature = "serde")]
            checkpoint: None,
        }
    }

    /// Ends the run at the next turn once `interrupt` is triggered.
    #[must_use]
    pub fn interrupt(mut self, interrupt: Interrupt) -> Self {
        self.interrupt = Some(interrupt);
        self
    }

    /// Shows `observer` every iteration (observers are called in the order added). Pass
    /// `&mut observer` to read it after the run. Observers are `Send`, so that a driver can
    /// run on another thread (the Python bindings run it with the interpreter released).
    #[must_use]
    pub fn observe(mut self, observer: impl Observer + Send + 'a) -> Self {
        self.observers.push(Box::new(observer));
        self
    }

    /// Evaluates every ask on `threads` workers ([`Workers::new`]: 0 is one per core),
    /// bit-identical to one.
    #[must_use]
    pub fn workers(mut self, threads: usize) -> Self {
        self.workers = Workers::new(threads);
        self
    }

    /// Saves the run to `checkpoint` when due and at every end, and resumes from its file
    /// when it exists (see [`Checkpoint`]).
    #[cfg(feature = "serde")]
    #[must_use]
    pub fn checkpoint(mut self, checkpoint: Checkpoint) -> Self {
        self.checkpoint = Some(checkpoint);
        self
    }

    /// Runs `method` with an [`Objective`]: each ask's points go to the workers, one
    /// [`Objective::evaluate_batch`] call per worker.
    ///
    /// # Errors
    /// As [`Driver::run`].
    pub fn run_objective<M, F>(self, method: M, f: &F) -> Result<M::Output, Failure<M::Output>>
    where
        M: AskAndTell,
        F: Objective + Sync + ?Sized,
    {
        self.run(method, |workers, ask, out| workers.evaluate(f, ask, out))
    }

    /// Runs `method`, with `evaluate(workers, ask, out)` writing the asked points' values
    /// into `out` ([`AskAndTell::values_per_point`] a point, in the points' order, zeros on
    /// entry). `evaluate` may use the driver's [`Workers`] or evaluate the points anywhere.
    ///
    /// ```
    /// use plateau_free::lifecycle::Driver;
    /// use plateau_free::{LeastSquares, vector::Sparsity};
    ///
    /// let r = |x: &[f64], _seed: u64, out: &mut [f64]| {
    ///     out[0] = x[0] - 1.0;
    ///     out[1] = 2.0 * (x[1] + 0.5);
    /// };
    /// let options = LeastSquares::new(Sparsity::dense(2, 2)?).budget(200).sigma0(0.5);
    /// let driven = Driver::new()
    ///     .workers(2)
    ///     .run(options.ask_tell(&[0.0, 0.0])?, |w, ask, out| w.evaluate_rows(&r, ask, 2, out))?;
    /// assert_eq!(driven, options.run(r, &[0.0, 0.0])?);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    ///
    /// # Errors
    /// What `evaluate` returns, or the method's errors (a refused value, an overflowing
    /// point), or a checkpoint that cannot be read, belongs to another run
    /// ([`Error::CheckpointMismatch`]) or cannot be written at the start or the end (a
    /// write that fails in between is told to the observers): a [`Failure`] with the result
    /// so far.
    pub fn run<M, E, V>(
        mut self,
        method: M,
        mut evaluate: V,
    ) -> Result<M::Output, Failure<M::Output, E>>
    where
        M: AskAndTell,
        E: From<Error>,
        V: FnMut(&Workers, Ask<'_>, &mut [f64]) -> Result<(), E>,
    {
        let started = Instant::now();
        let mut method = match self.begin(method) {
            Ok(method) => method,
            Err(error) => {
                return Err(Failure {
                    error: error.into(),
                    result: None,
                })
            }
        };
        let per_point = method.values_per_point();
        let mut values = Vec::new();
        loop {
            if self.interrupt.as_ref().is_some_and(Interrupt::is_triggered) {
                let result = method.so_far();
                return match self.close(&method, started) {
                    Ok(()) => Ok(result),
                    Err(error) => Err(Failure {
                        error: error.into(),
                        result: Some(Box::new(result)),
                    }),
                };
            }
            let ask = match method.ask() {
                Ok(Some(ask)) => ask,
                Ok(None) => break,
                Err(error) => return Err(self.fail(&method, started, error.into())),
            };
            values.clear();
            values.resize(ask.len() * per_point, 0.0);
            if let Err(error) = evaluate(&self.workers, ask, &mut values) {
                return Err(self.fail(&method, started, error));
            }
            if let Err(error) = method.tell(&values) {
                return Err(self.fail(&method, started, error.into()));
            }
            let progress = progress(&method, started);
            for observer in &mut self.observers {
                observer.observe(&progress);
            }
            if let Err(error) = self.save_when_due(&method) {
                return Err(self.fail(&method, started, error.into()));
            }
        }
        if let Err(error) = self.close(&method, started) {
            return Err(Failure {
                error: error.into(),
                result: Some(Box::new(method.so_far())),
            });
        }
        let so_far = method.so_far();
        method.finish().map_err(|error| Failure {
            error: error.into(),
            result: Some(Box::new(so_far)),
        })
    }

    /// Shows the observers the end of a run that failed and gives its result so far. The
    /// checkpoint gets the state of the last turn's end (the method may hold points waiting
    /// for values): resumed, the run redoes the failed turn. A failure to write it is not
    /// reported over the error that ended the run.
    fn fail<M: AskAndTell, E>(
        &mut self,
        method: &M,
        started: Instant,
        error: E,
    ) -> Failure<M::Output, E> {
        #[cfg(feature = "serde")]
        if let Some(checkpoint) = &mut self.checkpoint {
            let _ = checkpoint.write_remembered();
        }
        let progress = progress(method, started);
        for observer in &mut self.observers {
            observer.end(&progress);
        }
        Failure {
            error,
            result: Some(Box::new(method.so_far())),
        }
    }

    /// Ends a run that is done or interrupted: writes the checkpoint, then shows the
    /// observers the end.
    fn close<M: AskAndTell>(&mut self, method: &M, started: Instant) -> Result<(), Error> {
        let saved = self.save_now(method);
        let progress = progress(method, started);
        for observer in &mut self.observers {
            observer.end(&progress);
        }
        saved
    }

    /// The method to run: `fresh`, or the checkpoint's run when its file exists.
    fn begin<M: AskAndTell>(&mut self, fresh: M) -> Result<M, Error> {
        #[cfg(feature = "serde")]
        if let Some(checkpoint) = &mut self.checkpoint {
            return checkpoint.begin(fresh);
        }
        Ok(fresh)
    }

    /// Keeps the turn's end in the checkpoint, if one is set, and writes it if due. A write
    /// that fails is told to the observers ([`Observer::not_saved`]), and the run goes on:
    /// a full disk must not end hours of work that the file cannot keep anyway.
    fn save_when_due<M: AskAndTell>(&mut self, method: &M) -> Result<(), Error> {
        #[cfg(feature = "serde")]
        if let Some(checkpoint) = &mut self.checkpoint {
            checkpoint.remember(method)?;
            if checkpoint.due(method.iteration()) {
                if let Err(error) = checkpoint.write_remembered() {
                    for observer in &mut self.observers {
                        observer.not_saved(&error);
                    }
                }
            }
        }
        let _ = method;
        Ok(())
    }

    /// Writes the checkpoint, if one is set.
    fn save_now<M: AskAndTell>(&mut self, method: &M) -> Result<(), Error> {
        #[cfg(feature = "serde")]
        if let Some(checkpoint) = &mut self.checkpoint {
            return checkpoint.save(method);
        }
        let _ = method;
        Ok(())
    }
}

/// Where `method` stands.
fn progress<M: AskAndTell>(method: &M, started: Instant) -> Progress {
    Progress {
        iteration: method.iteration(),
        evaluations: method.evaluations(),
        budget: method.budget(),
        best: method.best_value(),
        sigma: method.sigma(),
        elapsed: started.elapsed(),
        failures: method.failures(),
    }
}
