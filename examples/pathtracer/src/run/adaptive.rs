//! `--method adaptive` and `--method polished`: the library's [`plateau_free::Minimizer`] on the
//! task's image loss (polished: its `Strategy::Paper` with `polish`), run as ask and tell.
//!
//! It gets what the paper loop gets and nothing tuned per task: a budget of N x iterations
//! evaluations (the task's Table 1), the task's sigma0 and box (if any), the run's seed, and
//! the same renderer seeds ([`super::Crn`]: with `fixed` every render uses the run's seed; with
//! `pair` every render of an iteration shares the seed the Minimizer gives it). Each ask's
//! points are rendered at once; after each batch one row of the history is written (its `loss`
//! is the mean over the batch, its `sigma` the spread of the batch's points, RMS per coordinate
//! around their mean, its parameter and image errors those of the best point so far, which is
//! what the run returns).
//!
//! Checkpoints hold the library's [`AskTell`] itself (its options, state and random
//! generators, serialised): a resumed run reads it back and goes on bit for bit, rendering
//! nothing again. They also keep every value told, in order, for the stop rule's study
//! ([`super::replay_stall`]).

use std::time::{Duration, Instant};

use plateau_free::{AskTell, Minimizer, Points, Stop as LibraryStop, Strategy};

use super::meter::{At, Meter, Unit};
use super::{Ended, Method, Progress, Row, Run};
use crate::report::Result;

/// The first row of the polish in a polished run of `budget` evaluations with `samples` per
/// estimate and the share `polish` for the polish: the loop's iterations (on its share of the
/// budget, the start and its final evaluation apart, as `plateau_free::Strategy::Paper`
/// counts them), then the final evaluation's row.
pub(super) fn polish_starts_at(budget: usize, samples: usize, polish: f64) -> usize {
    let loop_budget = budget - (budget as f64 * polish).floor() as usize;
    loop_budget.saturating_sub(2) / samples.max(1) + 1
}

/// How a run ended, its best point, its history, six snapshots for the progress strip and the
/// optimisation time: what both methods hand to the outputs.
pub(super) type Finished = (Ended, Vec<f64>, Vec<Row>, Vec<Vec<f64>>, Duration);

/// Above this many parameters the best point is not kept per iteration (the progress strip
/// then shows the start and the end).
const KEEP_BESTS_MAX_DIM: usize = 256;

/// The search's ask-and-tell run, new or read back from the checkpoint being continued.
fn search(run: &Run<'_>, budget: usize) -> Result<AskTell> {
    let (task, s) = (run.task, run.s);
    if let Some(c) = &run.ctl.resume {
        let Progress::Adaptive { state, .. } = &c.progress else {
            return Err("the checkpoint is of the paper's loop, this run is adaptive".into());
        };
        return serde_json::from_value(state.clone())
            .map_err(|e| format!("checkpoint: the search's state cannot be read: {e}").into());
    }
    let mut minimizer = Minimizer::without_objective()
        .budget(budget)
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
    Ok(minimizer.ask_tell(run.start)?)
}

/// Runs the adaptive search; returns how it ended, the best point, the history, six snapshots
/// of the best point for the progress strip, and the optimisation time (the image-error renders
/// excluded).
pub(super) fn run<L>(run: &Run<'_>, loss: &L) -> Result<Finished>
where
    L: Fn(&[f64], u64) -> f64,
{
    if run.s.budget_seconds.is_some() {
        return Err("a time budget (--budget) is not supported with --method adaptive".into());
    }
    let budget = run.s.samples.saturating_mul(run.s.iterations);
    let mut search = search(run, budget)?;
    let mut rec = Recorder::new(run, budget);
    let mut interrupted = false;
    let mut saved_at = (rec.history.len(), rec.optimisation_time);
    while let Some(ask) = search.ask()? {
        let values: Vec<f64> = ask.iter().map(|(x, seed)| loss(x, seed)).collect();
        let row = rec.record(ask.points(), &values);
        search.tell(&values)?;
        rec.values.extend_from_slice(&values);
        if !row || search.evaluations() >= budget {
            continue;
        }
        let done = rec.history.len();
        if run.stop_requested(done) {
            interrupted = true;
            break;
        }
        let since = (done - saved_at.0, rec.optimisation_time - saved_at.1);
        if run.ctl.every.is_due(since.0, since.1) {
            rec.save(&search, false);
            saved_at = (done, rec.optimisation_time);
            rec.last = Instant::now(); // The checkpoint's time is not the run's.
        }
    }
    rec.save(&search, !interrupted);
    let (iterations, evaluations, best, stalled) = if interrupted {
        let best = rec.best.1.clone();
        (rec.history.len(), search.evaluations(), best, false)
    } else {
        let minimum = search.finish()?;
        let stalled = minimum.stop == LibraryStop::Stalled;
        (minimum.iterations, minimum.evaluations, minimum.x, stalled)
    };
    rec.bar.finish();
    let snapshots = snapshots(&rec.bests, run.start, &best);
    let ended = Ended {
        iterations,
        evaluations,
        renders: evaluations,
        stopped_early: stalled,
        interrupted,
    };
    Ok((ended, best, rec.history, snapshots, rec.optimisation_time))
}

/// Six snapshots of the best point, evenly spaced over the iterations (the last is `best`,
/// the returned point).
fn snapshots(bests: &[Vec<f64>], start: &[f64], best: &[f64]) -> Vec<Vec<f64>> {
    let mut snapshots = if bests.len() <= 1 {
        vec![start.to_vec(); 6]
    } else {
        let last = bests.len() - 1;
        (0..6).map(|k| bests[k * last / 5].clone()).collect()
    };
    snapshots[5] = best.to_vec();
    snapshots
}

/// What the search records after each batch: the history, the best point so far (and after
/// every iteration, for the strip), every value told, the optimisation time (the image-error
/// renders and the checkpoints excluded), the progress bar; and the checkpoint it writes.
struct Recorder<'a> {
    run: &'a Run<'a>,
    budget: usize,
    /// The task's target, made once.
    target: Vec<f64>,
    /// The best value and point so far.
    best: (f64, Vec<f64>),
    history: Vec<Row>,
    /// The best point after every iteration (small tasks only; else the start alone).
    bests: Vec<Vec<f64>>,
    /// Every value told, in order.
    values: Vec<f64>,
    optimisation_time: Duration,
    last: Instant,
    bar: Meter,
}

impl<'a> Recorder<'a> {
    /// A new record, or the checkpoint's being continued.
    fn new(run: &'a Run<'a>, budget: usize) -> Self {
        let mut rec = Recorder {
            run,
            budget,
            target: run.task.target(),
            best: (f64::INFINITY, run.start.to_vec()),
            history: Vec::new(),
            bests: vec![run.start.to_vec()],
            values: Vec::new(),
            optimisation_time: Duration::ZERO,
            last: Instant::now(),
            bar: Meter::new(run.task.name(), budget, Unit::Renders, run.ctl.progress),
        };
        if let Some(c) = &run.ctl.resume {
            if let Progress::Adaptive {
                values,
                best_value,
                best_point,
                bests,
                ..
            } = &c.progress
            {
                rec.best = (best_value.unwrap_or(f64::INFINITY), best_point.clone());
                rec.history.clone_from(&c.history);
                rec.bests.clone_from(bests);
                rec.values.clone_from(values);
                rec.optimisation_time = Duration::from_secs_f64(c.optimisation_seconds);
                rec.bar.set_position(values.len());
            }
        }
        rec
    }

    /// Records the batch `points` with `values`: the best point, and a row of the history
    /// unless the batch is the start alone (returns whether a row was written).
    fn record(&mut self, points: Points<'_>, values: &[f64]) -> bool {
        let s = self.run.s;
        self.optimisation_time += self.last.elapsed();
        let (n, count) = (points.dim(), points.len());
        for (point, &v) in points.iter().zip(values) {
            if v.is_finite() && v < self.best.0 {
                self.best.0 = v;
                self.best.1.copy_from_slice(point);
            }
        }
        let before = self.values.len();
        let after = before + count;
        if before == 0 && after < self.budget {
            // The start, which the Minimizer evaluates first and alone: it counts for the best
            // point and the evaluations, and has no row of its own (a row is an iteration).
            self.bar.set_position(after);
            self.last = Instant::now();
            return false;
        }
        // The image error every eval_every x N evaluations (the paper loop's spacing), first
        // and last.
        let stride = s.eval_every.saturating_mul(s.samples).max(1);
        let measure =
            self.history.is_empty() || before / stride != after / stride || after >= self.budget;
        let image_mse = measure.then(|| {
            self.run
                .task
                .render(&self.best.1, s.seed, s.spp, s.view())
                .mse(self.run.reference)
        });
        let eval_renders = self.history.last().map_or(0, |r| r.eval_renders);
        let row = Row {
            iteration: self.history.len(),
            sigma: spread(points),
            loss: values.iter().sum::<f64>() / count.max(1) as f64,
            param_mse: self.run.task.param_mse_to(&self.best.1, &self.target),
            image_mse,
            renders: after,
            eval_renders: eval_renders + usize::from(image_mse.is_some()),
            seconds: self.optimisation_time.as_secs_f64(),
        };
        let message = format!("best {:.3e}  spread {:.3}", self.best.0, row.sigma);
        self.history.push(row);
        if n <= KEEP_BESTS_MAX_DIM {
            self.bests.push(self.best.1.clone());
        }
        let at = At {
            iterations: self.history.len(),
            renders: after,
            loss: self.best.0,
        };
        self.bar.update(at, message);
        self.last = Instant::now();
        true
    }

    /// Writes the checkpoint of the search so far.
    fn save(&self, search: &AskTell, finished: bool) {
        let state = match serde_json::to_value(search) {
            Ok(state) => state,
            Err(e) => {
                eprintln!("warning: the search's state cannot be saved ({e}); no checkpoint");
                return;
            }
        };
        let progress = Progress::Adaptive {
            state,
            values: self.values.clone(),
            best_value: self.best.0.is_finite().then_some(self.best.0),
            best_point: self.best.1.clone(),
            bests: self.bests.clone(),
        };
        let time = self.optimisation_time;
        self.run
            .saver
            .save(finished, progress, &self.history, &[], time);
    }
}

/// The spread of a batch's points: RMS per coordinate around their mean.
fn spread(points: Points<'_>) -> f64 {
    let (n, count) = (points.dim(), points.len());
    let mut centre = vec![0.0; n];
    for point in points.iter() {
        for (c, x) in centre.iter_mut().zip(point) {
            *c += x / count as f64;
        }
    }
    let squares: f64 = points
        .iter()
        .map(|p| {
            p.iter()
                .zip(&centre)
                .map(|(x, c)| (x - c).powi(2))
                .sum::<f64>()
        })
        .sum();
    (squares / (count * n).max(1) as f64).sqrt()
}
