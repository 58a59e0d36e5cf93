//! One optimisation of a task: the reference, the loop (plateau-free gradient or a
//! baseline), the progress bar, and the outputs.
//!
//! [`optimize`] reads as its steps: render the reference and the start, build the loss, the
//! estimator and the optimiser, run the loop under a [`Recorder`], measure the end, write the
//! files. What a run can be told is in `settings.rs`, what it yields in `outcome.rs`, the
//! files it writes in `outputs.rs`, the time-budget planner in `budget.rs`.

mod adaptive;
mod budget;
mod outcome;
mod outputs;
mod settings;

use std::cell::Cell;
use std::ops::ControlFlow;
use std::path::Path;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};
use plateau::baseline::{FiniteDifference, Spsa};
use plateau::{Adam, Annealer, GradientEstimator, Optimizer, PlateauFreeGradient, Seeded, Step};

pub use budget::{plan_for_budget, plan_with_render_time};
pub use outcome::{write_history, Outcome, Row, Summary};
pub use settings::{eval_every, Crn, Method, Settings, CURVE_POINTS};

use crate::render::Image;
use crate::report::Result;
use crate::tasks::{param_mse, Task};

/// Runs one optimisation of `task`, writing its outputs into `out` if given.
pub fn optimize(
    task: &Task,
    s: &Settings,
    out: Option<&Path>,
    show_progress: bool,
) -> Result<Outcome> {
    let view = s.view();
    let (start, target) = (task.start(), task.target());
    let reference = task.render(&target, s.seed, s.spp, view);
    let initial = task.render(&start, s.seed, s.spp, view);

    let render_time = Cell::new(Duration::ZERO);
    let loss = image_loss(task, s, &reference, &render_time);
    let (ended, final_theta, history, snapshots, optimisation_time) =
        if s.method == Method::Adaptive {
            adaptive::run(task, s, &loss, &reference, &start, show_progress)?
        } else {
            let mut estimator = estimator(s, &loss)?;
            let mut optimizer = optimizer(task, s)?;
            let mut recorder = Recorder::new(task, s, &reference, &start, show_progress);
            let run =
                optimizer.minimize_with(&mut *estimator, &start, |step| recorder.observe(step))?;
            drop(estimator);
            let (history, snapshots, optimisation_time) = recorder.finish();
            let final_theta = run
                .last_theta()
                .map_or_else(|| start.clone(), <[f64]>::to_vec);
            let ended = Ended {
                iterations: run.iterations(),
                evaluations: run.evaluations,
                stopped_early: run.stopped_early,
            };
            (ended, final_theta, history, snapshots, optimisation_time)
        };

    let final_image = task.render(&final_theta, s.seed, s.spp, view);
    let summary = summarize(
        task,
        s,
        &ended,
        &final_theta,
        [&reference, &initial, &final_image],
        [optimisation_time, render_time.get()],
    );
    let outcome = Outcome { summary, history };
    if let Some(dir) = out {
        outputs::write_outputs(
            task,
            s,
            &outcome,
            [&reference, &initial, &final_image],
            &snapshots,
            dir,
        )?;
    }
    Ok(outcome)
}

/// The objective: the image MSE of a render at `theta` against `reference`, with the seed
/// [`Crn`] picks; the time spent rendering accumulates in `render_time`.
fn image_loss<'a>(
    task: &'a Task,
    s: &'a Settings,
    reference: &'a Image,
    render_time: &'a Cell<Duration>,
) -> impl Fn(&[f64], u64) -> f64 + 'a {
    let view = s.view();
    move |theta: &[f64], pair_seed: u64| {
        let seed = match s.crn {
            Crn::Fixed => s.seed,
            Crn::Pair => pair_seed,
        };
        let t = Instant::now();
        let image = task.render(theta, seed, s.spp, view);
        render_time.set(render_time.get() + t.elapsed());
        image.mse(reference)
    }
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
        Method::Adaptive => unreachable!("the adaptive search has no gradient estimator"),
    })
}

/// Adam (projected onto the task's box, if it has one) under the paper's annealing schedule
/// or, for the ablation, a constant sigma.
fn optimizer(task: &Task, s: &Settings) -> Result<Optimizer> {
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
    Ok(Optimizer::new(adam, annealer).record_theta(false))
}

/// What the loop records after each iteration: a row of the history, six snapshots of theta
/// for the progress strip, the optimisation time (the image-error renders excluded), the
/// progress bar; and whether the time budget is spent.
struct Recorder<'a> {
    task: &'a Task,
    s: &'a Settings,
    reference: &'a Image,
    target: Vec<f64>,
    snapshot_at: Vec<usize>,
    snapshots: Vec<Vec<f64>>,
    history: Vec<Row>,
    optimisation_time: Duration,
    last: Instant,
    bar: ProgressBar,
}

impl<'a> Recorder<'a> {
    fn new(
        task: &'a Task,
        s: &'a Settings,
        reference: &'a Image,
        start: &[f64],
        show_progress: bool,
    ) -> Self {
        Recorder {
            task,
            s,
            reference,
            target: task.target(),
            snapshot_at: (0..6)
                .map(|k| k * s.iterations.saturating_sub(1) / 5)
                .collect(),
            snapshots: vec![start.to_vec()],
            history: Vec::with_capacity(s.iterations),
            optimisation_time: Duration::ZERO,
            bar: progress_bar(task.name(), s.iterations, show_progress),
            last: Instant::now(),
        }
    }

    /// The loop's observer: records `step`, and stops the run once the budget is spent.
    fn observe(&mut self, step: &Step<'_>) -> ControlFlow<()> {
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
        self.history.push(Row {
            iteration: step.iteration,
            sigma: step.sigma,
            loss: step.estimate.mean_value,
            param_mse: param_mse(step.theta, &self.target),
            image_mse,
            seconds,
        });
        self.bar.set_message(format!(
            "loss {:.3e}  sigma {:.3}",
            step.estimate.mean_value, step.sigma
        ));
        self.bar.inc(1);
        let over_budget = s.budget_seconds.is_some_and(|b| seconds >= b);
        self.last = Instant::now();
        if over_budget {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    }

    /// The history, the snapshots and the optimisation time.
    fn finish(self) -> (Vec<Row>, Vec<Vec<f64>>, Duration) {
        self.bar.finish_and_clear();
        (self.history, self.snapshots, self.optimisation_time)
    }
}

/// The summary of a finished run: its settings, errors at the start and the end (the end
/// also against a render with a seed the run never used), and where the time went
/// (`times`: optimisation, of which rendering).
fn summarize(
    task: &Task,
    s: &Settings,
    run: &Ended,
    final_theta: &[f64],
    [reference, initial, final_image]: [&Image; 3],
    [optimisation_time, render_time]: [Duration; 2],
) -> Summary {
    let (start, target) = (task.start(), task.target());
    let view = s.view();
    let other_seed = s.seed.wrapping_add(0x5EED);
    let image_mse_other_seed = task
        .render(final_theta, other_seed, s.spp, view)
        .mse(&task.render(&target, other_seed, s.spp, view));
    let done = run.iterations.max(1) as f64;
    let seconds_total = optimisation_time.as_secs_f64();
    let render_seconds = render_time.as_secs_f64();
    Summary {
        task: task.name().into(),
        method: s.method,
        sampling: s.sampling,
        antithetic: s.antithetic,
        anneal: s.anneal,
        crn: s.crn,
        iterations: run.iterations,
        samples: s.samples,
        spp: s.spp,
        sigma0: s.sigma0,
        lr: s.lr,
        seed: s.seed,
        width: reference.width,
        height: reference.height,
        dim: task.dim(),
        evaluations: run.evaluations,
        initial_param_mse: param_mse(&start, &target),
        initial_image_mse: initial.mse(reference),
        param_mse: param_mse(final_theta, &target),
        image_mse: final_image.mse(reference),
        image_mse_other_seed,
        seconds_per_iteration: seconds_total / done,
        render_seconds_per_iteration: render_seconds / done,
        overhead_seconds_per_iteration: (seconds_total - render_seconds).max(0.0) / done,
        seconds_total,
        stopped_early: run.stopped_early,
        final_theta: (task.dim() <= 16).then(|| final_theta.to_vec()),
        target_theta: (task.dim() <= 16).then(|| target.clone()),
    }
}

/// How a run's loop ended: its iterations, the evaluations of the loss, and whether a time
/// budget stopped it.
struct Ended {
    iterations: usize,
    evaluations: usize,
    stopped_early: bool,
}

/// The progress bar of a run (hidden unless `show`).
fn progress_bar(name: &str, iterations: usize, show: bool) -> ProgressBar {
    if !show {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(iterations as u64);
    let style = ProgressStyle::with_template(
        "{prefix:>10} [{elapsed_precise}] {bar:32} {pos}/{len} {msg} (ETA {eta})",
    )
    .unwrap_or_else(|_| ProgressStyle::default_bar());
    bar.set_style(style);
    bar.set_prefix(name.to_string());
    bar
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tasks;

    /// paper's start (the shadow far from the target's, a plateau for small moves).
    #[test]
    fn shadow_converges_from_its_plateau_and_finite_differences_stay_stuck() {
        let task = tasks::by_name("shadow").expect("the SHADOW task exists");
        let mut s = Settings::defaults(&task);
        s.scale = Some(0.25);
        s.spp = 4;
        s.eval_every = usize::MAX;
        let ours = optimize(&task, &s, None, false).expect("the run succeeds");
        let m = &ours.summary;
        // The paper reaches 1.81e-3 at full resolution; a sixteenth of the pixels is noisier,
        // so ask for an order of magnitude less than the start's 1.625 and well under 1e-2.
        assert!(
            m.param_mse < 1e-2,
            "plateau-free gradient: param MSE {} (from {})",
            m.param_mse,
            m.initial_param_mse
        );

        s.method = Method::Fd;
        let fd = optimize(&task, &s, None, false).expect("the run succeeds");
        // On the plateau a small-step difference sees nothing: the parameters barely move.
        assert!(
            fd.summary.param_mse > 0.5 * fd.summary.initial_param_mse,
            "finite differences should stay stuck: param MSE {} (from {})",
            fd.summary.param_mse,
            fd.summary.initial_param_mse
        );
    }

    /// `--method adaptive` (the library's Minimizer) leaves SHADOW's plateau too, within the
    /// paper loop's evaluations (here 2 x 150 = 300), with one history row per iteration.
    #[test]
    fn the_adaptive_search_converges_on_shadow_within_the_loops_evaluations() {
        let task = tasks::by_name("shadow").expect("the SHADOW task exists");
        let mut s = Settings::defaults(&task);
        s.scale = Some(0.25);
        s.spp = 4;
        s.iterations = 150;
        s.eval_every = usize::MAX;
        s.method = Method::Adaptive;
        let run = optimize(&task, &s, None, false).expect("the run succeeds");
        let m = &run.summary;
        assert!(
            m.param_mse < 1e-2,
            "adaptive search: param MSE {} (from {})",
            m.param_mse,
            m.initial_param_mse
        );
        assert!(
            m.evaluations <= s.samples * s.iterations,
            "{} evaluations",
            m.evaluations
        );
        assert_eq!(run.history.len(), m.iterations);
        assert!(run.history.last().is_some_and(|r| r.image_mse.is_some()));
    }
}
