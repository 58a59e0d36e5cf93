//! # plateau-free
//!
//! Usable gradients for black-box functions, including functions that are flat almost
//! everywhere or discontinuous: the image loss of a path tracer when the object you move is
//! hidden, a simulator, a game engine, a procedural model. No derivative of `f` is ever
//! needed, only its values.
//!
//! ## The method
//! Following Fischer and Ritschel, "Plateau-reduced Differentiable Path Tracing" (CVPR 2023),
//! the objective is smoothed by a Gaussian in parameter space,
//!
//! ```text
//! Q_sigma(theta) = E_{tau ~ N(0, sigma^2 I)} f(theta + tau),
//! grad Q_sigma(theta) = E[ f(theta + tau) tau ] / sigma^2,
//! ```
//!
//! and the optimiser follows `grad Q_sigma`. `Q` has no plateaus: the kernel's infinite
//! support lets every distant change of `f` be felt at `theta`. The gradient is estimated by
//! Monte Carlo: the perturbations are importance-sampled from the kernel's derivative and
//! paired with their opposites (antithetic sampling), see [`Sampling`]. A schedule
//! ([`Annealer`]) shrinks `sigma` as the optimisation closes in, and [`Adam`] takes the steps.
//!
//! ## The crate in one screen
//! - [`minimize`]`(f, x0, budget)`: the first thing to try, with no step size or learning rate
//!   to choose; [`Minimizer`] for options (bounds, seed, target, the paper's loop). A Gaussian
//!   search distribution whose spread and metric adapt to `f`, with restarts. Every method
//!   evaluates `x0` first (the result is never worse), spends at most the budget, and with
//!   bounds evaluates `f` only inside the box.
//!   [`Minimizer::polish`] runs the paper's loop and then this search from its best point
//!   (what the path-tracing tasks run by default).
//! - [`PlateauFreeGradient`]: the estimator for any `Fn(&[f64]) -> f64`, a seeded closure
//!   ([`Seeded`](objective::Seeded), for common random numbers), a batch closure ([`Batch`](objective::Batch)) or any
//!   [`Objective`]; returns an [`Estimate`].
//! - [`smoothed_hessian`](hessian::smoothed_hessian): the Hessian of the Gaussian-smoothed objective from values of `f`
//!   (antithetic pairs and a control variate), with standard errors.
//! - [`Sampling`]: `Radial` (default, exact in every dimension), `PerCoordinate` (the paper's
//!   reference sampler), `Gaussian` (plain evolution strategies).
//! - [`Annealer`]: the paper's warm-start-then-linear schedule, and constant, exponential and
//!   cosine ones.
//! - [`Adam`]: with optional box bounds, which are the run's box: the start must lie inside,
//!   and every point the estimator evaluates is clamped onto it
//!   ([`GradientEstimator::set_bounds`]).
//! - [`Optimizer`]: the loop, with an observer and a [`History`](run::History) (of the last million
//!   iterations by default, so that memory stays bounded: [`HistoryKeep`](run::HistoryKeep)).
//! - [`OptimizerState`](run::OptimizerState): a run's state as a value, to save and continue from
//!   ([`Optimizer::minimize_from`]); an error mid-run returns it with the history so far
//!   ([`RunError`](run::RunError)). A failing objective is reported, resampled ([`OnFailure`](estimator::OnFailure)) or, with
//!   [`PlateauFreeGradient::catch_panics`], caught; see `docs/reliability.md`.
//! - [`AskTell`] ([`Minimizer::ask_tell`]) and [`PaperAskTell`] ([`Optimizer::ask_tell`]):
//!   ask and tell, for points evaluated elsewhere (a queue, a game engine, a render farm).
//!   [`Ask`] gives an iteration's points and one seed per point; `tell` takes their values
//!   and takes the step. The callback forms are written on them: the same options and seed
//!   give the same bits ([`NoObjective`](objective::NoObjective) stands in for the objective a run does not need).
//! - [`lifecycle`]: a run's lifecycle for every ask-and-tell method, written once: a
//!   [`lifecycle::Driver`] (an interrupt, observers such as a progress line and a bounded
//!   trace, workers bit-identical to one, a checkpoint to resume from) and
//!   [`Minimizer::run_with`]; an error ends the run with its result so far.
//! - `argmin` (feature `argmin`): the estimate as [argmin](https://argmin-rs.org)'s
//!   `Gradient`, so that its steepest descent and L-BFGS run on plateau-ridden functions.
//! - [`LeastSquares`]: for an objective that returns many numbers (a residual image): the
//!   Gaussian-smoothed Jacobian by Stein's identity on a [`Sparsity`](vector::Sparsity) pattern
//!   ([`smoothed_jacobian`](vector::smoothed_jacobian)) and damped Gauss-Newton steps on the smoothed residuals, as ask
//!   and tell ([`LeastSquaresAskTell`](vector::LeastSquaresAskTell)) or with a callback; see the [`vector`] module.
//! - [`baseline`]: finite differences and SPSA, for comparison on the same loop.
//! - [`kernel`]: the Gaussian kernel, the inverse CDF of its derivative, `c_n`.
//! - [`seeding`]: how every random stream is seeded (SplitMix64 of the seed, the estimate's
//!   index and the stream), for objectives that derive seeds of their own.
//! - [`Error`]: every way an input can be wrong, with the value as it was given
//!   ([`ParameterValue`](error::ParameterValue)). Nothing here panics on bad input; a bad configuration is reported
//!   by [`PlateauFreeGradient::validate`] where it is made.
//!
//! [`Sampling`] and [`Schedule`](anneal::Schedule) print and parse under one spelling each (`radial`,
//! `per-coordinate`, `gaussian`; `constant`, `warm-linear:0.5`, `exponential`, `cosine`).
//! The optional feature `serde` derives `Serialize` and `Deserialize` for them (under the
//! same names) and for [`Estimate`] and [`History`](run::History), and makes a run's whole state a value:
//! [`AskTell`] and [`PaperAskTell`], saved at any tell and read back, go on bit for bit.
//!
//! ## Example
//! A tilted step `1[x + 2y > 0.3]` started on its flat side, where every plain gradient is
//! zero:
//!
//! ```
//! use plateau_free::{Adam, Annealer, Optimizer, PlateauFreeGradient};
//!
//! let f = |x: &[f64]| if x[0] + 2.0 * x[1] > 0.3 { 1.0 } else { 0.0 };
//! let mut grad = PlateauFreeGradient::new(f).samples(8).seed(7);
//! let mut opt = Optimizer::new(Adam::new(0.02)?, Annealer::paper(0.5, 200)?);
//! let history = opt.minimize(&mut grad, &[1.0, 1.0])?;
//! let x = history.last_theta().unwrap();
//! assert!(x[0] + 2.0 * x[1] < 0.3, "left the plateau: {x:?}");
//! # Ok::<(), plateau_free::Error>(())
//! ```
//!
//! The same search, asked and told: the points go wherever they are evaluated, the values
//! come back in the points' order.
//!
//! ```
//! use plateau_free::Minimizer;
//!
//! let f = |x: &[f64]| if x[0] + 2.0 * x[1] > 0.3 { 1.0 } else { 0.0 };
//! let mut run = Minimizer::without_objective().budget(400).seed(1).ask_tell(&[1.0, 1.0])?;
//! while let Some(ask) = run.ask()? {
//!     let values: Vec<f64> = ask.iter().map(|(x, _seed)| f(x)).collect();
//!     run.tell(&values)?;
//! }
//! let best = run.finish()?;
//! assert_eq!(best.fun, 0.0);
//! assert_eq!(best, Minimizer::new(f).budget(400).seed(1).run(&[1.0, 1.0])?);
//! # Ok::<(), plateau_free::Error>(())
//! ```

#![warn(missing_docs, missing_debug_implementations)]

// First: the macros are used by the modules below.
#[macro_use]
mod builder;

// The parts of a run: the estimator (estimator/), Adam, the annealer. The methods, each
// written once as an ask-and-tell state machine (method/: the paper's loop, the adaptive
// search, the two in turn); the types a run takes and gives back (run/); the callback forms,
// which drive the methods with an objective or an estimator (minimize.rs, optimize.rs),
// and the lifecycle every method's run goes through (lifecycle/: driver, interrupt,
// observers, workers, checkpoint).
// No module imports one that imports it back (scripts/module-cycles); the module map with
// every file is in docs/design.md.
pub mod adam;
pub mod anneal;
#[cfg(feature = "argmin")]
pub mod argmin;
pub mod baseline;
mod check;
pub mod error;
pub mod estimator;
pub mod hessian;
pub mod kernel;
pub mod lifecycle;
mod method;
mod minimize;
mod names;
pub mod objective;
mod optimize;
pub mod run;
mod sampling;
#[cfg(feature = "serde")]
mod saved;
pub mod seeding;
pub mod vector;

// The crate in one screen: what a first program names. Everything else is in the modules
// above, by what it is part of.
pub use adam::Adam;
pub use anneal::Annealer;
pub use error::Error;
pub use estimator::{Estimate, GradientEstimator, PlateauFreeGradient};
pub use method::{AskTell, Optimizer, PaperAskTell};
pub use minimize::{minimize, Minimizer};
pub use objective::Objective;
pub use run::{Ask, Minimum, Stop};
pub use sampling::Sampling;
pub use vector::LeastSquares;

/// The README's examples, compiled and run as doctests so that they stay true.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
