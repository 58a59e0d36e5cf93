//! `optimize <task>`: one optimisation end to end, its files in `out/<task>/`.

use std::path::{Path, PathBuf};

use super::{find_task, with_threads, RenderOptions};
use crate::report::Result;
use crate::run::{self, Crn, Method, SamplerArg, Settings};
use crate::tasks::Task;

/// The options of `optimize`.
#[derive(clap::Args)]
pub(super) struct Args {
    /// cup, shadow, occlusion, gi, sort, caustic or texture.
    task: String,
    #[command(flatten)]
    opts: RunOptions,
    /// Output directory (default out/<task>).
    #[arg(long)]
    out: Option<PathBuf>,
}

/// Overrides of a task's defaults (supplemental Table 1).
#[derive(clap::Args, Clone, Debug, Default)]
struct RunOptions {
    #[arg(long)]
    iterations: Option<usize>,
    /// N: evaluations of the objective per gradient.
    #[arg(long)]
    samples: Option<usize>,
    #[arg(long)]
    sigma0: Option<f64>,
    #[arg(long)]
    lr: Option<f64>,
    #[command(flatten)]
    render: RenderOptions,
    #[arg(long, value_enum)]
    sampling: Option<SamplerArg>,
    /// Ablation: no antithetic pairs.
    #[arg(long)]
    no_antithetic: bool,
    /// Ablation: constant sigma.
    #[arg(long)]
    no_anneal: bool,
    /// plateau (default), fd or spsa.
    #[arg(long, value_enum)]
    method: Option<Method>,
    /// Renderer seeds: fixed (every render uses the run's seed, as the paper's code) or pair.
    #[arg(long, value_enum)]
    crn: Option<Crn>,
    /// Finite-difference step (normalised units).
    #[arg(long)]
    fd_step: Option<f64>,
    /// Render the current parameters for the image-error curve every this many iterations.
    #[arg(long)]
    eval_every: Option<usize>,
    /// A time budget in seconds: picks resolution, spp (and if need be iterations) to fit,
    /// from the measured cost model, and stops when the budget is spent.
    #[arg(long)]
    budget: Option<f64>,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

impl RunOptions {
    /// The task's defaults with these overrides.
    fn settings(&self, task: &Task) -> Settings {
        let mut s = Settings::defaults(task);
        let o = self;
        s.iterations = o.iterations.unwrap_or(s.iterations);
        s.samples = o.samples.unwrap_or(s.samples);
        s.sigma0 = o.sigma0.unwrap_or(s.sigma0);
        s.lr = o.lr.unwrap_or(s.lr);
        s.spp = o.render.spp.unwrap_or(s.spp);
        s.sampling = o.sampling.unwrap_or(s.sampling);
        s.seed = o.render.seed;
        s.fov_degrees = o.render.fov;
        s.scale = o.render.scale;
        s.antithetic = !o.no_antithetic;
        s.anneal = !o.no_anneal;
        s.method = o.method.unwrap_or(s.method);
        s.crn = o.crn.unwrap_or(s.crn);
        s.fd_step = o.fd_step.unwrap_or(s.fd_step);
        s.eval_every = o
            .eval_every
            .unwrap_or(run::eval_every(s.iterations, run::CURVE_POINTS));
        s.budget_seconds = o.budget;
        s
    }
}

/// Runs `optimize` and prints one line: the errors before and after, the time, the outputs.
pub(super) fn run(args: Args) -> Result<()> {
    let Args { task, opts, out } = args;
    let task = find_task(&task)?;
    with_threads(opts.render.threads, || {
        let mut settings = opts.settings(&task);
        if let Some(budget) = opts.budget {
            if !(budget.is_finite() && budget > 0.0) {
                return Err(
                    format!("--budget must be a positive number of seconds, got {budget}").into(),
                );
            }
            let (plan, why) = run::plan_for_budget(&task, &settings, budget);
            eprintln!("{why}");
            settings = plan;
        }
        let dir = out.unwrap_or_else(|| Path::new("out").join(task.name()));
        let outcome = run::optimize(&task, &settings, Some(&dir), !opts.quiet)?;
        let s = &outcome.summary;
        println!(
            "{}: param MSE {:.3e} -> {:.3e}, image MSE {:.3e} -> {:.3e}, {:.3} s/iteration ({} iterations), outputs in {}",
            s.task,
            s.initial_param_mse,
            s.param_mse,
            s.initial_image_mse,
            s.image_mse,
            s.seconds_per_iteration,
            s.iterations,
            dir.display()
        );
        Ok(())
    })
}
