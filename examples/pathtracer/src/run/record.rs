//! What a [`Tracked`] run records after each tell: a row of the history (one per iteration
//! of the method), the progress strip's points, the searches' best point and every value.
//!
//! - The paper's loop, finite differences and SPSA: a row per iteration with the spread it
//!   estimated with, the mean value of its estimate, and the errors of theta after its step;
//!   theta at six evenly spaced iterations for the strip.
//! - The adaptive search and the polished loop: a row per batch after the start (which the
//!   search evaluates first and alone); its `loss` is the mean over the batch, its `sigma`
//!   the spread of the batch's points (RMS per coordinate around their mean), its errors
//!   those of the best point so far, which is what the run returns; the image error every
//!   `eval_every x N` evaluations (the paper loop's spacing), first and last.
//! - The image method: a row per ask told (a Jacobian's pairs or a step's point), with the
//!   current point's image MSE (no render is spent on evaluation alone).

use plateau_free::objective::Points;

use super::checkpoint::Progress;
use super::driven::{Ctx, Tracked};
use super::Row;

/// Above this many parameters the searches' best point (the image method's point) is not
/// kept per iteration: the progress strip then shows the start and the end.
const KEEP_MAX_DIM: usize = 256;

impl Tracked<'_> {
    /// Records an iteration of the paper's loop (or a baseline's) that moved to `theta`.
    pub(super) fn record_loop(&mut self, ctx: &Ctx<'_>, theta: &[f64], sigma: f64, loss: f64) {
        let (s, c) = (ctx.s, &mut self.saved);
        let iteration = c.history.len();
        // Six snapshots: k (iterations - 1) / 5 for k = 0..6, without overflow.
        let last = s.iterations.saturating_sub(1) as u128;
        if (1..6u128).any(|k| (k * last / 5) as usize == iteration) {
            c.snapshots.push(theta.to_vec());
        }
        let image_mse = s.records_image_error(iteration).then(|| {
            ctx.task
                .render(theta, s.seed, s.spp, s.view())
                .mse(ctx.reference)
        });
        let eval_renders = c.history.last().map_or(0, |r| r.eval_renders);
        c.history.push(Row {
            iteration,
            sigma,
            loss,
            param_mse: ctx.task.param_mse_to(theta, &ctx.target),
            image_mse,
            renders: c.renders,
            eval_renders: eval_renders + usize::from(image_mse.is_some()),
            seconds: c.optimisation_seconds,
        });
    }

    /// Records a batch of the searches, told `values`.
    pub(super) fn record_search(&mut self, ctx: &Ctx<'_>, values: &[f64]) {
        let (s, c) = (ctx.s, &mut self.saved);
        let n = c.best_point.len();
        let points = Points::new(&self.asked, n);
        for (point, &v) in points.iter().zip(values) {
            if v.is_finite() && c.best_value.is_none_or(|best| v < best) {
                c.best_value = Some(v);
                c.best_point.copy_from_slice(point);
            }
        }
        let before = c.values.len();
        c.values.extend_from_slice(values);
        let (after, budget) = (c.values.len(), s.samples.saturating_mul(s.iterations));
        if before == 0 && after < budget {
            return; // The start alone: no row (a row is an iteration).
        }
        let stride = s.eval_every.saturating_mul(s.samples).max(1);
        let measure = c.history.is_empty() || before / stride != after / stride || after >= budget;
        let image_mse = measure.then(|| {
            let image = ctx.task.render(&c.best_point, s.seed, s.spp, s.view());
            image.mse(ctx.reference)
        });
        let eval_renders = c.history.last().map_or(0, |r| r.eval_renders);
        c.history.push(Row {
            iteration: c.history.len(),
            sigma: spread(points),
            loss: values.iter().sum::<f64>() / values.len().max(1) as f64,
            param_mse: ctx.task.param_mse_to(&c.best_point, &ctx.target),
            image_mse,
            renders: after,
            eval_renders: eval_renders + usize::from(image_mse.is_some()),
            seconds: c.optimisation_seconds,
        });
        if n <= KEEP_MAX_DIM {
            c.snapshots.push(c.best_point.clone());
        }
    }

    /// Records an ask of the image method, told.
    pub(super) fn record_image(&mut self, ctx: &Ctx<'_>) {
        let c = &mut self.saved;
        let Progress::Image(m) = &c.progress else {
            return;
        };
        let mse = m.fun() / ctx.reference.data.len() as f64;
        c.history.push(Row {
            iteration: c.history.len(),
            sigma: m.sigma(),
            loss: mse,
            param_mse: ctx.task.param_mse_to(m.theta(), &ctx.target),
            image_mse: Some(mse),
            renders: m.evaluations(),
            eval_renders: 0,
            seconds: c.optimisation_seconds,
        });
        if m.theta().len() <= KEEP_MAX_DIM {
            c.snapshots.push(m.theta().to_vec());
        }
    }

    /// The progress strip's six points of a run ending at `theta`: the loop's snapshots (and
    /// `theta`, when interrupted), or six of the points kept, evenly spaced, the last `theta`.
    pub(super) fn strip(&self, theta: &[f64], interrupted: bool) -> Vec<Vec<f64>> {
        let kept = &self.saved.snapshots;
        if matches!(
            self.saved.progress,
            Progress::Loop(_) | Progress::Baseline(_)
        ) {
            let mut strip = kept.clone();
            if interrupted {
                strip.push(theta.to_vec());
            }
            return strip;
        }
        let last = kept.len().saturating_sub(1);
        let mut strip: Vec<Vec<f64>> = (0..6).map(|k| kept[k * last / 5].clone()).collect();
        strip[5] = theta.to_vec();
        strip
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
