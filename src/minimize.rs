//! `minimize(f, x0, budget)`: the entry point for users who bring only a function, a start
//! and a number of evaluations, and [`Minimizer`], the builder beside it. [`Minimizer::run`]
//! is the callback form: it drives the ask-and-tell run ([`AskTell`], `method/`) with the
//! objective. The methods themselves live in `method/`, the options and the result in
//! `run/`.

use std::fmt;

use crate::error::Error;
use crate::lifecycle::{Driver, Failure};
use crate::method::AskTell;
use crate::objective::{NoObjective, Objective};
use crate::run::{FailurePolicy, Metric, Minimum, Options, Strategy};
// For the documentation's links only.
#[cfg(doc)]
use crate::run::Stop;

/// Minimises `f` from `x0` with at most `budget` evaluations of `f`, with no other setting to
/// choose: the first thing to try.
///
/// The search is a Gaussian smoothing of `f` whose spread and metric adapt to the function
/// (see [`Minimizer`] for the method and its options). It returns the best point seen and its
/// value.
///
/// ```
/// // A staircase: the squared distance of the rounded point to an integer target.
/// let target = [1.0, -2.0, 3.0];
/// let f = |x: &[f64]| x.iter().zip(&target).map(|(v, t)| (v.round() - t).powi(2)).sum::<f64>();
/// let best = plateau_free::minimize(f, &[0.0; 3], 2000)?;
/// assert_eq!(best.fun, 0.0);
/// assert!(best.evaluations <= 2000);
/// # Ok::<(), plateau_free::Error>(())
/// ```
///
/// # Errors
/// An empty or non-finite `x0`, or a zero budget. A NaN or an infinity from `f` is a failed
/// point, ranked below every finite value and counted in [`Minimum::failures`].
pub fn minimize<F: Fn(&[f64]) -> f64>(f: F, x0: &[f64], budget: usize) -> Result<Minimum, Error> {
    Minimizer::new(f).budget(budget).run(x0)
}

/// `minimize` with options.
///
/// ```
/// use plateau_free::{Minimizer, Stop};
///
/// // An ill-conditioned, rotated quadratic: the metric is learnt from the samples.
/// let f = |x: &[f64]| (x[0] + x[1] - 1.0).powi(2) + 1e4 * (x[0] - x[1]).powi(2);
/// let best = Minimizer::new(f)
///     .budget(3000)
///     .seed(7)
///     .target(1e-10)
///     .run(&[3.0, -2.0])?;
/// assert_eq!(best.stop, Stop::Target);
/// assert!((best.x[0] - 0.5).abs() < 1e-4 && (best.x[1] - 0.5).abs() < 1e-4);
/// # Ok::<(), plateau_free::Error>(())
/// ```
///
/// # The method
/// Each iteration draws a population of points from a Gaussian `N(m, sigma^2 C)` around the
/// mean `m`, ranks them by `f`, and moves `m` along the rank-weighted best offsets: the natural
/// gradient of the Gaussian-smoothed, rank-transformed objective (a plateau-free gradient that
/// ignores the scale of `f`). `sigma` follows cumulative step-size adaptation (it shrinks with
/// progress, with no floor) and grows while the best quarter of a generation ties (a
/// plateau); `C` learns the function's metric with the CMA-ES rules (Hansen 2016). When a run
/// converges or stalls, the next run starts again from `x0` with twice the population, or
/// from the best point seen when the run found it again (the best point is the result
/// either way). Details, sources and measurements: `docs/convergence.md`.
///
/// # Promises
/// Whatever the strategy, the options and the budget:
/// - the start `x0` is evaluated first, so the result is never worse than `f(x0)`;
/// - at most `budget` evaluations are spent;
/// - with [`Minimizer::bounds`], `x0` must lie inside the box, `f` is called only inside it
///   (every point is clamped onto it, see `docs/design.md`, "Bounds"), and the result lies
///   inside it.
///
/// # Determinism
/// The result is a function of the objective, `x0`, the options and the seed alone. An
/// [`Objective`] that takes a seed ([`crate::objective::Seeded`]) receives the same seed for every point
/// of an iteration (common random numbers), a new one each iteration.
pub struct Minimizer<F> {
    objective: F,
    options: Options,
}

impl<F> fmt::Debug for Minimizer<F> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let o = &self.options;
        f.debug_struct("Minimizer")
            .field("budget", &o.budget)
            .field("seed", &o.seed)
            .field("sigma0", &o.sigma0)
            .field("bounds", &o.bounds)
            .field("steps", &o.steps)
            .field("target", &o.target)
            .field("population", &o.population)
            .field("restarts", &o.restarts)
            .field("mirrored", &o.mirrored)
            .field("flat_growth", &o.flat_growth)
            .field("metric", &o.metric)
            .field("strategy", &o.strategy)
            .field("polish", &o.polish)
            .field("stall", &o.stall)
            .finish_non_exhaustive()
    }
}

impl<F: Objective> Minimizer<F> {
    /// A minimiser of `objective`: any `Fn(&[f64]) -> f64`, a [`crate::objective::Seeded`] or
    /// [`crate::objective::Batch`] closure (a batch objective receives a whole iteration's points at
    /// once), or your own [`Objective`].
    pub fn new(objective: F) -> Self {
        Minimizer {
            objective,
            options: Options::default(),
        }
    }
}

impl Minimizer<NoObjective> {
    /// The options alone, for a run whose points are evaluated elsewhere
    /// ([`Minimizer::ask_tell`]): it has the builder methods but no `run`.
    ///
    /// ```
    /// let run = plateau_free::Minimizer::without_objective().budget(100).ask_tell(&[1.0, 2.0])?;
    /// assert!(!run.is_done());
    /// # Ok::<(), plateau_free::Error>(())
    /// ```
    pub fn without_objective() -> Self {
        Minimizer {
            objective: NoObjective,
            options: Options::default(),
        }
    }
}

impl<F> Minimizer<F> {
    setters! {
        /// The number of evaluations of `f` the run may spend (default: `1000 n`).
        budget(budget: usize) => options.budget = Some(budget);

        /// The seed of every random choice (default 0).
        seed(seed: u64) => options.seed = seed;

        /// The starting spread, in the units of `x` (default: a quarter of the mean finite box
        /// width with [`Minimizer::bounds`], else `max(1, max |x0_i|) / 2`). It adapts from there: a
        /// poor guess costs evaluations, not the result.
        sigma0(sigma0: f64) => options.sigma0 = Some(sigma0);

        /// A starting spread for each coordinate, in the units of `x` (positive, one per
        /// coordinate): for coordinates of different scales. It sets the adaptive search's
        /// starting spread and metric together (their product); set it or
        /// [`Minimizer::sigma0`], not both.
        sigma0_each(spreads: Vec<f64>) => options.sigma0_each = Some(spreads);

        /// How many restarts in a row must converge back at the best point seen before them
        /// for the run to be done ([`Stop::Done`], a success) before its budget (default
        /// [`crate::run::DEFAULT_PATIENCE`]; 0: the budget, the target or the stall rule alone end
        /// the run). A converged restart is one that ended with its spread, its values or its
        /// flat bottom below its own precision; "back at the best point" means its best value
        /// within that precision of the best seen before it, and its mean within a few of its
        /// standard deviations of that point. On an objective whose values tie (a staircase,
        /// a quantised render, or values rounded at the optimum), two more such restarts are
        /// asked for: restarts there can end on a step of the best value that is not the best
        /// step, and restarts with larger populations still find lower ones.
        patience(restarts: usize) => options.patience = restarts;

        /// A box: every evaluated point is projected onto it, and restarts stay inside it; `x0`
        /// must lie inside it. An infinite entry (`f64::NEG_INFINITY` below,
        /// `f64::INFINITY` above) leaves that side open; the default starting spread comes
        /// from the finite widths only.
        bounds(lower: Vec<f64>, upper: Vec<f64>) => options.bounds = Some((lower, upper));

        /// Discrete coordinates: one step per coordinate, `0.0` for a continuous one and
        /// `s > 0` for the grid of multiples `k s` (`1.0`: the integers), as a run with
        /// bounds gives one spread per coordinate ([`Minimizer::sigma0_each`]). Every point
        /// handed to `f` (the start included) and so the result have each such coordinate on
        /// its grid: the search's draws are rounded to the nearest multiple after they are
        /// clamped onto [`Minimizer::bounds`], and to the nearest multiple inside the box if
        /// that one is outside (so the box must hold a multiple on every discrete coordinate;
        /// `[0.5, 3.5]` with step 1 holds 1, 2, 3). The search learns from the unrounded draws,
        /// but from a selected draw that rounded off the mean's tread at its grid point, and
        /// keeps the spread along a discrete coordinate above a floor tied to its step
        /// (`docs/integers.md`). A coordinate more than `2^52` steps from zero is left as
        /// given: floats there are already spaced at least a step apart.
        ///
        /// ```
        /// use plateau_free::Minimizer;
        ///
        /// // Integers in [0, 10] and one continuous coordinate.
        /// let f = |x: &[f64]| (x[0] - 3.0).powi(2) + (x[1] - 7.0).powi(2) + (x[2] - 0.25).powi(2);
        /// let best = Minimizer::new(f)
        ///     .steps(vec![1.0, 1.0, 0.0])
        ///     .bounds(vec![0.0; 3], vec![10.0; 3])
        ///     .budget(3000)
        ///     .run(&[5.5, 5.5, 5.5])?;
        /// assert_eq!(&best.x[..2], &[3.0, 7.0]);
        /// assert!((best.x[2] - 0.25).abs() < 1e-4);
        /// # Ok::<(), plateau_free::Error>(())
        /// ```
        ///
        /// # Errors
        /// (At [`Minimizer::run`] and [`Minimizer::ask_tell`].) A step that is negative, NaN
        /// or infinite, a number of steps other than the dimension, a box with no multiple
        /// of a step between a coordinate's bounds ([`Error::InvalidParameter`],
        /// [`Error::LengthMismatch`]), or steps with [`Strategy::Paper`], whose loop takes
        /// continuous steps.
        steps(steps: Vec<f64>) => options.steps = Some(steps);

        /// Stop as soon as `f` reaches `target` or below: after the iteration (the adaptive
        /// search's generation, the paper loop's gradient estimate) that saw such a value,
        /// with [`Stop::Target`] and no polish.
        target(target: f64) => options.target = Some(target);

        /// The population of the first run (default `4 + floor(3 ln n)`); each restart doubles it.
        population(population: usize) => options.population = Some(population);

        /// Whether a run that converged or stalled restarts with a doubled population while
        /// budget remains (default: yes). Off, the run ends with
        /// [`Stop::Converged`].
        restarts(restarts: bool) => options.restarts = restarts;

        /// Mirrored (antithetic) draws, `y` and `-y`, as the paper's antithetic pairs (default:
        /// on; it won on Rastrigin and Rosenbrock, see `docs/convergence.md`).
        mirrored(mirrored: bool) => options.mirrored = mirrored;

        /// Whether the spread grows on generations where half the points tie with the best
        /// (default: yes; the plateau rule).
        flat_growth(flat_growth: bool) => options.flat_growth = flat_growth;

        /// Whether every restart starts from the best point seen. By default a restart starts
        /// from `x0`, or from the best point after a run that found it again (the further
        /// runs of [`Minimizer::patience`] then check it rather than search for it again).
        /// The default won on COCO's bbob and bbob-mixint (`docs/convergence.md`, table 2b);
        /// every restart from the best point won on the hand-written suite's Rastrigin.
        restart_from_best(from_best: bool) => options.restart_from_best = from_best;

        /// The metric the search distribution learns (default [`Metric::Auto`]).
        metric(metric: Metric) => options.metric = metric;

        /// The search method; [`Strategy::Paper`] runs the paper's loop (annealer and Adam) with
        /// the same budget, seed and bounds.
        strategy(strategy: Strategy) => options.strategy = strategy;

        /// With [`Strategy::Paper`]: spend the last `fraction` of the budget on the adaptive
        /// search, started at the loop's best point with the loop's last spread (default 0: the
        /// loop alone; with [`Strategy::Paper`], [`crate::run::DEFAULT_POLISH`] when not set).
        ///
        /// The paper's annealed loop finds the basin (its large early spread smooths plateaus
        /// away) but ends where Adam's fixed learning rate and the spread's floor leave it, about
        /// `lr` from the optimum; the adaptive search shrinks its spread with progress and has no
        /// floor, so it finishes the descent. On the path-tracing tasks a quarter won
        /// (`docs/convergence.md`, table 8), and a half reaches the paper's answer in fewer
        /// renders, so the tasks now use 0.5 ("Renders to the paper's answer").
        ///
        /// ```
        /// use plateau_free::{Minimizer, run::Strategy};
        ///
        /// // A cone, as an image loss is near its optimum: Adam's steps hover around the tip.
        /// let f = |x: &[f64]| ((x[0] - 0.3).powi(2) + (x[1] + 0.2).powi(2)).sqrt();
        /// let paper = Strategy::Paper { samples: 2, lr: 0.02, sigma0: 0.5 };
        /// let polished = Minimizer::new(f).strategy(paper).polish(0.5).budget(800).run(&[1.0, 1.0])?;
        /// assert!(polished.fun < 1e-5, "{polished:?}");
        /// assert_eq!(polished.evaluations, 800);
        /// # Ok::<(), plateau_free::Error>(())
        /// ```
        polish(fraction: f64) => options.polish = Some(fraction);

        /// Ends the run when the best value has not improved over the last `window` of the
        /// budget (a fraction in `(0, 1]`; [`crate::run::STALL_WINDOW`] is the tested choice), the
        /// rule [`crate::run::Stall`] with no tolerance: [`Stop::Stalled`]. Default: off, the budget
        /// alone ends the run. The budget stays the ceiling. The rule sees only the values: the
        /// adaptive search is judged from its first generation; with [`Strategy::Paper`], the
        /// loop runs its whole schedule (its annealing is planned over its share of the budget)
        /// and the polish is judged from the hand-over.
        ///
        /// ```
        /// use plateau_free::{Minimizer, Stop, run::STALL_WINDOW};
        ///
        /// // A floor: every point with |x| < 1 is as good as the optimum. (Without the
        /// // patience rule, which would end this run first.)
        /// let f = |x: &[f64]| (x[0].abs() - 1.0).max(0.0);
        /// let best = Minimizer::new(f)
        ///     .budget(5000)
        ///     .patience(0)
        ///     .stop_when_stalled(STALL_WINDOW)
        ///     .run(&[8.0])?;
        /// assert_eq!(best.stop, Stop::Stalled);
        /// assert_eq!(best.fun, 0.0);
        /// assert!(best.evaluations < 5000);
        /// # Ok::<(), plateau_free::Error>(())
        /// ```
        stop_when_stalled(window: f64) => options.stall = Some(window);

        /// What the run does with an evaluation that returned NaN or an infinity (see
        /// [`FailurePolicy`]).
        on_failure(policy: FailurePolicy) => options.on_failure = policy;
    }

    /// The objective.
    pub fn objective(&self) -> &F {
        &self.objective
    }

    /// An ask-and-tell run from `x0` with these options (the objective, if any, is not
    /// used): see [`AskTell`].
    ///
    /// # Errors
    /// Bad options or start, as [`Minimizer::run`].
    pub fn ask_tell(&self, x0: &[f64]) -> Result<AskTell, Error> {
        AskTell::new(self.options.clone(), x0)
    }
}

impl<F: Objective> Minimizer<F> {
    /// Runs from `x0`: [`Minimizer::ask_tell`], with every asked point evaluated by the
    /// objective (one [`Objective::evaluate_batch`] call per ask): a bare
    /// [`Driver`] run. [`Minimizer::run_with`] adds an interrupt, observers, workers and a
    /// checkpoint, and keeps the result so far on error.
    ///
    /// # Errors
    /// Bad options or start ([`Error::EmptyTheta`], [`Error::NonFiniteTheta`],
    /// [`Error::InvalidParameter`], [`Error::InvalidBounds`], [`Error::LengthMismatch`],
    /// [`Error::OutsideBounds`]), or
    /// `f` returning NaN or an infinity ([`Error::NonFiniteValue`], with the point).
    pub fn run(&self, x0: &[f64]) -> Result<Minimum, Error> {
        let run = self.ask_tell(x0)?;
        let f = &self.objective;
        Driver::new()
            .run(run, |_, ask, out| {
                f.evaluate_batch(ask.points(), ask.seeds(), out);
                Ok::<(), Error>(())
            })
            .map_err(Error::from)
    }
}

impl<F: Objective + Sync> Minimizer<F> {
    /// Runs from `x0` with `driver`: its [`crate::lifecycle::Interrupt`] (the run ends with
    /// [`Stop::Interrupted`] and the best point so far), observers, workers (bit-identical
    /// to one) and checkpoint (feature `serde`). Without any, it is [`Minimizer::run`].
    ///
    /// ```
    /// use plateau_free::lifecycle::{Driver, Trace};
    /// use plateau_free::Minimizer;
    ///
    /// let f = |x: &[f64]| (x[0] - 1.0).powi(2) + (x[1] + 1.0).powi(2);
    /// let m = Minimizer::new(f).budget(400).seed(5);
    /// let mut trace = Trace::new(100);
    /// let best = m.run_with(&[0.0, 0.0], Driver::new().workers(3).observe(&mut trace))?;
    /// assert_eq!(best, m.run(&[0.0, 0.0])?);
    /// assert_eq!(trace.rows().len(), best.iterations + 1);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    ///
    /// # Errors
    /// As [`Minimizer::run`], and a checkpoint that cannot be read or written or belongs to
    /// another run: a [`Failure`] with the result so far (`None` when the run did not begin).
    pub fn run_with(&self, x0: &[f64], driver: Driver<'_>) -> Result<Minimum, Failure<Minimum>> {
        let run = self.ask_tell(x0).map_err(|error| Failure {
            error,
            result: None,
        })?;
        driver.run_objective(run, &self.objective)
    }
}
