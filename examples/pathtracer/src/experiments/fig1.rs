//! Supplemental Fig. 1: seconds per iteration against N on SHADOW, and how little of it is
//! not rendering.

use std::fmt::Write as _;

use super::{cache, fit_line, header, summary_csv_row, task, write_page, Options};
use crate::report::{self, Axes, Result, Series};
use crate::run::Settings;

pub(super) fn run(opts: &Options) -> Result<()> {
    let shadow = task("shadow")?;
    let ns: Vec<usize> = if opts.quick {
        vec![2, 4, 8]
    } else {
        vec![2, 4, 6, 8, 10, 12, 14, 16]
    };
    let mut runs = Vec::new();
    for &n in &ns {
        let mut s = Settings::defaults(&shadow);
        s.samples = n;
        s.iterations = if opts.quick { 4 } else { 20 };
        s.eval_every = usize::MAX;
        if opts.quick {
            s.scale = Some(0.5);
        }
        runs.push((n, cache::optimize(opts, &shadow, &s)?));
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
        &Axes::log_y(
            "SHADOW: seconds per iteration against N",
            "N (evaluations per gradient)",
            "seconds per iteration",
        ),
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
