//! `PlateauFreeGradient`: the Monte Carlo estimate of the Gaussian-smoothed gradient.

use std::any::Any;
use std::fmt;

mod evaluate;
mod steps;

use evaluate::{evaluate_parallel, evaluate_sequential, panic_message};
use steps::{accumulate, write_points, Spreads, Stream, Uniform};

use crate::ask_tell::NoObjective;
use crate::check;
use crate::error::Error;
use crate::kernel::chi_mean;
use crate::objective::{Objective, Points};
use crate::sampling::{Sampling, Scales};
use crate::seeding::{stream_seed, RESAMPLE_STREAM};

/// One gradient estimate.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Estimate {
    /// The estimated gradient of the smoothed objective, one entry per coordinate of theta.
    pub gradient: Vec<f64>,
    /// How many times `f` was evaluated.
    pub evaluations: usize,
    /// The mean of the evaluated values of `f` (at the perturbed points, not at theta): a
    /// noisy estimate of the smoothed objective itself.
    pub mean_value: f64,
    /// How many times the estimate's perturbations were redrawn because `f` returned a
    /// non-finite value ([`OnFailure::Resample`]); 0 otherwise.
    #[cfg_attr(feature = "serde", serde(default))]
    pub resampled: usize,
}

impl Estimate {
    /// An estimate that needed no redraws: for a [`GradientEstimator`] of your own, so that
    /// it keeps compiling when `Estimate` gains fields.
    ///
    /// ```
    /// let e = plateau::Estimate::new(vec![1.0, -2.0], 4, 0.5);
    /// assert_eq!((e.evaluations, e.resampled), (4, 0));
    /// ```
    #[must_use]
    pub fn new(gradient: Vec<f64>, evaluations: usize, mean_value: f64) -> Self {
        Estimate {
            gradient,
            evaluations,
            mean_value,
            resampled: 0,
        }
    }
}

/// What an estimate does when `f` returns NaN or an infinity.
///
/// ```
/// use plateau::{OnFailure, PlateauFreeGradient};
/// // NaN on a quarter of the line: the estimate redraws until every value is finite.
/// let f = |x: &[f64]| if x[0].fract().abs() < 0.25 { f64::NAN } else { x[0] };
/// let mut grad = PlateauFreeGradient::new(f).on_failure(OnFailure::Resample { limit: 50 });
/// let est = grad.estimate(&[0.5], 0.3)?;
/// assert!(est.gradient[0].is_finite());
/// assert_eq!(est.evaluations, 2 * (est.resampled + 1));
/// # Ok::<(), plateau::Error>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum OnFailure {
    /// Return [`Error::NonFiniteValue`], naming the evaluation, the value and the point
    /// (the default).
    #[default]
    Fail,
    /// Redraw every perturbation of the estimate (from streams derived from the seed, the
    /// estimate's index and the attempt, so still deterministic) and evaluate again, up to
    /// `limit` times; then fail as [`OnFailure::Fail`]. The whole set is redrawn, not only
    /// the failed pair, so that antithetic pairs and orthogonal blocks stay intact. The
    /// redraws are counted in [`Estimate::resampled`] and their evaluations in
    /// [`Estimate::evaluations`]. Note that the estimate then averages over the region where
    /// `f` is finite: it is the gradient of `f` restricted to that region.
    Resample {
        /// The largest number of redraws per estimate.
        limit: usize,
    },
}

/// Anything that turns `(theta, sigma)` into a gradient [`Estimate`]: the plateau-free
/// estimator and the baselines in [`crate::baseline`]. The optimisation loop
/// ([`crate::Optimizer`]) accepts any of them.
pub trait GradientEstimator {
    /// Estimates the gradient at `theta` for the spread `sigma`.
    fn estimate(&mut self, theta: &[f64], sigma: f64) -> Result<Estimate, Error>;

    /// Where the estimator's random streams stand: the number of estimates drawn so far, or
    /// `None` for an estimator without seeded streams (the default). A saved
    /// [`crate::OptimizerState`] records it so that a resumed run draws what the
    /// uninterrupted run would have drawn.
    fn stream_position(&self) -> Option<u64> {
        None
    }

    /// Moves the random streams to `position` (the next estimate is estimate `position`).
    /// The default does nothing, matching a `stream_position` of `None`.
    fn set_stream_position(&mut self, position: u64) {
        let _ = position;
    }
}

/// Evaluates the objective at the points; with `catch`, a panic of `f` is caught and
/// returned as its payload.
type Evaluator<F> = fn(&F, Points<'_>, &[u64], &mut [f64], bool) -> Result<(), Panic>;

/// A caught panic's payload.
type Panic = Box<dyn Any + Send>;

/// The plateau-free gradient of an objective `f`: the gradient of `f` smoothed by a
/// Gaussian of spread `sigma` in parameter space, estimated from `samples` evaluations of `f`.
///
/// Builder-style configuration; defaults: [`Sampling::Radial`], antithetic pairs, 2 samples,
/// seed 0, sequential evaluation. [`PlateauFreeGradient::validate`] reports a bad
/// configuration as soon as it is made; every estimate checks it too.
///
/// ```
/// use plateau::{PlateauFreeGradient, Sampling};
///
/// // A tilted step: zero gradient almost everywhere, yet the smoothed gradient points uphill.
/// let f = |x: &[f64]| if x[0] + 2.0 * x[1] > 0.3 { 1.0 } else { 0.0 };
/// let mut grad = PlateauFreeGradient::new(f).samples(8).sampling(Sampling::Radial).seed(7);
/// grad.validate()?;
/// let est = grad.estimate(&[0.1, -0.2], 0.5)?;
/// assert_eq!(est.gradient.len(), 2);
/// assert_eq!(est.evaluations, 8);
/// # Ok::<(), plateau::Error>(())
/// ```
///
/// # Randomness and determinism
/// Estimate `e` (counted from 0 since construction or [`PlateauFreeGradient::reset`]) draws
/// its `k`-th perturbation from a generator seeded by `(seed, e, k)`, and hands the
/// objective the seed `(seed, e, k)` for both members of pair `k` (see [`crate::seeding`]).
/// The result is a function of the seed, the inputs and the estimate's index alone:
/// bit-for-bit the same sequentially, in parallel, and with any number of threads.
///
/// # When `f` fails
/// A NaN or infinite value is an [`Error::NonFiniteValue`] by default, or is redrawn with
/// [`OnFailure::Resample`] (see [`PlateauFreeGradient::on_failure`]).
///
/// A panic is not caught by default: it unwinds out of [`PlateauFreeGradient::estimate`]
/// (through rayon's worker when evaluating in parallel, which re-raises it on the caller's
/// thread). With [`PlateauFreeGradient::catch_panics`] it is returned as
/// [`Error::ObjectivePanicked`] instead (the panic hook still prints its message; in
/// parallel, points not yet started are skipped once one has panicked). Either way the
/// estimator stays usable afterwards; the estimate that panicked is lost but still counted,
/// so later estimates draw fresh perturbations.
pub struct PlateauFreeGradient<F> {
    objective: F,
    core: Core,
    evaluator: Evaluator<F>,
}

/// The estimator without its objective: the configuration, the count of estimates and the
/// scratch space. An estimate is [`Core::start`], then per attempt [`Core::draw`] (the points
/// and their seeds), the values written by whoever evaluates them, and [`Core::finish`]: the
/// callback form ([`PlateauFreeGradient::estimate`]) and the ask-and-tell form
/// ([`crate::PaperAskTell`]) are the same calls in the same order.
pub(crate) struct Core {
    settings: Settings,
    estimates: u64,
    buffers: Buffers,
}

/// An estimate between [`Core::start`] and [`Core::finish`].
#[derive(Debug)]
pub(crate) struct Pending {
    /// The estimate's index (its random streams).
    pub(crate) index: u64,
    /// Redraws so far ([`OnFailure::Resample`]); the attempt that [`Core::draw`] makes.
    resampled: usize,
    /// Draw 0 of the current attempt, the memory of the gradient to come.
    first: Vec<f64>,
    /// Whether theta's finiteness was checked by the caller.
    theta_checked: bool,
    /// Theta's dimension.
    n: usize,
}

impl Pending {
    /// Whether the attempt's draws are still there to finish (a failed finish may leave
    /// them, a finished estimate has used them).
    pub(crate) fn is_drawn(&self) -> bool {
        !self.first.is_empty()
    }
}

/// The configuration that the builder methods set.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Settings {
    samples: usize,
    sampling: Sampling,
    antithetic: bool,
    orthogonal: bool,
    seed: u64,
    parallel: bool,
    on_failure: OnFailure,
    catch_panics: bool,
}

impl Settings {
    /// Every rule a configuration must satisfy, whatever theta and sigma will be.
    #[inline]
    fn validate(&self) -> Result<(), Error> {
        if self.samples == 0 {
            return Err(Error::ZeroSamples);
        }
        if self.antithetic && self.samples % 2 == 1 {
            return Err(Error::OddSamples(self.samples));
        }
        if self.orthogonal && self.sampling == Sampling::PerCoordinate {
            return Err(Error::OrthogonalUnsupported(self.sampling));
        }
        Ok(())
    }

    /// Evaluations of `f` per draw: 2 with antithetic pairs, else 1.
    #[inline]
    fn per_draw(&self) -> usize {
        if self.antithetic {
            2
        } else {
            1
        }
    }

    /// Perturbations drawn per estimate.
    #[inline]
    fn draws(&self) -> usize {
        self.samples / self.per_draw()
    }
}

/// Scratch space reused across estimates so that the hot path does not allocate (except the
/// gradient it returns).
#[derive(Default)]
struct Buffers {
    /// Draws 1, 2, ... in compact form, rows of length `n` (see `Sampling::draw_raw`); draw
    /// 0 is held by the gradient's vector until the gradient overwrites it.
    raw: Vec<f64>,
    /// Every draw of an orthogonal block, before it is split like the independent draws.
    block: Vec<f64>,
    /// Per-coordinate weights of every draw, for the samplers that write them.
    weights: Vec<f64>,
    /// How each row of `raw` expands into an offset and a weight.
    scales: Vec<Scales>,
    points: Vec<f64>,
    seeds: Vec<u64>,
    values: Vec<f64>,
    diffs: Vec<f64>,
    /// `(n, c_n)` of the last estimate: two log-gammas per estimate are a noticeable share
    /// of the cost when `n` is small.
    chi_mean: Option<(usize, f64)>,
}

impl Buffers {
    /// Sizes every buffer for `draws` draws of dimension `n` and `evaluations` points
    /// (a no-op once the sizes repeat).
    #[inline]
    fn resize(&mut self, draws: usize, evaluations: usize, n: usize) {
        self.raw.resize((draws - 1) * n, 0.0);
        self.weights.resize(draws * n, 0.0);
        self.scales.resize(draws, Scales::default());
        self.points.resize(evaluations * n, 0.0);
        self.seeds.resize(evaluations, 0);
        self.values.resize(evaluations, 0.0);
        self.diffs.resize(draws, 0.0);
    }

    /// `c_n`, recomputed only when the dimension changes.
    #[inline]
    fn chi_mean(&mut self, n: usize) -> f64 {
        match self.chi_mean {
            Some((dim, c)) if dim == n => c,
            _ => {
                let c = chi_mean(n);
                self.chi_mean = Some((n, c));
                c
            }
        }
    }
}

impl<F> fmt::Debug for PlateauFreeGradient<F> {
    /// The configuration and the count of estimates; the objective by its type's name
    /// (closures have no `Debug`).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = &self.core.settings;
        f.debug_struct("PlateauFreeGradient")
            .field("objective", &std::any::type_name::<F>())
            .field("samples", &s.samples)
            .field("sampling", &s.sampling)
            .field("antithetic", &s.antithetic)
            .field("orthogonal", &s.orthogonal)
            .field("seed", &s.seed)
            .field("parallel", &s.parallel)
            .field("on_failure", &s.on_failure)
            .field("catch_panics", &s.catch_panics)
            .field("estimates", &self.core.estimates)
            .finish_non_exhaustive()
    }
}

impl fmt::Debug for Core {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Core")
            .field("settings", &self.settings)
            .field("estimates", &self.estimates)
            .finish_non_exhaustive()
    }
}

impl Default for Core {
    /// The defaults of [`PlateauFreeGradient::new`].
    fn default() -> Self {
        Core {
            settings: Settings {
                samples: 2,
                sampling: Sampling::Radial,
                antithetic: true,
                orthogonal: false,
                seed: 0,
                parallel: false,
                on_failure: OnFailure::Fail,
                catch_panics: false,
            },
            estimates: 0,
            buffers: Buffers::default(),
        }
    }
}

impl<F: Objective> PlateauFreeGradient<F> {
    /// The estimator for `objective`: any `Fn(&[f64]) -> f64`, a [`crate::Seeded`] or
    /// [`crate::Batch`] closure, or your own [`Objective`].
    #[must_use]
    pub fn new(objective: F) -> Self {
        PlateauFreeGradient {
            objective,
            core: Core::default(),
            evaluator: evaluate_sequential::<F>,
        }
    }
}

impl PlateauFreeGradient<NoObjective> {
    /// The estimator's configuration alone, for a run whose points are evaluated elsewhere
    /// ([`crate::Optimizer::ask_tell`]): it has the builder methods but no `estimate`.
    ///
    /// ```
    /// use plateau::{Adam, Annealer, Optimizer, PlateauFreeGradient};
    /// let grad = PlateauFreeGradient::without_objective().samples(4).seed(1);
    /// let opt = Optimizer::new(Adam::new(0.1)?, Annealer::constant(0.3, 10)?);
    /// let run = opt.ask_tell(grad, &[1.0, 2.0])?;
    /// assert_eq!(run.iteration(), 0);
    /// # Ok::<(), plateau::Error>(())
    /// ```
    #[must_use]
    pub fn without_objective() -> Self {
        PlateauFreeGradient {
            objective: NoObjective,
            core: Core::default(),
            // Never called (`estimate` needs an `Objective`), and harmless if it were.
            evaluator: |_, _, _, out, _| {
                out.fill(f64::NAN);
                Ok(())
            },
        }
    }
}

impl<F> PlateauFreeGradient<F> {
    /// The configuration, the stream position and the scratch space, without the objective.
    pub(crate) fn into_core(self) -> Core {
        self.core
    }

    /// `N`, the number of evaluations of `f` per estimate (the paper's "number of
    /// samples"). With antithetic pairs it must be even: `N / 2` pairs.
    #[must_use]
    pub fn samples(mut self, samples: usize) -> Self {
        self.core.settings.samples = samples;
        self
    }

    /// The sampler of perturbations.
    #[must_use]
    pub fn sampling(mut self, sampling: Sampling) -> Self {
        self.core.settings.sampling = sampling;
        self
    }

    /// Whether every perturbation `tau` is paired with `-tau` (default: yes). The pair's
    /// difference cancels the even part of `f`, including its constant offset.
    #[must_use]
    pub fn antithetic(mut self, antithetic: bool) -> Self {
        self.core.settings.antithetic = antithetic;
        self
    }

    /// Whether the directions within one estimate are drawn mutually orthogonal (for
    /// [`Sampling::Radial`] and [`Sampling::Gaussian`]; in blocks of `n` when there are more
    /// draws than dimensions). Still unbiased; lower variance when several draws share an
    /// estimate (see `docs/estimators.md`). Default: off.
    #[must_use]
    pub fn orthogonal(mut self, orthogonal: bool) -> Self {
        self.core.settings.orthogonal = orthogonal;
        self
    }

    /// The seed of every random choice the estimator makes, and of the seeds it hands to
    /// the objective.
    #[must_use]
    pub fn seed(mut self, seed: u64) -> Self {
        self.core.settings.seed = seed;
        self
    }

    /// What an estimate does when `f` returns NaN or an infinity (default:
    /// [`OnFailure::Fail`]).
    #[must_use]
    pub fn on_failure(mut self, policy: OnFailure) -> Self {
        self.core.settings.on_failure = policy;
        self
    }

    /// Whether a panic inside `f` is caught and returned as [`Error::ObjectivePanicked`]
    /// (default: off, the panic unwinds through the caller). In an [`crate::Optimizer`] run
    /// the error comes with the state of the last good iteration ([`crate::RunError`]).
    ///
    /// ```
    /// use plateau::{Error, PlateauFreeGradient};
    /// let f = |x: &[f64]| if x[0] > 10.0 { panic!("renderer crashed") } else { x[0] };
    /// let mut grad = PlateauFreeGradient::new(f).catch_panics(true);
    /// # std::panic::set_hook(Box::new(|_| {})); // keep the doctest's output clean
    /// match grad.estimate(&[100.0], 0.1) {
    ///     Err(Error::ObjectivePanicked { message, .. }) => assert_eq!(message, "renderer crashed"),
    ///     other => panic!("{other:?}"),
    /// }
    /// assert!(grad.estimate(&[0.0], 0.1).is_ok()); // still usable
    /// ```
    #[must_use]
    pub fn catch_panics(mut self, catch: bool) -> Self {
        self.core.settings.catch_panics = catch;
        self
    }

    /// Checks the configuration: the rules that do not depend on theta or sigma. Call it
    /// right after building to report a bad configuration where it is made; every estimate
    /// checks the same rules first.
    ///
    /// ```
    /// use plateau::{Error, PlateauFreeGradient};
    /// let f = |x: &[f64]| x[0];
    /// assert_eq!(PlateauFreeGradient::new(f).samples(3).validate(), Err(Error::OddSamples(3)));
    /// assert!(PlateauFreeGradient::new(f).samples(3).antithetic(false).validate().is_ok());
    /// ```
    ///
    /// # Errors
    /// Zero samples ([`Error::ZeroSamples`]); an odd sample count with antithetic pairs
    /// ([`Error::OddSamples`]); orthogonal directions with the per-coordinate sampler
    /// ([`Error::OrthogonalUnsupported`]).
    pub fn validate(&self) -> Result<(), Error> {
        self.core.settings.validate()
    }

    /// Restarts the count of estimates: the next estimate repeats the first one's draws.
    pub fn reset(&mut self) {
        self.core.estimates = 0;
    }

    /// The objective.
    pub fn objective(&self) -> &F {
        &self.objective
    }

    /// The number of estimates made since construction or the last reset.
    pub fn estimates_made(&self) -> u64 {
        self.core.estimates
    }
}

impl<F: Objective> PlateauFreeGradient<F> {
    /// Estimates the gradient of `f` smoothed by `N(0, sigma^2 I)` at `theta`.
    ///
    /// # Errors
    /// Empty or non-finite `theta`; `sigma` not finite and positive; a configuration that
    /// [`PlateauFreeGradient::validate`] rejects; a perturbed point that overflows; `f`
    /// returning NaN or an infinity (the error names the evaluation and the point); a
    /// gradient too large to represent.
    pub fn estimate(&mut self, theta: &[f64], sigma: f64) -> Result<Estimate, Error> {
        check::sigma(sigma)?;
        self.estimate_checked(theta, Uniform(sigma), false)
    }

    /// Estimates the gradient of `f` smoothed by `N(0, diag(spreads)^2)` at `theta`: one
    /// spread per coordinate, for parameters of different scales.
    ///
    /// # Errors
    /// As [`PlateauFreeGradient::estimate`], and `spreads` of the wrong length.
    pub fn estimate_with_spreads(
        &mut self,
        theta: &[f64],
        spreads: &[f64],
    ) -> Result<Estimate, Error> {
        check::theta(theta)?;
        check::spreads(spreads, theta.len())?;
        self.estimate_checked(theta, spreads, true)
    }

    /// The estimate proper, for valid spreads. Theta's finiteness is checked here unless
    /// `theta_checked`: a non-finite coordinate makes its perturbed points non-finite, so the
    /// check rides on the points' check instead of costing a pass of its own.
    fn estimate_checked<S: Spreads>(
        &mut self,
        theta: &[f64],
        spreads: S,
        theta_checked: bool,
    ) -> Result<Estimate, Error> {
        let mut pending = self.core.start(theta, theta_checked)?;
        loop {
            self.core.draw(theta, spreads, &mut pending)?;
            let b = &mut self.core.buffers;
            let evaluated = (self.evaluator)(
                &self.objective,
                Points::new(&b.points, theta.len()),
                &b.seeds,
                &mut b.values,
                self.core.settings.catch_panics,
            );
            if let Err(payload) = evaluated {
                return Err(Error::ObjectivePanicked {
                    estimate: pending.index,
                    message: panic_message(payload.as_ref()),
                });
            }
            if let Some(estimate) = self.core.finish(spreads, &mut pending)? {
                return Ok(estimate);
            }
        }
    }
}

impl Core {
    /// The configuration's rules ([`PlateauFreeGradient::validate`]).
    pub(crate) fn validate(&self) -> Result<(), Error> {
        self.settings.validate()
    }

    /// The index of the next estimate.
    pub(crate) fn position(&self) -> u64 {
        self.estimates
    }

    /// Moves the streams: the next estimate is estimate `position`.
    pub(crate) fn set_position(&mut self, position: u64) {
        self.estimates = position;
    }

    /// Starts an estimate at `theta`: checks what does not depend on the draws and sizes
    /// the buffers. Nothing is counted yet.
    pub(crate) fn start(&mut self, theta: &[f64], theta_checked: bool) -> Result<Pending, Error> {
        if theta.is_empty() {
            return Err(Error::EmptyTheta);
        }
        let settings = self.settings;
        settings.validate()?;
        self.buffers
            .resize(settings.draws(), settings.samples, theta.len());
        Ok(Pending {
            index: self.estimates,
            resampled: 0,
            first: Vec::new(),
            theta_checked,
            n: theta.len(),
        })
    }

    /// Draws the pending attempt's perturbations and writes its points and their seeds
    /// ([`Core::points`], [`Core::seeds`]). The estimate counts as made from here: one whose
    /// `f` fails or panics is still spent, so later estimates draw fresh perturbations.
    fn draw<S: Spreads>(
        &mut self,
        theta: &[f64],
        spreads: S,
        pending: &mut Pending,
    ) -> Result<(), Error> {
        let settings = self.settings;
        let n = theta.len();
        let index = pending.index;
        let b = &mut self.buffers;
        let c_n = b.chi_mean(n);
        // Attempt 0 is the estimate as it always was; a redraw takes streams derived from
        // the seed, the index and the attempt: deterministic, and the same on any thread.
        let seed = if pending.resampled == 0 {
            settings.seed
        } else {
            stream_seed(
                settings.seed,
                index,
                RESAMPLE_STREAM ^ pending.resampled as u64,
            )
        };
        let stream = Stream { seed, index };
        // The first draw lives in the memory of the gradient that will be returned: the
        // estimate has to write that memory anyway, and one vector less is touched.
        pending.first = stream.draw(&settings, c_n, n, b);
        if let Err(point_error) = write_points(&settings, theta, spreads, &mut pending.first, b) {
            if !pending.theta_checked && pending.resampled == 0 {
                // Bad input is reported as such and does not consume an estimate.
                check::theta(theta)?;
            }
            self.estimates = index + 1;
            return Err(point_error);
        }
        stream.objective_seeds(&settings, &mut b.seeds);
        // Counted before `f` runs: an estimate whose `f` panics is still spent.
        self.estimates = index + 1;
        Ok(())
    }

    /// [`Core::draw`] for one spread `sigma` (checked by the caller) in every coordinate.
    pub(crate) fn draw_uniform(
        &mut self,
        theta: &[f64],
        sigma: f64,
        pending: &mut Pending,
    ) -> Result<(), Error> {
        self.draw(theta, Uniform(sigma), pending)
    }

    /// [`Core::finish`] for one spread `sigma` in every coordinate.
    pub(crate) fn finish_uniform(
        &mut self,
        sigma: f64,
        pending: &mut Pending,
    ) -> Result<Option<Estimate>, Error> {
        self.finish(Uniform(sigma), pending)
    }

    /// The points of the drawn attempt, rows of theta's dimension `n`.
    pub(crate) fn points(&self, n: usize) -> Points<'_> {
        Points::new(&self.buffers.points, n)
    }

    /// The objective's seed of every point of the drawn attempt.
    pub(crate) fn seeds(&self) -> &[u64] {
        &self.buffers.seeds
    }

    /// Where the values of the drawn attempt's points go, in the points' order.
    pub(crate) fn values_mut(&mut self) -> &mut [f64] {
        &mut self.buffers.values
    }

    /// Finishes the attempt from its values: the estimate, or `None` when a non-finite value
    /// calls for a redraw ([`OnFailure::Resample`]; the next [`Core::draw`] makes it).
    ///
    /// # Errors
    /// A non-finite value beyond the policy's redraws ([`Error::NonFiniteValue`]): then the
    /// attempt is untouched and may be finished again with other values. An overflowing
    /// gradient ([`Error::NonFiniteGradient`]): the attempt is used up.
    fn finish<S: Spreads>(
        &mut self,
        spreads: S,
        pending: &mut Pending,
    ) -> Result<Option<Estimate>, Error> {
        let settings = self.settings;
        let b = &mut self.buffers;
        let n = pending.n;
        if let Err(e) = check::values(&b.values, &b.points, n) {
            return match settings.on_failure {
                OnFailure::Resample { limit } if pending.resampled < limit => {
                    pending.resampled += 1;
                    Ok(None)
                }
                _ => Err(e),
            };
        }
        let gradient = accumulate(&settings, spreads, std::mem::take(&mut pending.first), b)?;
        let mean_value = mean(&b.values);
        Ok(Some(Estimate {
            gradient,
            evaluations: settings.samples * (pending.resampled + 1),
            mean_value,
            resampled: pending.resampled,
        }))
    }
}

/// The mean of finite values, itself always finite. Summing the shares `v / N` is the
/// usual form (and gives the usual bits); for values near `+-f64::MAX` the sum of the shares
/// can round past the largest finite number, and in units of the largest value it cannot.
pub(crate) fn mean(values: &[f64]) -> f64 {
    let n = values.len() as f64;
    let plain: f64 = values.iter().map(|v| v / n).sum();
    if plain.is_finite() {
        return plain;
    }
    let scale = values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    values.iter().map(|v| v / scale).sum::<f64>() / n * scale
}

impl<F: Objective + Sync> PlateauFreeGradient<F> {
    /// Whether the `N` evaluations of one estimate run in parallel on rayon's thread pool
    /// (default: off, since a renderer usually parallelises within one evaluation already).
    /// Results are bit-for-bit those of the sequential run. A [`crate::Batch`] objective is
    /// then called once per point; leave this off for batch objectives.
    #[must_use]
    pub fn parallel(mut self, parallel: bool) -> Self {
        self.core.settings.parallel = parallel;
        self.evaluator = if parallel {
            evaluate_parallel::<F>
        } else {
            evaluate_sequential::<F>
        };
        self
    }
}

impl<F: Objective> GradientEstimator for PlateauFreeGradient<F> {
    fn estimate(&mut self, theta: &[f64], sigma: f64) -> Result<Estimate, Error> {
        PlateauFreeGradient::estimate(self, theta, sigma)
    }

    fn stream_position(&self) -> Option<u64> {
        Some(self.core.estimates)
    }

    fn set_stream_position(&mut self, position: u64) {
        self.core.estimates = position;
    }
}
