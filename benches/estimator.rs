//! The estimator's own cost, with a trivial objective, beside the cost of drawing `n`
//! standard normals with `rand_distr`: `cargo bench --bench estimator`.
//!
//! One estimate is `N = 2` evaluations (one antithetic pair) at `n` = 1, 150, 49,152 and
//! 10^6, for each sampler. The objective reads one coordinate, so what is measured is the
//! drawing, the perturbed points, the checks and the gradient's accumulation. The results
//! and their ratios to the baseline are recorded in `docs/estimators.md` ("Cost").

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use plateau::{PlateauFreeGradient, Sampling};
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;

const DIMENSIONS: [usize; 4] = [1, 150, 49_152, 1_000_000];

fn trivial(x: &[f64]) -> f64 {
    x[0]
}

fn estimator(c: &mut Criterion) {
    for n in DIMENSIONS {
        let mut group = c.benchmark_group(format!("n={n}"));
        group.throughput(Throughput::Elements(n as u64));
        group.warm_up_time(Duration::from_millis(500));
        group.measurement_time(Duration::from_secs(2));
        group.sample_size(if n >= 49_152 { 10 } else { 50 });

        // The baseline: n standard normals into a reused buffer, with the generator the
        // samplers use.
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(1);
        let mut buffer = vec![0.0f64; n];
        group.bench_function(BenchmarkId::new("normals", n), |b| {
            b.iter(|| {
                for x in buffer.iter_mut() {
                    *x = StandardNormal.sample(&mut rng);
                }
                black_box(&buffer);
            })
        });

        let theta = vec![0.5; n];
        for (name, sampling) in [
            ("radial", Sampling::Radial),
            ("per_coordinate", Sampling::PerCoordinate),
            ("gaussian", Sampling::Gaussian),
        ] {
            let mut est = PlateauFreeGradient::new(trivial)
                .sampling(sampling)
                .samples(2)
                .seed(1);
            group.bench_function(BenchmarkId::new(name, n), |b| {
                b.iter(|| black_box(est.estimate(black_box(&theta), 0.1).unwrap()))
            });
        }
        group.finish();
    }
}

criterion_group!(benches, estimator);
criterion_main!(benches);
