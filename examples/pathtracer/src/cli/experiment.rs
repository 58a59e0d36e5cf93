//! `experiment <name>`: one of the supplemental's experiments (see `experiments/`).

use std::path::PathBuf;

use super::{values, with_threads};
use crate::experiments::{self, Experiment, Options};
use crate::report::Result;

/// The options of `experiment`.
#[derive(clap::Args)]
pub(super) struct Args {
    /// The experiment.
    #[arg(value_enum)]
    name: Experiment,
    /// Minutes instead of hours (fewer iterations, seeds and points; lower resolution).
    #[arg(long)]
    quick: bool,
    /// Output directory.
    #[arg(long, default_value = "docs/results", value_parser = values::out_dir)]
    out: PathBuf,
    /// Only these tasks, for the experiments over every task (comma-separated) [default:
    /// every task; with --quick, cup and shadow].
    #[arg(long, value_delimiter = ',', value_parser = values::task)]
    tasks: Option<Vec<String>>,
    /// Seeds per point where the outcome is noisy [default: the experiment's own].
    #[arg(long, allow_negative_numbers = true, value_parser = values::at_least(1u64))]
    seeds: Option<u64>,
    /// Reuse runs in `<out>/runs/` made by an earlier build with the same settings (to
    /// rewrite pages after a change that cannot alter a run; timings are the earlier ones).
    #[arg(long)]
    reuse_runs: bool,
    /// Worker threads for rendering [default: all cores].
    #[arg(long, allow_negative_numbers = true, value_parser = values::at_least(1usize))]
    threads: Option<usize>,
}

/// Runs the experiment: its CSV, plots and page in the output directory.
pub(super) fn run(args: Args) -> Result<()> {
    let opts = Options {
        quick: args.quick,
        out: args.out,
        tasks: args.tasks,
        seeds: args.seeds,
        reuse_runs: args.reuse_runs,
        stop_after: None,
    };
    with_threads(args.threads, || experiments::run(args.name, &opts))
}
