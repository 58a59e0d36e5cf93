//! `stopping`: the stop rule (`--stop-when-stalled`, `plateau_free::run::Stall`) replayed on every
//! finished full-length run of some seeds studies, without rendering
//! ([`crate::run::replay_stall`]): per task and study, the renders at the stop against the
//! budget and the parameter MSE at the stop against at the end, for several windows.

use std::fmt::Write as _;
use std::path::PathBuf;

use super::values;
use crate::report::{sci, Result};
use crate::run::{self, Replayed};
use crate::tasks;

/// The options of `stopping`.
#[derive(clap::Args)]
pub(super) struct Args {
    /// The directories of runs (seeds studies as `all --seeds K` leaves them), comma-separated.
    #[arg(long, value_delimiter = ',', required = true, value_parser = values::runs_dir)]
    runs: Vec<PathBuf>,
    /// The windows to replay, fractions of the budget (comma-separated).
    #[arg(long, value_delimiter = ',', default_values_t = [0.05, 0.1, 0.2], value_parser = values::fraction)]
    windows: Vec<f64>,
    /// The page to write.
    #[arg(long, default_value = "docs/results/stopping.md", value_parser = values::out_file)]
    page: PathBuf,
}

/// Writes the page (and prints it).
pub(super) fn run(args: Args) -> Result<()> {
    let command = format!(
        "cargo run --release -p pathtracer -- stopping --runs {} --windows {}",
        args.runs
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(","),
        args.windows
            .iter()
            .map(ToString::to_string)
            .collect::<Vec<_>>()
            .join(",")
    );
    let mut md = format!("# Stop when done: the stop rule replayed on the committed runs\n\nWritten by `{command}`.\n\n");
    md.push_str(INTRO);
    for &window in &args.windows {
        let _ = writeln!(
            md,
            "\n## Window {window} of the budget{}\n",
            if window == plateau_free::run::STALL_WINDOW {
                " (the library's `STALL_WINDOW`)"
            } else {
                ""
            }
        );
        md.push_str("| task | study | runs (judged) | renders at the stop: median [min, max] | budget | renders saved | param MSE at the end: median | at the stop: median | worse at the stop | lost the paper's MSE |\n|---|---|---|---|---|---|---|---|---|---|\n");
        let mut worse_runs = Vec::new();
        let (mut spent, mut budget) = (0usize, 0usize);
        for dir in &args.runs {
            for name in tasks::names() {
                let runs = replays(dir, name, window);
                if runs.is_empty() {
                    continue;
                }
                spent += runs.iter().map(|r| r.renders_stop).sum::<usize>();
                budget += runs.iter().map(|r| r.renders_end).sum::<usize>();
                md.push_str(&row(dir, name, &runs));
                worse_runs.extend(runs.into_iter().filter(|r| r.param_stop > r.param_end));
            }
        }
        let _ = writeln!(
            md,
            "\nIn all: {spent} of {budget} renders ({:.1}% saved).",
            100.0 * (1.0 - spent as f64 / budget.max(1) as f64)
        );
        if worse_runs.is_empty() {
            md.push_str("No run's final parameter MSE got worse.\n");
        } else {
            md.push_str("\nRuns whose parameter MSE at the stop is worse than at the end:\n\n| task | method | seed | renders at the stop | param MSE at the stop | at the end | factor |\n|---|---|---|---|---|---|---|\n");
            for r in &worse_runs {
                let _ = writeln!(
                    md,
                    "| {} | {} | {} | {} of {} | {} | {} | {:.1e} |",
                    r.task,
                    r.method.as_arg(),
                    r.seed,
                    r.renders_stop,
                    r.budget,
                    sci(r.param_stop),
                    sci(r.param_end),
                    r.param_stop / r.param_end
                );
            }
        }
    }
    print!("{md}");
    if let Some(dir) = args.page.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    std::fs::write(&args.page, md)?;
    Ok(())
}

const INTRO: &str = "The rule (`plateau_free::run::Stall`, `Minimizer::stop_when_stalled`, `pathtracer optimize --stop-when-stalled FRACTION`): a run ends when the best value it has seen did not improve at all over the last `window` of its budget (evaluations). It sees only the values (never the true parameters); the budget stays the ceiling. It judges the adaptive search from its first generation and the polish from the hand-over; the paper's loop is not judged within its annealing schedule, which spans the loop's share of the budget (the loss falls there because the spread is annealed; stopping would skip the annealing), so the paper loop's runs are listed with no stop.\n\nEach finished full-length run is replayed without rendering: its checkpoint holds every value in order, cut into the iterations' batches by its history's renders, and the library's own `Stall` is fed each batch's smallest value as the `Minimizer` feeds it (`run::replay_stall`; the test `stop_rule_run_stops_where_the_replay_says` checks that a run made with the rule stops at the very iteration the replay names, bit for bit). Parameter MSE is of the best point so far, as the runs report it. \"Worse\": the parameter MSE at the stop is above the end's (by any amount; the factor is listed); \"lost the paper's MSE\": at or below the paper's at the end, above it at the stop. Left out: unfinished runs, runs without a checkpoint (`docs/results/seeds-adaptive`), and runs whose history has no renders (written before the runs counted, such as `docs/results/seeds-polished`); the command prints why for each.\n";

/// The replays of every finished run of `task` in `dir` (seeds 0, 1, ...).
fn replays(dir: &std::path::Path, task: &str, window: f64) -> Vec<Replayed> {
    (0..100)
        .filter_map(|k| {
            let run = match k {
                0 => dir.join(task),
                k => dir.join(format!("{task}-seed{k}")),
            };
            let path = run.join(run::checkpoint::FILE);
            if !path.exists() {
                return None;
            }
            match run::replay_stall(&path, window) {
                Ok(r) => Some(r),
                Err(e) => {
                    eprintln!("{}: not replayed: {e}", run.display());
                    None
                }
            }
        })
        .collect()
}

/// One table row: a task's runs in one study.
fn row(dir: &std::path::Path, task: &str, runs: &[Replayed]) -> String {
    let mut stops: Vec<usize> = runs.iter().map(|r| r.renders_stop).collect();
    stops.sort_unstable();
    let median_usize = |v: &[usize]| v[(v.len() - 1) / 2];
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        let k = v.len();
        if k % 2 == 1 {
            v[k / 2]
        } else {
            (v[k / 2 - 1] * v[k / 2]).sqrt()
        }
    };
    let spent: usize = stops.iter().sum();
    let full: usize = runs.iter().map(|r| r.renders_end).sum();
    let worse: Vec<f64> = runs
        .iter()
        .filter(|r| r.param_stop > r.param_end)
        .map(|r| r.param_stop / r.param_end)
        .collect();
    let paper = tasks::by_name(task)
        .and_then(|t| t.paper())
        .map(|p| p.param_mse);
    let lost = paper.map_or(0, |p| {
        runs.iter()
            .filter(|r| r.param_end <= p && r.param_stop > p)
            .count()
    });
    format!(
        "| {} | `{}` ({}) | {} ({}) | {} [{}, {}] | {} | {:.1}% | {} | {} | {} | {} |\n",
        task.to_uppercase(),
        dir.display(),
        runs[0].method.as_arg(),
        runs.len(),
        runs.iter().filter(|r| r.judged).count(),
        median_usize(&stops),
        stops[0],
        stops[stops.len() - 1],
        runs[0].budget,
        100.0 * (1.0 - spent as f64 / full.max(1) as f64),
        sci(median(runs.iter().map(|r| r.param_end).collect())),
        sci(median(runs.iter().map(|r| r.param_stop).collect())),
        if worse.is_empty() {
            "0".to_string()
        } else {
            format!(
                "{} (up to x{:.1e})",
                worse.len(),
                worse.iter().copied().fold(0.0, f64::max)
            )
        },
        lost
    )
}
