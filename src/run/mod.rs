//! The types a run takes and gives back, shared by the methods (`method/`) and the callback
//! forms that drive them (`minimize.rs`, `optimize.rs`), in a module of their own so that
//! neither side imports the other:
//! - `options.rs`: a [`crate::Minimizer`]'s options ([`Strategy`], [`Metric`], the rest);
//! - `minimum.rs`: its result ([`Minimum`], [`Stop`]) and its account (the evaluations
//!   spent, the best point seen);
//! - `history.rs`: what the paper's loop gives back and continues from ([`History`],
//!   [`OptimizerState`], [`RunError`]);
//! - `ask.rs`: the points of one ask ([`Ask`]) and the checks of told values;
//! - `stall.rs`: the stop rule ([`Stall`]): a run ends when its best value stopped improving;
//! - `grid.rs`: discrete coordinates (`crate::Minimizer::steps`): their checks and rounding.

mod ask;
mod grid;
mod history;
mod minimum;
mod options;
mod stall;

pub(crate) use ask::count;
pub use ask::Ask;
pub use history::{History, HistoryKeep, OptimizerState, RunError};
pub(crate) use minimum::{Best, Ledger};
pub use minimum::{Minimum, Stop};
pub(crate) use options::Options;
pub use options::{
    FailurePolicy, Metric, Strategy, DEFAULT_PATIENCE, DEFAULT_POLISH, FULL_METRIC_LIMIT,
    FULL_METRIC_MAX_DIM,
};
pub(crate) use stall::check_fraction;
pub use stall::{Stall, STALL_WINDOW};
