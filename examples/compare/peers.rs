//! The stronger peers' section of the page: pycma's BIPOP-CMA-ES and nevergrad's NGOpt, run by
//! `studies/peers/peers.py` on the instances `--export` wrote, their rows (columns of
//! `compare.csv`) read from `--peers FILE`. Each peer is compared with `minimize` on exactly the
//! instances the peer ran.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use crate::functions::Kind;

/// One run of a peer, or of `minimize` on the same instance.
pub struct PeerRun {
    pub method: String,
    pub kind: Kind,
    pub n: usize,
    pub seed: u64,
    /// How many of the 11 targets it reached.
    pub reached: usize,
}

/// The rows of `path` (a CSV of `peers.py`).
pub fn read(path: &str) -> Result<Vec<PeerRun>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{path}: {e}"))?;
    let mut runs = Vec::new();
    for (i, line) in text.lines().enumerate().skip(1) {
        let bad = |what: &str| format!("{path}:{}: {what}", i + 1);
        let f: Vec<&str> = line.split(',').collect();
        if f.len() != 20 {
            return Err(bad("wrong number of columns"));
        }
        runs.push(PeerRun {
            method: f[0].to_string(),
            kind: Kind::parse(f[1]).ok_or_else(|| bad("unknown function"))?,
            n: f[3].parse().map_err(|_| bad("n"))?,
            seed: f[4].parse().map_err(|_| bad("seed"))?,
            reached: f[7].parse().map_err(|_| bad("targets_reached"))?,
        });
    }
    Ok(runs)
}

/// The fraction of targets reached over `runs`.
fn fraction<'a>(runs: impl Iterator<Item = &'a PeerRun>) -> Option<f64> {
    let (mut hit, mut count) = (0, 0);
    for r in runs {
        hit += r.reached;
        count += 1;
    }
    (count > 0).then(|| hit as f64 / (11 * count) as f64)
}

/// The section: for each peer, on the instances it ran, `minimize`'s and its fraction of
/// targets reached per group and overall, and every (function, n) where `minimize` reaches
/// fewer. `ours` are `minimize`'s runs on the whole grid.
pub fn section(md: &mut String, path: &str, peers: &[PeerRun], ours: &[PeerRun]) {
    let names: Vec<&str> = {
        let mut v: Vec<&str> = peers.iter().map(|r| r.method.as_str()).collect();
        v.dedup();
        v.sort_unstable();
        v.dedup();
        v
    };
    writeln!(
        md,
        "\n## Stronger peers: pycma's BIPOP-CMA-ES and nevergrad's NGOpt\n\n\
         Rows from `{path}`, written by `studies/peers/peers.py` (run by \
         `scripts/compare-peers`, which also wrote this page) on the instances `compare \
         --export` wrote: the same shifts, rotations and start points, the functions written \
         again in numpy and checked against these at six points per instance before any run. \
         Each gets x0, the budget of 1000 n evaluations (only the first count) and the target \
         1e-8 as a reason to stop.\n\n\
         - **bipop-cma**: pycma (`cma` 4.5.0), `cma.fmin2(f, x0, 2, restarts=9, bipop=True)`, \
         step size 2 as the `cmaes` rows, `maxfevals` the budget, `ftarget` 1e-8; restarts \
         from uniform points of [-4, 4]^n.\n\
         - **ngopt**: nevergrad 1.0.12's `NGOpt` on `ng.p.Array(init=x0)`, `budget` the \
         budget, one worker, its defaults otherwise.\n\n\
         Each peer is compared with minimize on the instances the peer ran (the grid is \
         given; where it is smaller than the page's, the peer's runs did not fit the \
         machine's time: the seconds of every run are in the CSV).\n"
    )
    .unwrap();
    for name in names {
        let mine: Vec<&PeerRun> = peers.iter().filter(|r| r.method == name).collect();
        let key = |r: &PeerRun| (r.kind.name(), r.n, r.seed);
        let matched: Vec<&PeerRun> = ours
            .iter()
            .filter(|o| mine.iter().any(|p| key(p) == key(o)))
            .collect();
        let mut grid: BTreeMap<usize, usize> = BTreeMap::new();
        for r in &mine {
            *grid.entry(r.n).or_default() += 1;
        }
        let grid: Vec<String> = grid
            .iter()
            .map(|(n, k)| format!("n = {n}: {k} runs"))
            .collect();
        writeln!(
            md,
            "\n### minimize against {name}\n\nInstances: {}.\n",
            grid.join(", ")
        )
        .unwrap();
        writeln!(md, "| group | minimize | {name} |\n|---|---|---|").unwrap();
        let cell = |v: Option<f64>| v.map_or("-".to_string(), |f| format!("{f:.3}"));
        for g in ["smooth", "ill-conditioned", "multimodal", "plateau"] {
            let ours = fraction(matched.iter().copied().filter(|r| r.kind.group() == g));
            let theirs = fraction(mine.iter().copied().filter(|r| r.kind.group() == g));
            writeln!(md, "| {g} | {} | {} |", cell(ours), cell(theirs)).unwrap();
        }
        writeln!(
            md,
            "| **overall** | {} | {} |",
            cell(fraction(matched.iter().copied())),
            cell(fraction(mine.iter().copied()))
        )
        .unwrap();
        let mut losses = Vec::new();
        for kind in Kind::ALL {
            let dims: Vec<usize> = {
                let mut d: Vec<usize> = mine
                    .iter()
                    .filter(|r| r.kind == kind)
                    .map(|r| r.n)
                    .collect();
                d.sort_unstable();
                d.dedup();
                d
            };
            for n in dims {
                let at = |r: &&PeerRun| r.kind == kind && r.n == n;
                let (o, t) = (
                    fraction(matched.iter().copied().filter(at)),
                    fraction(mine.iter().copied().filter(at)),
                );
                if let (Some(o), Some(t)) = (o, t) {
                    if o < t {
                        losses.push(format!("{} {n} ({o:.3} against {t:.3})", kind.name()));
                    }
                }
            }
        }
        if losses.is_empty() {
            writeln!(
                md,
                "\nminimize reaches at least as many targets on every function and n."
            )
            .unwrap();
        } else {
            writeln!(
                md,
                "\nWhere minimize reaches fewer targets: {}.",
                losses.join(", ")
            )
            .unwrap();
        }
    }
}
