//! The command line: `optimize`, `render`, `all`, `experiment` and the other subcommands.

use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::{Args, Parser, Subcommand};

use crate::report::Result;
use crate::run::{Crn, Method, SamplerArg, Settings};
use crate::tasks::{Task, View};
use crate::{experiments, render, report, run, tasks};

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
    Optimize {
        /// cup, shadow, occlusion, gi, sort, caustic or texture.
        task: String,
        #[command(flatten)]
        opts: RunOptions,
        /// Output directory (default out/<task>).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Render one image at the target (default), the start or given parameters, and print
    /// `render_seconds: X` (the render alone, scene set-up excluded).
    Render {
        task: String,
        /// The start parameters.
        #[arg(long, conflicts_with_all = ["target", "params"])]
        initial: bool,
        /// The target parameters (the default).
        #[arg(long, conflicts_with = "params")]
        target: bool,
        /// Explicit parameters, comma-separated.
        #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
        params: Option<Vec<f64>>,
        /// Samples per pixel (default: the task's).
        #[arg(long)]
        spp: Option<u32>,
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Horizontal field of view in degrees (default: the task's).
        #[arg(long)]
        fov: Option<f64>,
        /// Resolution multiplier.
        #[arg(long)]
        scale: Option<f64>,
        #[arg(long)]
        threads: Option<usize>,
        /// Render this many times and print the median time (the image is the last one).
        #[arg(long, default_value_t = 1)]
        repeat: usize,
        /// A .png (sRGB) or .exr (linear) file.
        #[arg(long)]
        out: PathBuf,
    },
    /// Every task with the plateau-free gradient and the finite-difference baseline, then
    /// results.md: our numbers beside the paper's.
    All {
        /// Output directory (default out/).
        #[arg(long, default_value = "out")]
        out: PathBuf,
        /// A few minutes in all: a tenth of the iterations at half resolution.
        #[arg(long)]
        quick: bool,
        /// Only these tasks (comma-separated).
        #[arg(long, value_delimiter = ',')]
        tasks: Option<Vec<String>>,
        /// Runs of the plateau-free gradient per task (seeds 0, 1, ...): the table reports
        /// the median and the range.
        #[arg(long, default_value_t = 1)]
        seeds: u64,
        /// Skip the finite-difference baseline.
        #[arg(long)]
        no_baseline: bool,
        #[arg(long)]
        threads: Option<usize>,
    },
    /// Rewrites `results.md` in a directory of runs (as `all` leaves it) from their
    /// `summary.json` files.
    Summarize {
        #[arg(long, default_value = "out")]
        out: PathBuf,
        /// The command that produced the runs, for the page.
        #[arg(long, default_value = "cargo run --release -p pathtracer -- all")]
        command: String,
    },
    /// Median render time of every task at its defaults (target parameters, seed 0, scene
    /// set-up excluded), as a markdown table.
    Timings {
        #[arg(long, default_value_t = 11)]
        repeat: usize,
        #[arg(long)]
        threads: Option<usize>,
    },
    /// The loss along one coordinate through the target (or the start): a CSV of theta_i,
    /// the image MSE against the reference, and the loss smoothed by Gaussians of the given
    /// spreads (a quadrature over the same grid), to see plateaus and what smoothing does.
    Landscape {
        task: String,
        /// The coordinate to vary.
        #[arg(long, default_value_t = 0)]
        coordinate: usize,
        #[arg(long, allow_hyphen_values = true)]
        from: f64,
        #[arg(long, allow_hyphen_values = true)]
        to: f64,
        #[arg(long, default_value_t = 101)]
        steps: usize,
        /// Vary around the start instead of the target.
        #[arg(long)]
        around_start: bool,
        /// Spreads of the smoothed curves (comma-separated).
        #[arg(long, value_delimiter = ',', default_value = "0.1,0.25,0.5")]
        sigmas: Vec<f64>,
        #[arg(long)]
        spp: Option<u32>,
        #[arg(long, default_value_t = 0)]
        seed: u64,
    },
    /// One of the supplemental's experiments or the speed/accuracy study: CSV, plots and a
    /// markdown page in the output directory.
    Experiment {
        #[arg(value_enum)]
        name: experiments::Experiment,
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
        #[arg(long)]
        threads: Option<usize>,
    },
}

/// Overrides of a task's defaults (supplemental Table 1).
#[derive(Args, Clone, Debug, Default)]
struct RunOptions {
    #[arg(long)]
    iterations: Option<usize>,
    /// N: evaluations of the objective per gradient.
    #[arg(long)]
    samples: Option<usize>,
    #[arg(long)]
    sigma0: Option<f64>,
    #[arg(long)]
    lr: Option<f64>,
    #[arg(long)]
    spp: Option<u32>,
    #[arg(long, value_enum)]
    sampling: Option<SamplerArg>,
    #[arg(long)]
    seed: Option<u64>,
    /// Horizontal field of view in degrees.
    #[arg(long)]
    fov: Option<f64>,
    /// Resolution multiplier (0.5 renders a quarter of the pixels).
    #[arg(long)]
    scale: Option<f64>,
    /// Worker threads for rendering (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Ablation: no antithetic pairs.
    #[arg(long)]
    no_antithetic: bool,
    /// Ablation: constant sigma.
    #[arg(long)]
    no_anneal: bool,
    /// plateau (default), fd or spsa.
    #[arg(long, value_enum)]
    method: Option<Method>,
    /// Renderer seeds: fixed (every render uses the run's seed, as the paper's code) or pair.
    #[arg(long, value_enum)]
    crn: Option<Crn>,
    /// Finite-difference step (normalised units).
    #[arg(long)]
    fd_step: Option<f64>,
    /// Render the current parameters for the image-error curve every this many iterations.
    #[arg(long)]
    eval_every: Option<usize>,
    /// A time budget in seconds: picks resolution, spp (and if need be iterations) to fit,
    /// from the measured cost model, and stops when the budget is spent.
    #[arg(long)]
    budget: Option<f64>,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

impl RunOptions {
    fn settings(&self, task: &dyn Task) -> Settings {
        let mut s = Settings::defaults(task);
        let o = self;
        s.iterations = o.iterations.unwrap_or(s.iterations);
        s.samples = o.samples.unwrap_or(s.samples);
        s.sigma0 = o.sigma0.unwrap_or(s.sigma0);
        s.lr = o.lr.unwrap_or(s.lr);
        s.spp = o.spp.unwrap_or(s.spp);
        s.sampling = o.sampling.unwrap_or(s.sampling);
        s.seed = o.seed.unwrap_or(s.seed);
        s.fov_degrees = o.fov;
        s.scale = o.scale;
        s.antithetic = !o.no_antithetic;
        s.anneal = !o.no_anneal;
        s.method = o.method.unwrap_or(s.method);
        s.crn = o.crn.unwrap_or(s.crn);
        s.fd_step = o.fd_step.unwrap_or(s.fd_step);
        s.eval_every = o
            .eval_every
            .unwrap_or(run::eval_every(s.iterations, run::CURVE_POINTS));
        s.budget_seconds = o.budget;
        s
    }
}

/// Parses the command line and runs it; an error is printed on one line and exits 1.
pub fn main() {
    if let Err(e) = run_cli(Cli::parse()) {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

fn run_cli(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Optimize { task, opts, out } => {
            let task = find_task(&task)?;
            with_threads(opts.threads, || {
                let mut settings = opts.settings(task.as_ref());
                if let Some(budget) = opts.budget {
                    if !(budget.is_finite() && budget > 0.0) {
                        return Err(format!(
                            "--budget must be a positive number of seconds, got {budget}"
                        )
                        .into());
                    }
                    let (plan, why) = run::plan_for_budget(task.as_ref(), &settings, budget);
                    eprintln!("{why}");
                    settings = plan;
                }
                let dir = out.unwrap_or_else(|| Path::new("out").join(task.name()));
                let outcome = run::optimize(task.as_ref(), &settings, Some(&dir), !opts.quiet)?;
                let s = &outcome.summary;
                println!(
                    "{}: param MSE {:.3e} -> {:.3e}, image MSE {:.3e} -> {:.3e}, {:.3} s/iteration ({} iterations), outputs in {}",
                    s.task,
                    s.initial_param_mse,
                    s.param_mse,
                    s.initial_image_mse,
                    s.image_mse,
                    s.seconds_per_iteration,
                    s.iterations,
                    dir.display()
                );
                Ok(())
            })
        }
        Command::Render {
            task,
            initial,
            target: _,
            params,
            spp,
            seed,
            fov,
            scale,
            threads,
            repeat,
            out,
        } => {
            let task = find_task(&task)?;
            let theta = match params {
                Some(p) => p,
                None if initial => task.start(),
                None => task.target(),
            };
            if theta.len() != task.dim() {
                return Err(format!(
                    "{} takes {} parameters, got {}",
                    task.name(),
                    task.dim(),
                    theta.len()
                )
                .into());
            }
            if let Some(i) = theta.iter().position(|x| !x.is_finite()) {
                return Err(format!("parameter {i} is {}", theta[i]).into());
            }
            with_threads(threads, || {
                let spp = spp.unwrap_or(task.defaults().spp);
                let scene = task.scene(
                    &theta,
                    View {
                        fov_degrees: fov,
                        scale,
                    },
                );
                let settings = render::Settings::new(spp, seed, task.max_depth());
                let mut times = Vec::new();
                let mut image = None;
                for _ in 0..repeat.max(1) {
                    let t = Instant::now();
                    image = Some(render::render(&scene, &settings));
                    times.push(t.elapsed().as_secs_f64());
                }
                times.sort_by(f64::total_cmp);
                println!("render_seconds: {:.6}", times[times.len() / 2]);
                if let Some(image) = image {
                    image.save(&out)?;
                }
                Ok(())
            })
        }
        Command::All {
            out,
            quick,
            tasks,
            seeds,
            no_baseline,
            threads,
        } => with_threads(threads, || {
            all(&out, quick, tasks.as_deref(), seeds.max(1), !no_baseline)
        }),
        Command::Summarize { out, command } => summarize(&out, &command),
        Command::Timings { repeat, threads } => {
            with_threads(threads, || {
                println!("| task | resolution | spp | depth | median render (s) |\n|---|---|---|---|---|");
                for task in tasks::all() {
                    let scene = task.scene(&task.target(), View::default());
                    let spp = task.defaults().spp;
                    let settings = render::Settings::new(spp, 0, task.max_depth());
                    let mut times: Vec<f64> = (0..repeat.max(1))
                        .map(|_| {
                            let t = Instant::now();
                            let _ = render::render(&scene, &settings);
                            t.elapsed().as_secs_f64()
                        })
                        .collect();
                    times.sort_by(f64::total_cmp);
                    let (w, h) = (scene.camera.width, scene.camera.height);
                    println!(
                        "| {} | {w}x{h} | {spp} | {} | {:.4} |",
                        task.name(),
                        task.max_depth(),
                        times[times.len() / 2]
                    );
                }
                Ok(())
            })
        }
        Command::Landscape {
            task,
            coordinate,
            from,
            to,
            steps,
            around_start,
            sigmas,
            spp,
            seed,
        } => {
            let task = find_task(&task)?;
            if coordinate >= task.dim() || steps < 2 || from.is_nan() || to.is_nan() || from >= to {
                return Err("need coordinate < dim, steps >= 2 and from < to".into());
            }
            let spp = spp.unwrap_or(task.defaults().spp);
            let view = View::default();
            let reference = task.render(&task.target(), seed, spp, view);
            let mut theta = if around_start {
                task.start()
            } else {
                task.target()
            };
            let xs: Vec<f64> = (0..steps)
                .map(|k| from + (to - from) * k as f64 / (steps - 1) as f64)
                .collect();
            let losses: Vec<f64> = xs
                .iter()
                .map(|&x| {
                    theta[coordinate] = x;
                    task.render(&theta, seed, spp, view).mse(&reference)
                })
                .collect();
            print!("theta,loss");
            for s in &sigmas {
                print!(",smoothed_{s}");
            }
            println!();
            for (i, (&x, &l)) in xs.iter().zip(&losses).enumerate() {
                print!("{x},{l:e}");
                for &s in &sigmas {
                    // Gaussian quadrature over the grid, renormalised where the kernel leaves it.
                    let (mut num, mut den) = (0.0, 0.0);
                    for (j, &y) in xs.iter().enumerate() {
                        let w = (-0.5 * ((y - xs[i]) / s).powi(2)).exp();
                        num += w * losses[j];
                        den += w;
                    }
                    print!(",{:e}", num / den);
                }
                println!();
            }
            Ok(())
        }
        Command::Experiment {
            name,
            quick,
            out,
            tasks,
            seeds,
            reuse_runs,
            threads,
        } => with_threads(threads, || {
            experiments::run(
                name,
                &experiments::Options {
                    quick,
                    out,
                    tasks,
                    seeds,
                    reuse_runs,
                },
            )
        }),
    }
}

fn find_task(name: &str) -> Result<Box<dyn Task>> {
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

/// Every task with the plateau-free gradient and, where it is affordable, the finite-difference
/// baseline; then `results.md`.
fn all(out: &Path, quick: bool, only: Option<&[String]>, seeds: u64, baseline: bool) -> Result<()> {
    let command = format!(
        "cargo run --release -p pathtracer -- all{}{}{}{} --out {}",
        if quick { " --quick" } else { "" },
        if seeds > 1 {
            format!(" --seeds {seeds}")
        } else {
            String::new()
        },
        if baseline { "" } else { " --no-baseline" },
        only.map_or(String::new(), |t| format!(" --tasks {}", t.join(","))),
        out.display()
    );
    for task in tasks::all() {
        if only.is_some_and(|names| !names.iter().any(|n| n == task.name())) {
            continue;
        }
        let mut plateau = Settings::defaults(task.as_ref());
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
            ours.push(run::optimize(task.as_ref(), &s, Some(&dir), true)?);
        }
        // Central differences cost 2n renders per iteration: affordable for the
        // low-dimensional tasks only (SORT would need 300 renders an iteration).
        if baseline && task.dim() <= 8 {
            let mut fd = plateau.clone();
            fd.method = Method::Fd;
            run::optimize(
                task.as_ref(),
                &fd,
                Some(&out.join(format!("{}-fd", task.name()))),
                true,
            )?;
        }
        // Rewritten after every task, so that an interrupted run still leaves its table.
        summarize(out, &command)?;
    }
    println!("wrote {}", out.join("results.md").display());
    Ok(())
}

/// `results.md` in `out`: a table of every task's runs found there (`<task>/`,
/// `<task>-seed<k>/`, `<task>-fd/`, each with its `summary.json`) beside the paper's numbers.
/// `command` is what produced the runs.
fn summarize(out: &Path, command: &str) -> Result<()> {
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
        rows.push(results_row(task.as_ref(), &ours, fd.as_ref()));
    }
    let header = [
        "task",
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

fn results_row(task: &dyn Task, ours: &[run::Summary], fd: Option<&run::Summary>) -> Vec<String> {
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
