//! The speed/accuracy trade on SHADOW and GI with the tasks' default method (polished): one
//! factor at a time (N, spp, resolution) around the defaults, the methods side by side (the
//! paper's loop, polished, the adaptive search) with their parameter error against the
//! renders spent and the paper's point (N x iterations renders, its parameter MSE), the
//! Pareto front and cost exponents. Sized for a shared two-core machine: every run at a
//! quarter of the task's resolution (the page says so), the paper's iterations kept.

use std::fmt::Write as _;

use super::{cache, fit_line, header, summary_csv_row, task, write_page, Options};
use crate::report::{self, sci, Axes, Result, Series};

use crate::run::{self, Method, Settings};

/// The resolution of every run, a fraction of the task's: the page's runs fit a shared
/// two-core machine (the renders' count, which the page compares, does not depend on it).
const SCALE: f64 = 0.25;

/// The methods compared on renders against parameter error (the first is the default).
const METHODS: [Method; 3] = [Method::Polished, Method::Plateau, Method::Adaptive];

pub(super) fn run(opts: &Options) -> Result<()> {
    let mut csv = Vec::new();
    let mut body = String::from(
        "Every run uses the tasks' default method (the paper's loop polished by the adaptive search, `--method polished`) unless its label names another, the task's Table 1 settings and iterations (so N x iterations renders of the objective), seed 0, at a quarter of the task's resolution (the runs fit a shared two-core machine; the renders' count does not depend on the resolution). One factor at a time around the defaults; every run records its wall time (optimisation only), its renders of the objective, and its final errors. The Pareto front (no other run both faster and more accurate) is marked. The first plot is the parameter MSE (of the best point so far; of the current point for the paper's loop) against the renders spent, per method, with the paper's point: its N x iterations renders and its parameter MSE (main paper Table 2). Reductions against the earlier version of this page: a quarter resolution, no sampler sweep, no seed check of the fastest settings (the seeds page, `docs/results/seeds.md`, holds the seeds).\n\n",
    );
    for name in ["shadow", "gi"] {
        let t = task(name)?;
        if !opts.wants(&t) {
            continue;
        }
        let mut base = Settings::defaults(&t);
        base.method = Method::TASK_DEFAULT;
        base.scale = Some(SCALE);
        let mut configs: Vec<(String, Settings)> = Vec::new();
        let ns: &[usize] = if opts.quick { &[2, 4] } else { &[2, 4, 8] };
        let spps: &[u32] = if opts.quick { &[8] } else { &[8, 16, 32] };
        let scales: &[f64] = if opts.quick {
            &[SCALE]
        } else {
            &[SCALE, 2.0 * SCALE]
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
            s.scale = Some(scale);
            configs.push((format!("scale={scale}"), s));
        }
        for method in &METHODS[1..] {
            let mut s = base.clone();
            s.method = *method;
            configs.push((format!("method={}", method.as_arg()), s));
        }
        let mut results = Vec::new();
        let mut curves = Vec::new();
        for (label, mut s) in configs {
            opts.shrink(&mut s, 30);
            let o = cache::optimize(opts, &t, &s)?;
            csv.push(summary_csv_row(&o, std::slice::from_ref(&label)));
            let default_n = label == format!("N={}", base.samples);
            if default_n || label.starts_with("method=") {
                let curve: Vec<(f64, f64)> = o
                    .history
                    .iter()
                    .map(|r| (r.renders as f64, r.param_mse))
                    .collect();
                curves.push(Series::line(s.method.as_arg(), curve));
            }
            results.push((label, o.summary));
        }
        let paper_point = t.paper().map(|p| {
            let renders = (base.samples * base.iterations) as f64;
            Series::markers(
                format!("the paper ({} renders, its parameter MSE)", renders),
                vec![(renders, p.param_mse)],
            )
        });
        curves.extend(paper_point);
        report::plot(
            &opts.out.join(format!("tradeoff_{name}_renders.png")),
            &Axes::log_log(
                &format!(
                    "{}: parameter MSE against renders of the objective",
                    name.to_uppercase()
                ),
                "renders of the objective",
                "parameter MSE",
            ),
            &curves,
        )?;
        let points: Vec<(f64, f64)> = results
            .iter()
            .map(|(_, m)| (m.seconds_total, m.param_mse))
            .collect();
        let front = pareto(&points);
        report::plot(
            &opts.out.join(format!("tradeoff_{name}.png")),
            &Axes::log_log(
                &format!(
                    "{}: final parameter MSE against wall time",
                    name.to_uppercase()
                ),
                "seconds (optimisation)",
                "final parameter MSE",
            ),
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
                    m.renders.to_string(),
                    m.renders_to_paper
                        .map_or_else(|| "never".to_string(), |r| r.to_string()),
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
        let verdict = fastest.map_or_else(
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
        let _ = write!(
            body,
            "## {}\n\n![renders](tradeoff_{name}_renders.png)\n\n![tradeoff](tradeoff_{name}.png)\n\n{}\nCost per iteration grows as N^{e_n:.2}, spp^{e_spp:.2} and pixels^{e_px:.2} (least-squares slopes in log-log over the one-factor sweeps).\n\n{verdict}\n\n",
            name.to_uppercase(),
            report::markdown_table(&["run", "resolution", "s/iteration", "seconds", "renders", "renders to the paper's param MSE", "image MSE", "param MSE", "Pareto"], &rows)
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
}
