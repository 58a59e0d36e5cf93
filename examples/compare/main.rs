//! The comparison of `plateau_free::minimize` with CMA-ES (the `cmaes` crate), random search, the
//! paper's loop and Newton steps on the smoothed objective (`newton.rs`), on shifted and rotated
//! classic test functions.
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

mod args;
mod functions;
mod methods;
mod newton;
mod page;
mod peers;
mod variant;

use std::time::Instant;

use args::{parse_args, Args};
use functions::{Kind, Problem};
use methods::{Method, Recorder};
use page::write_outputs;

/// The targets, above the optimum, that a run may reach.
const TARGETS: [f64; 11] = [
    1e2, 1e1, 1e0, 1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8,
];
/// The index of 1e-2 in `TARGETS`.
const T_1EM2: usize = 4;

/// One run of one method on one problem: what it spent and when it reached each target.
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
