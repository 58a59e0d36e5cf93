//! The supplemental's experiments and the speed/accuracy study, one command each:
//! `cargo run --release -p pathtracer -- experiment <name> [--quick]`.
//!
//! Every experiment writes `<out>/<name>.csv` (the raw runs), one or more plots and
//! `<out>/<name>.md` (a table and what it shows) with the command that made it.

use std::fmt::Write as _;
use std::fs;

use plateau::{PlateauFreeGradient, Seeded};

use crate::report::{self, sci, spread, Axes, Result, Scale, Series};
use crate::run::{self, Outcome, SamplerArg, Settings};
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
    /// Accept cached runs of another build (see [`quiet`]).
    pub reuse_runs: bool,
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
        s.eval_every = (s.iterations / 50).max(1);
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
    fn wants(&self, task: &dyn Task) -> bool {
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
        Experiment::Fig1 => fig1(opts),
        Experiment::Fig2 => fig2(opts),
        Experiment::Fig3 => fig3(opts),
        Experiment::Table2 => table2(opts),
        Experiment::Fig4 => fig4(opts),
        Experiment::Ablation => ablation(opts),
        Experiment::Samplers => samplers(opts),
        Experiment::Tradeoff => tradeoff(opts),
        Experiment::GradientQuality => gradient_quality(opts),
    }
}

fn task(name: &str) -> Result<Box<dyn Task>> {
    tasks::by_name(name).ok_or_else(|| format!("no task {name}").into())
}

/// Runs `task` with `s`, or reads the run back from `<out>/runs/` when this very binary made
/// it before with the same settings: the experiments share many runs (the task defaults are
/// the full method of the ablation, the radial sampler of the sampler study, the base of the
/// trade-off, N = 2 of Fig. 2), and runs are deterministic, so each is made once. The key is
/// the task and every setting; the entry also holds a hash of the executable, so any change
/// of code misses the cache instead of reusing a stale run. `runs/` is not committed: a clean
/// checkout recomputes everything.
fn quiet(opts: &Options, task: &dyn Task, s: &Settings) -> Result<Outcome> {
    let key = format!("{} {:?}", task.name(), s);
    let file = opts.out.join("runs").join(format!(
        "{}-{:016x}.json",
        task.name(),
        fnv1a(key.as_bytes())
    ));
    let build = executable_hash();
    let cached = fs::read(&file)
        .ok()
        .and_then(|bytes| serde_json::from_slice::<CachedRun>(&bytes).ok())
        .filter(|c| c.key == key && (opts.reuse_runs || Some(c.build) == build));
    let (outcome, source) = match cached {
        Some(c) => (c.outcome, "cached"),
        None => {
            let outcome = run::optimize(task, s, None, false)?;
            if let Some(build) = build {
                let entry = CachedRun {
                    key,
                    build,
                    outcome,
                };
                fs::create_dir_all(file.parent().expect("runs/ has a parent"))?;
                // Write then rename, so a concurrent experiment never reads half a file.
                let tmp = file.with_extension(format!("tmp{}", std::process::id()));
                fs::write(&tmp, serde_json::to_vec(&entry)?)?;
                fs::rename(&tmp, &file)?;
                (entry.outcome, "ran")
            } else {
                (outcome, "ran")
            }
        }
    };
    let m = &outcome.summary;
    eprintln!(
        "  {:>9} {:<32} N={:<2} spp={:<3} sigma0={:<5} seed={} -> param MSE {:.3e}, image MSE {:.3e}, {:.4} s/it ({source})",
        m.task,
        s.label(),
        s.samples,
        s.spp,
        s.sigma0,
        s.seed,
        m.param_mse,
        m.image_mse,
        m.seconds_per_iteration
    );
    Ok(outcome)
}

/// One entry of the run cache.
#[derive(serde::Serialize, serde::Deserialize)]
struct CachedRun {
    key: String,
    build: u64,
    outcome: Outcome,
}

/// A hash of the running executable (`None` if it cannot be read: then nothing is cached).
fn executable_hash() -> Option<u64> {
    static HASH: std::sync::OnceLock<Option<u64>> = std::sync::OnceLock::new();
    *HASH.get_or_init(|| {
        let exe = std::env::current_exe().ok()?;
        fs::read(exe).ok().map(|bytes| fnv1a(&bytes))
    })
}

/// 64-bit FNV-1a: stable across runs and Rust versions, unlike `DefaultHasher`.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
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

fn write_page(opts: &Options, name: &str, title: &str, body: &str) -> Result<()> {
    let text = format!(
        "# {title}\n\nProduced by `{}`.\n\n{body}",
        opts.command(name)
    );
    fs::write(opts.out.join(format!("{name}.md")), text)?;
    eprintln!("wrote {}", opts.out.join(format!("{name}.md")).display());
    Ok(())
}

fn summary_csv_row(o: &Outcome, extra: &[String]) -> Vec<String> {
    let m = &o.summary;
    let mut row = extra.to_vec();
    row.extend([
        m.task.clone(),
        format!("{:?}", m.method).to_lowercase(),
        format!("{:?}", m.sampling).to_lowercase(),
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

fn header<'a>(extra: &[&'a str]) -> Vec<&'a str> {
    extra.iter().copied().chain(SUMMARY_COLUMNS).collect()
}

// ---------------------------------------------------------------------------------------
// Fig. 1: runtime against N.

fn fig1(opts: &Options) -> Result<()> {
    let shadow = task("shadow")?;
    let ns: Vec<usize> = if opts.quick {
        vec![2, 4, 8]
    } else {
        vec![2, 4, 6, 8, 10, 12, 14, 16]
    };
    let mut runs = Vec::new();
    for &n in &ns {
        let mut s = Settings::defaults(shadow.as_ref());
        s.samples = n;
        s.iterations = if opts.quick { 4 } else { 20 };
        s.eval_every = usize::MAX;
        if opts.quick {
            s.scale = Some(0.5);
        }
        runs.push((n, quiet(opts, shadow.as_ref(), &s)?));
    }
    let total: Vec<(f64, f64)> = runs
        .iter()
        .map(|(n, o)| (*n as f64, o.summary.seconds_per_iteration))
        .collect();
    let overhead: Vec<(f64, f64)> = runs
        .iter()
        .map(|(n, o)| (*n as f64, o.summary.overhead_seconds_per_iteration))
        .collect();
    let (a, b) = fit_line(&total);
    let fitted: Vec<(f64, f64)> = ns.iter().map(|&n| (n as f64, a + b * n as f64)).collect();
    report::write_csv(
        &opts.out.join("fig1.csv"),
        &header(&["N"]),
        runs.iter()
            .map(|(n, o)| summary_csv_row(o, &[n.to_string()])),
    )?;
    report::plot(
        &opts.out.join("fig1.png"),
        &Axes {
            title: "SHADOW: seconds per iteration against N",
            x_label: "N (evaluations per gradient)",
            y_label: "seconds per iteration",
            x_scale: Scale::Linear,
            y_scale: Scale::Log,
        },
        &[
            Series::markers("measured (render + estimator + Adam)", total.clone()),
            Series::line(format!("fit {a:.4} + {b:.4} N"), fitted),
            Series::markers(
                "everything but rendering (estimator, Adam, loss)",
                overhead.clone(),
            ),
        ],
    )?;
    let rows: Vec<Vec<String>> = runs
        .iter()
        .map(|(n, o)| {
            let m = &o.summary;
            vec![
                n.to_string(),
                format!("{:.4}", m.seconds_per_iteration),
                format!("{:.4}", m.render_seconds_per_iteration),
                format!("{:.2e}", m.overhead_seconds_per_iteration),
                format!(
                    "{:.4} %",
                    100.0 * m.overhead_seconds_per_iteration / m.seconds_per_iteration
                ),
            ]
        })
        .collect();
    let s0 = &runs[0].1.summary;
    let mut body = format!(
        "SHADOW at {}x{}, {} spp, depth 6; {} iterations per point, timed on this machine's cores.\n\n![fig1](fig1.png)\n\n",
        s0.width, s0.height, s0.spp, s0.iterations
    );
    body.push_str(&report::markdown_table(
        &[
            "N",
            "s/iteration",
            "of which rendering",
            "everything else (s)",
            "everything else, share",
        ],
        &rows,
    ));
    let _ = write!(
        body,
        "\nThe least-squares line is {a:.4} s + {b:.4} s x N: the cost is linear in N, and each evaluation costs one render. Everything but rendering (the estimator, Adam and the image loss) stays below {:.3} % of an iteration at every N: the renderer is the cost, as in the paper's Fig. 1.\n",
        rows.iter()
            .zip(&runs)
            .map(|(_, (_, o))| 100.0 * o.summary.overhead_seconds_per_iteration / o.summary.seconds_per_iteration)
            .fold(0.0, f64::max)
    );
    write_page(
        opts,
        "fig1",
        "Supplemental Fig. 1: runtime against N (SHADOW)",
        &body,
    )
}

// ---------------------------------------------------------------------------------------
// Fig. 2: convergence against N.

/// Parameter MSEs at which Fig. 2 times a SHADOW run: 1e-2 is reached while sigma is still
/// sigma0 (the smoothed optimum lies near 5e-3), 1e-3 mostly once sigma anneals.
const REACHED: [f64; 2] = [1e-2, 1e-3];

/// "k of S runs; median iteration I, median T s" for the first row of each run's history at
/// or below `threshold`.
fn time_to_reach(histories: &[Vec<run::Row>], threshold: f64) -> String {
    let hits: Vec<&run::Row> = histories
        .iter()
        .filter_map(|h| h.iter().find(|r| r.param_mse <= threshold))
        .collect();
    if hits.is_empty() {
        return format!("0 of {}", histories.len());
    }
    let iterations: Vec<f64> = hits.iter().map(|r| r.iteration as f64).collect();
    let seconds: Vec<f64> = hits.iter().map(|r| r.seconds).collect();
    format!(
        "{} of {}: iteration {:.0}, {:.1} s",
        hits.len(),
        histories.len(),
        spread(&iterations).0,
        spread(&seconds).0
    )
}

fn fig2(opts: &Options) -> Result<()> {
    let shadow = task("shadow")?;
    let seeds = opts.seeds(3);
    let mut series = Vec::new();
    let mut rows = Vec::new();
    let mut csv = Vec::new();
    for n in [2usize, 4, 8, 16] {
        let mut finals = Vec::new();
        let mut histories = Vec::new();
        let mut curves: Vec<Vec<f64>> = Vec::new();
        for &seed in &seeds {
            let mut s = Settings::defaults(shadow.as_ref());
            s.samples = n;
            s.seed = seed;
            opts.shrink(&mut s, 40);
            let o = quiet(opts, shadow.as_ref(), &s)?;
            finals.push(o.summary.param_mse);
            curves.push(o.history.iter().map(|r| r.param_mse).collect());
            for r in &o.history {
                csv.push(vec![
                    n.to_string(),
                    seed.to_string(),
                    r.iteration.to_string(),
                    format!("{:e}", r.param_mse),
                    format!("{:e}", r.loss),
                    format!("{:.4}", r.seconds),
                ]);
            }
            histories.push(o.history);
        }
        let len = curves.iter().map(Vec::len).min().unwrap_or(0);
        let median: Vec<(f64, f64)> = (0..len)
            .map(|i| {
                (
                    i as f64,
                    spread(&curves.iter().map(|c| c[i]).collect::<Vec<_>>()).0,
                )
            })
            .collect();
        series.push(Series::line(format!("N = {n}"), median));
        let (m, lo, hi) = spread(&finals);
        rows.push(vec![
            n.to_string(),
            sci(m),
            format!("[{}, {}]", sci(lo), sci(hi)),
            time_to_reach(&histories, REACHED[0]),
            time_to_reach(&histories, REACHED[1]),
        ]);
    }
    report::write_csv(
        &opts.out.join("fig2.csv"),
        &["N", "seed", "iteration", "param_mse", "loss", "seconds"],
        csv,
    )?;
    report::plot(
        &opts.out.join("fig2.png"),
        &Axes {
            title: "SHADOW: parameter MSE against iteration (median over seeds)",
            x_label: "iteration",
            y_label: "parameter MSE",
            x_scale: Scale::Linear,
            y_scale: Scale::Log,
        },
        &series,
    )?;
    let mut body = format!(
        "{} seed(s) per N; the curve is the median over seeds.\n\n![fig2](fig2.png)\n\n",
        seeds.len()
    );
    body.push_str(&report::markdown_table(
        &[
            "N",
            "final parameter MSE (median)",
            "[min, max] over seeds",
            "runs reaching 1e-2: median iteration, seconds",
            "runs reaching 1e-3: median iteration, seconds",
        ],
        &rows,
    ));
    body.push_str("\nA run reaches 1e-2 (or 1e-3) at the first iteration whose parameter MSE is at most that; its seconds are optimisation time on this machine, so they weigh faster convergence against N renders per iteration (Fig. 1). On SHADOW the error levels off near 5e-3 while sigma stays at sigma0 = 0.5 (the first half of the run: the minimum of the smoothed loss lies there, not at the target) and falls far below 1e-3 once sigma anneals; so 1e-2 measures how N speeds up the descent, 1e-3 mostly when annealing begins.\n");
    body.push_str(
        "\nPaper (supplemental Sec. 2): parameter MSE 9.5e-5 at N = 2 and 4.7e-6 at N = 16.\n",
    );
    write_page(
        opts,
        "fig2",
        "Supplemental Fig. 2: convergence against N (SHADOW)",
        &body,
    )
}

// ---------------------------------------------------------------------------------------
// Fig. 3: final error against sigma0 at two fields of view.

/// SHADOW's own horizontal field of view (degrees): the paper's 40.
const SHADOW_FOV: f64 = 39.597755;

fn fig3(opts: &Options) -> Result<()> {
    let shadow = task("shadow")?;
    let sigmas: Vec<f64> = if opts.quick {
        vec![0.05, 0.5, 1.0]
    } else {
        vec![0.05, 0.1, 0.25, 0.5, 0.75, 1.0]
    };
    let seeds = opts.seeds(2);
    let mut series = Vec::new();
    let mut csv = Vec::new();
    let mut rows = Vec::new();
    let paper = shadow.paper().map_or(f64::NAN, |p| p.param_mse);
    let mut findings = String::new();
    for fov in [SHADOW_FOV, 60.0] {
        let mut medians = Vec::new();
        let mut counts = Vec::new();
        for &sigma0 in &sigmas {
            let mut finals = Vec::new();
            for &seed in &seeds {
                let mut s = Settings::defaults(shadow.as_ref());
                s.sigma0 = sigma0;
                s.seed = seed;
                // The task's own view is `None`, so the run is shared with the other experiments.
                s.fov_degrees = (fov != SHADOW_FOV).then_some(fov);
                opts.shrink(&mut s, 40);
                let o = quiet(opts, shadow.as_ref(), &s)?;
                finals.push(o.summary.param_mse);
                csv.push(summary_csv_row(&o, &[format!("{fov}")]));
            }
            let (m, lo, hi) = spread(&finals);
            medians.push((sigma0, m));
            let good = finals.iter().filter(|&&f| f <= paper).count();
            counts.push(format!("{sigma0}: {good} of {}", finals.len()));
            rows.push(vec![
                format!("{fov:.0}"),
                sigma0.to_string(),
                sci(m),
                format!("[{}, {}]", sci(lo), sci(hi)),
                format!("{good} of {}", finals.len()),
            ]);
        }
        let _ = writeln!(
            findings,
            "- {fov:.0} degrees, runs at or below the paper's SHADOW result ({}) per sigma0: {}.",
            sci(paper),
            counts.join("; ")
        );
        series.push(Series::line(
            format!("{fov:.0} degrees field of view"),
            medians,
        ));
    }
    report::write_csv(&opts.out.join("fig3.csv"), &header(&["fov"]), csv)?;
    report::plot(
        &opts.out.join("fig3.png"),
        &Axes {
            title: "SHADOW: final parameter MSE against sigma0 (median over seeds)",
            x_label: "sigma0",
            y_label: "final parameter MSE",
            x_scale: Scale::Linear,
            y_scale: Scale::Log,
        },
        &series,
    )?;
    let mut body = format!(
        "{} seed(s) per point.\n\n![fig3](fig3.png)\n\n",
        seeds.len()
    );
    body.push_str(&report::markdown_table(
        &[
            "fov (degrees)",
            "sigma0",
            "final parameter MSE (median)",
            "[min, max]",
            "runs at or below the paper's 1.81e-3",
        ],
        &rows,
    ));
    body.push('\n');
    body.push_str(&findings);
    body.push_str("\nPaper (supplemental Fig. 3): below sigma0 = 0.2 the run fails like a plain gradient; near sigma0 = 1 samples leave the view at 40 degrees, fixed at 60 degrees.\n");
    write_page(
        opts,
        "fig3",
        "Supplemental Fig. 3: final error against sigma0 (SHADOW)",
        &body,
    )
}

// ---------------------------------------------------------------------------------------
// Table 2: sigma0 = 0.5 on the tasks whose default differs.

fn table2(opts: &Options) -> Result<()> {
    let mut rows = Vec::new();
    let mut csv = Vec::new();
    let mut at_or_below = 0;
    for name in ["cup", "occlusion", "gi", "caustic"] {
        let t = task(name)?;
        if !opts.wants(t.as_ref()) {
            continue;
        }
        let mut s = Settings::defaults(t.as_ref());
        s.sigma0 = 0.5;
        opts.shrink(&mut s, 40);
        let o = quiet(opts, t.as_ref(), &s)?;
        let paper = t.paper().and_then(|p| p.sigma05);
        let ratio = paper.map_or(f64::NAN, |p| o.summary.param_mse / p.1);
        at_or_below += usize::from(ratio <= 1.0);
        rows.push(vec![
            name.to_uppercase(),
            sci(o.summary.image_mse),
            sci(o.summary.param_mse),
            paper.map_or("-".into(), |p| sci(p.0)),
            paper.map_or("-".into(), |p| sci(p.1)),
            format!("{ratio:.2}"),
        ]);
        csv.push(summary_csv_row(&o, &[]));
    }
    report::write_csv(&opts.out.join("table2.csv"), &header(&[]), csv)?;
    let mut body = String::from("Every task whose default sigma0 differs from 0.5, re-run at sigma0 = 0.5 with its other defaults.\n\n");
    body.push_str(&report::markdown_table(
        &[
            "task",
            "ours image MSE",
            "ours parameter MSE",
            "paper image MSE",
            "paper parameter MSE",
            "ours / paper (parameter MSE)",
        ],
        &rows,
    ));
    let _ = writeln!(
        body,
        "\n{at_or_below} of {} tasks end at or below the paper's parameter MSE at sigma0 = 0.5 (one seed, 0).",
        rows.len()
    );
    write_page(opts, "table2", "Supplemental Table 2: sigma0 = 0.5", &body)
}

// ---------------------------------------------------------------------------------------
// Fig. 4: the TEXTURE task.

fn fig4(opts: &Options) -> Result<()> {
    let t = task("texture")?;
    let mut s = Settings::defaults(t.as_ref());
    opts.shrink(&mut s, 30);
    let dir = opts.out.join("fig4");
    let o = run::optimize(t.as_ref(), &s, Some(&dir), false)?;
    run::write_history(&opts.out.join("fig4.csv"), &o.history)?;
    let m = &o.summary;
    let body = format!(
        "{} parameters, N = {}, sigma0 = {}, lr = {}, {} iterations, {} spp.\n\n![convergence](fig4/convergence.png)\n\nTarget, start and result: ![target](fig4/target.png) ![initial](fig4/initial.png) ![final](fig4/final.png)\n\n{}",
        m.dim,
        m.samples,
        m.sigma0,
        m.lr,
        m.iterations,
        m.spp,
        report::markdown_table(
            &["", "image MSE", "parameter MSE"],
            &[vec!["start".into(), sci(m.initial_image_mse), sci(m.initial_param_mse)], vec!["end".into(), sci(m.image_mse), sci(m.param_mse)]]
        )
    );
    // Whether the run was still improving: the parameter error over its last tenth.
    let tail = o.history.len() - o.history.len() / 10;
    let before = o
        .history
        .get(tail.saturating_sub(1))
        .map_or(f64::NAN, |r| r.param_mse);
    let body = format!(
        "{body}\nOver the run the image MSE fell {:.1}x and the parameter MSE {:.1}x; over its last tenth the parameter MSE changed by {:+.1} % (from {} to {}): {}.\n",
        m.initial_image_mse / m.image_mse,
        m.initial_param_mse / m.param_mse,
        100.0 * (m.param_mse / before - 1.0),
        sci(before),
        sci(m.param_mse),
        if m.param_mse < 0.99 * before {
            "still falling, so more iterations would go on improving it"
        } else {
            "levelled off"
        }
    );
    write_page(
        opts,
        "fig4",
        "Supplemental Fig. 4: TEXTURE (49,152 parameters)",
        &body,
    )
}

// ---------------------------------------------------------------------------------------
// Table 4 and the samplers: variants on every task.

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
        if !opts.wants(t.as_ref()) {
            continue;
        }
        let mut outcomes = Vec::new();
        for (label, change) in variants {
            let mut runs = Vec::new();
            for &seed in &seeds {
                let mut s = Settings::defaults(t.as_ref());
                change(&mut s);
                s.seed = seed;
                opts.shrink(&mut s, 30);
                let o = quiet(opts, t.as_ref(), &s)?;
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

/// "One seed (0) per cell." or "Seeds 0 to K-1 per cell; ...", for the pages over tasks.
fn seeds_sentence(opts: &Options, aggregate: &str) -> String {
    match opts.seeds(1).len() {
        1 => "One seed (0) per cell.".into(),
        k => format!("Seeds 0 to {} per cell; {aggregate}.", k - 1),
    }
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

fn ablation(opts: &Options) -> Result<()> {
    let variants: [Variant; 4] = [
        ("full", |_| {}),
        ("no importance sampling", |s| {
            s.sampling = SamplerArg::Gaussian
        }),
        ("no annealing", |s| s.anneal = false),
        ("no antithetic", |s| s.antithetic = false),
    ];
    let per_task = variants_on_tasks(opts, "ablation", &variants)?;
    let mut rows = Vec::new();
    let mut sums = vec![0.0; variants.len()];
    // [worse, about equal, better] per ablation.
    let mut verdicts = vec![[0usize; 3]; variants.len()];
    for (name, outcomes) in &per_task {
        let full = final_mse(&outcomes[0]);
        let mut row = vec![name.clone(), with_range(&full, sci)];
        for (k, runs) in outcomes.iter().enumerate().skip(1) {
            // Paired by seed: the same seed draws the same renderer noise for both runs.
            let ratios: Vec<f64> = runs
                .iter()
                .zip(&full)
                .map(|(o, f)| (o.summary.param_mse / f).log10())
                .collect();
            let median_ratio = spread(&ratios).0;
            sums[k] += median_ratio;
            verdicts[k][verdict(median_ratio)] += 1;
            row.push(format!(
                "{} ({})",
                sci(spread(&final_mse(runs)).0),
                with_range(&ratios, |r| format!("{r:+.2}"))
            ));
        }
        rows.push(row);
    }
    let count = per_task.len().max(1) as f64;
    let mut mean = vec!["mean log10 ratio".into(), String::new()];
    mean.extend(sums.iter().skip(1).map(|s| format!("{:+.2}", s / count)));
    rows.push(mean);
    let mut head = vec!["task", "full: param MSE"];
    head.extend(variants.iter().skip(1).map(|v| v.0));
    let mut body = format!(
        "Final parameter MSE of each ablation, and in brackets log10(ablation / full): positive means the ablation is worse. \"No importance sampling\" is the Gaussian sampler; \"no antithetic\" draws N independent perturbations. {}\n\n",
        seeds_sentence(
            opts,
            "each cell shows the median parameter MSE over seeds and the median [min, max] of the per-seed log ratios (an ablation and the full method with the same seed form a pair); the mean row averages the medians"
        )
    );
    body.push_str(&report::markdown_table(&head, &rows));
    let verdicts: Vec<String> = variants
        .iter()
        .zip(&verdicts)
        .skip(1)
        .map(|(v, [worse, equal, better])| {
            format!(
                "{}: worse than the full method on {worse} of {}, about equal on {equal}, better on {better}",
                v.0,
                per_task.len()
            )
        })
        .collect();
    let _ = writeln!(
        body,
        "\n{}{}. About equal means within a factor {:.2} (|log10 ratio| <= {TIE_DECADES}); one seed's noise alone moves a run by more than that on several tasks.",
        verdicts.join("; "),
        if opts.seeds(1).len() > 1 {
            " (by the median log ratio)"
        } else {
            ""
        },
        10f64.powf(TIE_DECADES)
    );
    write_page(
        opts,
        "ablation",
        "Main paper Table 4: ablations on every task",
        &body,
    )
}

fn samplers(opts: &Options) -> Result<()> {
    let variants: [Variant; 3] = [
        ("radial", |s| s.sampling = SamplerArg::Radial),
        ("per-coordinate", |s| s.sampling = SamplerArg::PerCoordinate),
        ("gaussian", |s| s.sampling = SamplerArg::Gaussian),
    ];
    let per_task = variants_on_tasks(opts, "samplers", &variants)?;
    let seeds = opts.seeds(1).len();
    let mut rows = Vec::new();
    let mut wins = vec![0usize; variants.len()];
    let mut ties = 0;
    for (name, outcomes) in &per_task {
        // Error at equal time: each sampler's parameter MSE when the fastest of the three
        // runs with the same seed ended.
        let budgets: Vec<f64> = (0..seeds)
            .map(|i| {
                outcomes
                    .iter()
                    .map(|runs| runs[i].summary.seconds_total)
                    .fold(f64::INFINITY, f64::min)
            })
            .collect();
        let mut row = vec![name.clone()];
        let mut medians = Vec::new();
        for runs in outcomes {
            let at_budget: Vec<f64> = runs
                .iter()
                .zip(&budgets)
                .map(|(o, &budget)| {
                    o.history
                        .iter()
                        .take_while(|r| r.seconds <= budget)
                        .last()
                        .map_or(f64::NAN, |r| r.param_mse)
                })
                .collect();
            let finals = final_mse(runs);
            medians.push(spread(&finals).0);
            row.push(format!(
                "{} / {}",
                with_range(&finals, sci),
                sci(spread(&at_budget).0)
            ));
        }
        let mut order: Vec<usize> = (0..medians.len()).collect();
        order.sort_by(|&a, &b| medians[a].total_cmp(&medians[b]));
        if verdict((medians[order[1]] / medians[order[0]]).log10()) == 0 {
            wins[order[0]] += 1;
        } else {
            ties += 1;
        }
        rows.push(row);
    }
    let mut head = vec!["task"];
    head.extend(variants.iter().map(|v| v.0));
    let mut body = format!(
        "Each cell: final parameter MSE / parameter MSE at the time the fastest of the three runs finished (equal time). {}\n\n",
        seeds_sentence(
            opts,
            "each cell shows the median final MSE [min, max] over seeds / the median at equal time; wins are counted by the median"
        )
    );
    body.push_str(&report::markdown_table(&head, &rows));
    let wins: Vec<String> = variants
        .iter()
        .zip(&wins)
        .map(|(v, w)| format!("{}: {w}", v.0))
        .collect();
    let _ = writeln!(
        body,
        "\nLowest final parameter MSE by more than a factor {:.2} over the next sampler, tasks won out of {}: {}; ties (the best two within that factor): {ties}.",
        10f64.powf(TIE_DECADES),
        per_task.len(),
        wins.join(", ")
    );
    // The samplers differ only in the estimator, whose cost is tiny next to a render.
    let spread_of_cost = per_task
        .iter()
        .map(|(_, o)| {
            let (lo, hi) = o
                .iter()
                .flatten()
                .fold((f64::INFINITY, 0.0f64), |(lo, hi), o| {
                    let t = o.summary.seconds_per_iteration;
                    (lo.min(t), hi.max(t))
                });
            hi / lo - 1.0
        })
        .fold(0.0f64, f64::max);
    let _ = writeln!(
        body,
        "\nSeconds per iteration differ between the samplers by at most {:.1} % on any task (timing noise: the estimator's cost is negligible next to the renders), so equal time is equal iterations give or take a few, and the equal-time column differs from the final one only by how much a run still fluctuates at its end.",
        100.0 * spread_of_cost
    );
    write_page(opts, "samplers", "Samplers on every task", &body)
}

// ---------------------------------------------------------------------------------------
// The speed/accuracy trade.

fn tradeoff(opts: &Options) -> Result<()> {
    let mut csv = Vec::new();
    let mut body = String::from(
        "One factor at a time around each task's defaults; every run records its wall time (optimisation only) and final errors. The Pareto front (no other run both faster and more accurate) is marked.\n\n",
    );
    for name in ["shadow", "gi"] {
        let t = task(name)?;
        if !opts.wants(t.as_ref()) {
            continue;
        }
        let base = Settings::defaults(t.as_ref());
        let mut configs: Vec<(String, Settings)> = Vec::new();
        let ns: &[usize] = if opts.quick { &[2, 4] } else { &[2, 4, 8, 16] };
        let spps: &[u32] = if opts.quick {
            &[8]
        } else {
            &[4, 8, 16, 32, 64]
        };
        let scales: &[f64] = if opts.quick {
            &[0.5]
        } else {
            &[0.25, 0.5, 0.75, 1.0]
        };
        for &n in ns {
            let mut s = base.clone();
            s.samples = n;
            configs.push((format!("N={n}"), s));
        }
        for &spp in spps {
            let mut s = base.clone();
            s.spp = spp;
            configs.push((format!("spp={spp}"), s));
        }
        for &scale in scales {
            let mut s = base.clone();
            s.scale = (scale != 1.0).then_some(scale);
            configs.push((format!("scale={scale}"), s));
        }
        for sampler in [SamplerArg::PerCoordinate, SamplerArg::Gaussian] {
            let mut s = base.clone();
            s.sampling = sampler;
            configs.push((format!("{sampler:?}").to_lowercase(), s));
        }
        let mut results = Vec::new();
        let mut ran = Vec::new();
        for (label, mut s) in configs {
            if opts.quick {
                s.iterations = (s.iterations / 20).max(30);
                s.scale = Some(s.scale.unwrap_or(1.0) * 0.5);
            }
            s.eval_every = (s.iterations / 50).max(1);
            let o = quiet(opts, t.as_ref(), &s)?;
            csv.push(summary_csv_row(&o, std::slice::from_ref(&label)));
            results.push((label, o.summary));
            ran.push(s);
        }
        let points: Vec<(f64, f64)> = results
            .iter()
            .map(|(_, m)| (m.seconds_total, m.param_mse))
            .collect();
        let front = pareto(&points);
        report::plot(
            &opts.out.join(format!("tradeoff_{name}.png")),
            &Axes {
                title: &format!(
                    "{}: final parameter MSE against wall time",
                    name.to_uppercase()
                ),
                x_label: "seconds (optimisation)",
                y_label: "final parameter MSE",
                x_scale: Scale::Log,
                y_scale: Scale::Log,
            },
            &[
                Series::markers("runs", points.clone()),
                Series::line("Pareto front", front.iter().map(|&i| points[i]).collect()),
            ],
        )?;
        // Cost exponents from the one-factor sweeps: log(seconds per iteration) against log(factor).
        let exponent = |prefix: &str, value: &dyn Fn(&run::Summary) -> f64| {
            let pts: Vec<(f64, f64)> = results
                .iter()
                .filter(|(l, _)| l.starts_with(prefix))
                .map(|(_, m)| (value(m).ln(), m.seconds_per_iteration.ln()))
                .collect();
            fit_line(&pts).1
        };
        let e_n = exponent("N=", &|m| m.samples as f64);
        let e_spp = exponent("spp=", &|m| m.spp as f64);
        let e_px = exponent("scale=", &|m| (m.width * m.height) as f64);
        let rows: Vec<Vec<String>> = results
            .iter()
            .enumerate()
            .map(|(i, (label, m))| {
                vec![
                    label.clone(),
                    format!("{}x{}", m.width, m.height),
                    format!("{:.4}", m.seconds_per_iteration),
                    format!("{:.1}", m.seconds_total),
                    sci(m.image_mse),
                    sci(m.param_mse),
                    if front.contains(&i) {
                        "yes".into()
                    } else {
                        String::new()
                    },
                ]
            })
            .collect();
        let paper = t.paper().map_or(f64::NAN, |p| p.param_mse);
        // The N sweep's run at the default N is the task's defaults.
        let default_index = results
            .iter()
            .position(|(l, _)| *l == format!("N={}", base.samples));
        let default_seconds = default_index.map_or(f64::NAN, |d| results[d].1.seconds_total);
        let fastest_index = (0..results.len())
            .filter(|&i| results[i].1.param_mse <= paper)
            .min_by(|&a, &b| {
                results[a]
                    .1
                    .seconds_total
                    .total_cmp(&results[b].1.seconds_total)
            });
        let fastest = fastest_index.map(|i| &results[i]);
        let mut verdict = fastest.map_or_else(
            || format!("No run ended at or below the paper's parameter MSE ({}).", sci(paper)),
            |(label, m)| {
                format!(
                    "Fastest run at or below the paper's parameter MSE ({}): {label}, {:.1} s ({:.4} s/iteration), against {:.1} s for the task's defaults.",
                    sci(paper),
                    m.seconds_total,
                    m.seconds_per_iteration,
                    default_seconds
                )
            },
        );
        // One seed can be lucky: the fastest converging settings and the defaults again over
        // three seeds (the sweep's seed-0 runs are reused).
        if let Some(i) = fastest_index {
            let mut checks = vec![(results[i].0.clone(), ran[i].clone())];
            if let Some(d) = default_index.filter(|&d| d != i) {
                checks.push(("defaults".to_string(), ran[d].clone()));
            }
            let seeds = opts.seeds(3);
            let mut parts = Vec::new();
            for (label, settings) in checks {
                let mut finals = Vec::new();
                for &seed in &seeds {
                    let mut s = settings.clone();
                    s.seed = seed;
                    let o = quiet(opts, t.as_ref(), &s)?;
                    csv.push(summary_csv_row(&o, &[format!("seeds: {label}")]));
                    finals.push(o.summary.param_mse);
                }
                let good = finals.iter().filter(|&&m| m <= paper).count();
                let (median, lo, hi) = spread(&finals);
                parts.push(format!(
                    "{label}: {good} of {} at or below it (median {}, range [{}, {}])",
                    finals.len(),
                    sci(median),
                    sci(lo),
                    sci(hi)
                ));
            }
            let _ = write!(
                verdict,
                " Over seeds 0 to {}: {}.",
                seeds.len() - 1,
                parts.join("; ")
            );
        }
        let _ = write!(
            body,
            "## {}\n\n![tradeoff](tradeoff_{name}.png)\n\n{}\nCost per iteration grows as N^{e_n:.2}, spp^{e_spp:.2} and pixels^{e_px:.2} (least-squares slopes in log-log over the one-factor sweeps).\n\n{verdict}\n\n",
            name.to_uppercase(),
            report::markdown_table(&["run", "resolution", "s/iteration", "seconds", "image MSE", "param MSE", "Pareto"], &rows)
        );
    }
    body.push_str("Dimension: the estimator's own cost is linear in n (see `docs/estimators.md`, `cargo bench --bench estimator`); the renders' cost does not depend on n.\n");
    report::write_csv(&opts.out.join("tradeoff.csv"), &header(&["run"]), csv)?;
    write_page(
        opts,
        "tradeoff",
        "The speed/accuracy trade (SHADOW and GI)",
        &body,
    )
}

/// Indices of the points no other point beats in both coordinates (smaller is better), by
/// increasing first coordinate.
fn pareto(points: &[(f64, f64)]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..points.len())
        .filter(|&i| points[i].0.is_finite() && points[i].1.is_finite())
        .collect();
    order.sort_by(|&a, &b| points[a].0.total_cmp(&points[b].0));
    let mut best = f64::INFINITY;
    order
        .into_iter()
        .filter(|&i| {
            let keep = points[i].1 < best;
            if keep {
                best = points[i].1;
            }
            keep
        })
        .collect()
}

// ---------------------------------------------------------------------------------------
// Gradient quality at fixed cost.

fn gradient_quality(opts: &Options) -> Result<()> {
    let shadow = task("shadow")?;
    let defaults = Settings::defaults(shadow.as_ref());
    let target = shadow.target();
    let near: Vec<f64> = target.iter().map(|x| x + 0.1).collect();
    let places = [
        ("start", shadow.start(), defaults.sigma0),
        ("near the optimum", near, 0.05),
    ];
    let ns: &[usize] = if opts.quick { &[2, 8] } else { &[2, 4, 8, 16] };
    let spps: &[u32] = if opts.quick { &[4, 16] } else { &[4, 16, 64] };
    let repeats = if opts.quick { 4 } else { 24 };
    let reference_evals = if opts.quick { 32 } else { 512 };
    let scale = if opts.quick { 0.25 } else { 0.5 };
    let view = tasks::View {
        fov_degrees: None,
        scale: Some(scale),
    };
    let seed = defaults.seed;
    let mut rows = Vec::new();
    let mut csv = Vec::new();
    for (place, theta, sigma) in &places {
        let max_spp = *spps.iter().max().unwrap_or(&32);
        let reference_image = shadow.render(&target, seed, max_spp, view);
        let loss = |x: &[f64], _: u64| shadow.render(x, seed, max_spp, view).mse(&reference_image);
        let mut reference = PlateauFreeGradient::new(Seeded(loss))
            .samples(reference_evals)
            .seed(999);
        let g_ref = reference.estimate(theta, *sigma)?.gradient;
        let norm_ref = g_ref.iter().map(|g| g * g).sum::<f64>().sqrt();
        for &spp in spps {
            let reference_image = shadow.render(&target, seed, spp, view);
            let loss = |x: &[f64], _: u64| shadow.render(x, seed, spp, view).mse(&reference_image);
            for &n in ns {
                let mut est = PlateauFreeGradient::new(Seeded(&loss)).samples(n).seed(1);
                let mut errors = Vec::new();
                for _ in 0..repeats {
                    let g = est.estimate(theta, *sigma)?.gradient;
                    let err = g
                        .iter()
                        .zip(&g_ref)
                        .map(|(a, b)| (a - b) * (a - b))
                        .sum::<f64>()
                        .sqrt()
                        / norm_ref;
                    errors.push(err);
                }
                let mean = errors.iter().sum::<f64>() / errors.len() as f64;
                rows.push(vec![
                    place.to_string(),
                    n.to_string(),
                    spp.to_string(),
                    format!("{mean:.3}"),
                ]);
                csv.push(vec![
                    place.to_string(),
                    n.to_string(),
                    spp.to_string(),
                    format!("{sigma}"),
                    format!("{mean:e}"),
                    format!("{norm_ref:e}"),
                ]);
            }
        }
    }
    report::write_csv(
        &opts.out.join("gradient_quality.csv"),
        &[
            "place",
            "N",
            "spp",
            "sigma",
            "mean_relative_error",
            "reference_norm",
        ],
        csv,
    )?;
    let mut body = format!(
        "SHADOW at scale {:?}, every render with the run's fixed seed (as in the optimisation). Reference: one estimate from {reference_evals} evaluations at the highest spp; each cell is the mean over {repeats} estimates of |g - g_ref| / |g_ref|. At the start sigma = {}; near the optimum (target + 0.1 in both coordinates) sigma = 0.05.\n\n",
        scale,
        defaults.sigma0
    );
    body.push_str(&report::markdown_table(
        &["place", "N", "spp", "mean relative error"],
        &rows,
    ));
    write_page(
        opts,
        "gradient_quality",
        "Gradient quality against N and spp (SHADOW)",
        &body,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pareto_front_keeps_only_undominated_points() {
        // (seconds, error): 1 is beaten by 0 (faster and better), 4 is not finite.
        let points = [
            (1.0, 0.5),
            (2.0, 0.6),
            (3.0, 0.1),
            (0.5, 0.9),
            (4.0, f64::NAN),
            (5.0, 0.05),
        ];
        assert_eq!(pareto(&points), vec![3, 0, 2, 5]);
    }

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

    /// `--quick` options writing into a fresh temporary directory named after `tag`.
    fn quick_options(tag: &str) -> Options {
        Options {
            quick: true,
            out: std::env::temp_dir().join(format!("plateau-{tag}-{}", std::process::id())),
            tasks: None,
            seeds: None,
            reuse_runs: false,
        }
    }

    /// A second identical run is read back (its measured seconds are the first run's, which a
    /// new run would not repeat); another setting is a new run.
    #[test]
    fn runs_are_cached_by_settings() {
        let opts = quick_options("cache");
        let out = opts.out.clone();
        let t = task("shadow").unwrap();
        let mut s = Settings::defaults(t.as_ref());
        s.iterations = 3;
        s.spp = 2;
        s.scale = Some(0.125);
        let first = quiet(&opts, t.as_ref(), &s).unwrap();
        let again = quiet(&opts, t.as_ref(), &s).unwrap();
        assert_eq!(first.summary.seconds_total, again.summary.seconds_total);
        assert_eq!(first.summary.param_mse, again.summary.param_mse);
        assert_eq!(first.history.len(), again.history.len());
        s.seed = 1;
        let other = quiet(&opts, t.as_ref(), &s).unwrap();
        assert_ne!(first.summary.seconds_total, other.summary.seconds_total);
        assert_eq!(fs::read_dir(out.join("runs")).unwrap().count(), 2);
        let _ = fs::remove_dir_all(&out);
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
