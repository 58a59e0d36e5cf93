//! The command line: `optimize`, `render`, `all`, `experiment` and the other subcommands.
//!
//! One file per subcommand, each with its options (a `clap::Args` struct) and a `run` that
//! does the work; this file holds the parser, the dispatch and what several commands share.

mod all;
mod experiment;
mod landscape;
mod optimize;
mod render;
mod summarize;
mod timings;

use std::time::Instant;

use clap::{Parser, Subcommand};

use crate::report::Result;
use crate::tasks::{self, Task, View};

#[derive(Parser)]
#[command(
    about = "Plateau-free differentiable path tracing: the paper's tasks on a CPU path tracer"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render the reference, optimise from the start, write images, plot, CSV and summary.
    Optimize(optimize::Args),
    /// Render one image at the target (default), the start or given parameters, and print
    /// `render_seconds: X` (the render alone, scene set-up excluded).
    Render(render::Args),
    /// Every task with the plateau-free gradient and the finite-difference baseline, then
    /// results.md: our numbers beside the paper's.
    All(all::Args),
    /// Rewrites `results.md` in a directory of runs (as `all` leaves it) from their
    /// `summary.json` files.
    Summarize(summarize::Args),
    /// Median render time of every task at its defaults (target parameters, seed 0, scene
    /// set-up excluded), as a markdown table.
    Timings(timings::Args),
    /// The loss along one coordinate through the target (or the start): a CSV of theta_i,
    /// the image MSE against the reference, and the loss smoothed by Gaussians of the given
    /// spreads (a quadrature over the same grid), to see plateaus and what smoothing does.
    Landscape(landscape::Args),
    /// One of the supplemental's experiments or the speed/accuracy study: CSV, plots and a
    /// markdown page in the output directory.
    Experiment(experiment::Args),
}

/// How every render of a command is made: the options `optimize` and `render` share.
#[derive(clap::Args, Clone, Debug, Default)]
struct RenderOptions {
    /// Samples per pixel (default: the task's).
    #[arg(long)]
    spp: Option<u32>,
    /// The renderer's seed (and the estimator's, in `optimize`).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Horizontal field of view in degrees (default: the task's).
    #[arg(long)]
    fov: Option<f64>,
    /// Resolution multiplier (0.5 renders a quarter of the pixels).
    #[arg(long)]
    scale: Option<f64>,
    /// Worker threads for rendering (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
}

impl RenderOptions {
    /// The view overrides these options ask for.
    fn view(&self) -> View {
        View {
            fov_degrees: self.fov,
            scale: self.scale,
        }
    }
}

/// Parses the command line and runs it; an error is printed on one line and exits 1.
pub fn main() {
    if let Err(e) = run_cli(Cli::parse()) {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

/// Runs one parsed command line.
fn run_cli(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Optimize(args) => optimize::run(args),
        Command::Render(args) => render::run(args),
        Command::All(args) => all::run(args),
        Command::Summarize(args) => summarize::run(args),
        Command::Timings(args) => timings::run(args),
        Command::Landscape(args) => landscape::run(args),
        Command::Experiment(args) => experiment::run(args),
    }
}

/// The task called `name`, or an error listing the tasks.
fn find_task(name: &str) -> Result<Task> {
    tasks::by_name(name).ok_or_else(|| {
        let names: Vec<_> = tasks::all().iter().map(|t| t.name()).collect();
        format!("unknown task {name:?}; the tasks are {}", names.join(", ")).into()
    })
}

/// Runs `f` on a rayon pool of `threads` workers (the global pool if `None`).
fn with_threads<T>(threads: Option<usize>, f: impl FnOnce() -> Result<T> + Send) -> Result<T>
where
    T: Send,
{
    match threads {
        None => f(),
        Some(0) => Err("--threads must be at least 1".into()),
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()?
            .install(f),
    }
}

/// Calls `f` `repeat` times (at least once) and returns the median of its wall times.
fn median_seconds(repeat: usize, mut f: impl FnMut()) -> f64 {
    let mut times: Vec<f64> = (0..repeat.max(1))
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

#[cfg(test)]
mod tests {
    use clap::CommandFactory;

    use super::*;

    /// clap's own consistency checks of every subcommand (names, conflicts, defaults): in a
    /// release build they run only here.
    #[test]
    fn the_command_line_is_consistent() {
        Cli::command().debug_assert();
    }
}
