//! `--method adaptive` and `--method polished`: the library's [`plateau_free::Minimizer`] on
//! the task's image loss (polished: its `Strategy::Paper` with `polish`), as ask and tell.
//!
//! It gets what the paper loop gets and nothing tuned per task: a budget of N x iterations
//! evaluations (the task's Table 1), the task's sigma0 and box (if any), the run's seed, and
//! the same renderer seeds ([`super::Crn`]: with `fixed` every render uses the run's seed;
//! with `pair` every render of an iteration shares the seed the Minimizer gives it). Each
//! ask's points are rendered at once; what each batch records is in `record.rs`.
//!
//! The checkpoint holds the library's [`AskTell`] itself (its options, state and random
//! generators, serialised): a resumed run goes on bit for bit, rendering nothing again. It
//! also keeps every value told, in order, for the stop rule's study
//! ([`super::replay_stall`]).

use plateau_free::{run::Strategy, AskTell, Minimizer};

use super::{Method, Settings};
use crate::report::Result;
use crate::tasks::Task;

/// The first row of the polish in a polished run of `budget` evaluations with `samples` per
/// estimate and the share `polish` for the polish: the loop's iterations (on its share of the
/// budget, the start and its final evaluation apart, as `plateau_free::run::Strategy::Paper`
/// counts them), then the final evaluation's row.
pub(super) fn polish_starts_at(budget: usize, samples: usize, polish: f64) -> usize {
    let loop_budget = budget - (budget as f64 * polish).floor() as usize;
    loop_budget.saturating_sub(2) / samples.max(1) + 1
}

/// The search's ask-and-tell run from `start`.
///
/// # Errors
/// A time budget (the paper's loop only), settings the library rejects.
pub(super) fn search(task: &Task, s: &Settings, start: &[f64]) -> Result<AskTell> {
    if s.budget_seconds.is_some() {
        return Err("a time budget (--budget) is not supported with --method adaptive".into());
    }
    let mut minimizer = Minimizer::without_objective()
        .budget(s.samples.saturating_mul(s.iterations))
        .sigma0(s.sigma0)
        .seed(s.seed);
    if s.method == Method::Polished {
        minimizer = minimizer
            .strategy(Strategy::Paper {
                samples: s.samples,
                lr: s.lr,
                sigma0: s.sigma0,
            })
            .polish(s.polish);
    }
    if let Some((lower, upper)) = task.bounds() {
        minimizer = minimizer.bounds(lower, upper);
    }
    if let Some(window) = s.stall {
        minimizer = minimizer.stop_when_stalled(window);
    }
    Ok(minimizer.ask_tell(start)?)
}
