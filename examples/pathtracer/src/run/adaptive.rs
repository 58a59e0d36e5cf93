//! `--method adaptive`: the library's [`plateau::Minimizer`] on the task's image loss.
//!
//! It gets what the paper loop gets and nothing tuned per task: a budget of N x iterations
//! evaluations (the task's Table 1), the task's sigma0 and box (if any), the run's seed, and
//! the same renderer seeds ([`super::Crn`]: with `fixed` every render uses the run's seed; with
//! `pair` every render of an iteration shares the seed the Minimizer gives it). The Minimizer
//! hands each iteration's points over at once; after each batch one row of the history is
//! written (its `loss` is the mean over the batch, its `sigma` the spread of the batch's points,
//! RMS per coordinate around their mean, its parameter and image errors those of the best point
//! so far, which is what the run returns).

use std::cell::{Cell, RefCell};
use std::time::{Duration, Instant};

use plateau::{Minimizer, Objective, Points};

use super::{progress_bar, Ended, Row, Settings};
use crate::render::Image;
use crate::report::Result;
use crate::tasks::{param_mse, Task};

/// How a run ended, its best point, its history, six snapshots for the progress strip and the
/// optimisation time: what both methods hand to the outputs.
pub(super) type Finished = (Ended, Vec<f64>, Vec<Row>, Vec<Vec<f64>>, Duration);

/// Runs the adaptive search; returns how it ended, the best point, the history, six snapshots
/// of the best point for the progress strip, and the optimisation time (the image-error renders
/// excluded).
pub(super) fn run<L>(
    task: &Task,
    s: &Settings,
    loss: &L,
    reference: &Image,
    start: &[f64],
    show_progress: bool,
) -> Result<Finished>
where
    L: Fn(&[f64], u64) -> f64,
{
    if s.budget_seconds.is_some() {
        return Err("a time budget (--budget) is not supported with --method adaptive".into());
    }
    let budget = s.samples * s.iterations;
    let objective = Recording {
        task,
        s,
        loss,
        reference,
        target: task.target(),
        budget,
        best: RefCell::new((f64::INFINITY, start.to_vec())),
        evaluations: Cell::new(0),
        history: RefCell::new(Vec::new()),
        bests: RefCell::new(vec![start.to_vec()]),
        optimisation_time: Cell::new(Duration::ZERO),
        last: Cell::new(Instant::now()),
        bar: progress_bar(task.name(), budget, show_progress),
    };
    let mut minimizer = Minimizer::new(&objective)
        .budget(budget)
        .sigma0(s.sigma0)
        .seed(s.seed);
    if let Some((lower, upper)) = task.bounds() {
        minimizer = minimizer.bounds(lower, upper);
    }
    let minimum = minimizer.run(start)?;
    objective.bar.finish_and_clear();
    let history = objective.history.into_inner();
    let bests = objective.bests.into_inner();
    // Six snapshots, evenly spaced over the iterations (the last is the returned point).
    let snapshots = if bests.len() <= 1 {
        vec![start.to_vec(); 6]
    } else {
        let last = bests.len() - 1;
        (0..6).map(|k| bests[k * last / 5].clone()).collect()
    };
    let mut snapshots = snapshots;
    snapshots[5] = minimum.x.clone();
    let ended = Ended {
        iterations: minimum.iterations,
        evaluations: minimum.evaluations,
        stopped_early: false,
    };
    Ok((
        ended,
        minimum.x,
        history,
        snapshots,
        objective.optimisation_time.get(),
    ))
}

/// The loss as an [`Objective`] that records a row of the history after every batch.
struct Recording<'a, L> {
    task: &'a Task,
    s: &'a Settings,
    loss: &'a L,
    reference: &'a Image,
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
    bar: indicatif::ProgressBar,
}

/// Above this many parameters the best point is not kept per iteration (the progress strip
/// then shows the start and the end).
const KEEP_BESTS_MAX_DIM: usize = 256;

impl<L: Fn(&[f64], u64) -> f64> Objective for &Recording<'_, L> {
    fn evaluate(&self, point: &[f64], seed: u64) -> f64 {
        (self.loss)(point, seed)
    }

    fn evaluate_batch(&self, points: Points<'_>, seeds: &[u64], out: &mut [f64]) {
        for ((point, &seed), o) in points.iter().zip(seeds).zip(out.iter_mut()) {
            *o = (self.loss)(point, seed);
        }
        self.record(points, out);
    }
}

impl<L> Recording<'_, L> {
    /// One row of the history for the batch `points` with values `values`.
    fn record(&self, points: Points<'_>, values: &[f64]) {
        let s = self.s;
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
        // The image error every eval_every x N evaluations (the paper loop's spacing), and last.
        let stride = s.eval_every.saturating_mul(s.samples).max(1);
        let measure = before == 0 || before / stride != after / stride || after >= self.budget;
        let image_mse = measure.then(|| {
            self.task
                .render(&best.1, s.seed, s.spp, s.view())
                .mse(self.reference)
        });
        let mut history = self.history.borrow_mut();
        let iteration = history.len();
        history.push(Row {
            iteration,
            sigma: spread,
            loss: mean_value,
            param_mse: param_mse(&best.1, &self.target),
            image_mse,
            seconds: t.as_secs_f64(),
        });
        if n <= KEEP_BESTS_MAX_DIM {
            self.bests.borrow_mut().push(best.1.clone());
        }
        self.bar
            .set_message(format!("best {:.3e}  spread {:.3}", best.0, spread));
        self.bar.inc(count as u64);
        self.last.set(Instant::now());
    }
}
