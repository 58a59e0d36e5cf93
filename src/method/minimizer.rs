//! [`AskTell`]: a [`Minimizer`] run as a state machine. It asks for the start `x0` first and
//! alone (so that the result is never worse than it), then hands every ask and tell to the
//! strategy's method: the adaptive search (`adaptive/`) or the paper's loop and its polish
//! (`polished.rs`). [`Minimizer::run`] is this machine with the objective evaluating every
//! ask.

use std::fmt;

use super::adaptive::Adaptive;
use super::polished::Polished;
#[cfg(feature = "serde")]
use crate::check;
use crate::error::Error;
use crate::objective::Points;
use crate::run::{Ask, Best, Ledger, Minimum, Options, Stop, Strategy};
// For the documentation's links only.
#[cfg(doc)]
use crate::{Minimizer, PaperAskTell};

/// A [`Minimizer`] run, asked and told: each ask gives one iteration's points (first the
/// start alone, then a generation of the adaptive search, or a gradient estimate of
/// [`Strategy::Paper`] and, last, its final point), each tell takes their values. It ends
/// with the [`Minimum`] that [`Minimizer::run`] returns, which is this loop with the
/// objective evaluating every ask.
///
/// ```
/// use plateau_free::Minimizer;
///
/// let f = |x: &[f64]| x.iter().map(|v| (v.round() - 1.0).powi(2)).sum::<f64>();
/// let mut run = Minimizer::without_objective().budget(600).seed(3).ask_tell(&[0.0; 3])?;
/// while let Some(ask) = run.ask()? {
///     // The points could go to a queue, a game engine, a render farm; the seeds with them.
///     let values: Vec<f64> = ask.iter().map(|(x, _seed)| f(x)).collect();
///     run.tell(&values)?;
/// }
/// let told = run.finish()?;
/// assert_eq!(told, Minimizer::new(f).budget(600).seed(3).run(&[0.0; 3])?);
/// assert_eq!(told.fun, 0.0);
/// # Ok::<(), plateau_free::Error>(())
/// ```
///
/// # A run's state is a value
/// With the `serde` feature, `AskTell` is `Serialize` and `Deserialize`: the whole run (the
/// options, the method's state, its random generators, the points waiting for values), and
/// no objective. Saved after any tell, or between an ask and its tell, and read back, it
/// goes on bit for bit as the uninterrupted run, so an experiment manager can checkpoint
/// it in its own storage. Non-finite numbers (the best value before the first tell, an
/// infinite target) are written as `"inf"`, `"-inf"`, `"nan"`, so JSON keeps them.
///
/// ```
/// # #[cfg(feature = "serde")] {
/// use plateau_free::{AskTell, Minimizer};
///
/// let f = |x: &[f64]| x.iter().map(|v| (v.round() - 1.0).powi(2)).sum::<f64>();
/// let m = Minimizer::without_objective().budget(300).seed(3);
/// let mut run = m.ask_tell(&[0.0; 3]).unwrap();
/// for _ in 0..5 {
///     let ask = run.ask().unwrap().unwrap();
///     let values: Vec<f64> = ask.iter().map(|(x, _seed)| f(x)).collect();
///     run.tell(&values).unwrap();
/// }
/// let saved = serde_json::to_string(&run).unwrap(); // a checkpoint
/// drop(run);
/// let mut run: AskTell = serde_json::from_str(&saved).unwrap();
/// while let Some(ask) = run.ask().unwrap() {
///     let values: Vec<f64> = ask.iter().map(|(x, _seed)| f(x)).collect();
///     run.tell(&values).unwrap();
/// }
/// let uninterrupted = Minimizer::new(f).budget(300).seed(3).run(&[0.0; 3]).unwrap();
/// assert_eq!(run.finish().unwrap(), uninterrupted);
/// # }
/// ```
///
/// Reading back checks the form (every field, of its type), the options as
/// [`Minimizer::ask_tell`] does, and the lengths of the run's vectors (the adaptive search's
/// and its Gaussian's, the paper loop's theta, Adam's moments, the estimator's buffers of an
/// estimate in progress) against the run's dimension: a state that fails is an error of the
/// deserialiser naming the [`Error`], not a panic later (`tests/state_value.rs` lengthens
/// and shortens every array of a saved run). The values themselves are the state's: read
/// back what serialising wrote.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "Unchecked"))]
pub struct AskTell {
    /// The options, the budget, the evaluations told and the best point seen.
    ledger: Ledger,
    n: usize,
    /// The start, evaluated first and alone (so that the result is never worse than it),
    /// and its seed (the run's).
    x0: Vec<f64>,
    x0_seed: [u64; 1],
    start: Start,
    method: Method,
    result: Option<Minimum>,
    /// An error that ends the run (a point that overflowed): every later ask repeats it.
    #[cfg_attr(feature = "serde", serde(with = "crate::saved::failed"))]
    failed: Option<Error>,
}

impl fmt::Debug for AskTell {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("AskTell")
            .field("strategy", &self.ledger.options.strategy)
            .field("budget", &self.ledger.budget)
            .field("evaluations", &self.ledger.evaluations)
            .field("best", &self.ledger.best.fun)
            .field("result", &self.result)
            .finish_non_exhaustive()
    }
}

/// The strategy's method, between asks.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
enum Method {
    Adaptive(Box<Adaptive>),
    Polished(Box<Polished>),
}

impl Method {
    /// The spread before the first iteration.
    fn start_sigma(&self) -> f64 {
        match self {
            Method::Adaptive(a) => a.start_sigma(),
            Method::Polished(p) => p.start_sigma(),
        }
    }

    /// Iterations and restarts so far, and the spread of the next iteration.
    fn progress(&self) -> (usize, usize, f64) {
        match self {
            Method::Adaptive(a) => a.progress(),
            Method::Polished(p) => p.progress(),
        }
    }

    /// Whether a failed ask ends the run: a point of the adaptive search that overflows
    /// does (its draws are spent), the paper's loop draws the same points again.
    fn failed_ask_ends_run(&self) -> bool {
        match self {
            Method::Adaptive(_) => true,
            Method::Polished(p) => p.polishing(),
        }
    }

    fn ask(&mut self, ledger: &Ledger) -> Result<Option<Ask<'_>>, Error> {
        match self {
            Method::Adaptive(a) => a.ask(ledger).map(Some),
            Method::Polished(p) => p.ask(ledger),
        }
    }

    /// Takes the values of the method's asked points; the result once the run has ended.
    fn tell(&mut self, ledger: &mut Ledger, values: &[f64]) -> Result<Option<Minimum>, Error> {
        match self {
            Method::Adaptive(a) => a.tell(ledger, values),
            Method::Polished(p) => p.tell(ledger, values),
        }
    }

    /// The run's result, unless the method goes on from `end` (the polish after the loop).
    fn hand_over(&mut self, ledger: &Ledger, end: Option<Minimum>) -> Option<Minimum> {
        match (self, end) {
            (Method::Polished(p), Some(end)) => p.hand_over(ledger, end),
            (_, end) => end,
        }
    }
}

/// Where a run stands with its start, which is evaluated first, alone.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
enum Start {
    /// The next ask is the start.
    ToAsk,
    /// The start waits for its value.
    Asked,
    /// The start's value is told: the method asks from here on.
    Told,
}

/// [`AskTell`]'s fields as read, before [`AskTell::check`].
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct Unchecked {
    ledger: Ledger,
    n: usize,
    x0: Vec<f64>,
    x0_seed: [u64; 1],
    start: Start,
    method: Method,
    result: Option<Minimum>,
    #[serde(with = "crate::saved::failed")]
    failed: Option<Error>,
}

#[cfg(feature = "serde")]
impl TryFrom<Unchecked> for AskTell {
    type Error = Error;

    fn try_from(u: Unchecked) -> Result<AskTell, Error> {
        let run = AskTell {
            ledger: u.ledger,
            n: u.n,
            x0: u.x0,
            x0_seed: u.x0_seed,
            start: u.start,
            method: u.method,
            result: u.result,
            failed: u.failed,
        };
        run.check()?;
        Ok(run)
    }
}

impl AskTell {
    /// The invariants that a read-back state must keep for its asks and tells not to
    /// panic: the options valid for the start, and every vector of the run's dimension.
    #[cfg(feature = "serde")]
    fn check(&self) -> Result<(), Error> {
        let n = self.n;
        check::len("x0", self.x0.len(), n)?;
        let budget = self.ledger.options.check(&self.x0)?;
        if budget != self.ledger.budget {
            return Err(Error::InvalidParameter {
                name: "budget",
                value: self.ledger.budget.into(),
                reason: "must be the options' budget",
            });
        }
        check::len("best point", self.ledger.best.x.len(), n)?;
        match &self.method {
            Method::Adaptive(a) => a.check(n),
            Method::Polished(p) => p.check(n),
        }
    }

    pub(crate) fn new(options: Options, x0: &[f64]) -> Result<AskTell, Error> {
        let budget = options.check(x0)?;
        // With discrete coordinates the start is rounded onto their grid first.
        let mut start = x0.to_vec();
        options.snap(&mut start);
        let x0 = &start[..];
        let method = match options.strategy {
            Strategy::Adaptive => Method::Adaptive(Box::new(
                Adaptive::new(&options, x0).judged(&options, budget),
            )),
            Strategy::Paper {
                samples,
                lr,
                sigma0,
            } => Method::Polished(Box::new(Polished::new(
                &options, x0, budget, samples, lr, sigma0,
            )?)),
        };
        Ok(AskTell {
            n: x0.len(),
            x0: x0.to_vec(),
            x0_seed: [options.seed],
            start: Start::ToAsk,
            method,
            result: None,
            failed: None,
            ledger: Ledger {
                options,
                budget,
                evaluations: 0,
                best: Best::new(x0),
                failures: 0,
            },
        })
    }

    /// The next points to evaluate and their seeds, or `None` once the run has ended (budget
    /// spent, target reached, converged without restarts).
    ///
    /// The first ask is the start `x0` alone, with the run's seed: the result is the best
    /// point seen, and so never worse than the start. Then the adaptive search asks for one
    /// generation (its population, cut to the budget left), all points of a generation with
    /// one seed (common random numbers), a new seed each generation. [`Strategy::Paper`]
    /// asks for each estimate's `N` points (a seed per antithetic pair), and last for the
    /// final parameters alone. With [`Minimizer::bounds`], every asked point lies inside the
    /// box.
    ///
    /// # Errors
    /// [`Error::AskPending`] if the last asked points still wait for their values; a point
    /// that overflows ([`Error::NonFinitePoint`], which ends an adaptive run: later asks
    /// repeat it).
    pub fn ask(&mut self) -> Result<Option<Ask<'_>>, Error> {
        if let Some(error) = &self.failed {
            return Err(error.clone());
        }
        if self.result.is_some() {
            return Ok(None);
        }
        match self.start {
            Start::ToAsk => {
                self.start = Start::Asked;
                let points = Points::new(&self.x0, self.n);
                return Ok(Some(Ask::new(points, &self.x0_seed)));
            }
            Start::Asked => return Err(Error::AskPending),
            Start::Told => {}
        }
        let ends_run = self.method.failed_ask_ends_run();
        match self.method.ask(&self.ledger) {
            Ok(ask) => Ok(ask),
            Err(error) => {
                if ends_run && !matches!(error, Error::AskPending) {
                    self.failed = Some(error.clone());
                }
                Err(error)
            }
        }
    }

    /// Tells the values of the asked points, in their order, and takes the iteration's step.
    ///
    /// # Errors
    /// [`Error::NothingAsked`] without an ask waiting for values; [`Error::TellCount`] for
    /// the wrong number of values; [`Error::NonFiniteValue`] for a NaN or an infinity (as
    /// the callback form reports it: the adaptive search counts `sample` over the run, the
    /// paper's loop within the estimate). After these the run is unchanged and the same
    /// points still wait for their values. The paper's loop may also report an overflowing
    /// gradient or step ([`PaperAskTell::tell`]).
    pub fn tell(&mut self, values: &[f64]) -> Result<(), Error> {
        if self.result.is_some() {
            return Err(Error::NothingAsked);
        }
        let end = match self.start {
            Start::ToAsk => return Err(Error::NothingAsked),
            Start::Asked => self.tell_start(values)?,
            Start::Told => self.method.tell(&mut self.ledger, values)?,
        };
        self.result = self.method.hand_over(&self.ledger, end);
        Ok(())
    }

    /// Takes the start's value: the first best point. The run ends there when the target
    /// is reached, when the budget is spent, or when the paper's loop has no iteration to
    /// make (then the polish, if any, follows).
    fn tell_start(&mut self, values: &[f64]) -> Result<Option<Minimum>, Error> {
        self.ledger.take(Points::new(&self.x0, self.n), values)?;
        self.start = Start::Told;
        let no_loop = matches!(&self.method, Method::Polished(p) if !p.has_iterations());
        let stop = if self.ledger.target_reached() {
            Stop::Target
        } else if self.ledger.evaluations >= self.ledger.budget || no_loop {
            Stop::Budget
        } else {
            return Ok(None);
        };
        let sigma = self.method.start_sigma();
        Ok(Some(self.ledger.minimum(0, 0, sigma, stop)))
    }

    /// Whether the run has ended (the next ask gives `None`; [`AskTell::result`] is set).
    pub fn is_done(&self) -> bool {
        self.result.is_some()
    }

    /// The result, once the run has ended.
    pub fn result(&self) -> Option<&Minimum> {
        self.result.as_ref()
    }

    /// The result: what [`Minimizer::run`] returns.
    ///
    /// # Errors
    /// [`Error::Unfinished`] before the run has ended (ask and tell until ask gives `None`);
    /// the error that ended a failed run.
    pub fn finish(self) -> Result<Minimum, Error> {
        if let Some(error) = self.failed {
            return Err(error);
        }
        self.result.ok_or(Error::Unfinished {
            evaluations: self.ledger.evaluations,
            budget: self.ledger.budget,
        })
    }

    /// The best point told so far and its value; `None` before the first value.
    pub fn best(&self) -> Option<(&[f64], f64)> {
        let best = &self.ledger.best;
        (best.fun < f64::INFINITY).then_some((best.x.as_slice(), best.fun))
    }

    /// Evaluations told so far.
    pub fn evaluations(&self) -> usize {
        self.ledger.evaluations
    }

    /// The budget of evaluations.
    pub fn budget(&self) -> usize {
        self.ledger.budget
    }

    /// Evaluations told whose value was NaN or infinite ([`Minimum::failures`] so far).
    pub fn failures(&self) -> usize {
        self.ledger.failures
    }

    /// The dimension of the points.
    pub fn dim(&self) -> usize {
        self.n
    }

    /// Iterations completed (generations of the adaptive search, gradient steps of the
    /// paper's loop): [`Minimum::iterations`] as it stands.
    ///
    /// ```
    /// let m = plateau_free::Minimizer::without_objective().budget(100).sigma0(0.5);
    /// let mut run = m.ask_tell(&[1.0])?;
    /// assert_eq!((run.iteration(), run.sigma()), (0, 0.5));
    /// while let Some(ask) = run.ask()? {
    ///     let values: Vec<f64> = ask.iter().map(|(x, _)| x[0].abs()).collect();
    ///     run.tell(&values)?;
    /// }
    /// let best = run.result().unwrap();
    /// assert_eq!((run.iteration(), run.sigma()), (best.iterations, best.sigma));
    /// # Ok::<(), plateau_free::Error>(())
    /// ```
    pub fn iteration(&self) -> usize {
        self.method.progress().0
    }

    /// The spread of the next iteration (the last one's once the run has ended).
    pub fn sigma(&self) -> f64 {
        match &self.result {
            Some(result) => result.sigma,
            None => self.method.progress().2,
        }
    }

    /// The result as it stands: once the run has ended, its result; before, the best point
    /// told so far with [`Stop::Interrupted`] (the start, with an infinite value, before
    /// any value is told). What a run ended early (an interrupt, an error) gives back.
    ///
    /// ```
    /// use plateau_free::{Minimizer, Stop};
    ///
    /// let mut run = Minimizer::without_objective().budget(100).ask_tell(&[2.0])?;
    /// let ask = run.ask()?.unwrap();
    /// let values: Vec<f64> = ask.iter().map(|(x, _)| x[0] * x[0]).collect();
    /// run.tell(&values)?;
    /// let so_far = run.so_far();
    /// assert_eq!((so_far.fun, so_far.stop, so_far.evaluations), (4.0, Stop::Interrupted, 1));
    /// # Ok::<(), plateau_free::Error>(())
    /// ```
    pub fn so_far(&self) -> Minimum {
        if let Some(result) = &self.result {
            return result.clone();
        }
        let (iterations, restarts, sigma) = self.method.progress();
        self.ledger
            .minimum(iterations, restarts, sigma, Stop::Interrupted)
    }

    /// The options the run was made with (for a checkpoint's identity).
    pub(crate) fn options(&self) -> &Options {
        &self.ledger.options
    }

    /// The start.
    pub(crate) fn x0(&self) -> &[f64] {
        &self.x0
    }
}
