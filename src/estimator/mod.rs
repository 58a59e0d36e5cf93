//! The estimator of the Gaussian-smoothed gradient: [`PlateauFreeGradient`], the
//! plateau-free estimate for any [`crate::Objective`]; the [`Estimate`] it returns; what an
//! estimate does when `f` fails ([`OnFailure`]); and [`GradientEstimator`], the interface the
//! paper's loop drives (the baselines of [`crate::baseline`] implement it too).

// This file holds what the estimator's parts share: the public types above and the
// estimator's state (`Core`: its settings and scratch space). `gradient.rs` is the public
// builder and callback form, `engine.rs` the steps of one estimate, `steps.rs` the
// arithmetic of those steps, `evaluate.rs` the calls of `f`.

use std::any::Any;

mod engine;
mod evaluate;
mod gradient;
mod steps;

pub(crate) use engine::mean;
pub use gradient::PlateauFreeGradient;

use crate::error::Error;
use crate::kernel::chi_mean;
use crate::sampling::{Sampling, Scales};

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
    #[cfg_attr(feature = "serde", serde(with = "crate::saved::float"))]
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
    /// let e = plateau_free::Estimate::new(vec![1.0, -2.0], 4, 0.5);
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
/// use plateau_free::{estimator::OnFailure, PlateauFreeGradient};
/// // NaN on a quarter of the line: the estimate redraws until every value is finite.
/// let f = |x: &[f64]| if x[0].fract().abs() < 0.25 { f64::NAN } else { x[0] };
/// let mut grad = PlateauFreeGradient::new(f).on_failure(OnFailure::Resample { limit: 50 });
/// let est = grad.estimate(&[0.5], 0.3)?;
/// assert!(est.gradient[0].is_finite());
/// assert_eq!(est.evaluations, 2 * (est.resampled + 1));
/// # Ok::<(), plateau_free::Error>(())
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
    /// [`crate::run::OptimizerState`] records it so that a resumed run draws what the
    /// uninterrupted run would have drawn.
    fn stream_position(&self) -> Option<u64> {
        None
    }

    /// Moves the random streams to `position` (the next estimate is estimate `position`).
    /// The default does nothing, matching a `stream_position` of `None`.
    fn set_stream_position(&mut self, position: u64) {
        let _ = position;
    }

    /// Keeps every point the estimator evaluates inside the box `[lower[i], upper[i]]` from
    /// now on: the estimators of this crate clamp each coordinate of every perturbed point
    /// onto the box (see `docs/design.md`, "Bounds"), so that the estimate is the gradient
    /// of `f` composed with the projection, and `f` is never called outside.
    ///
    /// [`crate::Optimizer`] calls it with [`crate::Adam`]'s bounds when a run starts (before
    /// anything is evaluated), and leaves them set; without bounds on Adam it does not call
    /// it. The default refuses with [`Error::BoundsUnsupported`]: an estimator of your own
    /// that does not override it cannot keep the promise that `f` is only called inside the
    /// box, so a run with bounds refuses to start rather than break it.
    ///
    /// ```
    /// use plateau_free::{Adam, Annealer, Error, Estimate, GradientEstimator, Optimizer};
    ///
    /// // An estimator of your own that ignores bounds.
    /// struct Zero;
    /// impl GradientEstimator for Zero {
    ///     fn estimate(&mut self, theta: &[f64], _sigma: f64) -> Result<Estimate, Error> {
    ///         Ok(Estimate::new(vec![0.0; theta.len()], 0, 0.0))
    ///     }
    /// }
    /// let adam = Adam::new(0.1)?.bounds(vec![0.0], vec![1.0])?;
    /// let mut opt = Optimizer::new(adam, Annealer::constant(0.1, 5)?);
    /// assert!(matches!(opt.minimize(&mut Zero, &[0.5]), Err(Error::BoundsUnsupported { .. })));
    /// # Ok::<(), plateau_free::Error>(())
    /// ```
    ///
    /// # Errors
    /// [`Error::BoundsUnsupported`] (the default); bounds that are not a box
    /// ([`Error::InvalidBounds`], [`Error::LengthMismatch`]).
    fn set_bounds(&mut self, lower: &[f64], upper: &[f64]) -> Result<(), Error> {
        let _ = (lower, upper);
        Err(Error::BoundsUnsupported {
            estimator: std::any::type_name::<Self>(),
        })
    }
}

/// A box `[lower[i], upper[i]]` that the estimators keep their points in.
#[derive(Debug, Clone, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub(crate) struct Bounds {
    #[cfg_attr(feature = "serde", serde(with = "crate::saved::floats"))]
    pub(crate) lower: Vec<f64>,
    #[cfg_attr(feature = "serde", serde(with = "crate::saved::floats"))]
    pub(crate) upper: Vec<f64>,
}

impl Bounds {
    /// The box, checked (equal lengths, no NaN, `lower <= upper`; infinite sides allowed).
    pub(crate) fn new(lower: &[f64], upper: &[f64]) -> Result<Bounds, Error> {
        crate::check::bounds(lower, upper)?;
        Ok(Bounds {
            lower: lower.to_vec(),
            upper: upper.to_vec(),
        })
    }

    /// Clamps every row of `points` (rows of `n` = the box's dimension) onto the box.
    #[inline]
    pub(crate) fn project(&self, points: &mut [f64]) {
        crate::check::project(points, &self.lower, &self.upper);
    }

    /// The box's dimension against theta's.
    pub(crate) fn check_dim(&self, n: usize) -> Result<(), Error> {
        crate::check::len("bounds", self.lower.len(), n)
    }
}

/// A caught panic's payload.
type Panic = Box<dyn Any + Send>;

/// The estimator without its objective: the configuration, the count of estimates and the
/// scratch space. An estimate is [`Core::start`], then per attempt [`Core::draw`] (the points
/// and their seeds), the values written by whoever evaluates them, and [`Core::finish`]: the
/// callback form ([`PlateauFreeGradient::estimate`]) and the ask-and-tell form
/// ([`crate::PaperAskTell`]) are the same calls in the same order.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub(crate) struct Core {
    settings: Settings,
    /// The box every evaluated point is clamped onto, if any.
    bounds: Option<Bounds>,
    estimates: u64,
    buffers: Buffers,
}

/// An estimate between [`Core::start`] and [`Core::finish`].
#[derive(Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
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
    /// A read-back estimate in progress against theta's dimension `n`.
    #[cfg(feature = "serde")]
    pub(crate) fn check(&self, n: usize) -> Result<(), Error> {
        crate::check::len("pending estimate's dimension", self.n, n)?;
        if !self.first.is_empty() {
            crate::check::len("pending estimate's first draw", self.first.len(), n)?;
        }
        Ok(())
    }

    /// Whether the attempt's draws are still there to finish (a failed finish may leave
    /// them, a finished estimate has used them).
    pub(crate) fn is_drawn(&self) -> bool {
        !self.first.is_empty()
    }
}

/// The configuration that the builder methods set.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
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
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
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
    #[cfg_attr(feature = "serde", serde(with = "crate::saved::floats"))]
    points: Vec<f64>,
    seeds: Vec<u64>,
    #[cfg_attr(feature = "serde", serde(with = "crate::saved::floats"))]
    values: Vec<f64>,
    #[cfg_attr(feature = "serde", serde(with = "crate::saved::floats"))]
    diffs: Vec<f64>,
    /// `(n, c_n)` of the last estimate: two log-gammas per estimate are a noticeable share
    /// of the cost when `n` is small.
    chi_mean: Option<(usize, f64)>,
}

impl Buffers {
    /// Reserves what [`Buffers::resize`] will need, so that a number of samples too large
    /// for memory is an error rather than an abort of the process (a failed allocation in
    /// `resize` cannot be caught).
    fn try_reserve(&mut self, draws: usize, evaluations: usize, n: usize) -> Result<(), ()> {
        fn room<T>(v: &mut Vec<T>, rows: usize, n: usize) -> Result<(), ()> {
            let len = rows.checked_mul(n).ok_or(())?;
            v.try_reserve_exact(len.saturating_sub(v.len()))
                .map_err(|_| ())
        }
        room(&mut self.raw, draws, n)?;
        room(&mut self.weights, draws, n)?;
        room(&mut self.scales, draws, 1)?;
        room(&mut self.points, evaluations, n)?;
        room(&mut self.seeds, evaluations, 1)?;
        room(&mut self.values, evaluations, 1)?;
        room(&mut self.diffs, draws, 1)
    }

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
