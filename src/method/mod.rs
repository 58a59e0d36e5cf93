//! The methods, each written once, as an ask-and-tell state machine: the run hands out an
//! iteration's points and takes their values back, and whoever holds the run evaluates the
//! points wherever it likes (a callback, a queue, a game engine, a render farm).
//!
//! - `paper/`: the paper's loop ([`Optimizer`]: annealed spread, gradient estimate, Adam's
//!   step), and [`PaperAskTell`], the loop asked and told point by point;
//! - `adaptive/`: the adaptive search (a Gaussian search distribution with restarts);
//! - `polished.rs`: [`crate::run::Strategy::Paper`] in a [`crate::Minimizer`] run: the paper's
//!   loop, then (with [`crate::Minimizer::polish`]) the adaptive search from its best point;
//! - `minimizer.rs`: [`AskTell`], a [`crate::Minimizer`] run: its start, then the
//!   strategy's method.
//!
//! The callback forms drive these machines: [`crate::Minimizer::run`] (`minimize.rs`) asks
//! and evaluates with the objective until the run ends; [`Optimizer::minimize_from`]
//! (`optimize.rs`) drives the paper's loop one estimate at a time with any
//! [`crate::GradientEstimator`]. With the same options and seed both forms give the same
//! bits (`tests/ask_tell.rs`, `tests/ask_tell_pinned.rs`).
//!
//! Each ask gives the points (rows of `n`) and one seed per point: the seeds the
//! [`crate::objective::Seeded`] and [`crate::objective::Batch`] forms of the objective receive. Each tell takes
//! one value per point, in the points' order, and finishes the iteration. A failed `tell`
//! changes nothing: the points still wait for their values (for the one exception, see
//! [`PaperAskTell::tell`]).

mod adaptive;
mod minimizer;
mod paper;
mod polished;

pub use minimizer::AskTell;
pub(crate) use paper::Progress;
pub use paper::{Optimizer, PaperAskTell};
