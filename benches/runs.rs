//! What the run loops cost around a cheap objective: `cargo bench --bench runs`.
//!
//! Each method is run to its end on the sphere `sum x_i^2` at `n = 10`, in its callback form
//! and asked and told: the adaptive search ([`Minimizer::run`] and [`Minimizer::ask_tell`],
//! 2,000 evaluations), the polished run (the paper's loop then the search, 2,000
//! evaluations) and the paper's loop ([`Optimizer::minimize`] and [`Optimizer::ask_tell`],
//! 200 iterations of `N = 2`). The objective costs nanoseconds, so what is measured is the
//! drivers, the state machines and the methods' own arithmetic: the overhead a user pays on
//! top of `f`.
//!
//! Timing is best-of-runs, as in `benches/estimator.rs`: each sample times its runs one by
//! one and keeps the fastest. The machine is shared; a run the scheduler interrupted is
//! slower, never faster, so the fastest run is the cost of the code.

use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{criterion_group, criterion_main, Criterion};
use plateau_free::{run::Strategy, Adam, Annealer, Minimizer, Optimizer, PlateauFreeGradient};

const N: usize = 10;

/// `iters` runs of `f`, timed as `iters` times the fastest one.
fn best_of_runs<T>(iters: u64, mut f: impl FnMut() -> T) -> Duration {
    let mut best = Duration::MAX;
    for _ in 0..iters {
        let start = Instant::now();
        black_box(f());
        best = best.min(start.elapsed());
    }
    best * iters as u32
}

fn sphere(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum()
}

fn paper_optimizer() -> Optimizer {
    Optimizer::new(Adam::new(0.05).unwrap(), Annealer::paper(0.5, 200).unwrap())
}

const PAPER: Strategy = Strategy::Paper {
    samples: 2,
    lr: 0.05,
    sigma0: 0.5,
};

fn runs(c: &mut Criterion) {
    let mut group = c.benchmark_group("runs");
    group.warm_up_time(Duration::from_millis(500));
    group.measurement_time(Duration::from_secs(2));
    group.sample_size(20);
    let x0 = [1.0; N];

    group.bench_function("adaptive/run", |b| {
        let m = Minimizer::new(sphere).budget(2000).seed(1);
        b.iter_custom(|iters| best_of_runs(iters, || m.run(black_box(&x0)).unwrap()))
    });
    group.bench_function("adaptive/ask_tell", |b| {
        let m = Minimizer::without_objective().budget(2000).seed(1);
        b.iter_custom(|iters| {
            best_of_runs(iters, || {
                let mut run = m.ask_tell(black_box(&x0)).unwrap();
                let mut values = Vec::new();
                while let Some(ask) = run.ask().unwrap() {
                    values.clear();
                    values.extend(ask.points().iter().map(sphere));
                    run.tell(&values).unwrap();
                }
                run.finish().unwrap()
            })
        })
    });
    group.bench_function("polished/run", |b| {
        let m = Minimizer::new(sphere)
            .strategy(PAPER)
            .polish(0.25)
            .budget(2000)
            .seed(1);
        b.iter_custom(|iters| best_of_runs(iters, || m.run(black_box(&x0)).unwrap()))
    });
    group.bench_function("paper/minimize", |b| {
        b.iter_custom(|iters| {
            best_of_runs(iters, || {
                let mut grad = PlateauFreeGradient::new(sphere).samples(2).seed(1);
                paper_optimizer()
                    .minimize(&mut grad, black_box(&x0))
                    .unwrap()
            })
        })
    });
    group.bench_function("paper/ask_tell", |b| {
        b.iter_custom(|iters| {
            best_of_runs(iters, || {
                let grad = PlateauFreeGradient::without_objective().samples(2).seed(1);
                let mut run = paper_optimizer().ask_tell(grad, black_box(&x0)).unwrap();
                let mut values = Vec::new();
                while let Some(ask) = run.ask().unwrap() {
                    values.clear();
                    values.extend(ask.points().iter().map(sphere));
                    run.tell(&values).unwrap();
                }
                run.finish()
            })
        })
    });
    group.finish();
}

criterion_group!(benches, runs);
criterion_main!(benches);
