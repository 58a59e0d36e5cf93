//! The types a run takes and gives back: a [`crate::Minimizer`]'s options ([`Strategy`],
//! [`Metric`], [`FailurePolicy`], the stop rule [`Stall`]) and its result ([`Minimum`],
//! [`Stop`]); the points of one ask ([`Ask`]); what the paper's loop gives back and
//! continues from ([`History`], [`OptimizerState`], [`RunError`]) and what its observer sees
//! ([`Step`]).

// A module of its own, shared by the methods (`method/`) and the callback forms that drive
// them (`minimize.rs`, `optimize.rs`), so that neither side imports the other. The files:
// `options.rs` (the options), `minimum.rs` (the result and the account: the evaluations
// spent, the best point seen), `history.rs` (the paper loop's record), `ask.rs` (the points
// of one ask and the checks of told values), `stall.rs` (the stop rule), `grid.rs` (discrete
// coordinates, `Minimizer::steps`: their checks and rounding), `step.rs` (the observer's view).

mod ask;
mod grid;
mod history;
mod minimum;
mod options;
mod stall;
mod step;

pub(crate) use ask::count;
pub use ask::Ask;
pub use history::{History, HistoryKeep, OptimizerState, RunError};
pub(crate) use minimum::{Best, Ledger};
pub use minimum::{Minimum, Stop};
pub(crate) use options::Options;
pub use options::{
    FailurePolicy, Metric, Strategy, DECODING_MIN_DIM, DEFAULT_PATIENCE, DEFAULT_POLISH,
    FULL_METRIC_LIMIT, FULL_METRIC_MAX_DIM,
};
pub(crate) use stall::check_fraction;
pub use stall::{Stall, STALL_WINDOW};
pub use step::Step;
