//! `seeds`: several seeds studies (directories of runs as `all --seeds K` leaves them) side
//! by side on one page: per task, each seed's final parameter MSE under each method, how many
//! reach the paper's, the median and the range, the same for the final image MSE, and the
//! seconds per iteration.

use std::path::{Path, PathBuf};

use super::{summarize, values};
use crate::report::{self, Result};
use crate::run;
use crate::tasks;

/// The options of `seeds`.
#[derive(clap::Args)]
pub(super) struct Args {
    /// The directories of runs, one column each, in this order (comma-separated).
    #[arg(long, value_delimiter = ',', required = true, value_parser = values::runs_dir)]
    runs: Vec<PathBuf>,
    /// The page to write.
    #[arg(long, default_value = "docs/results/seeds.md")]
    page: PathBuf,
}

/// The most seeds a column looks for (`<task>`, `<task>-seed1`, ...).
const MAX_SEEDS: usize = 100;

/// Writes the page.
pub(super) fn run(args: Args) -> Result<()> {
    let page = page(&args.runs);
    if let Some(dir) = args.page.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    std::fs::write(&args.page, page)?;
    Ok(())
}

/// One study's runs of one task: the summary of every seed found, by seed.
fn study(dir: &Path, task: &str) -> Vec<Option<run::Summary>> {
    let read = |path: PathBuf| -> Option<run::Summary> {
        let text = std::fs::read_to_string(path.join("summary.json")).ok()?;
        serde_json::from_str(&text).ok()
    };
    let mut seeds: Vec<Option<run::Summary>> = (0..MAX_SEEDS)
        .map(|k| match k {
            0 => read(dir.join(task)),
            k => read(dir.join(format!("{task}-seed{k}"))),
        })
        .collect();
    while seeds.last().is_some_and(Option::is_none) {
        seeds.pop();
    }
    seeds
}

/// The page: a section per task that any study ran.
fn page(dirs: &[PathBuf]) -> String {
    let dirs_arg: Vec<String> = dirs.iter().map(|d| d.display().to_string()).collect();
    let mut md = String::from("# Seeds studies side by side\n\n");
    md.push_str(&format!(
        "Written by `cargo run --release -p pathtracer -- seeds --runs {}` from the runs' `summary.json` files (each directory made by `all --seeds K --method M --out DIR`; its own `results.md` by `summarize`). Final parameter MSE per seed; bold: at or below the paper's (main paper Table 2). Every method gets the task's Table 1 settings and N x iterations evaluations.\n",
        dirs_arg.join(",")
    ));
    for task in tasks::all() {
        let columns: Vec<Vec<Option<run::Summary>>> =
            dirs.iter().map(|d| study(d, task.name())).collect();
        let seeds = columns.iter().map(Vec::len).max().unwrap_or(0);
        if seeds == 0 {
            continue;
        }
        let paper = task.paper().map(|p| p.param_mse);
        let label = |column: &[Option<run::Summary>], dir: &Path| {
            let method = column
                .iter()
                .flatten()
                .next()
                .map_or("no runs".into(), summarize::method_label);
            format!("{method} (`{}`)", dir.display())
        };
        let mut header = vec!["seed".to_string()];
        header.extend(columns.iter().zip(dirs).map(|(c, d)| label(c, d)));
        let mut rows: Vec<Vec<String>> = (0..seeds)
            .map(|k| {
                let mut row = vec![k.to_string()];
                row.extend(columns.iter().map(|c| match c.get(k) {
                    Some(Some(s)) => bold_if(s.param_mse, paper),
                    _ => "not run".into(),
                }));
                row
            })
            .collect();
        let ran = |c: &[Option<run::Summary>]| finals(c, |s| s.param_mse);
        let footer = |name: &str, cell: &dyn Fn(&[Option<run::Summary>]) -> String| {
            let mut row = vec![name.to_string()];
            row.extend(columns.iter().map(|c| cell(c)));
            row
        };
        if let Some(p) = paper {
            rows.push(footer("at or below the paper", &|c| count_cell(&ran(c), p)));
        }
        rows.push(footer("median [min, max]", &|c| spread_cell(&ran(c))));
        // Some tasks are judged by the image (SORT: cubes of one colour are interchangeable,
        // so the parameter MSE against one assignment says little), so the image MSE is
        // summarised too.
        let images = |c: &[Option<run::Summary>]| finals(c, |s| s.image_mse);
        if let Some(p) = task.paper().map(|p| p.image_mse) {
            rows.push(footer(
                &format!("image MSE at or below the paper's ({})", report::sci(p)),
                &|c| count_cell(&images(c), p),
            ));
        }
        rows.push(footer("image MSE median [min, max]", &|c| {
            spread_cell(&images(c))
        }));
        rows.push(footer("s/iteration (median)", &|c| {
            let v = finals(c, |s| s.seconds_per_iteration);
            if v.is_empty() {
                return "-".into();
            }
            format!("{:.3}", report::spread(&v).0)
        }));
        let header: Vec<&str> = header.iter().map(String::as_str).collect();
        md.push_str(&format!(
            "\n## {} (paper's parameter MSE {})\n\n",
            task.name().to_uppercase(),
            paper.map_or("-".into(), report::sci)
        ));
        md.push_str(&report::markdown_table(&header, &rows));
    }
    md.push_str("\nSeconds per iteration are wall-clock on a shared 2-core machine: an iteration of the adaptive search and of the polish is a generation (several renders), of the paper's loop one estimate (N renders); compare them only within a column.\n");
    md
}

/// One number of every run found in a column.
fn finals(column: &[Option<run::Summary>], get: fn(&run::Summary) -> f64) -> Vec<f64> {
    column.iter().flatten().map(get).collect()
}

/// How many of `v` are at or below `limit`, as "k of n".
fn count_cell(v: &[f64], limit: f64) -> String {
    format!(
        "{} of {}",
        v.iter().filter(|&&m| m <= limit).count(),
        v.len()
    )
}

/// The median and range of `v` as one cell, `-` when empty.
fn spread_cell(v: &[f64]) -> String {
    if v.is_empty() {
        return "-".into();
    }
    let (median, lo, hi) = report::spread(v);
    format!(
        "{} [{}, {}]",
        report::sci(median),
        report::sci(lo),
        report::sci(hi)
    )
}

/// `v` in scientific notation, bold when at or below `paper`.
fn bold_if(v: f64, paper: Option<f64>) -> String {
    match paper {
        Some(p) if v <= p => format!("**{}**", report::sci(v)),
        _ => report::sci(v),
    }
}
