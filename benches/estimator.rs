//! The estimator's own cost, with a trivial objective, beside the cost of drawing `n`
//! standard normals with `rand_distr`: `cargo bench --bench estimator`.
//!
//! One estimate is `N = 2` evaluations (one antithetic pair) at `n` = 1, 150, 49,152 and
//! 10^6, for each sampler. The objective reads one coordinate, so what is measured is the
//! drawing, the perturbed points, the checks and the gradient's accumulation. The results
//! and their ratios to the baseline are recorded in `docs/estimators.md` ("Cost"); the
//! target is radial at n = 49,152 within 1.5x of the normals.
//!
//! Timing is best-of-blocks: each sample times short blocks of iterations and keeps the
//! fastest block. The machine is shared; a block that the scheduler interrupted is slower,
//! never faster, so the fastest block is the cost of the code. Both sides of every ratio are
//! timed the same way.

use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use plateau_free::{PlateauFreeGradient, Sampling};
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;

const DIMENSIONS: [usize; 4] = [1, 150, 49_152, 1_000_000];

fn trivial(x: &[f64]) -> f64 {
    x[0]
}

/// `iters` calls of `f` in blocks of `block`, timed as `iters` times the fastest block's
/// time per call.
fn best_of_blocks(iters: u64, block: u64, mut f: impl FnMut()) -> Duration {
    let mut best = Duration::MAX;
    let mut done = 0;
    while done < iters {
        let k = block.min(iters - done);
        let start = Instant::now();
        for _ in 0..k {
            f();
        }
        best = best.min(start.elapsed() / k as u32);
        done += k;
    }
    best * iters as u32
}

/// `buffer` filled with standard normals, the fastest plain way: on a local copy of the
/// generator. Drawn through the `&mut` that a closure captures, the loop stores the
/// generator's state after every draw and takes about 1.3x as long, which would flatter
/// every ratio to it.
fn fill_normals(rng: &mut Xoshiro256PlusPlus, buffer: &mut [f64]) {
    let mut local = rng.clone();
    for x in buffer.iter_mut() {
        *x = StandardNormal.sample(&mut local);
    }
    *rng = local;
}

fn estimator(c: &mut Criterion) {
    for n in DIMENSIONS {
        let mut group = c.benchmark_group(format!("n={n}"));
        group.throughput(Throughput::Elements(n as u64));
        group.warm_up_time(Duration::from_millis(500));
        group.measurement_time(Duration::from_secs(2));
        group.sample_size(if n >= 49_152 { 10 } else { 50 });
        // Blocks of about 4,096 coordinates' work: long enough to time, short enough to
        // fit between the scheduler's interruptions.
        let block = (4096 / n as u64).max(1);

        // The baseline: n standard normals into a reused buffer, with the generator the
        // samplers use.
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(1);
        let mut buffer = vec![0.0f64; n];
        group.bench_function(BenchmarkId::new("normals", n), |b| {
            b.iter_custom(|iters| {
                best_of_blocks(iters, block, || {
                    fill_normals(&mut rng, &mut buffer);
                    black_box(&buffer);
                })
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
                b.iter_custom(|iters| {
                    best_of_blocks(iters, block, || {
                        black_box(est.estimate(black_box(&theta), 0.1).unwrap());
                    })
                })
            });
        }
        group.finish();
    }
}

criterion_group!(benches, estimator);
criterion_main!(benches);
