//! `experiment <name>`: one of the supplemental's experiments (see `experiments/`).

use std::path::PathBuf;

use super::with_threads;
use crate::experiments::{self, Experiment, Options};
use crate::report::Result;

/// The options of `experiment`.
#[derive(clap::Args)]
pub(super) struct Args {
    #[arg(value_enum)]
    name: Experiment,
    /// Minutes instead of hours (fewer iterations, seeds and points; lower resolution).
    #[arg(long)]
    quick: bool,
    /// Output directory.
    #[arg(long, default_value = "docs/results")]
    out: PathBuf,
    /// Only these tasks, for the experiments over every task (comma-separated).
    #[arg(long, value_delimiter = ',')]
    tasks: Option<Vec<String>>,
    /// Seeds per point where the outcome is noisy (default: the experiment's own).
    #[arg(long)]
    seeds: Option<u64>,
    /// Reuse runs in `<out>/runs/` made by an earlier build with the same settings (to
    /// rewrite pages after a change that cannot alter a run; timings are the earlier ones).
    #[arg(long)]
    reuse_runs: bool,
    /// Worker threads for rendering (default: all cores).
    #[arg(long)]
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
    };
    with_threads(args.threads, || experiments::run(args.name, &opts))
}
