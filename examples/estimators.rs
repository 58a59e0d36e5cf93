//! Measures every sampler and option of the estimator and writes `docs/estimators.md`:
//!
//! ```text
//! cargo bench --bench estimator                                   # optional: the Cost section
//! cargo run --release --example estimators -- --out docs/estimators.md
//! cargo run --release --example estimators -- --quick             # 10x fewer repetitions, to stdout
//! ```
//!
//! For each sampler and option (antithetic pairs, orthogonal directions, N = 2 or 8), each
//! test function and each dimension n in {1, 2, 10, 150, 49152}, it draws R seeded estimates
//! at a fixed theta and reports
//! - the relative MSE per evaluation, `N * mean |g - truth|^2 / |truth|^2`, so that samplers
//!   with different N compare at equal cost;
//! - the bias, `|mean g - truth| / |truth|`, beside its noise floor `sqrt(tr Cov / R) / |truth|`
//!   (what an unbiased estimator's bias column shows from finite R alone).
//!
//! It also measures common random numbers on a noisy objective and, when `cargo bench` has
//! run, copies the benchmark's medians into the Cost section. A hand-written section between
//! the markers `<!-- BEGIN hand-written -->` and `<!-- END hand-written -->` in an existing
//! output file is carried over.

use std::f64::consts::PI;
use std::fmt::Write as _;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use plateau::kernel::normal_cdf;
use plateau::{Objective, PlateauFreeGradient, Sampling, Seeded};

const DIMENSIONS: [usize; 5] = [1, 2, 10, 150, 49_152];
const SIGMA: f64 = 0.5;
const BEGIN: &str = "<!-- BEGIN hand-written -->";
const END: &str = "<!-- END hand-written -->";

fn phi(x: f64) -> f64 {
    (-0.5 * x * x).exp() / (2.0 * PI).sqrt()
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn norm(a: &[f64]) -> f64 {
    dot(a, a).sqrt()
}

type Function = Box<dyn Fn(&[f64]) -> f64 + Sync>;

/// A test function at a fixed theta with its analytic smoothed gradient.
struct Case {
    name: &'static str,
    f: Function,
    theta: Vec<f64>,
    truth: Vec<f64>,
}

/// Coefficients of moderate, varied size with alternating signs, scaled so that `|a|` does
/// not grow with n.
fn slope(n: usize) -> Vec<f64> {
    let rt = (n as f64).sqrt();
    (0..n)
        .map(|i| {
            let sign = if i % 2 == 0 { 1.0 } else { -1.0 };
            sign * (1.0 + 0.5 * (i % 3) as f64) / rt
        })
        .collect()
}

fn generic_theta(n: usize) -> Vec<f64> {
    (0..n).map(|i| 0.2 * ((i + 1) as f64).sin()).collect()
}

/// The functions of the issue, each placed so that its smoothed gradient is of order one in
/// every dimension (a product of n sines or n box factors would otherwise vanish).
fn cases(n: usize) -> Vec<Case> {
    let s = SIGMA;
    let a = slope(n);
    let theta = generic_theta(n);
    let mut out = Vec::new();

    {
        let a2 = a.clone();
        out.push(Case {
            name: "linear a.x",
            f: Box::new(move |x| dot(&a2, x)),
            theta: theta.clone(),
            truth: a.clone(),
        });
    }
    {
        // sum d_i x_i^2 + (v.x)^2 + a.x: gradient 2 d x + 2 (v.x) v + a for every spread.
        let d: Vec<f64> = (0..n).map(|i| 0.5 + 0.25 * (i % 3) as f64).collect();
        let v: Vec<f64> = a.iter().map(|x| x.abs()).collect();
        let vt = dot(&v, &theta);
        let truth = (0..n)
            .map(|i| 2.0 * d[i] * theta[i] + 2.0 * vt * v[i] + a[i])
            .collect();
        let a2 = a.clone();
        out.push(Case {
            name: "quadratic",
            f: Box::new(move |x| {
                let dx: f64 = x.iter().zip(&d).map(|(xi, di)| di * xi * xi).sum();
                dx + dot(&v, x).powi(2) + dot(&a2, x)
            }),
            theta: theta.clone(),
            truth,
        });
    }
    {
        // 1[a.x > b] with theta one smoothed width below the edge, on the plateau.
        let big_s = s * norm(&a);
        let m = -1.0;
        let b = dot(&a, &theta) - m * big_s;
        let truth = a.iter().map(|ai| ai * phi(m) / big_s).collect();
        let a2 = a.clone();
        out.push(Case {
            name: "tilted step 1[a.x > b]",
            f: Box::new(move |x| if dot(&a2, x) > b { 1.0 } else { 0.0 }),
            theta: theta.clone(),
            truth,
        });
    }
    {
        // Box: theta lies half a spread below the box in coordinate 0 (its plateau); the other
        // edges sit k spreads away, k chosen so that those n - 1 factors hold 0.9 in all.
        let k = if n > 1 {
            let tail = 0.5 * (1.0 - 0.9f64.powf(1.0 / (n - 1) as f64));
            let (mut lo, mut hi) = (0.0, 40.0);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if normal_cdf(-mid) > tail {
                    lo = mid
                } else {
                    hi = mid
                }
            }
            0.5 * (lo + hi)
        } else {
            1.0
        };
        let mut l: Vec<f64> = theta.iter().map(|t| t - k * s).collect();
        let mut u: Vec<f64> = theta.iter().map(|t| t + k * s).collect();
        l[0] = theta[0] + 0.5 * s;
        u[0] = theta[0] + 2.5 * s;
        let val: Vec<f64> = (0..n)
            .map(|i| normal_cdf((u[i] - theta[i]) / s) - normal_cdf((l[i] - theta[i]) / s))
            .collect();
        let der: Vec<f64> = (0..n)
            .map(|i| (phi((l[i] - theta[i]) / s) - phi((u[i] - theta[i]) / s)) / s)
            .collect();
        let total: f64 = val.iter().product();
        let truth = (0..n).map(|i| der[i] * total / val[i]).collect();
        out.push(Case {
            name: "box indicator",
            f: Box::new(move |x| {
                let inside = x
                    .iter()
                    .zip(l.iter().zip(&u))
                    .all(|(xi, (li, ui))| li < xi && xi < ui);
                if inside {
                    1.0
                } else {
                    0.0
                }
            }),
            theta: theta.clone(),
            truth,
        });
    }
    {
        // ReLU(a.x - b), theta half a smoothed width below the kink.
        let big_s = s * norm(&a);
        let m = -0.5;
        let b = dot(&a, &theta) - m * big_s;
        let truth = a.iter().map(|ai| ai * normal_cdf(m)).collect();
        let a2 = a.clone();
        out.push(Case {
            name: "ReLU(a.x - b)",
            f: Box::new(move |x| (dot(&a2, x) - b).max(0.0)),
            theta: theta.clone(),
            truth,
        });
    }
    {
        // prod sin(c_i x_i) near the crest of every factor, so that the product is of order
        // one: c_i theta_i = pi/2 - q_i / sqrt(n).
        let rt = (n as f64).sqrt();
        let c: Vec<f64> = a.iter().map(|x| x.abs()).collect();
        let th: Vec<f64> = (0..n)
            .map(|i| (PI / 2.0 - (0.7 + 0.3 * (i % 2) as f64) / rt) / c[i])
            .collect();
        let damp: Vec<f64> = c.iter().map(|ci| (-0.5 * (ci * s).powi(2)).exp()).collect();
        let val: Vec<f64> = (0..n).map(|i| (c[i] * th[i]).sin() * damp[i]).collect();
        let total: f64 = val.iter().product();
        let truth = (0..n)
            .map(|i| c[i] * (c[i] * th[i]).cos() * damp[i] * total / val[i])
            .collect();
        out.push(Case {
            name: "product of sines",
            f: Box::new(move |x| x.iter().zip(&c).map(|(xi, ci)| (ci * xi).sin()).product()),
            theta: th,
            truth,
        });
    }
    {
        // exp(a.x / 2): gradient a/2 exp(a.x/2 + s^2 |a/2|^2 / 2).
        let h: Vec<f64> = a.iter().map(|x| 0.5 * x).collect();
        let q = (dot(&h, &theta) + 0.5 * s * s * dot(&h, &h)).exp();
        let truth = h.iter().map(|hi| hi * q).collect();
        out.push(Case {
            name: "exp(a.x / 2)",
            f: Box::new(move |x| dot(&h, x).exp()),
            theta: theta.clone(),
            truth,
        });
    }
    out
}

#[derive(Debug, Clone, Copy)]
struct Config {
    sampling: Sampling,
    antithetic: bool,
    orthogonal: bool,
    samples: usize,
}

impl Config {
    fn label(&self) -> String {
        let name = match self.sampling {
            Sampling::Radial => "radial",
            Sampling::PerCoordinate => "per-coordinate",
            Sampling::Gaussian => "Gaussian",
        };
        format!(
            "{name} | {} | {} | {}",
            if self.antithetic { "yes" } else { "no" },
            if self.orthogonal { "yes" } else { "no" },
            self.samples
        )
    }
}

fn configs() -> Vec<Config> {
    let mut all = Vec::new();
    for sampling in [
        Sampling::Radial,
        Sampling::Gaussian,
        Sampling::PerCoordinate,
    ] {
        for antithetic in [true, false] {
            for orthogonal in [false, true] {
                if orthogonal && sampling == Sampling::PerCoordinate {
                    continue;
                }
                for samples in [2, 8] {
                    all.push(Config {
                        sampling,
                        antithetic,
                        orthogonal,
                        samples,
                    });
                }
            }
        }
    }
    all
}

/// Relative MSE per evaluation, relative bias, and the bias's noise floor.
#[derive(Debug, Clone, Copy)]
struct Stats {
    rmse: f64,
    bias: f64,
    floor: f64,
}

fn measure<F: Objective>(
    f: F,
    config: Config,
    theta: &[f64],
    truth: &[f64],
    reps: usize,
    seed: u64,
) -> Stats {
    measure_relative_to(f, config, theta, truth, dot(truth, truth), reps, seed)
}

/// As [`measure`], with errors relative to `t2` rather than `|truth|^2` (for a component
/// whose own gradient is zero).
fn measure_relative_to<F: Objective>(
    f: F,
    config: Config,
    theta: &[f64],
    truth: &[f64],
    t2: f64,
    reps: usize,
    seed: u64,
) -> Stats {
    let n = theta.len();
    let mut est = PlateauFreeGradient::new(f)
        .sampling(config.sampling)
        .antithetic(config.antithetic)
        .orthogonal(config.orthogonal)
        .samples(config.samples)
        .seed(seed);
    let (mut mean, mut m2) = (vec![0.0; n], vec![0.0; n]);
    let mut sq_err = 0.0;
    for r in 0..reps {
        let g = est.estimate(theta, SIGMA).expect("valid input").gradient;
        for i in 0..n {
            let delta = g[i] - mean[i];
            mean[i] += delta / (r + 1) as f64;
            m2[i] += delta * (g[i] - mean[i]);
            sq_err += (g[i] - truth[i]).powi(2);
        }
    }
    let trace_cov: f64 = m2.iter().sum::<f64>() / (reps - 1) as f64;
    let diff: Vec<f64> = mean.iter().zip(truth).map(|(m, t)| m - t).collect();
    Stats {
        rmse: config.samples as f64 * sq_err / reps as f64 / t2,
        bias: norm(&diff) / t2.sqrt(),
        floor: (trace_cov / reps as f64).sqrt() / t2.sqrt(),
    }
}

fn reps_for(n: usize, quick: bool) -> usize {
    let r = match n {
        1 | 2 => 40_000,
        10 => 20_000,
        150 => 4_000,
        _ => 300,
    };
    if quick {
        (r / 10).max(10)
    } else {
        r
    }
}

fn fmt_num(x: f64) -> String {
    if x == 0.0 {
        "0".into()
    } else if !(1e-3..1e4).contains(&x.abs()) {
        format!("{x:.2e}")
    } else if x.abs() >= 100.0 {
        format!("{x:.0}")
    } else {
        format!("{x:.3}")
    }
}

/// A relative size as a percentage with two significant digits (`x` above 10 as a number).
fn pct(x: f64) -> String {
    if x >= 10.0 {
        format!("{x:.1e}")
    } else if x >= 0.1 {
        format!("{:.0} %", 100.0 * x)
    } else if x >= 0.01 {
        format!("{:.1} %", 100.0 * x)
    } else {
        format!("{:.2} %", 100.0 * x)
    }
}

/// A 64-bit mix (SplitMix64's finaliser) for the noise of the noisy objective.
fn hash(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A uniform in [-1, 1) from a seed.
fn noise(seed: u64) -> f64 {
    (hash(seed) >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

fn main() {
    let mut quick = false;
    let mut out_path: Option<String> = None;
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--quick" => quick = true,
            "--out" => out_path = args.next(),
            other => {
                eprintln!("unknown argument {other}; usage: estimators [--quick] [--out FILE]");
                std::process::exit(2);
            }
        }
    }
    let started = Instant::now();
    let configs = configs();
    let names: Vec<&str> = cases(1).iter().map(|c| c.name).collect();
    // results[function][config][dimension]
    let mut results = vec![vec![Vec::new(); configs.len()]; names.len()];
    for (di, &n) in DIMENSIONS.iter().enumerate() {
        let reps = reps_for(n, quick);
        for (fi, case) in cases(n).into_iter().enumerate() {
            for (ci, config) in configs.iter().enumerate() {
                let seed = hash(((fi * 100 + ci) * 10 + di) as u64);
                let stats = measure(&case.f, *config, &case.theta, &case.truth, reps, seed);
                results[fi][ci].push(stats);
            }
            eprintln!(
                "n = {n}: {} done ({:.0} s)",
                case.name,
                started.elapsed().as_secs_f64()
            );
        }
    }
    let crn = common_random_numbers(quick);
    eprintln!(
        "common random numbers done ({:.0} s)",
        started.elapsed().as_secs_f64()
    );

    let mut page = String::new();
    let command = format!(
        "cargo run --release --example estimators --{} --out docs/estimators.md",
        if quick { " --quick" } else { "" }
    );
    writeln!(page, "# The estimators, measured\n").unwrap();
    writeln!(
        page,
        "Generated by `{command}` (deterministic: fixed seeds; {:.0} s on this machine). \
         The Cost section is filled from `cargo bench --bench estimator` when its results are \
         in `target/criterion`.\n",
        started.elapsed().as_secs_f64()
    )
    .unwrap();
    writeln!(
        page,
        "Every estimate is of the gradient of f smoothed by N(0, sigma^2 I), sigma = {SIGMA}, \
         at a fixed theta, compared with the closed-form smoothed gradient. Repetitions R per \
         cell: {}.\n",
        DIMENSIONS
            .iter()
            .map(|&n| format!("{} at n = {n}", reps_for(n, quick)))
            .collect::<Vec<_>>()
            .join(", ")
    )
    .unwrap();
    writeln!(
        page,
        "- **rel. MSE / eval** = N * mean |g - truth|^2 / |truth|^2: the relative mean squared \
         error of one estimate times its number of evaluations of f, so that rows with \
         different N compare at equal cost (lower is better; an estimator that averages k \
         times more evaluations divides its MSE by k and keeps this number).\n\
         - **bias** = |mean g - truth| / |truth| over the R estimates, and in brackets its \
         noise floor sqrt(tr Cov / R) / |truth|: an unbiased estimator's bias is of the size of \
         its floor; a bias many floors above it is real.\n"
    )
    .unwrap();

    let hand = out_path
        .as_ref()
        .and_then(|p| std::fs::read_to_string(p).ok())
        .and_then(|old| {
            let start = old.find(BEGIN)?;
            let end = old.find(END)?;
            Some(old[start..end + END.len()].to_string())
        })
        .unwrap_or_else(|| format!("{BEGIN}\n## What this shows\n\n(to be written)\n{END}"));
    writeln!(page, "{hand}\n").unwrap();

    summary(&mut page, &configs, &names, &results);
    write_crn(&mut page, &crn);
    cost(&mut page);

    writeln!(page, "## Full tables\n").unwrap();
    for (fi, name) in names.iter().enumerate() {
        writeln!(page, "### {name}\n").unwrap();
        write!(page, "| sampler | antithetic | orthogonal | N |").unwrap();
        for n in DIMENSIONS {
            write!(page, " n = {n} |").unwrap();
        }
        writeln!(page).unwrap();
        writeln!(page, "|---|---|---|---|{}", "---|".repeat(DIMENSIONS.len())).unwrap();
        for (ci, config) in configs.iter().enumerate() {
            write!(page, "| {} |", config.label()).unwrap();
            for s in &results[fi][ci] {
                write!(
                    page,
                    " {} ; {} ({}) |",
                    fmt_num(s.rmse),
                    pct(s.bias),
                    pct(s.floor)
                )
                .unwrap();
            }
            writeln!(page).unwrap();
        }
        writeln!(page, "\nCells: rel. MSE / eval ; bias (noise floor).\n").unwrap();
    }

    match out_path {
        Some(p) => {
            std::fs::write(&p, page).expect("write the page");
            eprintln!("wrote {p}");
        }
        None => print!("{page}"),
    }
}

fn find(configs: &[Config], sampling: Sampling, anti: bool, orth: bool, samples: usize) -> usize {
    configs
        .iter()
        .position(|c| {
            c.sampling == sampling
                && c.antithetic == anti
                && c.orthogonal == orth
                && c.samples == samples
        })
        .expect("configuration measured")
}

/// Ratios of rel. MSE / eval between two configurations, per function and dimension, with
/// their geometric mean per dimension.
fn ratio_table(
    page: &mut String,
    title: &str,
    names: &[&str],
    results: &[Vec<Vec<Stats>>],
    (num, den): (usize, usize),
) {
    writeln!(page, "{title}\n").unwrap();
    write!(page, "| function |").unwrap();
    for n in DIMENSIONS {
        write!(page, " n = {n} |").unwrap();
    }
    writeln!(page).unwrap();
    writeln!(page, "|---|{}", "---|".repeat(DIMENSIONS.len())).unwrap();
    let mut logs = vec![0.0; DIMENSIONS.len()];
    for (fi, name) in names.iter().enumerate() {
        write!(page, "| {name} |").unwrap();
        for di in 0..DIMENSIONS.len() {
            let r = results[fi][num][di].rmse / results[fi][den][di].rmse;
            logs[di] += r.ln();
            write!(page, " {r:.2} |").unwrap();
        }
        writeln!(page).unwrap();
    }
    write!(page, "| **geometric mean** |").unwrap();
    for l in logs {
        write!(page, " **{:.2}** |", (l / names.len() as f64).exp()).unwrap();
    }
    writeln!(page, "\n").unwrap();
}

fn summary(page: &mut String, configs: &[Config], names: &[&str], results: &[Vec<Vec<Stats>>]) {
    writeln!(page, "## Summary\n").unwrap();
    writeln!(
        page,
        "Ratios of rel. MSE / eval (below 1: the first configuration is better at equal \
         cost).\n"
    )
    .unwrap();
    let r = Sampling::Radial;
    let g = Sampling::Gaussian;
    let p = Sampling::PerCoordinate;
    ratio_table(
        page,
        "**Orthogonal / independent directions**, radial, antithetic, N = 8 (4 pairs):",
        names,
        results,
        (
            find(configs, r, true, true, 8),
            find(configs, r, true, false, 8),
        ),
    );
    ratio_table(
        page,
        "**Orthogonal / independent directions**, Gaussian, antithetic, N = 8:",
        names,
        results,
        (
            find(configs, g, true, true, 8),
            find(configs, g, true, false, 8),
        ),
    );
    ratio_table(
        page,
        "**Orthogonal / independent directions**, radial, no pairs, N = 8 (8 draws):",
        names,
        results,
        (
            find(configs, r, false, true, 8),
            find(configs, r, false, false, 8),
        ),
    );
    ratio_table(
        page,
        "**Radial / Gaussian**, antithetic, N = 2:",
        names,
        results,
        (
            find(configs, r, true, false, 2),
            find(configs, g, true, false, 2),
        ),
    );
    ratio_table(
        page,
        "**Antithetic / no pairs**, radial, N = 8:",
        names,
        results,
        (
            find(configs, r, true, false, 8),
            find(configs, r, false, false, 8),
        ),
    );
    ratio_table(
        page,
        "**Per-coordinate / radial**, antithetic, N = 2 (MSE includes the per-coordinate bias):",
        names,
        results,
        (
            find(configs, p, true, false, 2),
            find(configs, r, true, false, 2),
        ),
    );
    // The per-coordinate bias in floors.
    let pc = find(configs, p, true, false, 8);
    let rad = find(configs, r, true, false, 8);
    writeln!(
        page,
        "**Bias in units of its noise floor**, antithetic, N = 8: per-coordinate [its \
         relative bias] vs radial. An unbiased estimator shows about 1, rarely above \
         3.\n"
    )
    .unwrap();
    write!(page, "| function |").unwrap();
    for n in DIMENSIONS {
        write!(page, " n = {n} |").unwrap();
    }
    writeln!(page).unwrap();
    writeln!(page, "|---|{}", "---|".repeat(DIMENSIONS.len())).unwrap();
    for (fi, name) in names.iter().enumerate() {
        write!(page, "| {name} |").unwrap();
        for (a, b) in results[fi][pc].iter().zip(&results[fi][rad]) {
            write!(
                page,
                " {:.1} [{}] vs {:.1} |",
                a.bias / a.floor,
                pct(a.bias),
                b.bias / b.floor
            )
            .unwrap();
        }
        writeln!(page).unwrap();
    }
    writeln!(page).unwrap();
}

/// Independent noise: ignores the estimator's seed and draws a fresh one per call from a
/// counter, as an objective with its own random state would.
fn fresh_noise<'a>(
    f: &'a dyn Fn(&[f64], u64) -> f64,
    start: u64,
) -> impl Fn(&[f64], u64) -> f64 + 'a {
    let counter = AtomicU64::new(start);
    move |x: &[f64], _seed: u64| f(x, hash(counter.fetch_add(1, Ordering::Relaxed)))
}

/// One row of the common-random-numbers table.
struct CrnRow {
    n: usize,
    amplitude: f64,
    samples: usize,
    sampling: Sampling,
    clean: f64,
    shared: f64,
    independent: f64,
    /// The noise term alone (its smoothed gradient is zero), relative to the step's gradient.
    noise_shared: f64,
    noise_independent: f64,
}

/// A noisy tilted step: `1[a.x > b] + A u(seed) (1 + 0.2 sin(x_0))`, with `u` uniform in
/// [-1, 1]. The noise has mean zero, so the smoothed gradient is the step's. The same
/// estimator seed in all three modes draws the same perturbations, so their differences are
/// the noise's alone.
fn common_random_numbers(quick: bool) -> Vec<CrnRow> {
    let mut rows = Vec::new();
    for (n, amplitude) in [1usize, 10, 150]
        .into_iter()
        .flat_map(|n| [(n, 0.3), (n, 1.0)])
    {
        let step = &cases(n)[2];
        let (theta, truth) = (&step.theta, &step.truth);
        let reps = reps_for(n, quick);
        let noisy =
            |x: &[f64], seed: u64| (step.f)(x) + amplitude * noise(seed) * (1.0 + 0.2 * x[0].sin());
        for (sampling, samples) in [
            (Sampling::Radial, 2),
            (Sampling::Radial, 8),
            (Sampling::Gaussian, 2),
        ] {
            let config = Config {
                sampling,
                antithetic: true,
                orthogonal: false,
                samples,
            };
            let seed = hash(n as u64 * 31 + samples as u64);
            let fresh = |f| fresh_noise(f, hash(seed));
            let only_noise =
                |x: &[f64], seed: u64| amplitude * noise(seed) * (1.0 + 0.2 * x[0].sin());
            let t2 = dot(truth, truth);
            let zero = vec![0.0; n];
            let run = |f: &dyn Fn(&[f64], u64) -> f64, truth: &[f64]| {
                measure_relative_to(Seeded(f), config, theta, truth, t2, reps, seed).rmse
            };
            rows.push(CrnRow {
                n,
                amplitude,
                samples,
                sampling,
                clean: measure(&step.f, config, theta, truth, reps, seed).rmse,
                shared: run(&noisy, truth),
                independent: run(&fresh(&noisy), truth),
                noise_shared: run(&only_noise, &zero),
                noise_independent: run(&fresh(&only_noise), &zero),
            });
        }
    }
    rows
}

fn write_crn(page: &mut String, rows: &[CrnRow]) {
    writeln!(page, "## Common random numbers\n").unwrap();
    writeln!(
        page,
        "A noisy objective, f(x, seed) = 1[a.x > b] + A u(seed) (1 + 0.2 sin x_0), with u \
         uniform in [-1, 1] from a hash of the seed (noise that depends on the seed, and \
         weakly on x), at the tilted step's theta (one smoothed width below the edge). \
         **Shared**: the library's behaviour with `Seeded` (both members of a pair get the \
         same seed). **Independent**: a `Seeded` wrapper that ignores the seed it is given and \
         draws its own from a counter, as a renderer with its own random state would. \
         **Noise-free**: the step alone. Antithetic pairs; rel. MSE / eval, relative to the \
         step's smoothed gradient. The last three columns estimate the gradient of the noise \
         term alone (whose smoothed gradient is zero): the error that the noise itself adds, \
         and by how much sharing the seed divides it.\n"
    )
    .unwrap();
    writeln!(
        page,
        "| n | A | sampler | N | noise-free | shared seed | independent noise | independent / shared | noise term alone: shared | independent | ratio |"
    )
    .unwrap();
    writeln!(page, "|---|---|---|---|---|---|---|---|---|---|---|").unwrap();
    for r in rows {
        writeln!(
            page,
            "| {} | {} | {:?} | {} | {} | {} | {} | {:.2} | {} | {} | {:.0} |",
            r.n,
            r.amplitude,
            r.sampling,
            r.samples,
            fmt_num(r.clean),
            fmt_num(r.shared),
            fmt_num(r.independent),
            r.independent / r.shared,
            fmt_num(r.noise_shared),
            fmt_num(r.noise_independent),
            r.noise_independent / r.noise_shared
        )
        .unwrap();
    }
    writeln!(page).unwrap();
}

/// The median time of one criterion benchmark, in nanoseconds, if it has run.
fn bench_median(n: usize, name: &str) -> Option<f64> {
    let path = format!("target/criterion/n={n}/{name}/{n}/new/estimates.json");
    let text = std::fs::read_to_string(path).ok()?;
    let json: serde_json::Value = serde_json::from_str(&text).ok()?;
    json["median"]["point_estimate"].as_f64()
}

fn fmt_time(ns: f64) -> String {
    if ns < 1e3 {
        format!("{ns:.0} ns")
    } else if ns < 1e6 {
        format!("{:.1} µs", ns / 1e3)
    } else {
        format!("{:.2} ms", ns / 1e6)
    }
}

fn cost(page: &mut String) {
    writeln!(page, "## Cost\n").unwrap();
    writeln!(
        page,
        "`cargo bench --bench estimator`: one estimate with N = 2 (one antithetic pair) of a \
         trivial f (`x[0]`), one core, beside drawing n standard normals with `rand_distr` \
         (`StandardNormal`, the same Xoshiro256++ generator) into a buffer. Median times; \
         the ratio is estimate / normals.\n"
    )
    .unwrap();
    let dims = [1usize, 150, 49_152, 1_000_000];
    if bench_median(1, "normals").is_none() {
        writeln!(
            page,
            "(No benchmark results in `target/criterion`: run `cargo bench --bench estimator` \
             and then this example.)\n"
        )
        .unwrap();
        return;
    }
    writeln!(
        page,
        "| n | n normals | radial | per-coordinate | Gaussian |"
    )
    .unwrap();
    writeln!(page, "|---|---|---|---|---|").unwrap();
    for n in dims {
        let base = bench_median(n, "normals");
        write!(page, "| {n} | {} |", base.map_or("-".into(), fmt_time)).unwrap();
        for name in ["radial", "per_coordinate", "gaussian"] {
            match (bench_median(n, name), base) {
                (Some(t), Some(b)) => write!(page, " {} ({:.1}x) |", fmt_time(t), t / b).unwrap(),
                _ => write!(page, " - |").unwrap(),
            }
        }
        writeln!(page).unwrap();
    }
    if let Some(t) = bench_median(49_152, "radial") {
        writeln!(
            page,
            "\nOne estimate at n = 49,152, N = 2 (radial): {} — {} 1 ms.",
            fmt_time(t),
            if t < 1e6 { "under" } else { "NOT under" }
        )
        .unwrap();
    }
    writeln!(page).unwrap();
}
