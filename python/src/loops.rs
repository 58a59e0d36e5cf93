//! [`Loop`]: the paper's loop as `_AskTell` runs it, with the plateau-free estimator
//! (`method='plateau'`) or a baseline (`'fd'`, `'spsa'`): the library's two ask-and-tell
//! forms of the loop behind one set of calls.

use plateau_free::baseline::BaselineAskTell;
use plateau_free::lifecycle::AskAndTell;
use plateau_free::{run::History, Ask, Error, Estimate, PaperAskTell};

/// The paper's loop with either estimator. Untagged in its saved form: a run saved before
/// baselines were asked and told reads back as the plateau-free one.
#[derive(serde::Serialize, serde::Deserialize)]
#[serde(untagged)]
pub(crate) enum Loop {
    Gaussian(Box<PaperAskTell>),
    Baseline(Box<BaselineAskTell>),
}

/// The same call on either run.
macro_rules! either {
    ($self:ident, $run:ident => $call:expr) => {
        match $self {
            Loop::Gaussian($run) => $call,
            Loop::Baseline($run) => $call,
        }
    };
}

impl Loop {
    pub(crate) fn ask(&mut self) -> Result<Option<Ask<'_>>, Error> {
        either!(self, run => run.ask())
    }

    pub(crate) fn tell(&mut self, values: &[f64]) -> Result<(), Error> {
        either!(self, run => run.tell(values))
    }

    pub(crate) fn is_done(&self) -> bool {
        either!(self, run => run.is_done())
    }

    pub(crate) fn iteration(&self) -> usize {
        either!(self, run => run.iteration())
    }

    pub(crate) fn theta(&self) -> &[f64] {
        either!(self, run => run.theta())
    }

    pub(crate) fn history(&self) -> &History {
        either!(self, run => run.history())
    }

    pub(crate) fn last_estimate(&self) -> Option<&Estimate> {
        either!(self, run => run.last_estimate())
    }

    /// The library's settings of the run, for a checkpoint's identity.
    pub(crate) fn identity(&self) -> Vec<(&'static str, String)> {
        either!(self, run => AskAndTell::identity(&**run))
    }
}
