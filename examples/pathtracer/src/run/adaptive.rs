//! `--method adaptive` and `--method polished`: the library's [`plateau_free::Minimizer`] on the
//! task's image loss (polished: its `Strategy::Paper` with `polish`).
//!
//! It gets what the paper loop gets and nothing tuned per task: a budget of N x iterations
//! evaluations (the task's Table 1), the task's sigma0 and box (if any), the run's seed, and
//! the same renderer seeds ([`super::Crn`]: with `fixed` every render uses the run's seed; with
//! `pair` every render of an iteration shares the seed the Minimizer gives it). The Minimizer
//! hands each iteration's points over at once; after each batch one row of the history is
//! written (its `loss` is the mean over the batch, its `sigma` the spread of the batch's points,
//! RMS per coordinate around their mean, its parameter and image errors those of the best point
//! so far, which is what the run returns).
//!
//! Checkpoints: the `Minimizer` keeps its state inside, so a checkpoint holds the value of
//! every evaluation so far instead. A resumed run starts the same `Minimizer` again and
//! answers its first evaluations from those values, without rendering (the search is a
//! function of the seed and the values alone, so it retraces its steps exactly), checks that
//! it asked for the very points it asked for before (a hash of their bits), and goes on. A
//! stop (Ctrl-C, `stop_after`) leaves the `Minimizer` by unwinding with a marker of ours
//! ([`std::panic::resume_unwind`], which prints nothing), caught in [`run`].

use std::cell::{Cell, RefCell};
use std::panic::{self, AssertUnwindSafe};
use std::time::{Duration, Instant};

use plateau_free::{Minimizer, Objective, Points, Stop as LibraryStop, Strategy};

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

/// Why the search was left by unwinding.
enum Stop {
    /// Ctrl-C or `stop_after`: the checkpoint is written.
    Interrupted,
    /// The replay of a checkpoint asked for other points.
    Diverged(String),
}

/// Runs the adaptive search; returns how it ended, the best point, the history, six snapshots
/// of the best point for the progress strip, and the optimisation time (the image-error renders
/// excluded).
pub(super) fn run<L>(run: &Run<'_>, loss: &L) -> Result<Finished>
where
    L: Fn(&[f64], u64) -> f64,
{
    let (task, s, start) = (run.task, run.s, run.start);
    if s.budget_seconds.is_some() {
        return Err("a time budget (--budget) is not supported with --method adaptive".into());
    }
    let budget = s.samples.saturating_mul(s.iterations);
    let mut objective = Recording {
        run,
        loss,
        target: task.target(),
        budget,
        best: RefCell::new((f64::INFINITY, start.to_vec())),
        evaluations: Cell::new(0),
        history: RefCell::new(Vec::new()),
        bests: RefCell::new(vec![start.to_vec()]),
        optimisation_time: Cell::new(Duration::ZERO),
        last: Cell::new(Instant::now()),
        bar: Meter::new(task.name(), budget, Unit::Renders, run.ctl.progress),
        log: RefCell::new(Vec::new()),
        points_hash: Cell::new(FNV_START),
        replay: Vec::new(),
        replay_hash: FNV_START,
        checkpoint_at: Cell::new(None),
        replayed_rows: Cell::new(0),
    };
    let mut finished = false;
    if let Some(c) = &run.ctl.resume {
        let Progress::Adaptive {
            values,
            points_hash,
            best_value,
            best_point,
            bests,
        } = &c.progress
        else {
            return Err("the checkpoint is of the paper's loop, this run is adaptive".into());
        };
        objective.replay.clone_from(values);
        objective.replay_hash = *points_hash;
        *objective.best.get_mut() = (best_value.unwrap_or(f64::INFINITY), best_point.clone());
        objective.evaluations.set(values.len());
        *objective.history.get_mut() = c.history.clone();
        *objective.bests.get_mut() = bests.clone();
        objective
            .optimisation_time
            .set(Duration::from_secs_f64(c.optimisation_seconds));
        objective.bar.set_position(values.len());
        finished = c.finished;
    }
    objective.schedule_checkpoint();
    let mut minimizer = Minimizer::new(&objective)
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
    let ran = panic::catch_unwind(AssertUnwindSafe(|| minimizer.run(start)));
    drop(minimizer);
    let mut stalled = false;
    let (iterations, evaluations, best, interrupted) = match ran {
        Ok(minimum) => {
            let minimum = minimum?;
            finished = true;
            stalled = minimum.stop == LibraryStop::Stalled;
            (minimum.iterations, minimum.evaluations, minimum.x, false)
        }
        Err(payload) => match payload.downcast::<Stop>() {
            Ok(stop) => match *stop {
                Stop::Interrupted => {
                    let history = objective.history.borrow().len();
                    let best = objective.best.borrow().1.clone();
                    (history, objective.evaluations.get(), best, true)
                }
                Stop::Diverged(why) => return Err(why.into()),
            },
            Err(other) => panic::resume_unwind(other),
        },
    };
    if !interrupted {
        // At the end (also when a finished checkpoint was replayed to its end).
        objective.save(finished);
    }
    objective.bar.finish();
    let history = objective.history.into_inner();
    let bests = objective.bests.into_inner();
    // Six snapshots, evenly spaced over the iterations (the last is the returned point).
    let mut snapshots = if bests.len() <= 1 {
        vec![start.to_vec(); 6]
    } else {
        let last = bests.len() - 1;
        (0..6).map(|k| bests[k * last / 5].clone()).collect()
    };
    snapshots[5] = best.clone();
    let ended = Ended {
        iterations,
        evaluations,
        renders: objective.log.borrow().len(),
        stopped_early: stalled,
        interrupted,
    };
    Ok((
        ended,
        best,
        history,
        snapshots,
        objective.optimisation_time.get(),
    ))
}

/// FNV-1a's starting value.
const FNV_START: u64 = 0xcbf2_9ce4_8422_2325;

/// The loss as an [`Objective`] that records a row of the history after every batch, writes
/// the checkpoints and stops when asked.
struct Recording<'a, L> {
    run: &'a Run<'a>,
    loss: &'a L,
    /// The task's target, made once.
    target: Vec<f64>,
    budget: usize,
    /// The best value and point so far.
    best: RefCell<(f64, Vec<f64>)>,
    evaluations: Cell<usize>,
    history: RefCell<Vec<Row>>,
    /// The best point after every iteration (small tasks only; else the start alone).
    bests: RefCell<Vec<Vec<f64>>>,
    optimisation_time: Cell<Duration>,
    last: Cell<Instant>,
    bar: Meter,
    /// Every value so far, in order (the checkpoint's).
    log: RefCell<Vec<f64>>,
    /// FNV-1a of every point so far.
    points_hash: Cell<u64>,
    /// The values of the checkpoint being continued, answered without rendering.
    replay: Vec<f64>,
    /// The checkpoint's hash of its points, checked when the replay ends.
    replay_hash: u64,
    /// The iteration count at which the next checkpoint is due.
    checkpoint_at: Cell<Option<usize>>,
    /// The checkpoint's rows whose render counts the replay has derived.
    replayed_rows: Cell<usize>,
}

/// Above this many parameters the best point is not kept per iteration (the progress strip
/// then shows the start and the end).
const KEEP_BESTS_MAX_DIM: usize = 256;

impl<L: Fn(&[f64], u64) -> f64> Objective for &Recording<'_, L> {
    fn evaluate(&self, point: &[f64], seed: u64) -> f64 {
        let mut out = [0.0];
        self.values(std::iter::once(point), &[seed], &mut out);
        out[0]
    }

    fn evaluate_batch(&self, points: Points<'_>, seeds: &[u64], out: &mut [f64]) {
        let before = self.log.borrow().len();
        if self.values(points.iter(), seeds, out) {
            self.record(points, out);
        } else {
            self.recount(before, self.log.borrow().len());
        }
    }
}

impl<L: Fn(&[f64], u64) -> f64> Recording<'_, L> {
    /// The values at `points` into `out`: from the replayed checkpoint while it lasts, else
    /// rendered and logged. Returns whether they are new (to be recorded).
    fn values<'p>(
        &self,
        points: impl Iterator<Item = &'p [f64]>,
        seeds: &[u64],
        out: &mut [f64],
    ) -> bool {
        let position = self.log.borrow().len();
        let mut hash = self.points_hash.get();
        let mut count = 0;
        let replaying = position < self.replay.len();
        for ((point, &seed), o) in points.zip(seeds).zip(out.iter_mut()) {
            for x in point {
                hash = fnv1a_continue(hash, &x.to_bits().to_le_bytes());
            }
            *o = match self.replay.get(position + count) {
                Some(&v) => v,
                None if replaying => stop(Stop::Diverged(
                    "checkpoint: the adaptive search asked for more points than the run it continues (another build?)".into(),
                )),
                None => (self.loss)(point, seed),
            };
            count += 1;
        }
        self.points_hash.set(hash);
        self.log.borrow_mut().extend_from_slice(&out[..count]);
        if replaying && position + count == self.replay.len() {
            if hash != self.replay_hash {
                stop(Stop::Diverged(
                    "checkpoint: the adaptive search asked for other points than the run it continues (another build?)".into(),
                ));
            }
            // The replay is not the run's time.
            self.last.set(Instant::now());
        }
        !replaying
    }

    /// The render counts of the checkpoint's row for the replayed batch of evaluations
    /// `before..after`, derived as [`Self::record`] counts them (a checkpoint of a build that
    /// did not count has none; one that did gets the same numbers again).
    fn recount(&self, before: usize, after: usize) {
        if before == 0 && after < self.budget {
            return; // The start alone: no row, as in `record`.
        }
        let row = self.replayed_rows.get();
        let mut history = self.history.borrow_mut();
        let eval_renders = row.checked_sub(1).map_or(0, |k| history[k].eval_renders);
        let Some(r) = history.get_mut(row) else {
            drop(history);
            stop(Stop::Diverged(
                "checkpoint: the adaptive search made more iterations than the run it continues (another build?)".into(),
            ))
        };
        r.renders = after;
        r.eval_renders = eval_renders + usize::from(r.image_mse.is_some());
        self.replayed_rows.set(row + 1);
    }

    /// One row of the history for the batch `points` with values `values`; then the
    /// checkpoint if due, and the stop if asked.
    fn record(&self, points: Points<'_>, values: &[f64]) {
        let s = self.run.s;
        let t = self.optimisation_time.get() + self.last.get().elapsed();
        self.optimisation_time.set(t);
        let n = points.dim();
        let count = points.len();
        let mut best = self.best.borrow_mut();
        for (point, &v) in points.iter().zip(values) {
            if v.is_finite() && v < best.0 {
                best.0 = v;
                best.1.copy_from_slice(point);
            }
        }
        let mean_value = values.iter().sum::<f64>() / count.max(1) as f64;
        let mut centre = vec![0.0; n];
        for point in points.iter() {
            for (c, x) in centre.iter_mut().zip(point) {
                *c += x / count as f64;
            }
        }
        let spread = (points
            .iter()
            .map(|p| {
                p.iter()
                    .zip(&centre)
                    .map(|(x, c)| (x - c).powi(2))
                    .sum::<f64>()
            })
            .sum::<f64>()
            / (count * n).max(1) as f64)
            .sqrt();
        let before = self.evaluations.get();
        let after = before + count;
        self.evaluations.set(after);
        if before == 0 && after < self.budget {
            // The start, which the Minimizer evaluates first and alone: it counts for the best
            // point and the evaluations, and has no row of its own (a row is an iteration).
            drop(best);
            self.bar.set_position(self.log.borrow().len());
            self.last.set(Instant::now());
            return;
        }
        // The image error every eval_every x N evaluations (the paper loop's spacing), first
        // and last.
        let stride = s.eval_every.saturating_mul(s.samples).max(1);
        let first_row = self.history.borrow().is_empty();
        let measure = first_row || before / stride != after / stride || after >= self.budget;
        let image_mse = measure.then(|| {
            self.run
                .task
                .render(&best.1, s.seed, s.spp, s.view())
                .mse(self.run.reference)
        });
        let mut history = self.history.borrow_mut();
        let iteration = history.len();
        let eval_renders = history.last().map_or(0, |r| r.eval_renders);
        history.push(Row {
            iteration,
            sigma: spread,
            loss: mean_value,
            param_mse: self.run.task.param_mse_to(&best.1, &self.target),
            image_mse,
            // Every value logged was rendered once (by this run or the one it continues).
            renders: self.log.borrow().len(),
            eval_renders: eval_renders + usize::from(image_mse.is_some()),
            seconds: t.as_secs_f64(),
        });
        if n <= KEEP_BESTS_MAX_DIM {
            self.bests.borrow_mut().push(best.1.clone());
        }
        let done = history.len();
        self.bar.update(
            At {
                iterations: done,
                renders: self.log.borrow().len(),
                loss: best.0,
            },
            format!("best {:.3e}  spread {:.3}", best.0, spread),
        );
        drop((best, history));
        if after < self.budget {
            if self.run.stop_requested(done) {
                self.save(false);
                stop(Stop::Interrupted);
            }
            if self.checkpoint_at.get().is_some_and(|k| done >= k) {
                self.save(false);
                self.schedule_checkpoint();
            }
        }
        self.last.set(Instant::now());
    }
}

impl<L> Recording<'_, L> {
    /// Sets when the next checkpoint is due, from the cadence and the cost so far.
    fn schedule_checkpoint(&self) {
        let done = self.history.borrow().len();
        let per_iteration = self.optimisation_time.get().as_secs_f64() / done.max(1) as f64;
        self.checkpoint_at.set(
            self.run
                .ctl
                .every
                .next_after(done, per_iteration)
                .map(|k| done + k),
        );
    }

    /// Writes the checkpoint of the search so far.
    fn save(&self, finished: bool) {
        let best = self.best.borrow();
        let progress = Progress::Adaptive {
            values: self.log.borrow().clone(),
            points_hash: self.points_hash.get(),
            best_value: best.0.is_finite().then_some(best.0),
            best_point: best.1.clone(),
            bests: self.bests.borrow().clone(),
        };
        self.run.saver.save(
            finished,
            progress,
            &self.history.borrow(),
            &[],
            self.optimisation_time.get(),
        );
    }
}

/// Leaves the search by unwinding with `why` (no panic message: `resume_unwind` skips the
/// hook).
fn stop(why: Stop) -> ! {
    panic::resume_unwind(Box::new(why))
}

/// FNV-1a over `bytes`, continuing from `hash`.
fn fnv1a_continue(hash: u64, bytes: &[u8]) -> u64 {
    bytes.iter().fold(hash, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}
