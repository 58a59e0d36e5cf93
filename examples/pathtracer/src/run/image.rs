//! `--method image`: the library's [`plateau_free::LeastSquares`] on the residual image
//! (rendered minus reference, per pixel and channel), with the smoothed Jacobian estimated on
//! the task's footprint ([`crate::tasks::Task::footprint`]: derived from the scene for
//! TEXTURE, every pixel on every parameter for the other tasks).
//!
//! It gets what the other methods get, nothing tuned per task: N x iterations renders, N / 2
//! antithetic pairs per Jacobian, the task's sigma0 and box, the run's seed and renderer
//! seeds ([`super::Crn`]). One row of the history per ask told (a Jacobian's pairs or a
//! step's point), one iteration of the method: its `renders` is the count of renders so far
//! (the axis on which methods of different iteration costs compare), `loss` and `image_mse`
//! the current point's image MSE, `sigma` the spread of the last Jacobian. No checkpoint: a
//! run of this method starts over.

use std::cell::Cell;
use std::time::{Duration, Instant};

use plateau_free::LeastSquares;

use super::adaptive::Finished;
use super::meter::{At, Meter, Unit};
use super::{Crn, Ended, Row, Run};
use crate::report::Result;

/// Above this many parameters the current point is not kept per row (the progress strip
/// then shows six evenly spaced points all the same).
const KEEP_MAX_DIM: usize = 256;

/// Runs the method; returns how it ended, its best point, the history, six snapshots and the
/// optimisation time (rendering included).
pub(super) fn run(run: &Run<'_>, render_time: &Cell<Duration>) -> Result<Finished> {
    let (task, s, start) = (run.task, run.s, run.start);
    if s.budget_seconds.is_some() || run.ctl.resume.is_some() {
        return Err("--method image supports neither a time budget nor --resume".into());
    }
    let view = s.view();
    let pattern = task.footprint(view)?;
    let budget = s.samples.saturating_mul(s.iterations);
    let mut options = LeastSquares::new(pattern)
        .budget(budget)
        .pairs((s.samples / 2).max(1))
        .sigma0(s.sigma0)
        .seed(s.seed);
    if let Some((lower, upper)) = task.bounds() {
        options = options.bounds(lower, upper);
    }
    let mut method = options.ask_tell(start)?;
    let reference = &run.reference.data;
    let m = reference.len();
    let target = task.target();
    let bar = Meter::new(task.name(), budget, Unit::Renders, run.ctl.progress);
    let clock = Instant::now();
    let (mut history, mut kept) = (Vec::new(), vec![start.to_vec()]);
    let mut outputs = Vec::new();
    while let Some(ask) = method.ask()? {
        outputs.resize(ask.len() * m, 0.0);
        for ((x, seed), out) in ask.iter().zip(outputs.chunks_exact_mut(m)) {
            let seed = match s.crn {
                Crn::Fixed => s.seed,
                Crn::Pair => seed,
            };
            let t = Instant::now();
            let image = task.render(x, seed, s.spp, view);
            render_time.set(render_time.get() + t.elapsed());
            for ((o, &v), &r) in out.iter_mut().zip(&image.data).zip(reference) {
                *o = f64::from(v) - f64::from(r);
            }
        }
        method.tell(&outputs)?;
        let mse = method.fun() / m as f64;
        history.push(Row {
            iteration: history.len(),
            sigma: method.sigma(),
            loss: mse,
            param_mse: task.param_mse_to(method.theta(), &target),
            image_mse: Some(mse),
            // Every render is the method's own; the image MSE is that of the point just
            // evaluated, so no render is spent on evaluation alone.
            renders: method.evaluations(),
            eval_renders: 0,
            seconds: clock.elapsed().as_secs_f64(),
        });
        if task.dim() <= KEEP_MAX_DIM {
            kept.push(method.theta().to_vec());
        }
        bar.update(
            At {
                iterations: history.len(),
                renders: method.evaluations(),
                loss: mse,
            },
            format!("image MSE {mse:.3e}  sigma {:.3}", method.sigma()),
        );
    }
    bar.finish();
    let best = method.finish()?;
    let last = kept.len() - 1;
    let mut snapshots: Vec<Vec<f64>> = (0..6).map(|k| kept[k * last / 5].clone()).collect();
    snapshots[5].clone_from(&best.x);
    let ended = Ended {
        iterations: history.len(),
        evaluations: best.nfev,
        renders: best.nfev,
        stopped_early: false,
        interrupted: false,
    };
    Ok((ended, best.x, history, snapshots, clock.elapsed()))
}
