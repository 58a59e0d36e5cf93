//! Helpers of the ask-and-tell tests (`ask_tell*.rs`): the objectives, the drivers that
//! evaluate an ask "elsewhere", the lines the pinned results are written as, and the pinned
//! paper loops' settings.

use plateau_free::{
    estimator::OnFailure, objective::Points, run::Strategy, Adam, Annealer, Ask, AskTell,
    Minimizer, Minimum, Optimizer, PaperAskTell, PlateauFreeGradient, Sampling,
};

pub fn rosen(x: &[f64]) -> f64 {
    x.windows(2)
        .map(|w| 100.0 * (w[1] - w[0] * w[0]).powi(2) + (1.0 - w[0]).powi(2))
        .sum()
}

/// A staircase with its minimum 0 at `(0, 1, 2, ...)`: flat almost everywhere.
pub fn stairs(x: &[f64]) -> f64 {
    x.iter()
        .enumerate()
        .map(|(i, v)| (v.round() - i as f64).powi(2))
        .sum()
}

/// The staircase with noise that depends on the seed alone (a renderer's noise).
pub fn noisy(x: &[f64], seed: u64) -> f64 {
    stairs(x) + 1e-3 * (seed % 97) as f64
}

/// `noisy` as a batch objective.
pub fn noisy_batch(p: Points<'_>, s: &[u64], out: &mut [f64]) {
    for ((x, &seed), o) in p.iter().zip(s).zip(out.iter_mut()) {
        *o = noisy(x, seed);
    }
}

pub const PAPER: Strategy = Strategy::Paper {
    samples: 4,
    lr: 0.05,
    sigma0: 1.0,
};

/// The values of an ask, computed "elsewhere": the points copied out, evaluated last to
/// first (the order must not matter), the values put back in the points' order.
pub fn evaluate_elsewhere(ask: Ask<'_>, f: impl Fn(&[f64], u64) -> f64) -> Vec<f64> {
    let jobs: Vec<(Vec<f64>, u64)> = ask.iter().map(|(x, s)| (x.to_vec(), s)).collect();
    let mut values = vec![0.0; jobs.len()];
    for (k, (x, seed)) in jobs.iter().enumerate().rev() {
        values[k] = f(x, *seed);
    }
    values
}

/// Drives an ask-and-tell `minimize` run to its end.
pub fn drive(mut run: AskTell, f: impl Fn(&[f64], u64) -> f64) -> Minimum {
    while let Some(ask) = run.ask().unwrap() {
        let values = evaluate_elsewhere(ask, &f);
        run.tell(&values).unwrap();
    }
    assert!(run.is_done());
    assert!(
        run.ask().unwrap().is_none(),
        "a finished run asks for nothing"
    );
    run.finish().unwrap()
}

/// Drives an ask-and-tell paper loop to its end.
pub fn drive_paper(
    mut run: PaperAskTell,
    f: impl Fn(&[f64], u64) -> f64,
) -> plateau_free::run::History {
    while let Some(ask) = run.ask().unwrap() {
        let values = evaluate_elsewhere(ask, &f);
        run.tell(&values).unwrap();
    }
    run.finish()
}

/// The line `PINNED` holds for a result.
pub fn show(tag: &str, m: &Minimum) -> String {
    let bits: Vec<u64> = m.x.iter().map(|v| v.to_bits()).collect();
    format!(
        "{tag}: x={:x?} fun={:x} ev={} it={} re={} sigma={:x} stop={:?}",
        bits,
        m.fun.to_bits(),
        m.evaluations,
        m.iterations,
        m.restarts,
        m.sigma.to_bits(),
        m.stop
    )
}

/// The line `PINNED` holds for a paper loop's history.
pub fn show_history(tag: &str, h: &plateau_free::run::History) -> String {
    let bits: Vec<u64> = h
        .theta
        .iter()
        .flatten()
        .chain(&h.value)
        .chain(&h.sigma)
        .map(|v| v.to_bits())
        .collect();
    let hash = bits
        .iter()
        .fold(0u64, |a, b| plateau_free::seeding::mix(a ^ b));
    let last: Vec<u64> = h
        .last_theta()
        .unwrap()
        .iter()
        .map(|v| v.to_bits())
        .collect();
    format!(
        "optimizer {tag}: hash={hash:x} ev={} last={last:x?}",
        h.evaluations
    )
}

/// The pinned paper loops: (name, sampler, antithetic, orthogonal).
pub const LOOPS: [(&str, Sampling, bool, bool); 3] = [
    ("radial", Sampling::Radial, true, false),
    ("percoord", Sampling::PerCoordinate, true, false),
    ("gauss-orth", Sampling::Gaussian, false, true),
];

pub fn loop_estimator<F>(
    grad: PlateauFreeGradient<F>,
    seed: u64,
    sampling: Sampling,
    antithetic: bool,
    orthogonal: bool,
) -> PlateauFreeGradient<F> {
    grad.samples(6)
        .sampling(sampling)
        .antithetic(antithetic)
        .orthogonal(orthogonal)
        .seed(seed)
        .on_failure(OnFailure::Resample { limit: 5 })
}

pub fn loop_optimizer() -> Optimizer {
    Optimizer::new(Adam::new(0.05).unwrap(), Annealer::paper(0.8, 60).unwrap()).record_theta(true)
}

pub const LOOP_START: [f64; 3] = [0.2, -0.3, 0.9];

/// The options of the identity tests.
pub fn opts<F>(m: Minimizer<F>, seed: u64, strategy: Strategy) -> Minimizer<F> {
    m.budget(900).seed(seed).strategy(strategy)
}
