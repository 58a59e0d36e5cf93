//! One optimisation of a task: the reference, the method, its progress, and the outputs.
//!
//! [`optimize`] reads as its steps: render the reference and the start, build the loss, run
//! the method under the library's [`Driver`] (its interrupt, observers and checkpoint: the
//! run's lifecycle is the library's), measure the end, write the files. Every method is one
//! ask-and-tell run for the driver, wrapped with the path tracer's record in `driven.rs`
//! (what it records after each tell in `record.rs`): the paper's loop and the baselines in
//! `paper.rs`, the library's adaptive search (and polished loop) in `adaptive.rs`, the image
//! method in `image.rs`. What a run can be told is in `settings.rs`, what it yields in
//! `outcome.rs`, the files it writes in `outputs.rs`, its progress display in `meter.rs`, the
//! time-budget planner in `budget.rs`, what an earlier run left in `earlier.rs`, the stop rule
//! replayed on a finished run in `stall_replay.rs`, Ctrl-C in `interrupt.rs`.

mod adaptive;
mod budget;
pub mod checkpoint;
mod driven;
mod earlier;
mod image;
pub mod interrupt;
mod meter;
mod outcome;
mod outputs;
mod paper;
mod record;
mod settings;
mod stall_replay;

use std::cell::Cell;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use plateau_free::lifecycle::{Driver, Interrupt, Observer, Progress as Seen};

pub use budget::{plan_for_budget, plan_with_render_time};
pub use checkpoint::{Checkpoint, CheckpointError, Every, Progress};
pub use earlier::Earlier;
pub use meter::{LINE_SECONDS, LINE_SECONDS_VAR};
pub use outcome::{loop_renders, renders_to, write_history, Outcome, Row, Summary};
pub use paper::optimizer;
pub use settings::{
    eval_every, Crn, Method, Settings, CURVE_POINTS, MAX_SAMPLES, MAX_SCALE, POLISH, POLISH_BEFORE,
};
pub use stall_replay::{replay as replay_stall, Replayed};

use crate::render::Image;
use crate::report::Result;
use crate::tasks::Task;
use driven::{Ctx, Finished, Tracked};
use meter::{Meter, Unit};

/// Runs one optimisation of `task`, writing its outputs into `out` if given (no checkpoint,
/// never interrupted: [`optimize_with`] has those).
pub fn optimize(
    task: &Task,
    s: &Settings,
    out: Option<&Path>,
    show_progress: bool,
) -> Result<Outcome> {
    optimize_with(
        task,
        s,
        Control {
            out,
            progress: show_progress,
            ..Control::default()
        },
    )
}

/// How a run is kept and stopped: its outputs, its checkpoint and how often, the checkpoint
/// it continues, when to stop early.
#[derive(Default)]
pub struct Control<'a> {
    /// The directory of the outputs, if any.
    pub out: Option<&'a Path>,
    /// The checkpoint file to write, if any (the command line's: `<out>/checkpoint.json`).
    pub checkpoint: Option<PathBuf>,
    /// How often to write it (besides at the end and when interrupted).
    pub every: Every,
    /// A loaded checkpoint to continue from, already checked against the task and the
    /// settings ([`Checkpoint::check_matches`]); the run's settings must be its `settings`.
    pub resume: Option<Checkpoint>,
    /// The settings the command line asked for, kept in the checkpoint to compare with on
    /// `--resume` (they differ from the run's after `--budget`'s plan) [default: the run's].
    pub requested: Option<Settings>,
    /// Stop as Ctrl-C would, once this many iterations are done (tests, and the hidden
    /// `--stop-after`).
    pub stop_after: Option<usize>,
    /// Whether to show a progress bar.
    pub progress: bool,
}

/// Runs one optimisation of `task` under `ctl`, driven by the library's [`Driver`]: with a
/// checkpoint every so often and at the end (the library's), continuing `ctl.resume`'s run if
/// given (else a checkpoint at the path is replaced), stopping after the current iteration
/// on Ctrl-C ([`interrupt::requested`]) or at `ctl.stop_after`. An interrupted run writes its
/// checkpoint and its outputs for the iterations done, and says so in its summary
/// (`interrupted: true`); continued from that checkpoint it ends bit for bit as the run left
/// alone (timings aside).
pub fn optimize_with(task: &Task, s: &Settings, ctl: Control<'_>) -> Result<Outcome> {
    let view = s.view();
    let (start, target) = (task.start(), task.target());
    let progress = match s.method {
        Method::Adaptive | Method::Polished => {
            Progress::Adaptive(Box::new(adaptive::search(task, s, &start)?))
        }
        Method::Image => Progress::Image(Box::new(image::least_squares(task, s, &start)?)),
        Method::Plateau | Method::Fd | Method::Spsa => paper::progress(task, s, &start)?,
    };
    let reference = task.render(&target, s.seed, s.spp, view);
    let initial = task.render(&start, s.seed, s.spp, view);
    let (render_time, renders) = (Cell::new(Duration::ZERO), Cell::new(0));
    let loss = image_loss(task, s, &reference, &render_time, &renders);
    let ctx = Ctx {
        task,
        s,
        reference: &reference,
        start: &start,
        target: target.clone(),
        loss: &loss,
        renders: &renders,
        render_time: &render_time,
    };
    let fresh = Tracked::new(&ctx, progress, ctl.requested.as_ref().unwrap_or(s));
    let Finished {
        ended,
        theta: final_theta,
        history,
        snapshots,
        time: optimisation_time,
    } = drive(&ctx, fresh, &ctl)?;

    let final_image = task.render(&final_theta, s.seed, s.spp, view);
    let mut summary = summarize(
        task,
        s,
        &ended,
        &final_theta,
        [&reference, &initial, &final_image],
        [optimisation_time, render_time.get()],
    );
    // The strip's frames are rendered only when the outputs are written.
    let strip = if ctl.out.is_some() && snapshots.len() > 1 {
        snapshots.len()
    } else {
        0
    };
    count_renders(
        &mut summary,
        &history,
        strip,
        task.paper().map(|p| p.param_mse),
    );
    let outcome = Outcome { summary, history };
    if let Some(dir) = ctl.out {
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

/// Runs `fresh` under the library's driver: Ctrl-C and `stop_after` end it at the next turn,
/// the meter shows it, its checkpoint (if any) is written when due
/// and at the end. The asked points are rendered one after the other, each render on the
/// renderer's own threads.
fn drive(ctx: &Ctx<'_>, fresh: Tracked<'_>, ctl: &Control<'_>) -> Result<Finished> {
    let (task, s) = (ctx.task, ctx.s);
    let stop = Interrupt::new();
    let (total, unit) = match s.method {
        Method::Plateau | Method::Fd | Method::Spsa => (s.iterations, Unit::Iterations),
        _ => (s.samples.saturating_mul(s.iterations), Unit::Renders),
    };
    let mut driver = Driver::new()
        .interrupt(stop.clone())
        .observe(Stopper {
            stop,
            after: ctl.stop_after,
        })
        .observe(Meter::new(task.name(), total, unit, ctl.progress));
    if let Some(path) = &ctl.checkpoint {
        if ctl.resume.is_none() {
            // A new run: the file of an earlier one is replaced, not continued.
            let _ = std::fs::remove_file(path);
        }
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir)?;
        }
        driver = driver.checkpoint(ctl.every.checkpoint(path));
    }
    let image = s.method == Method::Image;
    let finished = driver.run(fresh, |_, ask, out| {
        if image {
            image::residuals(ctx, ask, out);
        } else {
            for ((x, seed), value) in ask.iter().zip(out.iter_mut()) {
                *value = (ctx.loss)(x, seed);
            }
        }
        Ok::<(), plateau_free::Error>(())
    });
    match finished {
        // The last write failed (a full disk): the run is whole, its outputs still count.
        Err(failure) if matches!(failure.error, plateau_free::Error::Checkpoint { .. }) => {
            let Some(result) = failure.result else {
                return Err(failure.error.into());
            };
            eprintln!("warning: {}", failure.error);
            Ok(*result)
        }
        finished => finished.map_err(|failure| failure.error.into()),
    }
}

/// Asks the driver to stop the run after the current iteration, on Ctrl-C or once `after`
/// iterations are done.
struct Stopper {
    stop: Interrupt,
    after: Option<usize>,
}

impl Observer for Stopper {
    fn observe(&mut self, p: &Seen) {
        if interrupt::requested() || self.after.is_some_and(|k| p.iteration >= k) {
            self.stop.trigger();
        }
    }
}

/// The objective: the image MSE of a render at `theta` against `reference`, with the seed
/// [`Crn`] picks; the time spent rendering accumulates in `render_time`, the renders are
/// counted in `renders`.
fn image_loss<'a>(
    task: &'a Task,
    s: &'a Settings,
    reference: &'a Image,
    render_time: &'a Cell<Duration>,
    renders: &'a Cell<usize>,
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
        renders.set(renders.get() + 1);
        image.mse(reference)
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
        renders: run.renders,
        renders_to_paper: None,
        evaluation_renders: 0,
        reference_renders: 0,
        initial_param_mse: task.param_mse_to(&start, &target),
        initial_image_mse: initial.mse(reference),
        param_mse: task.param_mse_to(final_theta, &target),
        image_mse: final_image.mse(reference),
        image_mse_other_seed,
        seconds_per_iteration: seconds_total / done,
        render_seconds_per_iteration: render_seconds / done,
        overhead_seconds_per_iteration: (seconds_total - render_seconds).max(0.0) / done,
        seconds_total,
        stopped_early: run.stopped_early,
        interrupted: run.interrupted,
        polish: (s.method == Method::Polished).then_some(s.polish),
        final_theta: (task.dim() <= 16).then(|| final_theta.to_vec()),
        target_theta: (task.dim() <= 16).then(|| target.clone()),
    }
}

/// The render counts of a summary besides the objective's: the paper's parameter MSE first
/// reached (`paper`), the evaluation-only renders (the history's image MSE, the initial and
/// the final image, the final image at another seed, `strip` frames), the reference renders
/// (the target at the run's seed and at another).
fn count_renders(summary: &mut Summary, history: &[Row], strip: usize, paper: Option<f64>) {
    summary.renders_to_paper = outcome::renders_to(history, paper);
    let in_loop = history.last().map_or(0, |r| r.eval_renders);
    summary.evaluation_renders = in_loop + 3 + strip;
    summary.reference_renders = 2;
}

/// How a run's loop ended: its iterations, the evaluations of the loss, the renders of the
/// objective, whether a time budget stopped it, whether it was interrupted (to be continued).
struct Ended {
    iterations: usize,
    evaluations: usize,
    renders: usize,
    stopped_early: bool,
    interrupted: bool,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tasks;

    /// SHADOW at a sixteenth of the pixels and 4 spp, the image error never rendered: the
    /// task and the settings of the quick runs below.
    fn quick_shadow() -> (Task, Settings) {
        let task = tasks::by_name("shadow").expect("the SHADOW task exists");
        let mut s = Settings::defaults(&task);
        s.scale = Some(0.25);
        s.spp = 4;
        s.eval_every = usize::MAX;
        (task, s)
    }

    /// A quick SHADOW run that left the plateau. The paper reaches 1.81e-3 at full
    /// resolution; a sixteenth of the pixels is noisier, so ask for an order of magnitude
    /// less than the start's 1.625 and well under 1e-2.
    fn assert_converged(method: &str, m: &Summary) {
        assert!(
            m.param_mse < 1e-2,
            "{method}: param MSE {} (from {})",
            m.param_mse,
            m.initial_param_mse
        );
    }

    /// SHADOW from the paper's start (the shadow far from the target's, a plateau for small
    /// moves): the plateau-free gradient leaves the plateau, finite differences stay stuck.
    #[test]
    fn shadow_converges_from_its_plateau_and_finite_differences_stay_stuck() {
        let (task, mut s) = quick_shadow();
        let ours = optimize(&task, &s, None, false).expect("the run succeeds");
        assert_converged("plateau-free gradient", &ours.summary);

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
        let (task, mut s) = quick_shadow();
        s.iterations = 150;
        s.method = Method::Adaptive;
        let run = optimize(&task, &s, None, false).expect("the run succeeds");
        let m = &run.summary;
        assert_converged("adaptive search", m);
        assert!(
            m.evaluations <= s.samples * s.iterations,
            "{} evaluations",
            m.evaluations
        );
        assert_eq!(run.history.len(), m.iterations);
        assert!(run.history.last().is_some_and(|r| r.image_mse.is_some()));
    }

    /// `--method image` on TEXTURE (1 spp, 400 renders): the residual image on the footprint
    /// brings the parameter error down by more than an order of magnitude within the budget.
    #[test]
    fn the_image_method_recovers_the_texture_within_its_renders() {
        let task = tasks::by_name("texture").expect("the TEXTURE task exists");
        let mut s = Settings::defaults(&task);
        s.method = Method::Image;
        s.spp = 1;
        s.samples = 8;
        s.iterations = 50;
        s.eval_every = usize::MAX;
        let run = optimize(&task, &s, None, false).expect("the run succeeds");
        let m = &run.summary;
        assert!(
            m.param_mse < 0.1 * m.initial_param_mse,
            "param MSE {} from {}",
            m.param_mse,
            m.initial_param_mse
        );
        assert!(m.evaluations <= 400, "{} renders", m.evaluations);
    }
}
