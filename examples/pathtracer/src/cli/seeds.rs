//! `seeds`: several seeds studies (directories of runs as `all --seeds K` leaves them) side
//! by side on one page: per task, each seed's final parameter MSE under each method, how many
//! reach the paper's, the median and the range, the same for the final image MSE, the renders
//! of the objective at which the parameter MSE first reached the paper's and from which it
//! stayed there, and the seconds per iteration.

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
    #[arg(long, default_value = "docs/results/seeds.md", value_parser = values::out_file)]
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

/// The directory of seed `k` of `task` in a study.
fn run_dir(dir: &Path, task: &str, k: usize) -> PathBuf {
    match k {
        0 => dir.join(task),
        k => dir.join(format!("{task}-seed{k}")),
    }
}

/// One study's runs of one task: the summary of every seed found, by seed.
fn study(dir: &Path, task: &str) -> Vec<Option<run::Summary>> {
    let read = |path: PathBuf| -> Option<run::Summary> {
        let text = std::fs::read_to_string(path.join("summary.json")).ok()?;
        serde_json::from_str(&text).ok()
    };
    let mut seeds: Vec<Option<run::Summary>> = (0..MAX_SEEDS)
        .map(|k| read(run_dir(dir, task, k)))
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
        // Per column, per seed found: the renders to the paper's parameter MSE, or why they
        // cannot be counted.
        let counts: Vec<Vec<std::result::Result<Reach, String>>> = columns
            .iter()
            .zip(dirs)
            .map(|(c, d)| {
                (0..c.len())
                    .filter(|&k| c[k].is_some())
                    .map(|k| {
                        let dir = run_dir(d, task.name(), k);
                        let counted = c[k]
                            .as_ref()
                            .map_or(Ok(Reach::NEVER), |s| renders_to_paper(&dir, &task, s));
                        if let Err(why) = &counted {
                            eprintln!("renders not countable: {why}");
                        }
                        counted
                    })
                    .collect()
            })
            .collect();
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
        if task.paper().is_some() {
            let mut row = vec!["reached the paper's parameter MSE (renders counted)".to_string()];
            row.extend(counts.iter().map(|c| reached_cell(c)));
            rows.push(row);
            let mut row =
                vec!["renders to the paper's parameter MSE: median [min, max]".to_string()];
            row.extend(counts.iter().map(|c| renders_cell(c, |r| r.first)));
            rows.push(row);
            let mut row = vec![
                "renders from which it stays at the paper's parameter MSE: median [min, max]"
                    .to_string(),
            ];
            row.extend(counts.iter().map(|c| renders_cell(c, |r| r.kept)));
            rows.push(row);
        }
        rows.push(footer("renders of the objective per run (median)", &|c| {
            let v = finals(c, |s| s.evaluations as f64);
            if v.is_empty() {
                return "-".into();
            }
            format!("{:.0}", report::spread(&v).0)
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
    md.push_str("\nRenders to the paper's parameter MSE: the renders of the objective (every evaluation of the loss; not the evaluation-only renders of the image MSE, nor the reference) at the end of the first iteration whose parameter MSE (of the current point in the paper's loop, of the best point so far in the adaptive search and the polish) is at or below the paper's; \"stays\": the renders at the end of the first iteration from which every later one is at or below it (a loop whose current point swings through the target and out again reaches it early and stays late). The median is over every seed run, a run that never reached it counted as never (so the median is \"never\" when fewer than half reached it); the range runs from the fewest renders to the most, \"never\" included. They come from each run's `history.csv` (its `renders` column) or, for the paper's loop written before the runs counted, from its summary: the loop spends the same number of renders every iteration. A search whose history has no renders is \"not countable\"; such runs must be made again to be counted (the command prints why for each).\n");
    md.push_str("\nSeconds per iteration are wall-clock on a shared 2-core machine: an iteration of the adaptive search and of the polish is a generation (several renders), of the paper's loop one estimate (N renders); compare them only within a column.\n");
    md
}

/// When a run reached the paper's parameter MSE, in renders of the objective (`None`: never).
#[derive(Clone, Copy)]
struct Reach {
    /// At the end of the first iteration at or below it.
    first: Option<usize>,
    /// At the end of the first iteration from which every later one is at or below it.
    kept: Option<usize>,
}

impl Reach {
    const NEVER: Reach = Reach {
        first: None,
        kept: None,
    };

    /// From each iteration's parameter MSE and renders so far, in order.
    fn of(rows: &[(f64, usize)], paper: f64) -> Reach {
        let first = rows.iter().find(|(mse, _)| *mse <= paper).map(|r| r.1);
        let above = rows.iter().rposition(|(mse, _)| *mse > paper);
        let kept = match above {
            None => rows.first().map(|r| r.1),
            Some(k) => rows.get(k + 1).map(|r| r.1),
        };
        Reach { first, kept }
    }
}

/// When the run in `dir` reached the paper's parameter MSE for `task`, from its
/// `history.csv`, else, for the paper's loop, derived from its summary
/// ([`run::loop_renders`]); why not, if neither can tell (a search written before the runs
/// counted: made again, it counts).
fn renders_to_paper(
    dir: &Path,
    task: &tasks::Task,
    summary: &run::Summary,
) -> std::result::Result<Reach, String> {
    let Some(paper) = task.paper().map(|p| p.param_mse) else {
        return Ok(Reach::NEVER);
    };
    let history = dir.join("history.csv");
    let (rows, counted) =
        read_history(&history).ok_or_else(|| format!("{} cannot be read", history.display()))?;
    let renders = match counted {
        Some(renders) => renders,
        None if matches!(
            summary.method,
            run::Method::Plateau | run::Method::Fd | run::Method::Spsa
        ) =>
        {
            run::loop_renders(rows.len(), summary.evaluations, summary.iterations)
                .map_err(|e| format!("{}: {e}", dir.display()))?
        }
        None => {
            return Err(format!(
                "{}: no renders column (a search written before the runs counted; run it again)",
                history.display()
            ))
        }
    };
    Ok(Reach::of(
        &rows.into_iter().zip(renders).collect::<Vec<_>>(),
        paper,
    ))
}

/// The parameter MSE of every row of a `history.csv`, and its renders if it has a `renders`
/// column; `None` if it cannot be read.
#[allow(clippy::type_complexity)]
fn read_history(path: &Path) -> Option<(Vec<f64>, Option<Vec<usize>>)> {
    let text = std::fs::read_to_string(path).ok()?;
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next()?.split(',').collect();
    let at = |name: &str| header.iter().position(|h| *h == name);
    let (mse, renders) = (at("param_mse")?, at("renders"));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let mses = rows
        .iter()
        .map(|f| f.get(mse)?.parse().ok())
        .collect::<Option<Vec<f64>>>()?;
    let counts = match renders {
        Some(k) => Some(
            rows.iter()
                .map(|f| f.get(k)?.parse().ok())
                .collect::<Option<Vec<usize>>>()?,
        ),
        None => None,
    };
    Some((mses, counts))
}

/// How many runs reached the paper's parameter MSE, "k of n", and how many could not be
/// counted.
fn reached_cell(counts: &[std::result::Result<Reach, String>]) -> String {
    let counted = counts.iter().filter(|c| c.is_ok()).count();
    let reached = counts
        .iter()
        .filter(|c| matches!(c, Ok(r) if r.first.is_some()))
        .count();
    let uncounted = counts.len() - counted;
    if counts.is_empty() {
        "-".into()
    } else if uncounted > 0 {
        format!("{reached} of {counted} ({uncounted} not countable)")
    } else {
        format!("{reached} of {counted}")
    }
}

/// The median and range of the renders to the paper's (`at`: first or kept), a run that never
/// reached it counted as never (larger than any count).
fn renders_cell(
    counts: &[std::result::Result<Reach, String>],
    at: fn(&Reach) -> Option<usize>,
) -> String {
    let mut v: Vec<Option<usize>> = counts
        .iter()
        .filter_map(|c| c.as_ref().ok().map(at))
        .collect();
    if v.is_empty() {
        return "-".into();
    }
    // `None` (never) after every count.
    v.sort_by_key(|c| c.map_or(usize::MAX, |r| r));
    let show = |c: Option<usize>| c.map_or("never".to_string(), |r| r.to_string());
    let mid = v.len() / 2;
    let median = if v.len() % 2 == 1 {
        show(v[mid])
    } else {
        match (v[mid - 1], v[mid]) {
            (Some(a), Some(b)) => format!("{}", (a + b) as f64 / 2.0),
            _ => "never".into(),
        }
    };
    format!("{median} [{}, {}]", show(v[0]), show(v[v.len() - 1]))
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

#[cfg(test)]
mod tests {
    use super::Reach;

    #[test]
    fn a_run_that_swings_through_the_target_reaches_it_early_and_stays_late() {
        // (parameter MSE, renders so far) per iteration; the paper's MSE is 1.0.
        let swing = [(4.0, 2), (0.5, 4), (3.0, 6), (0.9, 8), (0.2, 10)];
        let r = Reach::of(&swing, 1.0);
        assert_eq!((r.first, r.kept), (Some(4), Some(8)));
        let steady = [(4.0, 2), (1.0, 4), (0.1, 6)];
        let r = Reach::of(&steady, 1.0);
        assert_eq!(
            (r.first, r.kept),
            (Some(4), Some(4)),
            "at the paper's counts"
        );
        let r = Reach::of(&[(0.5, 3), (0.4, 5)], 1.0);
        assert_eq!((r.first, r.kept), (Some(3), Some(3)), "from the first row");
        let r = Reach::of(&[(0.5, 3), (2.0, 5)], 1.0);
        assert_eq!((r.first, r.kept), (Some(3), None), "left it at the end");
        let r = Reach::of(&[(2.0, 3)], 1.0);
        assert_eq!((r.first, r.kept), (None, None));
        let r = Reach::of(&[], 1.0);
        assert_eq!((r.first, r.kept), (None, None));
    }
}
