//! The supplemental's experiments and the speed/accuracy study, one command each:
//! `cargo run --release -p pathtracer -- experiment <name> [--quick]`.
//!
//! Every experiment writes `<out>/<name>.csv` (the raw runs), one or more plots and
//! `<out>/<name>.md` (a table and what it shows) with the command that made it.
//!
//! One file per experiment; this file holds what they share: the options, the page and CSV
//! writers, the runs of variants over every task (Table 4 and the samplers) and the fitting.
//! Runs go through [`cache`], so an experiment that repeats another's run reads it back.
//! To add an experiment: a file with `pub(super) fn run(opts: &Options) -> Result<()>`, a
//! variant of [`Experiment`] and a line in [`run`].

mod ablation;
mod cache;
mod fig1;
mod fig2;
mod fig3;
mod fig4;
mod gradient_quality;
mod samplers;
mod table2;
mod tradeoff;

use std::fs;

use crate::report::{self, spread, Result};
use crate::run::{self, Outcome, Settings};
use crate::tasks::{self, Task};

/// The experiments, by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Experiment {
    /// Supplemental Fig. 1: seconds per iteration against N on SHADOW.
    Fig1,
    /// Supplemental Fig. 2: parameter MSE against iteration for N = 2, 4, 8, 16 on SHADOW.
    Fig2,
    /// Supplemental Fig. 3: final error against sigma0 on SHADOW at 40 and 60 degrees.
    Fig3,
    /// Supplemental Table 2: CUP, OCCLUSION, GI, CAUSTIC at sigma0 = 0.5.
    Table2,
    /// Supplemental Fig. 4: TEXTURE convergence.
    Fig4,
    /// Main paper Table 4: the ablations on every task.
    Ablation,
    /// Radial against per-coordinate against Gaussian on every task.
    Samplers,
    /// The speed/accuracy trade on SHADOW and GI: N, spp, resolution, sampler.
    Tradeoff,
    /// Relative error of one gradient estimate against N and spp on SHADOW.
    GradientQuality,
}

/// A named change of a task's default settings.
type Variant = (&'static str, fn(&mut Settings));

/// Points on the image-error curve of an experiment's run (fewer than a single run's
/// [`run::CURVE_POINTS`]: experiments make many runs and plot the parameter error).
const CURVE_POINTS: usize = 50;

/// Options shared by every experiment.
pub struct Options {
    /// Minutes instead of hours: fewer iterations, seeds and points, lower resolution.
    pub quick: bool,
    /// Where the files go.
    pub out: std::path::PathBuf,
    /// Only these tasks (for the experiments that run every task).
    pub tasks: Option<Vec<String>>,
    /// Seeds per point where the outcome is noisy (default: the experiment's own).
    pub seeds: Option<u64>,
    /// Accept cached runs of another build (see [`cache`]).
    pub reuse_runs: bool,
    /// Stop the first run not cached as Ctrl-C does, once this many iterations are done
    /// (testing).
    pub stop_after: Option<usize>,
}

impl Options {
    fn seeds(&self, full: u64) -> Vec<u64> {
        let count = self
            .seeds
            .unwrap_or(if self.quick { 1 } else { full })
            .max(1);
        (0..count).collect()
    }

    /// Scales a run down for `--quick`: a twentieth of the iterations (at least `min`), half
    /// the resolution. Quick runs only check that the experiment works end to end.
    fn shrink(&self, s: &mut Settings, min: usize) {
        if self.quick {
            s.iterations = (s.iterations / 20).max(min);
            s.scale = Some(s.scale.unwrap_or(1.0) * 0.5);
        }
        s.eval_every = run::eval_every(s.iterations, CURVE_POINTS);
    }

    fn command(&self, name: &str) -> String {
        format!(
            "cargo run --release -p pathtracer -- experiment {}{}{}{} --out {}",
            name.replace('_', "-"),
            if self.quick { " --quick" } else { "" },
            self.seeds
                .map_or(String::new(), |k| format!(" --seeds {k}")),
            self.tasks
                .as_ref()
                .map_or(String::new(), |t| format!(" --tasks {}", t.join(","))),
            self.out.display()
        )
    }

    /// Whether an experiment over every task includes `task`: the `--tasks` list if given;
    /// otherwise every task, or in a quick run the two cheapest (a smoke test, not a result).
    fn wants(&self, task: &Task) -> bool {
        match &self.tasks {
            Some(names) => names.iter().any(|n| n == task.name()),
            None => !self.quick || ["cup", "shadow"].contains(&task.name()),
        }
    }
}

/// Runs one experiment.
pub fn run(experiment: Experiment, opts: &Options) -> Result<()> {
    fs::create_dir_all(&opts.out)?;
    match experiment {
        Experiment::Fig1 => fig1::run(opts),
        Experiment::Fig2 => fig2::run(opts),
        Experiment::Fig3 => fig3::run(opts),
        Experiment::Table2 => table2::run(opts),
        Experiment::Fig4 => fig4::run(opts),
        Experiment::Ablation => ablation::run(opts),
        Experiment::Samplers => samplers::run(opts),
        Experiment::Tradeoff => tradeoff::run(opts),
        Experiment::GradientQuality => gradient_quality::run(opts),
    }
}

/// The task called `name`, or an error naming it.
fn task(name: &str) -> Result<Task> {
    tasks::by_name(name).ok_or_else(|| format!("no task {name}").into())
}

/// Least squares `y = a + b x`.
fn fit_line(points: &[(f64, f64)]) -> (f64, f64) {
    let n = points.len() as f64;
    let (sx, sy) = points
        .iter()
        .fold((0.0, 0.0), |(a, b), (x, y)| (a + x, b + y));
    let (mx, my) = (sx / n, sy / n);
    let sxx: f64 = points.iter().map(|(x, _)| (x - mx) * (x - mx)).sum();
    let sxy: f64 = points.iter().map(|(x, y)| (x - mx) * (y - my)).sum();
    let b = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    (my - b * mx, b)
}

/// `<out>/<name>.md`: the title, the command that made the page, then `body`.
fn write_page(opts: &Options, name: &str, title: &str, body: &str) -> Result<()> {
    let text = format!(
        "# {title}\n\nProduced by `{}`.\n\n{body}",
        opts.command(name)
    );
    fs::write(opts.out.join(format!("{name}.md")), text)?;
    eprintln!("wrote {}", opts.out.join(format!("{name}.md")).display());
    Ok(())
}

/// One run as a CSV row: `extra` cells, then [`SUMMARY_COLUMNS`].
fn summary_csv_row(o: &Outcome, extra: &[String]) -> Vec<String> {
    let m = &o.summary;
    let mut row = extra.to_vec();
    row.extend([
        m.task.clone(),
        format!("{:?}", m.method).to_lowercase(),
        m.sampling.to_string(),
        m.antithetic.to_string(),
        m.anneal.to_string(),
        m.samples.to_string(),
        m.spp.to_string(),
        m.sigma0.to_string(),
        m.seed.to_string(),
        m.width.to_string(),
        m.height.to_string(),
        m.iterations.to_string(),
        format!("{:e}", m.param_mse),
        format!("{:e}", m.image_mse),
        format!("{:.6}", m.seconds_per_iteration),
        format!("{:.6}", m.render_seconds_per_iteration),
        format!("{:.3e}", m.overhead_seconds_per_iteration),
        format!("{:.3}", m.seconds_total),
    ]);
    row
}

/// The columns of [`summary_csv_row`] after its `extra` cells.
const SUMMARY_COLUMNS: [&str; 18] = [
    "task",
    "method",
    "sampling",
    "antithetic",
    "anneal",
    "samples",
    "spp",
    "sigma0",
    "seed",
    "width",
    "height",
    "iterations",
    "param_mse",
    "image_mse",
    "seconds_per_iteration",
    "render_seconds_per_iteration",
    "overhead_seconds_per_iteration",
    "seconds_total",
];

/// A CSV header: `extra` columns, then [`SUMMARY_COLUMNS`].
fn header<'a>(extra: &[&'a str]) -> Vec<&'a str> {
    extra.iter().copied().chain(SUMMARY_COLUMNS).collect()
}

// What Table 4 (ablation.rs) and the sampler study (samplers.rs) share: variants on every task.

/// Every variant of every wanted task, over the seeds: `[task](name, [variant][seed])`.
/// One seed unless `--seeds` asks for more: Table 4 of the paper is one run per cell.
fn variants_on_tasks(
    opts: &Options,
    name: &str,
    variants: &[Variant],
) -> Result<Vec<(String, Vec<Vec<Outcome>>)>> {
    let seeds = opts.seeds(1);
    let mut per_task = Vec::new();
    let mut csv = Vec::new();
    for t in tasks::all() {
        if !opts.wants(&t) {
            continue;
        }
        let mut outcomes = Vec::new();
        for (label, change) in variants {
            let mut runs = Vec::new();
            for &seed in &seeds {
                let mut s = Settings::defaults(&t);
                change(&mut s);
                s.seed = seed;
                opts.shrink(&mut s, 30);
                let o = cache::optimize(opts, &t, &s)?;
                csv.push(summary_csv_row(&o, &[label.to_string()]));
                runs.push(o);
            }
            outcomes.push(runs);
        }
        per_task.push((t.name().to_uppercase(), outcomes));
    }
    report::write_csv(
        &opts.out.join(format!("{name}.csv")),
        &header(&["variant"]),
        csv,
    )?;
    Ok(per_task)
}

/// The start of a page over tasks: `intro`, the seeds per cell (with several, how a cell
/// aggregates them: `aggregate`), then the table.
fn page_over_tasks(
    opts: &Options,
    intro: &str,
    aggregate: &str,
    head: &[&str],
    rows: &[Vec<String>],
) -> String {
    let seeds = match opts.seeds(1).len() {
        1 => "One seed (0) per cell.".into(),
        k => format!("Seeds 0 to {} per cell; {aggregate}.", k - 1),
    };
    format!("{intro} {seeds}\n\n{}", report::markdown_table(head, rows))
}

/// `value` alone for one seed, `value [min, max]` for several.
fn with_range(values: &[f64], show: impl Fn(f64) -> String) -> String {
    let (m, lo, hi) = spread(values);
    if values.len() > 1 {
        format!("{} [{}, {}]", show(m), show(lo), show(hi))
    } else {
        show(m)
    }
}

/// The final parameter MSE of each run.
fn final_mse(runs: &[Outcome]) -> Vec<f64> {
    runs.iter().map(|o| o.summary.param_mse).collect()
}

/// Final errors within this many decades of each other count as a tie: one seed is not
/// enough to tell a few per cent apart.
const TIE_DECADES: f64 = 0.1;

/// 0 (worse), 1 (about equal) or 2 (better) for `log10(candidate / reference)`: an ablation
/// against the full method, or the runner-up sampler against the best (where 0 is a win).
fn verdict(log_ratio: f64) -> usize {
    if log_ratio > TIE_DECADES {
        0
    } else if log_ratio >= -TIE_DECADES {
        1
    } else {
        2
    }
}

/// `--quick` options writing into a fresh temporary directory named after `tag`.
#[cfg(test)]
pub(crate) fn quick_options(tag: &str) -> Options {
    Options {
        quick: true,
        out: std::env::temp_dir().join(format!("plateau-{tag}-{}", std::process::id())),
        tasks: None,
        seeds: None,
        reuse_runs: false,
        stop_after: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_line_recovers_slope_and_intercept() {
        let points: Vec<(f64, f64)> = (0..5).map(|i| (i as f64, 0.25 + 1.5 * i as f64)).collect();
        let (a, b) = fit_line(&points);
        assert!(
            (a - 0.25).abs() < 1e-12 && (b - 1.5).abs() < 1e-12,
            "{a} {b}"
        );
        // A cost that grows as x^0.9 gives exponent 0.9 in log-log.
        let power: Vec<(f64, f64)> = [2.0f64, 4.0, 8.0, 16.0]
            .iter()
            .map(|&x| (x.ln(), (0.07 * x.powf(0.9)).ln()))
            .collect();
        assert!((fit_line(&power).1 - 0.9).abs() < 1e-12);
    }

    /// Within a factor 10^0.1 an ablation or a sampler ties; beyond it, the sign decides.
    #[test]
    fn small_differences_are_ties() {
        assert_eq!(verdict(0.25), 0);
        assert_eq!(verdict(0.1), 1);
        assert_eq!(verdict(0.0), 1);
        assert_eq!(verdict(-0.1), 1);
        assert_eq!(verdict(-0.25), 2);
    }

    /// With several seeds the pages over tasks pair the runs by seed and show each cell's
    /// range; every seed is a run of its own, in the CSV.
    #[test]
    fn ablation_and_samplers_over_seeds_show_the_spread() {
        let mut opts = quick_options("seeds");
        opts.seeds = Some(2);
        opts.tasks = Some(vec!["cup".into()]);
        run(Experiment::Ablation, &opts).unwrap();
        run(Experiment::Samplers, &opts).unwrap();
        let ablation = fs::read_to_string(opts.out.join("ablation.md")).unwrap();
        assert!(ablation.contains("Seeds 0 to 1 per cell"), "{ablation}");
        assert!(ablation.contains("--seeds 2 --tasks cup"), "{ablation}");
        let cup = ablation.lines().find(|l| l.starts_with("| CUP")).unwrap();
        // The full method's range and one ratio range per ablation.
        assert_eq!(cup.matches('[').count(), 4, "{cup}");
        let csv = fs::read_to_string(opts.out.join("ablation.csv")).unwrap();
        assert_eq!(csv.lines().count(), 1 + 4 * 2);
        let samplers = fs::read_to_string(opts.out.join("samplers.md")).unwrap();
        assert!(samplers.contains("tasks won out of 1"), "{samplers}");
        assert!(ablation.contains("about equal on"), "{ablation}");
        let _ = fs::remove_dir_all(&opts.out);
    }

    /// CI's smoke test of every experiment command: the `--quick` variant of each writes its
    /// page (naming the command), its CSV and its plots. The numbers of such short runs mean
    /// nothing; that the commands work from a clean checkout is the point.
    #[test]
    fn every_quick_experiment_writes_its_page_csv_and_plots() {
        let opts = quick_options("experiments");
        let out = opts.out.clone();
        use clap::ValueEnum;
        for experiment in Experiment::value_variants() {
            run(*experiment, &opts).unwrap_or_else(|e| panic!("{experiment:?}: {e}"));
            let name = format!("{experiment:?}").to_lowercase();
            let stem = match name.as_str() {
                "gradientquality" => "gradient_quality".to_string(),
                other => other.to_string(),
            };
            let page = fs::read_to_string(out.join(format!("{stem}.md"))).expect("page written");
            assert!(
                page.contains("cargo run --release -p pathtracer -- experiment"),
                "{stem}: {page}"
            );
            assert!(out.join(format!("{stem}.csv")).exists(), "{stem}.csv");
        }
        for plot in [
            "fig1.png",
            "fig2.png",
            "fig3.png",
            "fig4/convergence.png",
            "tradeoff_shadow.png",
        ] {
            assert!(out.join(plot).exists(), "{plot}");
        }
        let _ = fs::remove_dir_all(&out);
    }
}
