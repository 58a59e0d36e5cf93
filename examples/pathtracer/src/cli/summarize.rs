//! `summarize`: rewrites `results.md` in a directory of runs (as `all` leaves it) from their
//! `summary.json` files; `all` writes the same page after every task.

use std::path::{Path, PathBuf};

use super::values;
use crate::report::{self, Result};
use crate::run;
use crate::tasks::{self, Task};

/// The options of `summarize`.
#[derive(clap::Args)]
pub(super) struct Args {
    /// The directory of runs.
    #[arg(long, default_value = "out", value_parser = values::out_dir)]
    out: PathBuf,
    /// The command that produced the runs, for the page.
    #[arg(long, default_value = "cargo run --release -p pathtracer -- all")]
    command: String,
}

/// Rewrites `<out>/results.md`.
pub(super) fn run(args: Args) -> Result<()> {
    write_results(&args.out, &args.command)
}

/// `results.md` in `out`: a table of every task's runs found there (`<task>/`,
/// `<task>-seed<k>/`, `<task>-fd/`, each with its `summary.json`) beside the paper's numbers.
/// `command` is what produced the runs.
pub(super) fn write_results(out: &Path, command: &str) -> Result<()> {
    let read = |dir: PathBuf| -> Option<run::Summary> {
        let text = std::fs::read_to_string(dir.join("summary.json")).ok()?;
        serde_json::from_str(&text).ok()
    };
    let mut rows = Vec::new();
    for task in tasks::all() {
        let Some(first) = read(out.join(task.name())) else {
            continue;
        };
        let mut ours = vec![first];
        ours.extend((1..).map_while(|k| read(out.join(format!("{}-seed{k}", task.name())))));
        let fd = read(out.join(format!("{}-fd", task.name())));
        rows.push(results_row(&task, &ours, fd.as_ref()));
    }
    let header = [
        "task",
        "method",
        "N",
        "sigma0",
        "spp",
        "iters",
        "seeds",
        "ours img MSE",
        "ours param MSE",
        "paper img MSE",
        "paper param MSE",
        "runs at or below paper param MSE",
        "FD img MSE",
        "FD param MSE",
        "Mitsuba 3 param MSE (paper)",
        "ours s/iter (CPU)",
        "paper s/iter (GPU)",
    ];
    let mut md = String::from("# Results: the paper's tasks\n\n");
    md.push_str(&format!(
        "Runs by `{command}`; this table by `cargo run --release -p pathtracer -- summarize --out {}` from their `summary.json` files. \"ours\" is the plateau-free gradient at the paper's hyperparameters (supplemental Table 1), with seeds 0, 1, ... (with several seeds: the median [min, max]); FD is a central finite difference (step 1e-3) on the same renderer, loop and settings (run only where its 2n renders per iteration are affordable). Paper numbers: main paper Tables 2 and 3.\n\n",
        out.display()
    ));
    md.push_str(&report::markdown_table(&header, &rows));
    std::fs::create_dir_all(out)?;
    std::fs::write(out.join("results.md"), md)?;
    Ok(())
}

/// The method of a run, as the tables name it.
pub(super) fn method_label(s: &run::Summary) -> String {
    let paper_loop = || format!("paper loop, {:?}", s.sampling).to_lowercase();
    s.method.label(paper_loop, s.polish)
}

/// One row of `results.md`: the settings, our errors over seeds, the paper's and the baseline's.
fn results_row(task: &Task, ours: &[run::Summary], fd: Option<&run::Summary>) -> Vec<String> {
    let s = &ours[0];
    let paper = task.paper();
    let cell = |v: Option<f64>| v.map_or("-".to_string(), report::sci);
    // One run: its value; several: the median and the range over seeds.
    let over_seeds = |value: fn(&run::Summary) -> f64| {
        let values: Vec<f64> = ours.iter().map(value).collect();
        let (median, lo, hi) = report::spread(&values);
        if values.len() == 1 {
            report::sci(median)
        } else {
            format!(
                "{} [{}, {}]",
                report::sci(median),
                report::sci(lo),
                report::sci(hi)
            )
        }
    };
    vec![
        task.name().to_uppercase(),
        method_label(s),
        s.samples.to_string(),
        s.sigma0.to_string(),
        s.spp.to_string(),
        s.iterations.to_string(),
        ours.len().to_string(),
        over_seeds(|m| m.image_mse),
        over_seeds(|m| m.param_mse),
        cell(paper.map(|p| p.image_mse)),
        cell(paper.map(|p| p.param_mse)),
        paper.map_or("-".into(), |p| {
            let below = ours.iter().filter(|m| m.param_mse <= p.param_mse).count();
            format!("{below} of {}", ours.len())
        }),
        cell(fd.map(|f| f.image_mse)),
        cell(fd.map(|f| f.param_mse)),
        cell(paper.map(|p| p.mitsuba_param_mse)),
        format!("{:.3}", s.seconds_per_iteration),
        paper.map_or("-".into(), |p| format!("{:.2}", p.seconds_per_iteration)),
    ]
}
