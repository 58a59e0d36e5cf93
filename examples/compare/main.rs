//! The comparison of `plateau_free::minimize` with CMA-ES (the `cmaes` crate), random search and the
//! paper's loop on shifted and rotated classic test functions.
//!
//! ```sh
//! cargo run --release --example compare                 # the full run: docs/results/compare.{md,csv}
//! cargo run --release --example compare -- --quick      # n = 2, 5 and 2 seeds, into target/compare-quick/
//! cargo run --release --example compare -- --dims 10 --seeds 3 --methods minimize,cmaes --out /tmp/c
//! cargo run --release --example compare -- --export FILE   # the instances, for the peers
//! scripts/compare-peers                                     # the page with pycma and NGOpt
//! ```
//!
//! Every method gets the same start point `x0` (uniform in `[-4, 4]^n`) and a budget of
//! `1000 n` evaluations; the record counts only the first `budget` evaluations. A target
//! `t` in `1e2, 1e1, ..., 1e-8` is reached when the best value seen is at most `t` above the
//! optimum. See `docs/results/compare.md` for what each method is given.

mod functions;
mod peers;
mod variant;

use std::cell::{Cell, RefCell};
use std::fmt::Write as _;
use std::time::Instant;

use functions::{Kind, Problem};
use plateau_free::{Adam, Annealer, Optimizer, PlateauFreeGradient};
use rand::{RngExt, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

const TARGETS: [f64; 11] = [
    1e2, 1e1, 1e0, 1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8,
];
/// The index of 1e-2 in `TARGETS`.
const T_1EM2: usize = 4;

/// Counts evaluations and records when each target is first reached.
struct Recorder<'a> {
    problem: &'a Problem,
    budget: usize,
    evals: Cell<usize>,
    best: Cell<f64>,
    hits: RefCell<[Option<usize>; 11]>,
}

impl<'a> Recorder<'a> {
    fn new(problem: &'a Problem, budget: usize) -> Self {
        Recorder {
            problem,
            budget,
            evals: Cell::new(0),
            best: Cell::new(f64::INFINITY),
            hits: RefCell::new([None; 11]),
        }
    }

    fn eval(&self, x: &[f64]) -> f64 {
        let v = self.problem.eval(x);
        let e = self.evals.get() + 1;
        self.evals.set(e);
        if e <= self.budget && v < self.best.get() {
            self.best.set(v);
            let mut hits = self.hits.borrow_mut();
            for (t, h) in TARGETS.iter().zip(hits.iter_mut()) {
                if h.is_none() && v <= *t {
                    *h = Some(e);
                }
            }
        }
        v
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Method {
    Minimize,
    Paper,
    Cmaes,
    CmaesIpop,
    Random,
}

impl Method {
    const ALL: [Method; 5] = [
        Method::Minimize,
        Method::Cmaes,
        Method::CmaesIpop,
        Method::Random,
        Method::Paper,
    ];

    fn name(self) -> &'static str {
        match self {
            Method::Minimize => "minimize",
            Method::Paper => "paper-loop",
            Method::Cmaes => "cmaes",
            Method::CmaesIpop => "cmaes-ipop",
            Method::Random => "random",
        }
    }

    fn parse(s: &str) -> Option<Method> {
        Method::ALL.into_iter().find(|m| m.name() == s)
    }

    fn run(self, rec: &Recorder<'_>, seed: u64) {
        let p = rec.problem;
        let n = p.n;
        let budget = rec.budget;
        let f = |x: &[f64]| rec.eval(x);
        match self {
            Method::Minimize => {
                // Stopping at 1e-8 only saves time: every target is reached there.
                let m = plateau_free::Minimizer::new(f)
                    .budget(budget)
                    .seed(seed)
                    .target(1e-8);
                let _ = variant::variant(m).run(&p.x0);
            }
            Method::Paper => {
                // The README's settings, as a new user would try them: N = 4, lr 0.02,
                // Annealer::paper(0.5, iterations) with the iterations the budget allows.
                let mut grad = PlateauFreeGradient::new(f).samples(4).seed(seed);
                let iterations = budget / 4;
                let mut opt = Optimizer::new(
                    Adam::new(0.02).expect("valid lr"),
                    Annealer::paper(0.5, iterations).expect("valid schedule"),
                )
                .record_theta(false);
                // The loop evaluates f only at perturbed points; its final point counts too.
                if let Ok(h) = opt.minimize(&mut grad, &p.x0) {
                    if let Some(x) = h.last_theta() {
                        rec.eval(x);
                    }
                }
            }
            Method::Cmaes => {
                // One run from x0 with step size 2 (a fifth of the domain [-5, 5], as the
                // BBOB setups of CMA-ES use), its default population and termination.
                let opts = cmaes::CMAESOptions::new(p.x0.clone(), 2.0)
                    .max_function_evals(budget)
                    .fun_target(1e-8)
                    .seed(seed);
                if let Ok(mut state) = opts.build(|x: &cmaes::DVector<f64>| rec.eval(x.as_slice()))
                {
                    state.run();
                }
            }
            Method::CmaesIpop => {
                // The crate's IPOP restarts (population doubled at each restart; each run
                // starts at a uniform point of [-5, 5]^n).
                use cmaes::restart::{RestartOptions, RestartStrategy, IPOP};
                let strategy = RestartStrategy::IPOP(IPOP::new(2).expect("valid factor"));
                if let Ok(r) = RestartOptions::new(n, -5.0..=5.0, strategy)
                    .max_function_evals(budget)
                    .fun_target(1e-8)
                    .seed(seed)
                    .build()
                {
                    r.run(|| |x: &cmaes::DVector<f64>| rec.eval(x.as_slice()));
                }
            }
            Method::Random => {
                let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0xA5A5);
                f(&p.x0);
                let mut x = vec![0.0; n];
                for _ in 1..budget {
                    x.iter_mut().for_each(|v| *v = rng.random_range(-5.0..5.0));
                    f(&x);
                }
            }
        }
    }
}

struct Run {
    method: Method,
    kind: Kind,
    n: usize,
    seed: u64,
    evals: usize,
    best: f64,
    hits: [Option<usize>; 11],
    seconds: f64,
}

impl Run {
    fn reached(&self) -> usize {
        self.hits.iter().filter(|h| h.is_some()).count()
    }
}

struct Args {
    dims: Vec<usize>,
    seeds: u64,
    methods: Vec<Method>,
    kinds: Vec<Kind>,
    factor: usize,
    out: String,
    quick: bool,
    /// Only these methods run; the other methods' rows are read back from the CSV in `out`
    /// (written by an earlier full run), so that a change to one method does not cost the
    /// others' minutes (CMA-ES IPOP alone takes most of the 21).
    rerun: Option<Vec<Method>>,
    /// Write every instance of the grid to this file (for `python/benchmarks/peers.py`) and
    /// stop.
    export: Option<String>,
    /// The rows of the peers (`python/benchmarks/peers.py`), for their section of the page.
    peers: Option<String>,
}

fn parse_args() -> Result<Args, String> {
    let mut a = Args {
        dims: vec![2, 5, 10, 20, 100],
        seeds: 5,
        methods: Method::ALL.to_vec(),
        kinds: Kind::ALL.to_vec(),
        factor: 1000,
        out: "docs/results".into(),
        quick: false,
        rerun: None,
        export: None,
        peers: None,
    };
    let mut it = std::env::args().skip(1);
    let mut out_set = false;
    while let Some(arg) = it.next() {
        let mut value = || it.next().ok_or(format!("{arg} needs a value"));
        match arg.as_str() {
            "--quick" => a.quick = true,
            "--dims" => {
                a.dims = value()?
                    .split(',')
                    .map(|s| s.parse().map_err(|e| format!("--dims {s}: {e}")))
                    .collect::<Result<_, _>>()?
            }
            "--seeds" => a.seeds = value()?.parse().map_err(|e| format!("--seeds: {e}"))?,
            "--factor" => a.factor = value()?.parse().map_err(|e| format!("--factor: {e}"))?,
            "--methods" => {
                a.methods = value()?
                    .split(',')
                    .map(|s| Method::parse(s).ok_or(format!("unknown method {s}")))
                    .collect::<Result<_, _>>()?
            }
            "--functions" => {
                a.kinds = value()?
                    .split(',')
                    .map(|s| Kind::parse(s).ok_or(format!("unknown function {s}")))
                    .collect::<Result<_, _>>()?
            }
            "--rerun" => {
                let v = value()?;
                // `none`: every row read back (to add the peers' section alone).
                a.rerun = Some(
                    v.split(',')
                        .filter(|s| *s != "none")
                        .map(|s| Method::parse(s).ok_or(format!("unknown method {s}")))
                        .collect::<Result<_, _>>()?,
                )
            }
            "--export" => a.export = Some(value()?),
            "--peers" => a.peers = Some(value()?),
            "--out" => {
                a.out = value()?;
                out_set = true
            }
            "--help" | "-h" => {
                return Err(
                    "usage: compare [--quick] [--dims 2,5,10,20,100] [--seeds 5] \
                     [--factor 1000] [--methods minimize,cmaes,cmaes-ipop,random,paper-loop] \
                     [--functions sphere,...] [--out docs/results] [--rerun minimize] \
                     [--export FILE] [--peers FILE]"
                        .into(),
                )
            }
            other => return Err(format!("unknown argument {other}; try --help")),
        }
    }
    if a.quick {
        a.dims.retain(|&d| d <= 5);
        a.seeds = a.seeds.min(2);
        if !out_set {
            a.out = "target/compare-quick".into();
        }
    }
    Ok(a)
}

fn main() {
    let args = match parse_args() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(2);
        }
    };
    if let Some(path) = &args.export {
        if let Err(e) = export(&args, path) {
            eprintln!("--export {path}: {e}");
            std::process::exit(1);
        }
        return;
    }
    let peer_runs = match args.peers.as_deref().map(peers::read) {
        Some(Ok(rows)) => Some(rows),
        Some(Err(e)) => {
            eprintln!("--peers: {e}");
            std::process::exit(2);
        }
        None => None,
    };
    let mut runs = match &args.rerun {
        Some(rerun) => match kept_runs(&args, rerun) {
            Ok(kept) => kept,
            Err(e) => {
                eprintln!("--rerun: {e}");
                std::process::exit(2);
            }
        },
        None => Vec::new(),
    };
    for &n in &args.dims {
        for &kind in &args.kinds {
            for seed in 0..args.seeds {
                let problem = Problem::new(kind, n, seed);
                for &method in &args.methods {
                    if args.rerun.as_ref().is_some_and(|r| !r.contains(&method)) {
                        continue;
                    }
                    let budget = args.factor * n;
                    let rec = Recorder::new(&problem, budget);
                    let t = Instant::now();
                    method.run(&rec, seed);
                    let run = Run {
                        method,
                        kind,
                        n,
                        seed,
                        evals: rec.evals.get().min(budget),
                        best: rec.best.get(),
                        hits: *rec.hits.borrow(),
                        seconds: t.elapsed().as_secs_f64(),
                    };
                    eprintln!(
                        "{:<11} {:<15} n={:<3} seed={} best {:>10.3e} targets {:>2}/11  {:.2}s",
                        method.name(),
                        kind.name(),
                        n,
                        seed,
                        run.best,
                        run.reached(),
                        run.seconds
                    );
                    runs.push(run);
                }
            }
        }
    }
    // The page's tables group by method, function and n, not by the order of the rows; the CSV
    // keeps the order of a full run.
    let order = |r: &Run| {
        (
            args.dims.iter().position(|&d| d == r.n),
            args.kinds.iter().position(|&k| k == r.kind),
            r.seed,
            args.methods.iter().position(|&m| m == r.method),
        )
    };
    runs.sort_by_key(order);
    if let Err(e) = write_outputs(&args, &runs, peer_runs.as_deref()) {
        eprintln!("writing {}: {e}", args.out);
        std::process::exit(1);
    }
}

/// Writes every instance of the grid (dimension, function, seed) to `path`.
fn export(args: &Args, path: &str) -> std::io::Result<()> {
    let mut text = String::new();
    for &n in &args.dims {
        for &kind in &args.kinds {
            for seed in 0..args.seeds {
                let problem = Problem::new(kind, n, seed);
                text.push_str(&problem.export(seed, &problem.check_points(seed)));
            }
        }
    }
    if let Some(dir) = std::path::Path::new(path).parent() {
        std::fs::create_dir_all(dir)?;
    }
    std::fs::write(path, text)
}

/// The rows of the methods that `--rerun` leaves out, read from `<out>/compare.csv`: every
/// (method, function, n, seed) of this run's grid must be there.
fn kept_runs(args: &Args, rerun: &[Method]) -> Result<Vec<Run>, String> {
    let path = format!("{}/compare.csv", args.out);
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{path}: {e}"))?;
    let mut kept = Vec::new();
    for (i, line) in text.lines().enumerate().skip(1) {
        let bad = |what: &str| format!("{path}:{}: {what}", i + 1);
        let f: Vec<&str> = line.split(',').collect();
        if f.len() != 9 + TARGETS.len() {
            return Err(bad("wrong number of columns"));
        }
        let method = Method::parse(f[0]).ok_or_else(|| bad("unknown method"))?;
        let kind = Kind::parse(f[1]).ok_or_else(|| bad("unknown function"))?;
        let n: usize = f[3].parse().map_err(|_| bad("n"))?;
        let seed: u64 = f[4].parse().map_err(|_| bad("seed"))?;
        if rerun.contains(&method)
            || !args.methods.contains(&method)
            || !args.kinds.contains(&kind)
            || !args.dims.contains(&n)
            || seed >= args.seeds
        {
            continue;
        }
        let mut hits = [None; 11];
        for (h, v) in hits.iter_mut().zip(&f[9..]) {
            if !v.is_empty() {
                *h = Some(v.parse().map_err(|_| bad("evals_to"))?);
            }
        }
        kept.push(Run {
            method,
            kind,
            n,
            seed,
            evals: f[5].parse().map_err(|_| bad("evaluations"))?,
            best: f[6].parse().map_err(|_| bad("best"))?,
            hits,
            seconds: f[8].parse().map_err(|_| bad("seconds"))?,
        });
    }
    let expected = args.dims.len()
        * args.kinds.len()
        * args.seeds as usize
        * args.methods.iter().filter(|m| !rerun.contains(m)).count();
    if kept.len() != expected {
        return Err(format!(
            "{path} holds {} of the {expected} rows the other methods need",
            kept.len()
        ));
    }
    Ok(kept)
}

fn fraction<'a>(runs: impl Iterator<Item = &'a Run>) -> (f64, usize) {
    let (mut hit, mut count) = (0, 0);
    for r in runs {
        hit += r.reached();
        count += 1;
    }
    if count == 0 {
        (f64::NAN, 0)
    } else {
        (hit as f64 / (11 * count) as f64, count)
    }
}

fn write_outputs(
    args: &Args,
    runs: &[Run],
    peer_runs: Option<&[peers::PeerRun]>,
) -> std::io::Result<()> {
    std::fs::create_dir_all(&args.out)?;
    let mut csv =
        String::from("method,function,group,n,seed,evaluations,best,targets_reached,seconds");
    for t in TARGETS {
        write!(csv, ",evals_to_{t:e}").unwrap();
    }
    csv.push('\n');
    for r in runs {
        write!(
            csv,
            "{},{},{},{},{},{},{:e},{},{:.3}",
            r.method.name(),
            r.kind.name(),
            r.kind.group(),
            r.n,
            r.seed,
            r.evals,
            r.best,
            r.reached(),
            r.seconds
        )
        .unwrap();
        for h in r.hits {
            match h {
                Some(e) => write!(csv, ",{e}").unwrap(),
                None => csv.push(','),
            }
        }
        csv.push('\n');
    }
    let csv_name = if args.quick {
        "compare-quick.csv"
    } else {
        "compare.csv"
    };
    std::fs::write(format!("{}/{csv_name}", args.out), csv)?;

    let methods = &args.methods;
    let mut md = String::new();
    let cmd: Vec<String> = std::env::args().skip(1).collect();
    writeln!(
        md,
        "# plateau_free::minimize against CMA-ES and random search\n"
    )
    .unwrap();
    writeln!(
        md,
        "Written by `cargo run --release --example compare{}{}` (every number on this page comes \
         from that command; per-run rows in `{csv_name}`).\n",
        if cmd.is_empty() { "" } else { " -- " },
        cmd.join(" ")
    )
    .unwrap();
    if args.rerun.as_ref().is_some_and(Vec::is_empty) {
        writeln!(
            md,
            "That command ran no method: every row is that of the previous full run \
             (`cargo run --release --example compare`), read back from `{csv_name}`.\n"
        )
        .unwrap();
    } else if let Some(rerun) = &args.rerun {
        writeln!(
            md,
            "That command ran {} only; the other methods' rows are those of the previous full \
             run (`cargo run --release --example compare`), read back from `{csv_name}`, \
             whose code they do not depend on.\n",
            rerun
                .iter()
                .map(|m| m.name())
                .collect::<Vec<_>>()
                .join(", ")
        )
        .unwrap();
    }
    writeln!(
        md,
        "Functions: {} (shifted to a random optimum in [-4, 4]^n and rotated; definitions in \
         `examples/compare/functions.rs`). Dimensions {:?}, seeds 0..{}, budget {} n \
         evaluations, start x0 uniform in [-4, 4]^n (the same for every method). A run \
         reaches target t when its best value is at most t above the optimum; the fraction is \
         over the 11 targets 1e2, 1e1, ..., 1e-8 and over runs.\n",
        args.kinds
            .iter()
            .map(|k| k.name())
            .collect::<Vec<_>>()
            .join(", "),
        args.dims,
        args.seeds,
        args.factor
    )
    .unwrap();
    writeln!(md, "Methods:\n").unwrap();
    for m in methods {
        let what = match m {
            Method::Minimize => "`plateau_free::minimize(f, x0, budget)` with its defaults (`Minimizer::new(f).budget(b).seed(s).target(1e-8)`; the target only ends a run early once every target is reached): no step size given",
            Method::Cmaes => "the `cmaes` crate (0.2), one run from x0, step size 2, default population and stopping rules, `fun_target(1e-8)` (a run that stops early leaves budget unused)",
            Method::CmaesIpop => "the `cmaes` crate's IPOP restarts over [-5, 5]^n (population doubled per restart), the whole budget, `fun_target(1e-8)`",
            Method::Random => "uniform random points in [-5, 5]^n (after x0)",
            Method::Paper => "the paper's loop with the README's settings: N = 4 radial antithetic samples, Adam lr 0.02, `Annealer::paper(0.5, budget / 4)`",
        };
        writeln!(md, "- **{}**: {what}.", m.name()).unwrap();
    }

    // Per group and overall.
    let groups = ["smooth", "ill-conditioned", "multimodal", "plateau"];
    writeln!(md, "\n## Fraction of targets reached, per function group\n").unwrap();
    header(&mut md, "group", methods);
    for g in groups {
        let sel: Vec<&Run> = runs.iter().filter(|r| r.kind.group() == g).collect();
        if sel.is_empty() {
            continue;
        }
        row(&mut md, g, methods, |m| {
            fraction(sel.iter().copied().filter(|r| r.method == m))
        });
    }
    row(&mut md, "**overall**", methods, |m| {
        fraction(runs.iter().filter(|r| r.method == m))
    });

    writeln!(md, "\n## Fraction of targets reached, per dimension\n").unwrap();
    header(&mut md, "n", methods);
    for &n in &args.dims {
        row(&mut md, &n.to_string(), methods, |m| {
            fraction(runs.iter().filter(|r| r.method == m && r.n == n))
        });
    }

    writeln!(
        md,
        "\n## Fraction of targets reached, per function and dimension\n"
    )
    .unwrap();
    header(&mut md, "function, n", methods);
    for &kind in &args.kinds {
        for &n in &args.dims {
            row(&mut md, &format!("{} {n}", kind.name()), methods, |m| {
                fraction(
                    runs.iter()
                        .filter(|r| r.method == m && r.n == n && r.kind == kind),
                )
            });
        }
    }

    writeln!(
        md,
        "\n## Evaluations to reach 1e-2 above the optimum\n\nRuns that reached it out of \
         runs, and the expected running time ERT = (evaluations spent by all runs until they \
         reached 1e-2 or their budget ran out) / (runs that reached it); `-` when none did.\n"
    )
    .unwrap();
    write!(md, "| function, n |").unwrap();
    for m in methods {
        write!(md, " {} |", m.name()).unwrap();
    }
    writeln!(md, "\n|---|{}", "---|".repeat(methods.len())).unwrap();
    for &kind in &args.kinds {
        for &n in &args.dims {
            write!(md, "| {} {n} |", kind.name()).unwrap();
            for &m in methods {
                let sel: Vec<&Run> = runs
                    .iter()
                    .filter(|r| r.method == m && r.n == n && r.kind == kind)
                    .collect();
                let ok = sel.iter().filter(|r| r.hits[T_1EM2].is_some()).count();
                let spent: usize = sel.iter().map(|r| r.hits[T_1EM2].unwrap_or(r.evals)).sum();
                if ok == 0 {
                    write!(md, " 0/{} - |", sel.len()).unwrap();
                } else {
                    write!(md, " {ok}/{} {:.0} |", sel.len(), spent as f64 / ok as f64).unwrap();
                }
            }
            md.push('\n');
        }
    }
    if let (Some(rows), Some(path)) = (peer_runs, &args.peers) {
        let ours: Vec<peers::PeerRun> = runs
            .iter()
            .filter(|r| r.method == Method::Minimize)
            .map(|r| peers::PeerRun {
                method: "minimize".into(),
                kind: r.kind,
                n: r.n,
                seed: r.seed,
                reached: r.reached(),
            })
            .collect();
        peers::section(&mut md, path, rows, &ours);
    }
    writeln!(md, "\n## Time\n").unwrap();
    header(&mut md, "", methods);
    write!(md, "| seconds in all |").unwrap();
    for &m in methods {
        let s: f64 = runs
            .iter()
            .filter(|r| r.method == m)
            .map(|r| r.seconds)
            .sum();
        write!(md, " {s:.1} |").unwrap();
    }
    md.push('\n');
    let md_name = if args.quick {
        "compare-quick.md"
    } else {
        "compare.md"
    };
    std::fs::write(format!("{}/{md_name}", args.out), &md)?;
    println!("{md}");
    Ok(())
}

fn header(md: &mut String, first: &str, methods: &[Method]) {
    write!(md, "| {first} |").unwrap();
    for m in methods {
        write!(md, " {} |", m.name()).unwrap();
    }
    writeln!(md, "\n|---|{}", "---|".repeat(methods.len())).unwrap();
}

fn row(md: &mut String, label: &str, methods: &[Method], f: impl Fn(Method) -> (f64, usize)) {
    write!(md, "| {label} |").unwrap();
    for &m in methods {
        let (frac, _) = f(m);
        write!(md, " {:.3} |", frac).unwrap();
    }
    md.push('\n');
}
