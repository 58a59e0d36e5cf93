//! `optimize <task>`: one optimisation end to end, its files in `out/<task>/`.

use std::path::{Path, PathBuf};

use super::{find_task, shell_line, usage, values, with_threads, RenderOptions};
use crate::report::Result;
use plateau_free::Sampling;

use crate::run::checkpoint::show;
use crate::run::interrupt::{self, Interrupted};
use crate::run::{self, Checkpoint, Control, Crn, Every, Method, Settings};
use crate::tasks::Task;

/// The options of `optimize`.
#[derive(clap::Args)]
pub(super) struct Args {
    /// The task: cup, shadow, occlusion, gi, sort, caustic or texture [default: with
    /// --resume, the checkpoint's].
    #[arg(value_parser = values::task, required_unless_present = "resume")]
    task: Option<String>,
    #[command(flatten)]
    opts: RunOptions,
    /// Output directory [default: out/<task>].
    #[arg(long, value_parser = values::out_dir, conflicts_with = "resume")]
    out: Option<PathBuf>,
    /// Continue the interrupted run in this directory (its checkpoint.json), writing there,
    /// with the task and settings in its checkpoint; an option given beside it must agree
    /// with them (a difference is refused, naming the option and both values) [default: a
    /// new run].
    #[arg(long, value_name = "DIR", value_parser = values::run_dir)]
    resume: Option<PathBuf>,
    /// Write the checkpoint every this many iterations; 0: only at the end and on Ctrl-C
    /// [default: about every 30 s, from the measured time per iteration].
    #[arg(long, value_name = "N", allow_negative_numbers = true, value_parser = values::at_least(0usize))]
    checkpoint_every: Option<usize>,
    /// Testing: stop as Ctrl-C does once this many iterations are done [default: never].
    #[arg(long, hide = true, value_name = "N", allow_negative_numbers = true, value_parser = values::at_least(1usize))]
    stop_after: Option<usize>,
}

/// Overrides of a task's defaults (supplemental Table 1).
#[derive(clap::Args, Clone, Debug, Default)]
struct RunOptions {
    /// Iterations of the paper's loop, each a step from one gradient of N renders; the other
    /// methods get the same N x iterations renders and count their own iterations (the
    /// adaptive search's generations, the image method's Jacobians and steps) [default: the
    /// task's].
    #[arg(long, allow_negative_numbers = true, value_parser = values::at_least(1usize))]
    iterations: Option<usize>,
    /// N: evaluations of the objective per gradient (even with antithetic pairs; at most
    /// 65536) [default: the task's].
    #[arg(long, allow_negative_numbers = true, value_parser = values::between(1usize, run::MAX_SAMPLES))]
    samples: Option<usize>,
    /// Initial smoothing spread sigma0, in parameter units [default: the task's].
    #[arg(long, allow_hyphen_values = true, value_parser = values::positive)]
    sigma0: Option<f64>,
    /// Adam's learning rate [default: the task's].
    #[arg(long, allow_hyphen_values = true, value_parser = values::positive)]
    lr: Option<f64>,
    #[command(flatten)]
    render: RenderOptions,
    /// How perturbations are drawn [default: radial].
    #[arg(long, value_parser = values::sampling)]
    sampling: Option<Sampling>,
    /// Ablation: no antithetic pairs (N independent perturbations) [default: pairs].
    #[arg(long)]
    no_antithetic: bool,
    /// Ablation: constant sigma = sigma0 [default: the paper's annealing].
    #[arg(long)]
    no_anneal: bool,
    /// polished: the paper's loop (plateau-free gradient, Adam, annealing) on half of the
    /// N x iterations evaluations (--polish), then the library's adaptive search from its best
    /// point; plateau: the paper's loop alone; fd (central finite differences) or spsa in the
    /// paper's loop; adaptive: the library's Minimizer alone (no loop, no learning rate) with
    /// the same evaluations, sigma0, bounds and seed; image: Gauss-Newton on the residual
    /// image with the smoothed Jacobian on the task's footprint (N / 2 pairs per Jacobian,
    /// N x iterations renders) [default: polished; plateau with --budget].
    #[arg(long, value_enum)]
    method: Option<Method>,
    /// Renderer seeds: fixed (every render uses the run's seed, as the paper's code) or pair
    /// (a fresh seed per antithetic pair) [default: fixed].
    #[arg(long, value_enum)]
    crn: Option<Crn>,
    /// Finite-difference step, in parameter units (with --method fd) [default: 0.001].
    #[arg(long, allow_hyphen_values = true, value_parser = values::positive)]
    fd_step: Option<f64>,
    /// Render the current parameters for the image-error curve every this many iterations
    /// (the adaptive search: every this many x N renders) [default: a hundredth of the
    /// iterations].
    #[arg(long, allow_negative_numbers = true, value_parser = values::at_least(1usize))]
    eval_every: Option<usize>,
    /// A time budget in seconds: picks resolution, spp (and if need be iterations) to fit,
    /// from the measured cost model, and stops when the budget is spent [default: none].
    #[arg(long, allow_hyphen_values = true, value_parser = values::positive)]
    budget: Option<f64>,
    /// The stop rule: end the run when its best value has not improved over this fraction
    /// of the N x iterations renders (0.2 is the library's `STALL_WINDOW`, tested in
    /// docs/results/stopping.md); the budget stays the ceiling [default: off].
    #[arg(long, value_name = "FRACTION", allow_hyphen_values = true, value_parser = values::fraction)]
    stop_when_stalled: Option<f64>,
    /// With --method polished: the share of the renders that the adaptive search gets after
    /// the paper's loop, whose annealing is compressed to the rest [default: 0.5].
    #[arg(long, value_name = "FRACTION", allow_hyphen_values = true, value_parser = values::share)]
    polish: Option<f64>,
    /// No progress: neither the bar (on a terminal) nor the plain line every few seconds
    /// (elsewhere) with the iteration, the renders, the best loss and the time.
    #[arg(long)]
    quiet: bool,
}

impl RunOptions {
    /// `--method`, or the default: [`Method::TASK_DEFAULT`], the paper's loop with a time
    /// budget.
    fn method(&self) -> Method {
        match (self.method, self.budget) {
            (Some(method), _) => method,
            (None, Some(_)) => Method::Plateau,
            (None, None) => Method::TASK_DEFAULT,
        }
    }

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
        s.method = o.method();
        s.crn = o.crn.unwrap_or(s.crn);
        s.fd_step = o.fd_step.unwrap_or(s.fd_step);
        s.eval_every = o
            .eval_every
            .unwrap_or(run::eval_every(s.iterations, run::CURVE_POINTS));
        s.budget_seconds = o.budget;
        s.stall = o.stop_when_stalled;
        s.polish = o.polish.unwrap_or(s.polish);
        s
    }
}

/// The options of `optimize` that set the run's [`Settings`], each with the setting (the
/// field of `Settings`) it sets. Beside `--resume`, an option written on the command line
/// must agree with the checkpoint's setting; one not written takes the checkpoint's.
const SETTING_OPTIONS: [(&str, &str); 18] = [
    ("iterations", "iterations"),
    ("samples", "samples"),
    ("sigma0", "sigma0"),
    ("lr", "lr"),
    ("spp", "spp"),
    ("seed", "seed"),
    ("fov", "fov_degrees"),
    ("scale", "scale"),
    ("sampling", "sampling"),
    ("no_antithetic", "antithetic"),
    ("no_anneal", "anneal"),
    ("method", "method"),
    ("crn", "crn"),
    ("fd_step", "fd_step"),
    ("eval_every", "eval_every"),
    ("budget", "budget_seconds"),
    ("stop_when_stalled", "stall"),
    ("polish", "polish"),
];

/// The options of `optimize` that are not settings of the run (what it is, where it writes,
/// how it is run): not kept in the checkpoint, free beside `--resume`.
#[cfg(test)]
const OTHER_OPTIONS: [&str; 7] = [
    "task",
    "out",
    "resume",
    "checkpoint_every",
    "stop_after",
    "threads",
    "quiet",
];

/// The option whose argument id is `id` as written: `no_anneal` is `--no-anneal`.
fn flag(id: &str) -> String {
    format!("--{}", id.replace('_', "-"))
}

/// Checks the setting options written on the command line (`given`) against the checkpoint
/// `c` at `path`: the first that contradicts it is refused, naming the option, its value
/// and the checkpoint's.
fn check_given_options(
    opts: &RunOptions,
    given: &dyn Fn(&str) -> bool,
    task: &Task,
    c: &Checkpoint,
    path: &Path,
) -> std::result::Result<(), String> {
    let (Ok(serde_json::Value::Object(here)), Ok(serde_json::Value::Object(found))) = (
        serde_json::to_value(opts.settings(task)),
        serde_json::to_value(&c.requested),
    ) else {
        return Err(format!(
            "checkpoint {}: the settings do not serialise",
            path.display()
        ));
    };
    for (id, key) in SETTING_OPTIONS {
        if !given(id) {
            continue;
        }
        let null = serde_json::Value::Null;
        let (mine, theirs) = (
            here.get(key).unwrap_or(&null),
            found.get(key).unwrap_or(&null),
        );
        if mine != theirs {
            let flag = flag(id);
            // `--no-anneal` takes no value; `--seed 2` does.
            let switch = id.starts_with("no_");
            let written = if switch {
                flag.clone()
            } else {
                format!("{flag} {}", show(mine))
            };
            let instead = if switch || theirs.is_null() {
                String::new()
            } else {
                format!("{flag} {}, or ", show(theirs))
            };
            return Err(format!(
                "{written} contradicts the checkpoint: {key} is {} in {}, {} here; allowed: {instead}no {flag} (the run continues with its own settings)",
                show(theirs),
                path.display(),
                show(mine)
            ));
        }
    }
    Ok(())
}

/// The command that continues the interrupted run in `dir`: `optimize TASK --resume DIR`
/// (the settings are in its checkpoint), with the options that are not settings (threads,
/// progress bar, checkpoint cadence) as they were given.
fn resume_command(task: &Task, dir: &Path, opts: &RunOptions, every: Option<usize>) -> String {
    let program = std::env::args()
        .next()
        .unwrap_or_else(|| "pathtracer".into());
    let mut args = vec![program, "optimize".into(), task.name().into()];
    args.extend(["--resume".into(), dir.display().to_string()]);
    if let Some(n) = opts.render.threads {
        args.extend(["--threads".into(), n.to_string()]);
    }
    if let Some(n) = every {
        args.extend(["--checkpoint-every".into(), n.to_string()]);
    }
    if opts.quiet {
        args.push("--quiet".into());
    }
    shell_line(&args)
}

/// Refuses, before any work, the options of a new run that cannot run together: an odd N
/// with antithetic pairs, a time budget with a method that has none.
fn check_combination(opts: &RunOptions, task: &Task) -> Result<()> {
    let samples = opts.samples.unwrap_or(task.defaults().samples);
    if opts.method().pairs() && samples % 2 == 1 && !opts.no_antithetic {
        return Err(usage(format!(
            "--samples {samples}: antithetic pairs need an even number; allowed: an even count, or add --no-antithetic"
        )));
    }
    if let (Some(_), Some(method @ (Method::Adaptive | Method::Polished | Method::Image))) =
        (opts.budget, opts.method)
    {
        return Err(usage(format!(
            "--budget with --method {}: the time budget applies to the paper's loop only; allowed: drop --budget, or another --method",
            method.as_arg()
        )));
    }
    super::check_polish(opts.polish, opts.method())
}

/// Runs `optimize` and prints one line: the errors before and after, the time, the outputs.
/// `given` tells which options were written on the command line. With `--resume`, the
/// checkpoint is read and checked before any work, and gives the task (if not given) and the
/// settings; a bad one, another task or a given option that contradicts it is refused with
/// one line and exit code 2. Interrupted (Ctrl-C), it prints the command that continues.
pub(super) fn run(args: Args, given: &dyn Fn(&str) -> bool) -> Result<()> {
    let Args {
        task,
        opts,
        out,
        resume,
        checkpoint_every,
        stop_after,
    } = args;
    let (task, requested, checkpoint) = match &resume {
        Some(dir) => {
            let path = dir.join(run::checkpoint::FILE);
            let refused = |e: String| usage(format!("--resume {}: {e}", dir.display()));
            let c = Checkpoint::load(&path).map_err(|e| refused(e.to_string()))?;
            let name = task.as_deref().unwrap_or(&c.task);
            let task = find_task(name).map_err(|e| refused(e.to_string()))?;
            // The task, and that the point has the task's dimension.
            c.check_matches(&task, &c.requested, &path)
                .map_err(|e| refused(e.to_string()))?;
            check_given_options(&opts, given, &task, &c, &path).map_err(refused)?;
            (task, c.requested.clone(), Some(c))
        }
        None => {
            let task = find_task(task.as_deref().unwrap_or_default())?;
            check_combination(&opts, &task)?;
            let requested = opts.settings(&task);
            (task, requested, None)
        }
    };
    let default_out = resume.is_none() && out.is_none();
    let dir = resume
        .clone()
        .or(out)
        .unwrap_or_else(|| Path::new("out").join(task.name()));
    if default_out {
        // The default, unlike a value written, has not been checked while parsing.
        values::writable_dir(&dir).map_err(|e| {
            usage(format!(
                "invalid value '{}' for '--out <OUT>' (its default): {e}",
                dir.display()
            ))
        })?;
    }
    interrupt::install_handler();
    with_threads(opts.render.threads, || {
        let settings = match &checkpoint {
            // The run's own settings (a budget's plan is not made again).
            Some(c) => c.settings.clone(),
            None => match opts.budget {
                Some(budget) => {
                    let (plan, why) = run::plan_for_budget(&task, &requested, budget);
                    eprintln!("{why}");
                    plan
                }
                None => requested.clone(),
            },
        };
        if let Some(c) = &checkpoint {
            eprintln!(
                "resuming {} from iteration {} of {}",
                dir.display(),
                c.history.len(),
                settings.iterations
            );
        }
        let control = Control {
            out: Some(&dir),
            checkpoint: Some(dir.join(run::checkpoint::FILE)),
            every: Every::from_option(checkpoint_every),
            resume: checkpoint,
            requested: Some(requested.clone()),
            stop_after,
            progress: !opts.quiet,
        };
        let outcome = run::optimize_with(&task, &settings, control)?;
        let s = &outcome.summary;
        println!(
            "{}: param MSE {:.3e} -> {:.3e}, image MSE {:.3e} -> {:.3e}, {:.3} s/iteration ({} iterations, {} renders{}), outputs in {}",
            s.task,
            s.initial_param_mse,
            s.param_mse,
            s.initial_image_mse,
            s.image_mse,
            s.seconds_per_iteration,
            s.iterations,
            s.renders,
            if s.interrupted { ", interrupted" } else { "" },
            dir.display()
        );
        if s.interrupted {
            return Err(Box::new(Interrupted {
                resume: resume_command(&task, &dir, &opts, checkpoint_every),
            }));
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use clap::CommandFactory;

    use super::*;

    /// Every option of `optimize` is either a setting (checked against the checkpoint beside
    /// `--resume`) or listed as not one, and every setting it names is a field of
    /// [`Settings`]: a new option cannot be silently ignored by `--resume`.
    #[test]
    fn every_option_is_a_setting_or_listed_as_not_one() {
        let cli = super::super::Cli::command();
        let optimize = cli.find_subcommand("optimize").unwrap();
        let task = crate::tasks::by_name("shadow").unwrap();
        let fields = serde_json::to_value(Settings::defaults(&task)).unwrap();
        for arg in optimize.get_arguments() {
            let id = arg.get_id().as_str();
            if id == "help" {
                continue;
            }
            let setting = SETTING_OPTIONS.iter().find(|(o, _)| *o == id);
            assert!(
                setting.is_some() != OTHER_OPTIONS.contains(&id),
                "--{id}: in neither list, or in both"
            );
            if let Some((_, key)) = setting {
                assert!(fields.get(key).is_some(), "--{id}: no setting {key}");
                assert_eq!(arg.get_long(), Some(&flag(id)[2..]), "--{id}");
            }
        }
        assert_eq!(
            SETTING_OPTIONS.len(),
            fields.as_object().unwrap().len(),
            "a setting no option sets"
        );
    }
}
