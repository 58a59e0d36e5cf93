//! The options of a [`Minimizer`] run: the strategy, the metric, and the rest of the
//! builder's settings as one value ([`Options`]), which both the callback form
//! ([`Minimizer::run`]) and the ask-and-tell run ([`crate::AskTell`]) take.

use crate::check;
use crate::error::Error;
// For the documentation's links only.
#[cfg(doc)]
use crate::Minimizer;

/// The search method of a [`Minimizer`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Strategy {
    /// The default: a Gaussian search distribution with adaptive spread and metric, flat-step
    /// growth of the spread on plateaus, and restarts from `x0` (from the best point once a
    /// run has found it again) with a doubled population. Needs no step size or learning
    /// rate.
    Adaptive,
    /// The paper's loop: the plateau-free gradient ([`crate::PlateauFreeGradient`], radial
    /// sampler, antithetic pairs) with `samples` evaluations per estimate, [`crate::Adam`]
    /// with learning rate `lr`, and [`crate::Annealer::paper`] from `sigma0` over the
    /// iterations the budget allows (`(budget - 2) / samples`: the first evaluation is at the
    /// start, the last at the final parameters; a budget too small for an iteration
    /// evaluates the start alone). With bounds, every perturbed point is clamped onto the
    /// box and every step projected onto it. With [`Minimizer::target`], the loop ends after
    /// the estimate whose points reached it (no final evaluation, no polish).
    Paper {
        /// `N`, evaluations of `f` per gradient estimate (even).
        samples: usize,
        /// Adam's learning rate.
        lr: f64,
        /// The starting spread of the annealer.
        sigma0: f64,
    },
}

/// The metric (covariance) the search distribution learns.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Metric {
    /// The default: [`Metric::Full`] up to `n = 19`, [`Metric::Decoded`] from 20 to 200
    /// ([`DECODING_MIN_DIM`], [`FULL_METRIC_MAX_DIM`]), [`Metric::Diagonal`] above.
    #[default]
    Auto,
    /// A full covariance: learns rotated, ill-conditioned metrics; `O(n^2)` per evaluation
    /// and `O(n^3)` per eigendecomposition (every few iterations). Refused above
    /// [`FULL_METRIC_LIMIT`] dimensions.
    Full,
    /// A diagonal covariance: per-coordinate spreads only, `O(n)` per evaluation (separable
    /// CMA-ES, Ros and Hansen 2008: positive weights only, rates `(n + 2) / 3` times the full
    /// metric's). For large `n`; slow on rotated, ill-conditioned functions.
    Diagonal,
    /// The diagonal covariance times a limited memory of directions (LM-MA-ES's matrix
    /// adaptation, Loshchilov, Glasmachers and Beyer 2019): `4 + 3 ln n` evolution paths of
    /// the selected steps stretch the draws along the search's recent progress, learning
    /// rotated structure a diagonal cannot, in `O(n ln n)` memory and time per evaluation.
    /// The diagonal under them learns at the full metric's rates.
    LowRank,
    /// The full covariance decoded by a diagonal one learned much faster (dd-CMA-ES: Akimoto
    /// and Hansen, Evolutionary Computation 28(3), 2020): the covariance is `D C D`, `C` learned
    /// as [`Metric::Full`] learns its covariance (at the paper's rates) and `D` at rates of
    /// order `n^-0.75`, slowed while `C` is far from a multiple of the identity. Learns axis-parallel scales about as fast as
    /// [`Metric::Diagonal`] and rotated structure as [`Metric::Full`] does; costs as much as
    /// the full metric. Refused above [`FULL_METRIC_LIMIT`] dimensions.
    Decoded,
}

/// What a run does with an evaluation that failed: a NaN or infinite value (or, in the
/// bindings, an exception raised by `f`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum FailurePolicy {
    /// The run goes on (the default): a failed point ranks below every finite value, is
    /// counted in [`crate::Minimum::failures`] and is never the best point.
    #[default]
    Continue,
    /// The run ends with [`Error::NonFiniteValue`] naming the point.
    Raise,
}

/// The share of the budget that polishes [`Strategy::Paper`]'s loop when
/// [`crate::Minimizer::polish`] is not set: the adaptive search finishes the descent that
/// Adam's fixed learning rate leaves about `lr` from the optimum (`docs/convergence.md`,
/// "Renders to the paper's answer").
pub const DEFAULT_POLISH: f64 = 0.5;

/// The default [`crate::Minimizer::patience`]: the run is done when one restart converges
/// back at the best point seen before it.
pub const DEFAULT_PATIENCE: usize = 1;

/// The largest dimension for which [`Metric::Auto`] learns a full covariance.
pub const FULL_METRIC_MAX_DIM: usize = 200;

/// The smallest dimension at which [`Metric::Auto`] decodes its full covariance by a diagonal
/// one ([`Metric::Decoded`]). On COCO's bbob-mixint the decoding wins at n = 20 and 40 with
/// and without the integers declared, and on bbob with the box at n = 20 (the step ellipsoid
/// most); at n = 5 and 10 it loses a little, where scales learned fast narrow the search onto
/// a step or into a basin, and at n = 20 without a box Rosenbrock ends in its local minimum
/// more often. From about n = 40 on the plain full metric cannot learn an axis-parallel
/// ellipsoid of condition 1e6 within `1000 n` evaluations (docs/convergence.md, table 5b).
pub const DECODING_MIN_DIM: usize = 20;

/// The largest dimension [`Metric::Full`] accepts. The full metric keeps `n x n` matrices
/// (the covariance and its eigenvectors: 1.6 GB at this size) and decomposes one every few
/// iterations (about `n^3` = 10^12 operations here); above it a run would abort on the
/// allocation or never finish a generation, so it is refused with an error instead.
pub const FULL_METRIC_LIMIT: usize = 10_000;

/// A [`Minimizer`]'s options: everything but the objective, which is all an ask-and-tell
/// run needs.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub(crate) struct Options {
    pub(crate) budget: Option<usize>,
    pub(crate) seed: u64,
    pub(crate) sigma0: Option<f64>,
    /// [`crate::Minimizer::sigma0_each`].
    #[cfg_attr(feature = "serde", serde(default))]
    pub(crate) sigma0_each: Option<Vec<f64>>,
    #[cfg_attr(feature = "serde", serde(with = "crate::saved::float_box"))]
    pub(crate) bounds: Option<(Vec<f64>, Vec<f64>)>,
    #[cfg_attr(feature = "serde", serde(with = "crate::saved::float_option"))]
    pub(crate) target: Option<f64>,
    pub(crate) population: Option<usize>,
    pub(crate) restarts: bool,
    pub(crate) mirrored: bool,
    pub(crate) flat_growth: bool,
    pub(crate) metric: Metric,
    pub(crate) restart_from_best: bool,
    pub(crate) strategy: Strategy,
    /// [`crate::Minimizer::polish`] as set (`None`: [`DEFAULT_POLISH`] with
    /// [`Strategy::Paper`], none with [`Strategy::Adaptive`]).
    pub(crate) polish: Option<f64>,
    /// [`crate::Minimizer::stop_when_stalled`]'s window, a fraction of the budget (`None`:
    /// the budget alone ends the run).
    #[cfg_attr(feature = "serde", serde(default, with = "crate::saved::float_option"))]
    pub(crate) stall: Option<f64>,
    /// [`crate::Minimizer::on_failure`].
    #[cfg_attr(feature = "serde", serde(default))]
    pub(crate) on_failure: FailurePolicy,
    /// [`crate::Minimizer::patience`] (0: off).
    #[cfg_attr(feature = "serde", serde(default))]
    pub(crate) patience: usize,
    /// [`crate::Minimizer::steps`]: a step per coordinate, 0 continuous.
    #[cfg_attr(feature = "serde", serde(default))]
    pub(crate) steps: Option<Vec<f64>>,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            budget: None,
            seed: 0,
            sigma0: None,
            bounds: None,
            target: None,
            population: None,
            restarts: true,
            mirrored: true,
            flat_growth: true,
            metric: Metric::Auto,
            restart_from_best: false,
            strategy: Strategy::Adaptive,
            polish: None,
            stall: None,
            on_failure: FailurePolicy::default(),
            patience: DEFAULT_PATIENCE,
            sigma0_each: None,
            steps: None,
        }
    }
}

impl Options {
    /// The share of the budget that polishes the paper's loop: as set, else
    /// [`DEFAULT_POLISH`] with [`Strategy::Paper`] and none with [`Strategy::Adaptive`].
    pub(crate) fn polish(&self) -> f64 {
        match (self.polish, self.strategy) {
            (Some(fraction), _) => fraction,
            (None, Strategy::Paper { .. }) => DEFAULT_POLISH,
            (None, Strategy::Adaptive) => 0.0,
        }
    }

    /// `x` rounded onto the grid of [`crate::Minimizer::steps`] inside the bounds (as is
    /// without steps).
    pub(crate) fn snap(&self, x: &mut [f64]) {
        if let Some(steps) = &self.steps {
            super::grid::snap(x, steps, self.bounds.as_ref());
        }
    }

    /// Checks the options and the start; returns the budget.
    pub(crate) fn check(&self, x0: &[f64]) -> Result<usize, Error> {
        check::theta(x0)?;
        let n = x0.len();
        let budget = self.budget.unwrap_or(1000 * n);
        if budget == 0 {
            return Err(Error::InvalidParameter {
                name: "budget",
                value: 0usize.into(),
                reason: "must be at least 1 evaluation",
            });
        }
        if let Some(s) = self.sigma0 {
            check::positive("sigma0", s)?;
        }
        if matches!(self.metric, Metric::Full | Metric::Decoded) && n > FULL_METRIC_LIMIT {
            return Err(Error::InvalidParameter {
                name: "dimension",
                value: n.into(),
                reason: "above 10000 is too large for Metric::Full and Metric::Decoded (they keep n x n matrices); use Metric::Diagonal or Metric::Auto",
            });
        }
        if let Some(t) = self.target {
            if t.is_nan() {
                return Err(Error::InvalidParameter {
                    name: "target",
                    value: t.into(),
                    reason: "must not be NaN",
                });
            }
        }
        if let Some(p) = self.population {
            if p < 2 {
                return Err(Error::InvalidParameter {
                    name: "population",
                    value: p.into(),
                    reason: "must be at least 2",
                });
            }
            // A generation's points are held at once: a population too large for memory is
            // an error here rather than a panic or an abort when the first generation is drawn.
            let fits = p
                .checked_mul(n)
                .is_some_and(|len| Vec::<f64>::new().try_reserve_exact(len).is_ok());
            if !fits {
                return Err(Error::InvalidParameter {
                    name: "population",
                    value: p.into(),
                    reason: "times the dimension is more memory than can be allocated",
                });
            }
        }
        if let Some((lo, hi)) = &self.bounds {
            // Infinite entries are open sides; NaN or crossed bounds are errors.
            check::len("lower bounds", lo.len(), n)?;
            check::len("upper bounds", hi.len(), n)?;
            check::bounds(lo, hi)?;
            check::inside("x0", x0, lo, hi)?;
        }
        if let Some(each) = &self.sigma0_each {
            check::len("sigma0_each", each.len(), n)?;
            if let Some(&s) = each.iter().find(|s| !(s.is_finite() && **s > 0.0)) {
                return Err(Error::InvalidParameter {
                    name: "sigma0_each",
                    value: s.into(),
                    reason: "must be finite and > 0 (every coordinate's spread)",
                });
            }
            if self.sigma0.is_some() {
                return Err(Error::InvalidParameter {
                    name: "sigma0_each",
                    value: each[0].into(),
                    reason: "and sigma0 both set the starting spread: set one",
                });
            }
        }
        if let Some(steps) = &self.steps {
            super::grid::check(steps, n, self.bounds.as_ref())?;
            if self.strategy != Strategy::Adaptive {
                return Err(Error::InvalidParameter {
                    name: "steps",
                    value: steps.len().into(),
                    reason: "(discrete coordinates) need Strategy::Adaptive: the paper's loop takes continuous steps",
                });
            }
        }
        self.check_polish()?;
        if let Some(fraction) = self.stall {
            super::check_fraction(fraction)?;
        }
        if let Strategy::Paper {
            samples,
            lr,
            sigma0,
        } = self.strategy
        {
            if samples == 0 {
                return Err(Error::ZeroSamples);
            }
            if samples % 2 == 1 {
                return Err(Error::OddSamples(samples));
            }
            check::positive("lr", lr)?;
            check::positive("sigma0", sigma0)?;
        }
        Ok(budget)
    }

    /// The polish as set: a fraction in `[0, 1)`, and only with [`Strategy::Paper`].
    fn check_polish(&self) -> Result<(), Error> {
        let Some(polish) = self.polish else {
            return Ok(());
        };
        if !(0.0..1.0).contains(&polish) {
            return Err(Error::InvalidParameter {
                name: "polish",
                value: polish.into(),
                reason: "must be a fraction of the budget in [0, 1): the share the adaptive search gets after the paper's loop",
            });
        }
        if polish > 0.0 && self.strategy == Strategy::Adaptive {
            return Err(Error::InvalidParameter {
                name: "polish",
                value: polish.into(),
                reason: "polishes the paper's loop: it needs Strategy::Paper",
            });
        }
        Ok(())
    }
}
