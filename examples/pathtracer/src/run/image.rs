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
//! the current point's image MSE, `sigma` the spread of the last Jacobian. Its checkpoint is
//! the library's saved least-squares run, resumed bit for bit as the other methods' are.

use std::time::Instant;

use plateau_free::{vector::LeastSquaresAskTell, Ask, LeastSquares};

use super::driven::Ctx;
use super::{Crn, Settings};
use crate::report::Result;
use crate::tasks::Task;

/// The method's run from `start`.
///
/// # Errors
/// A time budget, a task without a footprint, settings the library rejects.
pub(super) fn least_squares(
    task: &Task,
    s: &Settings,
    start: &[f64],
) -> Result<LeastSquaresAskTell> {
    if s.budget_seconds.is_some() {
        return Err("--method image supports no time budget".into());
    }
    let pattern = task.footprint(s.view())?;
    let mut options = LeastSquares::new(pattern)
        .budget(s.samples.saturating_mul(s.iterations))
        .pairs((s.samples / 2).max(1))
        .sigma0(s.sigma0)
        .seed(s.seed);
    if let Some((lower, upper)) = task.bounds() {
        options = options.bounds(lower, upper);
    }
    Ok(options.ask_tell(start)?)
}

/// Writes the residual images of the asked points into `out` (one image's values a point),
/// counting and timing the renders in `ctx`.
pub(super) fn residuals(ctx: &Ctx<'_>, ask: Ask<'_>, out: &mut [f64]) {
    let (s, reference) = (ctx.s, &ctx.reference.data);
    for ((x, seed), out) in ask.iter().zip(out.chunks_exact_mut(reference.len())) {
        let seed = match s.crn {
            Crn::Fixed => s.seed,
            Crn::Pair => seed,
        };
        let t = Instant::now();
        let image = ctx.task.render(x, seed, s.spp, s.view());
        ctx.render_time.set(ctx.render_time.get() + t.elapsed());
        ctx.renders.set(ctx.renders.get() + 1);
        for ((o, &v), &r) in out.iter_mut().zip(&image.data).zip(reference) {
            *o = f64::from(v) - f64::from(r);
        }
    }
}
