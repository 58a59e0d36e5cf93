//! The paper's loop (`--method plateau`, `fd`, `spsa`): Adam (projected onto the task's box)
//! under the paper's annealing schedule, with the plateau-free gradient or a baseline
//! estimator, as the library's ask-and-tell loops ([`plateau_free::PaperAskTell`],
//! [`plateau_free::baseline::BaselineAskTell`]).

use plateau_free::baseline::Baseline;
use plateau_free::{Adam, Annealer, Error, Optimizer, PlateauFreeGradient};

use super::checkpoint::Progress;
use super::{Method, Settings};
use crate::report::Result;
use crate::tasks::Task;

/// The method's run from `start`: the library's ask-and-tell loop with the plateau-free
/// gradient, finite differences or SPSA.
///
/// # Errors
/// Settings that Adam, the annealer or the estimator reject, a start outside the box.
pub(super) fn progress(task: &Task, s: &Settings, start: &[f64]) -> Result<Progress> {
    let baseline = match s.method {
        Method::Fd => Some(Baseline::FiniteDifference { step: s.fd_step }),
        Method::Spsa => Some(Baseline::Spsa),
        _ => None,
    };
    if let Some(baseline) = baseline {
        let run = loop_optimizer(task, s)?.ask_tell_baseline(baseline, s.seed, start)?;
        return Ok(Progress::Baseline(Box::new(run)));
    }
    let gradient = PlateauFreeGradient::without_objective()
        .samples(s.samples)
        .sampling(s.sampling)
        .antithetic(s.antithetic)
        .seed(s.seed);
    let run = loop_optimizer(task, s)?.ask_tell(gradient, start)?;
    Ok(Progress::Loop(Box::new(run)))
}

/// Adam (projected onto the task's box, if it has one) under the paper's annealing schedule
/// or, for the ablation, a constant sigma: the optimiser of [`super::optimize`], also for
/// loops that evaluate elsewhere (the MPI example).
///
/// # Errors
/// Settings that Adam or the annealer reject (a learning rate or sigma0 not positive, zero
/// iterations).
pub fn optimizer(task: &Task, s: &Settings) -> Result<Optimizer> {
    Ok(loop_optimizer(task, s)?)
}

/// [`optimizer`], with the library's error.
pub(super) fn loop_optimizer(task: &Task, s: &Settings) -> std::result::Result<Optimizer, Error> {
    let mut adam = Adam::new(s.lr)?;
    if let Some((lower, upper)) = task.bounds() {
        adam = adam.bounds(lower, upper)?;
    }
    let annealer = if s.anneal {
        Annealer::paper(s.sigma0, s.iterations)?
    } else {
        Annealer::constant(s.sigma0, s.iterations)?
    };
    // The loop keeps only the last theta; the run's record keeps six snapshots for the
    // progress strip (a 49,152-parameter theta per iteration would be 1.5 GB over 4000
    // iterations).
    let mut optimizer = Optimizer::new(adam, annealer).record_theta(false);
    if let Some(window) = s.stall {
        optimizer = optimizer.stop_when_stalled(window)?;
    }
    Ok(optimizer)
}
