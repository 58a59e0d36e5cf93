//! One optimisation of a task: the reference, the loop (plateau-free gradient or a
//! baseline), the progress bar, and the outputs.

use std::cell::Cell;
use std::fs;
use std::ops::ControlFlow;
use std::path::Path;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};
use plateau::baseline::{FiniteDifference, Spsa};
use plateau::{
    Adam, Annealer, GradientEstimator, Optimizer, PlateauFreeGradient, Sampling, Seeded,
};
use serde::{Deserialize, Serialize};

use crate::render::Image;
use crate::report::{self, Axes, Result, Scale, Series};
use crate::tasks::{param_mse, Task, View};

/// How the gradient is obtained.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// The plateau-free gradient (the paper's method).
    Plateau,
    /// Small-step central finite differences: what a gradient sees without smoothing.
    Fd,
    /// Simultaneous-perturbation stochastic approximation.
    Spsa,
}

/// The sampler, as named on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SamplerArg {
    Radial,
    PerCoordinate,
    Gaussian,
}

impl From<SamplerArg> for Sampling {
    fn from(s: SamplerArg) -> Self {
        match s {
            SamplerArg::Radial => Sampling::Radial,
            SamplerArg::PerCoordinate => Sampling::PerCoordinate,
            SamplerArg::Gaussian => Sampling::Gaussian,
        }
    }
}

/// Which renderer seed each evaluation uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Crn {
    /// Every render, the reference included, uses the run's seed: the loss is a
    /// deterministic function of theta and reaches zero at the target (the paper's code).
    Fixed,
    /// Each antithetic pair shares a fresh seed from the estimator; the reference keeps the
    /// run's seed (the loss keeps a noise floor).
    Pair,
}

/// Everything a run can be told.
#[derive(Clone, Debug, Serialize)]
pub struct Settings {
    pub method: Method,
    pub sampling: SamplerArg,
    pub antithetic: bool,
    pub anneal: bool,
    pub samples: usize,
    pub sigma0: f64,
    pub lr: f64,
    pub spp: u32,
    pub iterations: usize,
    pub seed: u64,
    pub crn: Crn,
    pub fd_step: f64,
    pub fov_degrees: Option<f64>,
    pub scale: Option<f64>,
    /// Render the current parameters for the image-error curve every this many iterations.
    pub eval_every: usize,
    /// Stop when the optimisation (renders for the gradient included) has used this much time.
    pub budget_seconds: Option<f64>,
}

impl Settings {
    /// The task's paper defaults (supplemental Table 1) with the plateau-free gradient.
    pub fn defaults(task: &dyn Task) -> Self {
        let d = task.defaults();
        Settings {
            method: Method::Plateau,
            sampling: SamplerArg::Radial,
            antithetic: true,
            anneal: true,
            samples: d.samples,
            sigma0: d.sigma0,
            lr: d.lr,
            spp: d.spp,
            iterations: d.iterations,
            seed: 0,
            crn: Crn::Fixed,
            fd_step: 1e-3,
            fov_degrees: None,
            scale: None,
            eval_every: (d.iterations / 100).max(1),
            budget_seconds: None,
        }
    }

    pub fn view(&self) -> View {
        View {
            fov_degrees: self.fov_degrees,
            scale: self.scale,
        }
    }

    /// A short label for tables and legends.
    pub fn label(&self) -> String {
        match self.method {
            Method::Fd => "finite difference".into(),
            Method::Spsa => "SPSA".into(),
            Method::Plateau => {
                let mut s = format!("{:?}", self.sampling).to_lowercase();
                if !self.antithetic {
                    s.push_str(", no antithetic");
                }
                if !self.anneal {
                    s.push_str(", no annealing");
                }
                s
            }
        }
    }
}

/// One row of `history.csv`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Row {
    pub iteration: usize,
    pub sigma: f64,
    /// Mean image MSE over the iteration's perturbed renders.
    pub loss: f64,
    pub param_mse: f64,
    /// Image MSE of the current parameters (every `eval_every` iterations).
    pub image_mse: Option<f64>,
    /// Optimisation time so far (renders for the gradient, estimator, Adam), seconds.
    pub seconds: f64,
}

/// `summary.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Summary {
    pub task: String,
    pub method: Method,
    pub sampling: SamplerArg,
    pub antithetic: bool,
    pub anneal: bool,
    pub crn: Crn,
    pub iterations: usize,
    pub samples: usize,
    pub spp: u32,
    pub sigma0: f64,
    pub lr: f64,
    pub seed: u64,
    pub width: u32,
    pub height: u32,
    pub dim: usize,
    pub evaluations: usize,
    pub initial_param_mse: f64,
    pub initial_image_mse: f64,
    pub param_mse: f64,
    /// Final image against the reference, both rendered with the run's seed.
    pub image_mse: f64,
    /// Final image against the reference, both rendered with a seed the run never used.
    pub image_mse_other_seed: f64,
    pub seconds_per_iteration: f64,
    /// Of which rendering.
    pub render_seconds_per_iteration: f64,
    /// Of which the estimator and Adam (everything but rendering).
    pub overhead_seconds_per_iteration: f64,
    pub seconds_total: f64,
    pub stopped_early: bool,
    /// The final parameters (omitted above 16 dimensions).
    pub final_theta: Option<Vec<f64>>,
    pub target_theta: Option<Vec<f64>>,
}

/// The result of a run.
#[derive(Serialize, Deserialize)]
pub struct Outcome {
    pub summary: Summary,
    pub history: Vec<Row>,
}

/// Runs one optimisation of `task`, writing its outputs into `out` if given.
pub fn optimize(
    task: &dyn Task,
    s: &Settings,
    out: Option<&Path>,
    show_progress: bool,
) -> Result<Outcome> {
    let view = s.view();
    let (start, target) = (task.start(), task.target());
    let reference = task.render(&target, s.seed, s.spp, view);
    let initial = task.render(&start, s.seed, s.spp, view);

    let render_time = Cell::new(Duration::ZERO);
    let loss = |theta: &[f64], pair_seed: u64| {
        let seed = match s.crn {
            Crn::Fixed => s.seed,
            Crn::Pair => pair_seed,
        };
        let t = Instant::now();
        let image = task.render(theta, seed, s.spp, view);
        render_time.set(render_time.get() + t.elapsed());
        image.mse(&reference)
    };
    let mut estimator: Box<dyn GradientEstimator + '_> = match s.method {
        Method::Plateau => Box::new(
            PlateauFreeGradient::new(Seeded(&loss))
                .samples(s.samples)
                .sampling(s.sampling.into())
                .antithetic(s.antithetic)
                .seed(s.seed),
        ),
        Method::Fd => Box::new(FiniteDifference::new(Seeded(&loss), s.fd_step)?.seed(s.seed)),
        Method::Spsa => Box::new(Spsa::new(Seeded(&loss)).seed(s.seed)),
    };
    let mut adam = Adam::new(s.lr)?;
    if let Some((lower, upper)) = task.bounds() {
        adam = adam.bounds(lower, upper)?;
    }
    let annealer = if s.anneal {
        Annealer::paper(s.sigma0, s.iterations)?
    } else {
        Annealer::constant(s.sigma0, s.iterations)?
    };
    // The loop keeps only the last theta; the run keeps six snapshots for the progress strip
    // (a 49,152-parameter theta per iteration would be 1.5 GB over 4000 iterations).
    let mut optimizer = Optimizer::new(adam, annealer).record_theta(false);
    let snapshot_at: Vec<usize> = (0..6)
        .map(|k| k * s.iterations.saturating_sub(1) / 5)
        .collect();
    let mut snapshots = vec![start.clone()];

    let bar = progress_bar(task.name(), s.iterations, show_progress);
    let mut history = Vec::with_capacity(s.iterations);
    let mut optimisation_time = Duration::ZERO;
    let mut last = Instant::now();
    let run = optimizer.minimize_with(&mut *estimator, &start, |step| {
        optimisation_time += last.elapsed();
        let seconds = optimisation_time.as_secs_f64();
        let is_last = step.iteration + 1 == s.iterations;
        if snapshot_at[1..].contains(&step.iteration) {
            snapshots.push(step.theta.to_vec());
        }
        let image_mse = (step.iteration % s.eval_every == 0 || is_last)
            .then(|| task.render(step.theta, s.seed, s.spp, view).mse(&reference));
        history.push(Row {
            iteration: step.iteration,
            sigma: step.sigma,
            loss: step.estimate.mean_value,
            param_mse: param_mse(step.theta, &target),
            image_mse,
            seconds,
        });
        bar.set_message(format!(
            "loss {:.3e}  sigma {:.3}",
            step.estimate.mean_value, step.sigma
        ));
        bar.inc(1);
        let over_budget = s.budget_seconds.is_some_and(|b| seconds >= b);
        last = Instant::now();
        if over_budget {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    })?;
    bar.finish_and_clear();
    drop(estimator);

    let final_theta = run
        .last_theta()
        .map_or_else(|| start.clone(), <[f64]>::to_vec);
    let final_image = task.render(&final_theta, s.seed, s.spp, view);
    let other_seed = s.seed.wrapping_add(0x5EED);
    let image_mse_other_seed = task
        .render(&final_theta, other_seed, s.spp, view)
        .mse(&task.render(&target, other_seed, s.spp, view));
    let done = run.iterations().max(1) as f64;
    let seconds_total = optimisation_time.as_secs_f64();
    let render_seconds = render_time.get().as_secs_f64();
    let summary = Summary {
        task: task.name().into(),
        method: s.method,
        sampling: s.sampling,
        antithetic: s.antithetic,
        anneal: s.anneal,
        crn: s.crn,
        iterations: run.iterations(),
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
        initial_image_mse: initial.mse(&reference),
        param_mse: param_mse(&final_theta, &target),
        image_mse: final_image.mse(&reference),
        image_mse_other_seed,
        seconds_per_iteration: seconds_total / done,
        render_seconds_per_iteration: render_seconds / done,
        overhead_seconds_per_iteration: (seconds_total - render_seconds).max(0.0) / done,
        seconds_total,
        stopped_early: run.stopped_early,
        final_theta: (task.dim() <= 16).then(|| final_theta.clone()),
        target_theta: (task.dim() <= 16).then(|| target.clone()),
    };
    let outcome = Outcome { summary, history };
    if let Some(dir) = out {
        write_outputs(
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

/// Settings that fit a run into `budget` seconds, and a line saying what was chosen: times one
/// render at the defaults, then [`plan_with_render_time`].
pub fn plan_for_budget(task: &dyn Task, s: &Settings, budget: f64) -> (Settings, String) {
    let view = s.view();
    // One warm-up render (caches, thread pool), then the timed one.
    let _ = task.render(&task.start(), s.seed, s.spp, view);
    let t = Instant::now();
    let _ = task.render(&task.start(), s.seed, s.spp, view);
    plan_with_render_time(t.elapsed().as_secs_f64(), s, budget)
}

/// The budget planner given the time of one render at the defaults.
///
/// The cost model: an iteration costs N renders, and a render's time is proportional to spp
/// times pixels (`experiment tradeoff` measured N^1.02, spp^0.99 and pixels^0.99 on SHADOW
/// and GI). The order of the cuts follows the same study's errors (docs/results/tradeoff.md):
/// iterations are kept (the annealing schedule needs them); the resolution goes first, down
/// to half (on GI a quarter of the pixels kept the default's error, 1.65e-3 against
/// 1.61e-3, while a quarter of the spp made it 3x worse); then spp, halved down to 4 at half
/// resolution; then the resolution again, to a quarter (GI: 10x worse, the last resort before
/// fewer iterations); only then fewer iterations. The loop also stops when the budget is
/// spent.
pub fn plan_with_render_time(render: f64, s: &Settings, budget: f64) -> (Settings, String) {
    let evaluations = (s.iterations * s.samples.max(1)) as f64;
    let predicted =
        |scale: f64, spp: u32| render * evaluations * (scale * scale) * (spp as f64 / s.spp as f64);
    let mut plan = s.clone();
    plan.budget_seconds = Some(budget);
    let base_scale = s.scale.unwrap_or(1.0);
    if predicted(1.0, s.spp) <= budget {
        return (
            plan,
            format!(
                "budget {budget} s: defaults fit (predicted {:.1} s)",
                predicted(1.0, s.spp)
            ),
        );
    }
    let mut spps = vec![s.spp];
    while spps.last().is_some_and(|&v| v / 2 >= 4) {
        spps.push(spps.last().copied().unwrap_or(4) / 2);
    }
    let fewest = spps.last().copied().unwrap_or(s.spp);
    let cuts: Vec<(f64, u32)> = [(1.0, s.spp), (0.75, s.spp)]
        .into_iter()
        .chain(spps.iter().map(|&spp| (0.5, spp)))
        .chain([(0.35, fewest), (0.25, fewest)])
        .collect();
    let chosen = cuts
        .iter()
        .copied()
        .find(|&(scale, spp)| predicted(scale, spp) <= budget);
    let (scale, spp) = chosen.unwrap_or((0.25, fewest));
    plan.scale = Some(base_scale * scale);
    plan.spp = spp;
    let per_iteration = predicted(scale, spp) / s.iterations as f64;
    if chosen.is_none() {
        plan.iterations = ((budget / per_iteration) as usize).max(1);
        plan.eval_every = (plan.iterations / 100).max(1);
    }
    let why = format!(
        "budget {budget} s: one render takes {render:.4} s at the defaults; chose resolution scale {:.2}, {} spp, {} iterations (predicted {:.1} s)",
        base_scale * scale,
        spp,
        plan.iterations,
        per_iteration * plan.iterations as f64
    );
    (plan, why)
}

/// `history.csv`: one row per iteration.
pub fn write_history(path: &Path, history: &[Row]) -> Result<()> {
    report::write_csv(
        path,
        &[
            "iteration",
            "sigma",
            "loss",
            "param_mse",
            "image_mse",
            "seconds",
        ],
        history.iter().map(|r| {
            vec![
                r.iteration.to_string(),
                format!("{:e}", r.sigma),
                format!("{:e}", r.loss),
                format!("{:e}", r.param_mse),
                r.image_mse.map_or(String::new(), |v| format!("{v:e}")),
                format!("{:.6}", r.seconds),
            ]
        }),
    )
}

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

/// Writes the images, the strip, the plot, the CSV and the summary of a run.
fn write_outputs(
    task: &dyn Task,
    s: &Settings,
    outcome: &Outcome,
    [target, initial, final_image]: [&Image; 3],
    thetas: &[Vec<f64>],
    dir: &Path,
) -> Result<()> {
    fs::create_dir_all(dir)?;
    target.save(&dir.join("target.png"))?;
    initial.save(&dir.join("initial.png"))?;
    final_image.save(&dir.join("final.png"))?;
    final_image.save(&dir.join("final.exr"))?;

    // The progress strip: the start, five moments of the run, then the target.
    if thetas.len() > 1 {
        let view = s.view();
        let mut frames: Vec<Image> = thetas
            .iter()
            .map(|theta| task.render(theta, s.seed, s.spp, view))
            .collect();
        frames.push(target.clone());
        report::strip(&frames).save(&dir.join("progress.png"))?;
    }

    let h = &outcome.history;
    write_history(&dir.join("history.csv"), h)?;
    let title = format!("{}: {}", task.name().to_uppercase(), s.label());
    report::plot(
        &dir.join("convergence.png"),
        &Axes {
            title: &title,
            x_label: "iteration",
            y_label: "MSE",
            x_scale: Scale::Linear,
            y_scale: Scale::Log,
        },
        &[
            Series::line(
                "image MSE",
                h.iter()
                    .filter_map(|r| r.image_mse.map(|v| (r.iteration as f64, v)))
                    .collect(),
            ),
            Series::line(
                "parameter MSE",
                h.iter()
                    .map(|r| (r.iteration as f64, r.param_mse))
                    .collect(),
            ),
        ],
    )?;
    fs::write(
        dir.join("summary.json"),
        serde_json::to_string_pretty(&outcome.summary)?,
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tasks;

    /// The planner's order of cuts: resolution to half, then spp to 4, then a quarter of the
    /// resolution, then iterations; and what it picks always fits the budget.
    #[test]
    fn budget_planner_cuts_resolution_then_spp_then_iterations() {
        let shadow = tasks::by_name("shadow").unwrap();
        let s = Settings::defaults(shadow.as_ref()); // N 2, 32 spp, 400 iterations
        let full = 0.1 * 800.0; // 0.1 s per render, 800 renders
        let pick = |fraction: f64| {
            let (p, _) = plan_with_render_time(0.1, &s, fraction * full);
            (p.scale.unwrap_or(1.0), p.spp, p.iterations)
        };
        assert_eq!(pick(1.0), (1.0, 32, 400));
        assert_eq!(pick(0.6), (0.75, 32, 400));
        assert_eq!(pick(0.25), (0.5, 32, 400));
        assert_eq!(pick(0.2), (0.5, 16, 400));
        assert_eq!(pick(0.25 / 8.0), (0.5, 4, 400));
        assert_eq!(pick(0.03), (0.35, 4, 400));
        assert_eq!(pick(0.25 * 0.25 / 8.0), (0.25, 4, 400));
        let (scale, spp, iterations) = pick(0.001);
        assert_eq!((scale, spp), (0.25, 4));
        assert!((1..400).contains(&iterations));
        for fraction in [0.9, 0.3, 0.1, 0.02, 0.005, 0.001] {
            let (p, _) = plan_with_render_time(0.1, &s, fraction * full);
            let predicted = 0.1
                * (p.iterations * p.samples) as f64
                * p.scale.unwrap_or(1.0).powi(2)
                * p.spp as f64
                / s.spp as f64;
            assert!(
                predicted <= fraction * full * 1.000001,
                "{fraction}: {predicted}"
            );
        }
    }

    /// The suite's end-to-end check: SHADOW at a sixteenth of its pixels and 4 spp, from the
    /// paper's start (the shadow far from the target's, a plateau for small moves).
    #[test]
    fn shadow_converges_from_its_plateau_and_finite_differences_stay_stuck() {
        let task = tasks::by_name("shadow").expect("the SHADOW task exists");
        let mut s = Settings::defaults(task.as_ref());
        s.scale = Some(0.25);
        s.spp = 4;
        s.eval_every = usize::MAX;
        let ours = optimize(task.as_ref(), &s, None, false).expect("the run succeeds");
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
        let fd = optimize(task.as_ref(), &s, None, false).expect("the run succeeds");
        // On the plateau a small-step difference sees nothing: the parameters barely move.
        assert!(
            fd.summary.param_mse > 0.5 * fd.summary.initial_param_mse,
            "finite differences should stay stuck: param MSE {} (from {})",
            fd.summary.param_mse,
            fd.summary.initial_param_mse
        );
    }
}
