//! `all`: every task with the plateau-free gradient and the finite-difference baseline, then
//! `results.md` beside the paper's numbers.

use std::path::{Path, PathBuf};

use super::{summarize, values, with_threads};
use crate::report::Result;
use crate::run::{self, Method, Settings};
use crate::tasks;

/// The options of `all`.
#[derive(clap::Args)]
pub(super) struct Args {
    /// Output directory.
    #[arg(long, default_value = "out", value_parser = values::out_dir)]
    out: PathBuf,
    /// A few minutes in all: a tenth of the iterations at half resolution.
    #[arg(long)]
    quick: bool,
    /// Only these tasks (comma-separated) [default: every task].
    #[arg(long, value_delimiter = ',', value_parser = values::task)]
    tasks: Option<Vec<String>>,
    /// Runs of the plateau-free gradient per task (seeds 0, 1, ...): the table reports
    /// the median and the range.
    #[arg(long, default_value_t = 1, allow_negative_numbers = true, value_parser = values::at_least(1u64))]
    seeds: u64,
    /// The method of the runs: plateau (the paper's loop: plateau-free gradient, Adam, the
    /// paper's annealing) or adaptive (the library's Minimizer with the same evaluations)
    /// [default: plateau].
    #[arg(long, value_enum)]
    method: Option<Method>,
    /// Skip the finite-difference baseline.
    #[arg(long)]
    no_baseline: bool,
    /// Worker threads for rendering [default: all cores].
    #[arg(long, allow_negative_numbers = true, value_parser = values::at_least(1usize))]
    threads: Option<usize>,
}

/// Runs every task (or those of `--tasks`), rewriting `results.md` after each.
pub(super) fn run(args: Args) -> Result<()> {
    with_threads(args.threads, || {
        all(
            &args.out,
            args.quick,
            args.tasks.as_deref(),
            args.seeds,
            args.method.unwrap_or(Method::Plateau),
            !args.no_baseline,
        )
    })
}

/// Every task with the plateau-free gradient and, where it is affordable, the finite-difference
/// baseline; then `results.md`.
fn all(
    out: &Path,
    quick: bool,
    only: Option<&[String]>,
    seeds: u64,
    method: Method,
    baseline: bool,
) -> Result<()> {
    let command = format!(
        "cargo run --release -p pathtracer -- all{}{}{}{}{} --out {}",
        if quick { " --quick" } else { "" },
        if seeds > 1 {
            format!(" --seeds {seeds}")
        } else {
            String::new()
        },
        match method {
            Method::Plateau => String::new(),
            m => format!(" --method {}", m.as_arg()),
        },
        if baseline { "" } else { " --no-baseline" },
        only.map_or(String::new(), |t| format!(" --tasks {}", t.join(","))),
        out.display()
    );
    for task in tasks::all() {
        if only.is_some_and(|names| !names.iter().any(|n| n == task.name())) {
            continue;
        }
        let mut plateau = Settings::defaults(&task);
        plateau.method = method;
        if quick {
            plateau.iterations = (plateau.iterations / 10).max(20);
            plateau.eval_every = run::eval_every(plateau.iterations, 20);
            plateau.scale = Some(0.5);
        }
        let mut ours = Vec::new();
        for seed in 0..seeds {
            let mut s = plateau.clone();
            s.seed = seed;
            let dir = match seed {
                0 => out.join(task.name()),
                k => out.join(format!("{}-seed{k}", task.name())),
            };
            ours.push(run::optimize(&task, &s, Some(&dir), true)?);
        }
        // Central differences cost 2n renders per iteration: affordable for the
        // low-dimensional tasks only (SORT would need 300 renders an iteration).
        if baseline && task.dim() <= 8 {
            let mut fd = Settings {
                method: Method::Plateau,
                ..plateau.clone()
            };
            fd.method = Method::Fd;
            run::optimize(
                &task,
                &fd,
                Some(&out.join(format!("{}-fd", task.name()))),
                true,
            )?;
        }
        // Rewritten after every task, so that an interrupted run still leaves its table.
        summarize::write_results(out, &command)?;
    }
    println!("wrote {}", out.join("results.md").display());
    Ok(())
}
