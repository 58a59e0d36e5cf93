//! [`PlateauFreeGradient`]: the builder, and the estimate with the objective called in place.

use std::fmt;

use super::evaluate::{evaluate_parallel, evaluate_sequential, panic_message, Batch};
use super::steps::{Spreads, Uniform};
use super::{Core, Estimate, GradientEstimator, OnFailure, Panic};
use crate::check;
use crate::error::Error;
use crate::objective::{NoObjective, Objective, Points};
use crate::sampling::Sampling;

/// Evaluates the objective at the points; with `catch`, a panic of `f` is caught and
/// returned as its payload.
type Evaluator<F> = fn(&F, Batch<'_>, bool) -> Result<(), Panic>;

/// The plateau-free gradient of an objective `f`: the gradient of `f` smoothed by a
/// Gaussian of spread `sigma` in parameter space, estimated from `samples` evaluations of `f`.
///
/// Builder-style configuration; defaults: [`Sampling::Radial`], antithetic pairs, 2 samples,
/// seed 0, sequential evaluation. [`PlateauFreeGradient::validate`] reports a bad
/// configuration as soon as it is made; every estimate checks it too.
///
/// ```
/// use plateau_free::{PlateauFreeGradient, Sampling};
///
/// // A tilted step: zero gradient almost everywhere, yet the smoothed gradient points uphill.
/// let f = |x: &[f64]| if x[0] + 2.0 * x[1] > 0.3 { 1.0 } else { 0.0 };
/// let mut grad = PlateauFreeGradient::new(f).samples(8).sampling(Sampling::Radial).seed(7);
/// grad.validate()?;
/// let est = grad.estimate(&[0.1, -0.2], 0.5)?;
/// assert_eq!(est.gradient.len(), 2);
/// assert_eq!(est.evaluations, 8);
/// # Ok::<(), plateau_free::Error>(())
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
            .field("bounds", &self.core.bounds())
            .field("estimates", &self.core.estimates)
            .finish_non_exhaustive()
    }
}

impl<F: Objective> PlateauFreeGradient<F> {
    /// The estimator for `objective`: any `Fn(&[f64]) -> f64`, a [`crate::objective::Seeded`] or
    /// [`crate::objective::Batch`] closure, or your own [`Objective`].
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
    /// use plateau_free::{Adam, Annealer, Optimizer, PlateauFreeGradient};
    /// let grad = PlateauFreeGradient::without_objective().samples(4).seed(1);
    /// let opt = Optimizer::new(Adam::new(0.1)?, Annealer::constant(0.3, 10)?);
    /// let run = opt.ask_tell(grad, &[1.0, 2.0])?;
    /// assert_eq!(run.iteration(), 0);
    /// # Ok::<(), plateau_free::Error>(())
    /// ```
    #[must_use]
    pub fn without_objective() -> Self {
        PlateauFreeGradient {
            objective: NoObjective,
            core: Core::default(),
            // Never called (`estimate` needs an `Objective`), and harmless if it were.
            evaluator: |_, batch, _| {
                batch.out.fill(f64::NAN);
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

    setters! {
        /// `N`, the number of evaluations of `f` per estimate (the paper's "number of
        /// samples"). With antithetic pairs it must be even: `N / 2` pairs.
        samples(samples: usize) => core.settings.samples = samples;

        /// The sampler of perturbations.
        sampling(sampling: Sampling) => core.settings.sampling = sampling;

        /// Whether every perturbation `tau` is paired with `-tau` (default: yes). The pair's
        /// difference cancels the even part of `f`, including its constant offset.
        antithetic(antithetic: bool) => core.settings.antithetic = antithetic;

        /// Whether the directions within one estimate are drawn mutually orthogonal (for
        /// [`Sampling::Radial`] and [`Sampling::Gaussian`]; in blocks of `n` when there are more
        /// draws than dimensions). Still unbiased; lower variance when several draws share an
        /// estimate (see `docs/estimators.md`). Default: off.
        orthogonal(orthogonal: bool) => core.settings.orthogonal = orthogonal;

        /// The seed of every random choice the estimator makes, and of the seeds it hands to
        /// the objective.
        seed(seed: u64) => core.settings.seed = seed;

        /// What an estimate does when `f` returns NaN or an infinity (default:
        /// [`OnFailure::Fail`]).
        on_failure(policy: OnFailure) => core.settings.on_failure = policy;

        /// Whether a panic inside `f` is caught and returned as [`Error::ObjectivePanicked`]
        /// (default: off, the panic unwinds through the caller). In an [`crate::Optimizer`] run
        /// the error comes with the state of the last good iteration ([`crate::run::RunError`]).
        ///
        /// ```
        /// use plateau_free::{Error, PlateauFreeGradient};
        /// let f = |x: &[f64]| if x[0] > 10.0 { panic!("renderer crashed") } else { x[0] };
        /// let mut grad = PlateauFreeGradient::new(f).catch_panics(true);
        /// # std::panic::set_hook(Box::new(|_| {})); // keep the doctest's output clean
        /// match grad.estimate(&[100.0], 0.1) {
        ///     Err(Error::ObjectivePanicked { message, .. }) => assert_eq!(message, "renderer crashed"),
        ///     other => panic!("{other:?}"),
        /// }
        /// assert!(grad.estimate(&[0.0], 0.1).is_ok()); // still usable
        /// ```
        catch_panics(catch: bool) => core.settings.catch_panics = catch;
    }

    /// Keeps every evaluated point inside the box `[lower[i], upper[i]]` (infinite sides
    /// allowed): each coordinate of every perturbed point is clamped onto the box, so `f` is
    /// never called outside it. The weights are unchanged, so the estimate is the smoothed
    /// gradient of `f` composed with the projection (`f` extended outside the box by its
    /// value on the nearest face): unbiased for that function; near a face, the component
    /// normal to the face is damped, since the half of the kernel beyond it sees the face's
    /// values. See `docs/design.md`, "Bounds".
    ///
    /// [`crate::Optimizer`] sets [`crate::Adam`]'s bounds on the estimator when a run starts
    /// ([`GradientEstimator::set_bounds`]); set them here to estimate with a box outside a run.
    /// [`PlateauFreeGradient::validate`] checks the box, and every estimate checks that it
    /// has theta's dimension.
    ///
    /// ```
    /// use plateau_free::PlateauFreeGradient;
    /// use std::cell::Cell;
    ///
    /// let lowest = Cell::new(f64::INFINITY);
    /// let f = |x: &[f64]| { lowest.set(lowest.get().min(x[0])); x[0] };
    /// let mut grad = PlateauFreeGradient::new(f).samples(8).bounds(vec![0.0], vec![1.0]);
    /// grad.validate()?;
    /// let est = grad.estimate(&[0.0], 0.5)?; // at the face: half the kernel is outside
    /// assert_eq!(lowest.get(), 0.0);
    /// assert!(est.gradient[0] > 0.0);
    /// # Ok::<(), plateau_free::Error>(())
    /// ```
    #[must_use]
    pub fn bounds(mut self, lower: Vec<f64>, upper: Vec<f64>) -> Self {
        self.core
            .set_bounds_unchecked(super::Bounds { lower, upper });
        self
    }

    /// Checks the configuration: the rules that do not depend on theta or sigma. Call it
    /// right after building to report a bad configuration where it is made; every estimate
    /// checks the same rules first.
    ///
    /// ```
    /// use plateau_free::{Error, PlateauFreeGradient};
    /// let f = |x: &[f64]| x[0];
    /// assert_eq!(PlateauFreeGradient::new(f).samples(3).validate(), Err(Error::OddSamples(3)));
    /// assert!(PlateauFreeGradient::new(f).samples(3).antithetic(false).validate().is_ok());
    /// ```
    ///
    /// # Errors
    /// Zero samples ([`Error::ZeroSamples`]); an odd sample count with antithetic pairs
    /// ([`Error::OddSamples`]); orthogonal directions with the per-coordinate sampler
    /// ([`Error::OrthogonalUnsupported`]); bounds that are not a box
    /// ([`Error::InvalidBounds`], [`Error::LengthMismatch`]).
    pub fn validate(&self) -> Result<(), Error> {
        self.core.validate()
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

    /// The configured seed, for adapters that draw streams of their own from it.
    #[cfg(feature = "argmin")]
    pub(crate) fn seed_setting(&self) -> u64 {
        self.core.settings.seed
    }

    /// The box set by [`PlateauFreeGradient::bounds`], if any (not yet checked).
    #[cfg(feature = "argmin")]
    pub(crate) fn box_bounds(&self) -> Option<&super::Bounds> {
        self.core.bounds()
    }
}

impl<F: Objective> PlateauFreeGradient<F> {
    /// Estimates the gradient of `f` smoothed by `N(0, sigma^2 I)` at `theta`.
    ///
    /// # Errors
    /// Empty or non-finite `theta`; `sigma` not finite and positive; a configuration that
    /// [`PlateauFreeGradient::validate`] rejects; bounds of another dimension than theta
    /// ([`Error::LengthMismatch`]); a perturbed point that overflows; `f` returning NaN or an
    /// infinity (the error names the evaluation and the point); a gradient too large to
    /// represent.
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
            let batch = Batch {
                points: Points::new(&b.points, theta.len()),
                seeds: &b.seeds,
                out: &mut b.values,
            };
            let evaluated =
                (self.evaluator)(&self.objective, batch, self.core.settings.catch_panics);
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

impl<F: Objective + Sync> PlateauFreeGradient<F> {
    /// Whether the `N` evaluations of one estimate run in parallel on rayon's thread pool
    /// (default: off, since a renderer usually parallelises within one evaluation already).
    /// Results are bit-for-bit those of the sequential run. A [`crate::objective::Batch`] objective is
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

    fn set_bounds(&mut self, lower: &[f64], upper: &[f64]) -> Result<(), Error> {
        self.core.set_bounds(lower, upper)
    }
}
