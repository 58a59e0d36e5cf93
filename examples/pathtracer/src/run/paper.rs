//! The paper's loop (`--method plateau`, `fd`, `spsa`): a gradient estimator, Adam and the
//! annealer, run in segments between checkpoints, with a recorder of each iteration.

use std::cell::Cell;
use std::ops::ControlFlow;
use std::time::{Duration, Instant};

use plateau_free::baseline::{FiniteDifference, Spsa};
use plateau_free::{
    Adam, Annealer, GradientEstimator, Optimizer, OptimizerState, PlateauFreeGradient, Seeded, Step,
};

use super::adaptive;
use super::meter::{At, Meter, Unit};
use super::{Checkpoint, Ended, Every, Method, Progress, Row, Run, Settings};
use crate::render::Image;
use crate::report::Result;
use crate::tasks::Task;

/// Why the paper loop's observer stopped a segment of the run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Why {
    /// The time budget is spent: the run ends.
    Budget,
    /// Ctrl-C or `stop_after`: the run stops, to be continued.
    Interrupt,
    /// A checkpoint is due: written, then the loop continues.
    Checkpoint,
}

/// The paper's loop (plateau-free gradient, finite differences or SPSA; Adam; annealing),
/// run in segments between checkpoints: each segment continues the library's
/// [`OptimizerState`] of the one before ([`Optimizer::minimize_from`]), so the segments give
/// bit for bit the run in one go.
pub(super) fn run<L>(run: &Run<'_>, loss: &L, renders: &Cell<usize>) -> Result<adaptive::Finished>
where
    L: Fn(&[f64], u64) -> f64,
{
    let (task, s, ctl) = (run.task, run.s, run.ctl);
    let mut estimator = estimator(s, loss)?;
    let mut optimizer = optimizer(task, s)?;
    let mut recorder = Recorder::new(
        task,
        s,
        run.reference,
        run.start,
        (ctl.progress, ctl.every),
        renders,
    );
    let (mut state, mut finished) = match &ctl.resume {
        Some(c) => {
            let Progress::Loop { state } = &c.progress else {
                return Err("the checkpoint is of an adaptive run, this run is not".into());
            };
            recorder.resume(c);
            (state.clone(), c.finished)
        }
        None => (OptimizerState::new(run.start)?, false),
    };
    let mut interrupted = false;
    while !finished {
        recorder.restart_clock();
        let segment = optimizer.minimize_from(&mut *estimator, state, |step| {
            let (over_budget, checkpoint_due) = recorder.observe(step);
            let why = if over_budget {
                Some(Why::Budget)
            } else if run.stop_requested(step.iteration + 1) {
                Some(Why::Interrupt)
            } else {
                checkpoint_due.then_some(Why::Checkpoint)
            };
            recorder.why = why;
            if why.is_some() {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        });
        state = match segment {
            Ok(state) => state,
            Err(e) => {
                // The state after the last good iteration is kept, to continue from.
                recorder.save(run, false, *e.state);
                return Err(e.error.into());
            }
        };
        let complete = state.iteration >= s.iterations;
        match recorder.why.take() {
            _ if complete => finished = true,
            None | Some(Why::Budget) => finished = true,
            Some(Why::Interrupt) => {
                interrupted = true;
                break;
            }
            Some(Why::Checkpoint) => {
                recorder.saved_at = (state.iteration, recorder.optimisation_time);
                recorder.save(run, false, state.clone());
            }
        }
    }
    drop(estimator);
    recorder.save(run, finished, state.clone());
    let (history, mut snapshots, optimisation_time) = recorder.finish();
    if interrupted {
        // The strip of an interrupted run ends where it stopped.
        snapshots.push(state.theta.clone());
    }
    let ended = Ended {
        iterations: state.iteration,
        evaluations: state.history.evaluations,
        renders: renders.get(),
        stopped_early: finished && state.iteration < s.iterations,
        interrupted,
    };
    Ok((ended, state.theta, history, snapshots, optimisation_time))
}

/// The gradient estimator [`Settings::method`] names, over `loss`.
fn estimator<'a, L>(s: &Settings, loss: &'a L) -> Result<Box<dyn GradientEstimator + 'a>>
where
    L: Fn(&[f64], u64) -> f64,
{
    Ok(match s.method {
        Method::Plateau => Box::new(
            PlateauFreeGradient::new(Seeded(loss))
                .samples(s.samples)
                .sampling(s.sampling)
                .antithetic(s.antithetic)
                .seed(s.seed),
        ),
        Method::Fd => Box::new(FiniteDifference::new(Seeded(loss), s.fd_step)?.seed(s.seed)),
        Method::Spsa => Box::new(Spsa::new(Seeded(loss)).seed(s.seed)),
        Method::Adaptive | Method::Polished | Method::Image => {
            unreachable!(
                "the library's Minimizer and LeastSquares run these: run::adaptive, run::image"
            )
        }
    })
}

/// Adam (projected onto the task's box, if it has one) under the paper's annealing schedule
/// or, for the ablation, a constant sigma: the optimiser of [`super::optimize`], also for loops that
/// evaluate elsewhere (the MPI example).
///
/// # Errors
/// Settings that Adam or the annealer reject (a learning rate or sigma0 not positive, zero
/// iterations).
pub fn optimizer(task: &Task, s: &Settings) -> Result<Optimizer> {
    let mut adam = Adam::new(s.lr)?;
    if let Some((lower, upper)) = task.bounds() {
        adam = adam.bounds(lower, upper)?;
    }
    let annealer = if s.anneal {
        Annealer::paper(s.sigma0, s.iterations)?
    } else {
        Annealer::constant(s.sigma0, s.iterations)?
    };
    // The loop keeps only the last theta; the recorder keeps six snapshots for the progress
    // strip (a 49,152-parameter theta per iteration would be 1.5 GB over 4000 iterations).
    let mut optimizer = Optimizer::new(adam, annealer).record_theta(false);
    if let Some(window) = s.stall {
        optimizer = optimizer.stop_when_stalled(window)?;
    }
    Ok(optimizer)
}

/// What the loop records after each iteration: a row of the history, six snapshots of theta
/// for the progress strip, the optimisation time (the image-error renders excluded), the
/// progress bar; whether the time budget is spent and a checkpoint due.
struct Recorder<'a> {
    task: &'a Task,
    s: &'a Settings,
    reference: &'a Image,
    /// The task's target, made once.
    target: Vec<f64>,
    snapshot_at: Vec<usize>,
    snapshots: Vec<Vec<f64>>,
    history: Vec<Row>,
    optimisation_time: Duration,
    last: Instant,
    bar: Meter,
    /// The iterations and the optimisation time at the last checkpoint.
    saved_at: (usize, Duration),
    /// When a checkpoint is due.
    every: Every,
    /// Why the observer last stopped the loop.
    why: Option<Why>,
    /// The loss's count of its renders.
    renders: &'a Cell<usize>,
}

impl<'a> Recorder<'a> {
    fn new(
        task: &'a Task,
        s: &'a Settings,
        reference: &'a Image,
        start: &[f64],
        (show_progress, every): (bool, Every),
        renders: &'a Cell<usize>,
    ) -> Self {
        Recorder {
            task,
            s,
            reference,
            target: task.target(),
            // k * (iterations - 1) / 5 without overflow, whatever the count.
            snapshot_at: (0..6u128)
                .map(|k| (k * s.iterations.saturating_sub(1) as u128 / 5) as usize)
                .collect(),
            snapshots: vec![start.to_vec()],
            // Not `iterations` rows ahead: a count near `usize::MAX` cannot be allocated.
            history: Vec::with_capacity(s.iterations.min(1 << 16)),
            optimisation_time: Duration::ZERO,
            bar: Meter::new(task.name(), s.iterations, Unit::Iterations, show_progress),
            last: Instant::now(),
            saved_at: (0, Duration::ZERO),
            every,
            why: None,
            renders,
        }
    }

    /// Takes up the record of a checkpoint.
    fn resume(&mut self, c: &Checkpoint) {
        self.history.clone_from(&c.history);
        self.snapshots.clone_from(&c.snapshots);
        self.optimisation_time = Duration::from_secs_f64(c.optimisation_seconds);
        self.bar.set_position(c.history.len());
        self.saved_at = (c.history.len(), self.optimisation_time);
    }

    /// Starts timing again (after a checkpoint was written: its time is not the run's).
    fn restart_clock(&mut self) {
        self.last = Instant::now();
    }

    /// The loop's observer: records `step`; says whether the budget is spent and whether a
    /// checkpoint is due.
    fn observe(&mut self, step: &Step<'_>) -> (bool, bool) {
        let s = self.s;
        self.optimisation_time += self.last.elapsed();
        let seconds = self.optimisation_time.as_secs_f64();
        if self.snapshot_at[1..].contains(&step.iteration) {
            self.snapshots.push(step.theta.to_vec());
        }
        let image_mse = s.records_image_error(step.iteration).then(|| {
            self.task
                .render(step.theta, s.seed, s.spp, s.view())
                .mse(self.reference)
        });
        let eval_renders = self.history.last().map_or(0, |r| r.eval_renders);
        self.history.push(Row {
            iteration: step.iteration,
            sigma: step.sigma,
            loss: step.estimate.mean_value,
            param_mse: self.task.param_mse_to(step.theta, &self.target),
            image_mse,
            renders: self.renders.get(),
            eval_renders: eval_renders + usize::from(image_mse.is_some()),
            seconds,
        });
        self.bar.update(
            At {
                iterations: step.iteration + 1,
                renders: self.renders.get(),
                loss: step.estimate.mean_value,
            },
            format!(
                "loss {:.3e}  sigma {:.3}",
                step.estimate.mean_value, step.sigma
            ),
        );
        let over_budget = s.budget_seconds.is_some_and(|b| seconds >= b);
        let checkpoint_due = self.every.is_due(
            (step.iteration + 1).saturating_sub(self.saved_at.0),
            self.optimisation_time.saturating_sub(self.saved_at.1),
        );
        self.last = Instant::now();
        (over_budget, checkpoint_due)
    }

    /// Writes the checkpoint of the loop at `state` with the record so far.
    fn save(&self, run: &Run<'_>, finished: bool, state: OptimizerState) {
        let progress = Progress::Loop { state };
        let time = self.optimisation_time;
        run.saver
            .save(finished, progress, &self.history, &self.snapshots, time);
    }

    /// The history, the snapshots and the optimisation time.
    fn finish(self) -> (Vec<Row>, Vec<Vec<f64>>, Duration) {
        self.bar.finish();
        (self.history, self.snapshots, self.optimisation_time)
    }
}
