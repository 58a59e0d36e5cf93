//! Relative error of one gradient estimate against N and spp on SHADOW, at the start and near
//! the optimum, at fixed renderer seed.

use plateau_free::{objective::Seeded, PlateauFreeGradient};

use super::{task, write_page, Options};
use crate::report::{self, Result};
use crate::run::Settings;
use crate::tasks;

pub(super) fn run(opts: &Options) -> Result<()> {
    let shadow = task("shadow")?;
    let defaults = Settings::defaults(&shadow);
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
