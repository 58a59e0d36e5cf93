//! The command line of the comparison.

use crate::functions::Kind;
use crate::methods::Method;

/// What the command line asks for.
pub(crate) struct Args {
    pub(crate) dims: Vec<usize>,
    pub(crate) seeds: u64,
    pub(crate) methods: Vec<Method>,
    pub(crate) kinds: Vec<Kind>,
    pub(crate) factor: usize,
    pub(crate) out: String,
    pub(crate) quick: bool,
    /// Only these methods run; the other methods' rows are read back from the CSV in `out`
    /// (written by an earlier full run), so that a change to one method does not cost the
    /// others' minutes (CMA-ES IPOP alone takes most of the 21).
    pub(crate) rerun: Option<Vec<Method>>,
    /// Write every instance of the grid to this file (for `studies/peers/peers.py`) and
    /// stop.
    pub(crate) export: Option<String>,
    /// The rows of the peers (`studies/peers/peers.py`), for their section of the page.
    pub(crate) peers: Option<String>,
}

/// Reads the command line; an unknown or bad argument is an error naming it.
pub(crate) fn parse_args() -> Result<Args, String> {
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
                     [--factor 1000] [--methods minimize,cmaes,cmaes-ipop,random,paper-loop,smoothed-newton] \
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
