//! What the comparison writes: `compare.csv` and the page `compare.md`.

use std::fmt::Write as _;

use crate::args::Args;
use crate::methods::Method;
use crate::{peers, Run, TARGETS, T_1EM2};

/// The share of the targets that `runs` reached, and how many runs.
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

/// Writes `compare.csv` and `compare.md` into `args.out`, with the peers' section if given.
pub(crate) fn write_outputs(
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
            Method::SmoothedNewton => "trust-region Newton steps on the smoothed objective (`examples/compare/newton.rs`): `max(n, 2)` antithetic pairs per step give the smoothed gradient and a Hessian estimate by Stein's identity, the Hessian averaged over the last `max(10, n)` steps, samples and trust region in a metric renewed from that Hessian, `sigma` equal to the trust radius (first 0.5), doubled on a plateau; a measurement of the smoothed Hessian as curvature (`docs/convergence.md`, table 9), not a method of the library",
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

/// A table's header: `first`, then a column per method.
fn header(md: &mut String, first: &str, methods: &[Method]) {
    write!(md, "| {first} |").unwrap();
    for m in methods {
        write!(md, " {} |", m.name()).unwrap();
    }
    writeln!(md, "\n|---|{}", "---|".repeat(methods.len())).unwrap();
}

/// A table's row: `label`, then each method's share of targets reached and its count of runs.
fn row(md: &mut String, label: &str, methods: &[Method], f: impl Fn(Method) -> (f64, usize)) {
    write!(md, "| {label} |").unwrap();
    for &m in methods {
        let (frac, _) = f(m);
        write!(md, " {:.3} |", frac).unwrap();
    }
    md.push('\n');
}
