//! [argmin](https://argmin-rs.org)'s gradient-based solvers on plateau-ridden functions
//! (feature `argmin`; argmin 0.11 needs Rust 1.87, newer than this crate's `rust-version`).
//!
//! [`ArgminProblem`] wraps a [`PlateauFreeGradient`] as an argmin problem: its
//! [`Gradient`] is the estimator's estimate of the gradient of `f`
//! smoothed by a Gaussian ([`Spread`]: a fixed spread or an [`Annealer`]'s), and its
//! [`CostFunction`] is the smoothed `f` itself, estimated with
//! common random numbers ([`Cost`]), so that a line search sees the descent the gradient
//! promises even where `f` is flat. Parameters and gradients are `Vec<f64>` (argmin-math's
//! `vec` backend), so argmin's steepest descent, L-BFGS, BFGS or conjugate gradients take it
//! with no generics to spell out.
//!
//! ```
//! use argmin::core::{Executor, State};
//! use argmin::solver::gradientdescent::SteepestDescent;
//! use argmin::solver::linesearch::{condition::ArmijoCondition, BacktrackingLineSearch};
//! use plateau_free::argmin::{ArgminProblem, Spread};
//! use plateau_free::PlateauFreeGradient;
//!
//! // A step: every plain gradient is zero, at the start and everywhere else.
//! let step = |x: &[f64]| if x[0] + 2.0 * x[1] > 0.3 { 1.0 } else { 0.0 };
//! let problem = ArgminProblem::new(
//!     PlateauFreeGradient::new(step).samples(16).seed(1),
//!     Spread::Fixed(1.0),
//! )?;
//! let line_search = BacktrackingLineSearch::new(ArmijoCondition::new(1e-4)?);
//! let result = Executor::new(problem, SteepestDescent::new(line_search))
//!     .configure(|state| state.param(vec![1.0, 1.0]).max_iters(20))
//!     .run()?;
//! let x = result.state().get_best_param().unwrap();
//! assert_eq!(step(x), 0.0, "left the plateau: {x:?}");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # The spread and its annealing
//! With [`Spread::Annealed`], gradient call `k` (counted from 0 by the problem, across every
//! solver iteration and line-search step that asks for a gradient) uses the annealer's
//! `sigma(k)`: the annealing advances by one per gradient call, so give the [`Annealer`] the
//! number of gradient calls the run will make (one per iteration for steepest descent and
//! L-BFGS with a backtracking line search, which asks for no gradient at its trial points;
//! more with More-Thuente, which does). A cost call uses the spread of the latest gradient
//! call (`sigma(0)` before the first).
//!
//! # Randomness and determinism
//! Gradient call `k` is the estimator's estimate `k` (see [`PlateauFreeGradient`]): bit for
//! bit what `estimate(theta, sigma)` returns as that estimator's `k`-th estimate. The cost's
//! perturbations are drawn once from the estimator's seed (on a stream no estimate uses) and
//! reused at every point: a deterministic function of theta and sigma, so that argmin's
//! comparisons of costs compare `f`, not noise. Same seed, same run.

use std::fmt;
use std::sync::{Mutex, MutexGuard, PoisonError};

use ::argmin::core::{CostFunction, Error as ArgminError, Gradient};
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;

use crate::check;
use crate::error::{Error, ParameterValue};
use crate::objective::Objective;
use crate::seeding::stream_seed;
use crate::{Annealer, PlateauFreeGradient};

/// The state argmin's gradient-based solvers keep for an [`ArgminProblem`] (parameters and
/// gradients `Vec<f64>`, costs `f64`), for naming a run's type without its generics:
/// `OptimizationResult<ArgminProblem<F>, Solver, ArgminState>`.
pub type ArgminState = ::argmin::core::IterState<Vec<f64>, Vec<f64>, (), (), (), f64>;

/// The estimate index of the cost's stream in [`stream_seed`]: one that no estimate reaches.
const COST_STREAM: u64 = u64::MAX;

/// The spread of the Gaussian that smooths `f`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Spread {
    /// The same spread for every call.
    Fixed(f64),
    /// The annealer's `sigma(k)` for gradient call `k` (see the module's documentation).
    Annealed(Annealer),
}

impl Spread {
    /// The spread of gradient call `call`.
    fn sigma(&self, call: u64) -> f64 {
        match self {
            Spread::Fixed(sigma) => *sigma,
            Spread::Annealed(annealer) => {
                annealer.sigma(usize::try_from(call).unwrap_or(usize::MAX))
            }
        }
    }
}

/// What the problem's [`CostFunction`] answers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Cost {
    /// The smoothed objective `E f(theta + sigma z)`, estimated from `pairs` antithetic pairs
    /// `theta +- sigma z_k` whose `z_k` are drawn once and reused at every theta (common
    /// random numbers): `2 * pairs` evaluations of `f` per cost. The default, with 8 pairs:
    /// on a plateau `f(theta)` does not change along the gradient's direction, the smoothed
    /// objective does, so a line search can accept the step.
    Smoothed {
        /// The number of antithetic pairs (at least 1).
        pairs: usize,
    },
    /// `f(theta)` itself: one evaluation per cost. A line search whose condition needs a
    /// decrease (Armijo's) then fails on a plateau; for solvers that use the cost only to
    /// report it.
    Objective,
}

impl Default for Cost {
    fn default() -> Self {
        Cost::Smoothed { pairs: 8 }
    }
}

/// An argmin problem whose gradient is [`PlateauFreeGradient`]'s estimate: see the
/// [module's documentation](self).
///
/// argmin asks for gradients and costs through `&self`, so the estimator sits behind a
/// mutex (the problem is `Sync` when the objective is `Send`); a panic of `f` unwinds
/// through argmin, and the problem stays usable.
pub struct ArgminProblem<F> {
    state: Mutex<State<F>>,
    spread: Spread,
    cost: Cost,
}

/// What the calls change.
struct State<F> {
    estimator: PlateauFreeGradient<F>,
    gradient_calls: u64,
    cost_calls: u64,
    /// The cost's standard normal draws, `pairs` rows of theta's dimension.
    cost_draws: Vec<f64>,
    /// Scratch space for one point.
    point: Vec<f64>,
}

impl<F> fmt::Debug for ArgminProblem<F> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let state = self.lock();
        f.debug_struct("ArgminProblem")
            .field("estimator", &state.estimator)
            .field("spread", &self.spread)
            .field("cost", &self.cost)
            .field("gradient_calls", &state.gradient_calls)
            .field("cost_calls", &state.cost_calls)
            .finish()
    }
}

impl<F: Objective> ArgminProblem<F> {
    /// The problem for `estimator`, smoothing by `spread`, with the default [`Cost`].
    ///
    /// # Errors
    /// A configuration that [`PlateauFreeGradient::validate`] rejects; a fixed spread that
    /// is not finite and positive ([`Error::InvalidSigma`]).
    pub fn new(estimator: PlateauFreeGradient<F>, spread: Spread) -> Result<Self, Error> {
        estimator.validate()?;
        if let Spread::Fixed(sigma) = spread {
            check::sigma(sigma)?;
        }
        Ok(ArgminProblem {
            state: Mutex::new(State {
                estimator,
                gradient_calls: 0,
                cost_calls: 0,
                cost_draws: Vec::new(),
                point: Vec::new(),
            }),
            spread,
            cost: Cost::default(),
        })
    }

    /// What the cost answers (default: [`Cost::Smoothed`] with 8 pairs).
    ///
    /// ```
    /// use plateau_free::argmin::{ArgminProblem, Cost, Spread};
    /// use plateau_free::{Error, PlateauFreeGradient};
    /// let grad = PlateauFreeGradient::new(|x: &[f64]| x[0]);
    /// let e = ArgminProblem::new(grad, Spread::Fixed(0.1))?.with_cost(Cost::Smoothed { pairs: 0 });
    /// assert_eq!(e.unwrap_err().to_string(), "pairs = 0 is invalid: must be at least 1");
    /// # Ok::<(), Error>(())
    /// ```
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for zero pairs.
    pub fn with_cost(mut self, cost: Cost) -> Result<Self, Error> {
        if cost == (Cost::Smoothed { pairs: 0 }) {
            return Err(Error::InvalidParameter {
                name: "pairs",
                value: ParameterValue::Integer(0),
                reason: "must be at least 1",
            });
        }
        self.cost = cost;
        Ok(self)
    }
}

impl<F> ArgminProblem<F> {
    /// The estimator behind the mutex; a panic of `f` during an earlier call poisoned the
    /// mutex but left the estimator consistent (see [`PlateauFreeGradient`]), so it is used.
    fn lock(&self) -> MutexGuard<'_, State<F>> {
        self.state.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// The number of gradients estimated so far.
    pub fn gradient_calls(&self) -> u64 {
        self.lock().gradient_calls
    }

    /// The number of costs computed so far.
    pub fn cost_calls(&self) -> u64 {
        self.lock().cost_calls
    }

    /// The spread the next gradient call will use.
    pub fn sigma(&self) -> f64 {
        self.spread.sigma(self.lock().gradient_calls)
    }

    /// The estimator back, with its count of estimates.
    pub fn into_estimator(self) -> PlateauFreeGradient<F> {
        self.state
            .into_inner()
            .unwrap_or_else(PoisonError::into_inner)
            .estimator
    }
}

impl<F: Objective> Gradient for ArgminProblem<F> {
    type Param = Vec<f64>;
    type Gradient = Vec<f64>;

    /// The estimator's next estimate at `param` for the current spread.
    fn gradient(&self, param: &Vec<f64>) -> Result<Vec<f64>, ArgminError> {
        let mut state = self.lock();
        let sigma = self.spread.sigma(state.gradient_calls);
        // Counted before estimating: a failed or panicking estimate still advances the
        // annealing, as it advances the estimator's stream.
        state.gradient_calls += 1;
        Ok(state.estimator.estimate(param, sigma)?.gradient)
    }
}

impl<F: Objective> CostFunction for ArgminProblem<F> {
    type Param = Vec<f64>;
    type Output = f64;

    /// The cost [`Cost`] names, at the spread of the latest gradient call.
    fn cost(&self, param: &Vec<f64>) -> Result<f64, ArgminError> {
        check::theta(param)?;
        let mut state = self.lock();
        let sigma = self.spread.sigma(state.gradient_calls.saturating_sub(1));
        state.cost_calls += 1;
        let value = match self.cost {
            Cost::Objective => state.value_at(param)?,
            Cost::Smoothed { pairs } => state.smoothed(param, sigma, pairs)?,
        };
        Ok(value)
    }
}

impl<F: Objective> State<F> {
    /// `f(theta)`, clamped onto the estimator's box, with the cost stream's seed.
    fn value_at(&mut self, theta: &[f64]) -> Result<f64, Error> {
        self.point.clear();
        self.point.extend_from_slice(theta);
        self.evaluate_point(0, 0)
    }

    /// The mean of `f` over the antithetic pairs `theta +- sigma z_k`.
    fn smoothed(&mut self, theta: &[f64], sigma: f64, pairs: usize) -> Result<f64, Error> {
        let n = theta.len();
        self.draw_cost_perturbations(n, pairs);
        let mut sum = 0.0;
        for k in 0..pairs {
            for (member, sign) in [1.0, -1.0].into_iter().enumerate() {
                self.point.clear();
                let z = &self.cost_draws[k * n..(k + 1) * n];
                let perturbed = theta.iter().zip(z).map(|(t, z)| t + sign * sigma * z);
                self.point.extend(perturbed);
                sum += self.evaluate_point(2 * k + member, k as u64)?;
            }
        }
        Ok(sum / (2 * pairs) as f64)
    }

    /// The cost's standard normal draws for dimension `n`, drawn once per dimension from the
    /// estimator's seed.
    fn draw_cost_perturbations(&mut self, n: usize, pairs: usize) {
        if self.cost_draws.len() == n * pairs {
            return;
        }
        let seed = self.estimator.seed_setting();
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(stream_seed(seed, COST_STREAM, 0));
        self.cost_draws = (0..n * pairs)
            .map(|_| StandardNormal.sample(&mut rng))
            .collect();
    }

    /// `f` at `self.point` (the cost's evaluation `sample`) clamped onto the box, seeded by
    /// the cost stream's `k`-th seed (the same at every theta: common random numbers for a
    /// seeded objective too; both members of a pair share it, as in the estimator).
    fn evaluate_point(&mut self, sample: usize, k: u64) -> Result<f64, Error> {
        if let Some(bounds) = self.estimator.box_bounds() {
            bounds.check_dim(self.point.len())?;
            bounds.project(&mut self.point);
        }
        if let Some(index) = self.point.iter().position(|x| !x.is_finite()) {
            return Err(Error::NonFinitePoint {
                sample,
                index,
                value: self.point[index],
            });
        }
        let seed = stream_seed(self.estimator.seed_setting(), COST_STREAM, k + 1);
        let value = self.estimator.objective().evaluate(&self.point, seed);
        if value.is_finite() {
            Ok(value)
        } else {
            Err(Error::NonFiniteValue {
                sample,
                value,
                point: self.point.clone(),
            })
        }
    }
}
