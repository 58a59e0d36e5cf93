//! Common random numbers: a noisy objective evaluated with the estimator's shared seed
//! within a pair, against independent noise.

use std::fmt::Write as _;
use std::sync::atomic::{AtomicU64, Ordering};

use plateau_free::seeding::mix;
use plateau_free::{objective::Seeded, Sampling};

use crate::cases::{cases, dot};
use crate::measure::{measure, measure_relative_to, reps_for, Config};
use crate::report::{fmt_num, table_header};

/// A uniform in [-1, 1) from a seed.
pub(crate) fn noise(seed: u64) -> f64 {
    (mix(seed) >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}

/// Independent noise: ignores the estimator's seed and draws a fresh one per call from a
/// counter, as an objective with its own random state would.
pub(crate) fn fresh_noise<'a>(
    f: &'a dyn Fn(&[f64], u64) -> f64,
    start: u64,
) -> impl Fn(&[f64], u64) -> f64 + 'a {
    let counter = AtomicU64::new(start);
    move |x: &[f64], _seed: u64| f(x, mix(counter.fetch_add(1, Ordering::Relaxed)))
}

/// One row of the common-random-numbers table.
pub(crate) struct CrnRow {
    pub(crate) n: usize,
    pub(crate) amplitude: f64,
    pub(crate) samples: usize,
    pub(crate) sampling: Sampling,
    pub(crate) clean: f64,
    pub(crate) shared: f64,
    pub(crate) independent: f64,
    /// The noise term alone (its smoothed gradient is zero), relative to the step's gradient.
    pub(crate) noise_shared: f64,
    pub(crate) noise_independent: f64,
}

/// A noisy tilted step: `1[a.x > b] + A u(seed) (1 + 0.2 sin(x_0))`, with `u` uniform in
/// [-1, 1]. The noise has mean zero, so the smoothed gradient is the step's. The same
/// estimator seed in all three modes draws the same perturbations, so their differences are
/// the noise's alone.
pub(crate) fn common_random_numbers(quick: bool) -> Vec<CrnRow> {
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
            let seed = mix(n as u64 * 31 + samples as u64);
            let fresh = |f| fresh_noise(f, mix(seed));
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

pub(crate) fn write_crn(page: &mut String, rows: &[CrnRow]) {
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
    table_header(
        page,
        &[
            "n",
            "A",
            "sampler",
            "N",
            "noise-free",
            "shared seed",
            "independent noise",
            "independent / shared",
            "noise term alone: shared",
            "independent",
            "ratio",
        ],
    );
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
