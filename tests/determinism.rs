//! Determinism: the same seed gives the same bits; parallel evaluation gives the bits of the
//! sequential run on any number of threads; and the seeds handed to a `Seeded` objective
//! follow the common-random-numbers contract.

use std::collections::HashSet;
use std::sync::Mutex;

use plateau_free::{
    objective::Batch, objective::Points, objective::Seeded, Adam, Annealer, Optimizer,
    PlateauFreeGradient, Sampling,
};

mod common;
use common::{assert_repeats_sequential_and_parallel, bits, tilted_2d};

/// Every (sampler, antithetic, orthogonal) combination the estimator accepts: all but the
/// per-coordinate sampler with orthogonal directions.
fn configurations() -> Vec<(Sampling, bool, bool)> {
    let accepted = |&(sampling, antithetic, orthogonal): &(Sampling, bool, bool)| {
        PlateauFreeGradient::new(bumpy)
            .sampling(sampling)
            .antithetic(antithetic)
            .orthogonal(orthogonal)
            .validate()
            .is_ok()
    };
    Sampling::ALL
        .into_iter()
        .flat_map(|s| {
            [
                (s, true, false),
                (s, true, true),
                (s, false, false),
                (s, false, true),
            ]
        })
        .filter(accepted)
        .collect()
}

/// A non-separable, discontinuous objective whose value depends on every coordinate.
fn bumpy(x: &[f64]) -> f64 {
    let s: f64 = x
        .iter()
        .enumerate()
        .map(|(i, v)| v * (1.0 + i as f64).sqrt())
        .sum();
    (3.0 * s).sin() + if s > 0.2 { 1.0 } else { 0.0 }
}

/// `estimates` consecutive estimates, as bit patterns.
fn run(
    (sampling, antithetic, orthogonal): (Sampling, bool, bool),
    parallel: bool,
    seed: u64,
    n: usize,
    samples: usize,
    estimates: usize,
) -> Vec<Vec<u64>> {
    let theta: Vec<f64> = (0..n).map(|i| 0.01 * i as f64 - 0.3).collect();
    let spreads: Vec<f64> = (0..n).map(|i| 0.2 + 0.01 * (i % 7) as f64).collect();
    let mut est = PlateauFreeGradient::new(bumpy)
        .sampling(sampling)
        .antithetic(antithetic)
        .orthogonal(orthogonal)
        .samples(samples)
        .seed(seed)
        .parallel(parallel);
    (0..estimates)
        .map(|_| {
            let e = est.estimate_with_spreads(&theta, &spreads).unwrap();
            let mut b = bits(&e.gradient);
            b.push(e.mean_value.to_bits());
            b
        })
        .collect()
}

#[test]
fn same_seed_same_bits_different_seed_different_bits() {
    for config in configurations() {
        for n in [1, 7, 64] {
            let a = run(config, false, 42, n, 8, 5);
            assert_eq!(a, run(config, false, 42, n, 8, 5), "{config:?} n={n}");
            assert_ne!(a, run(config, false, 43, n, 8, 5), "{config:?} n={n}");
            // Consecutive estimates draw fresh perturbations.
            assert_ne!(a[0], a[1], "{config:?} n={n}");
        }
    }
}

#[test]
fn reset_repeats_the_first_estimate() {
    let mut est = PlateauFreeGradient::new(bumpy).samples(4).seed(5);
    let first = est.estimate(&[0.1, 0.2], 0.3).unwrap();
    est.estimate(&[0.1, 0.2], 0.3).unwrap();
    assert_eq!(est.estimates_made(), 2);
    est.reset();
    assert_eq!(est.estimate(&[0.1, 0.2], 0.3).unwrap(), first);
}

#[test]
fn parallel_equals_sequential_on_one_two_and_four_threads() {
    // n = 5000 with 16 samples puts more than 2^15 coordinates in one estimate, so the draws
    // themselves also go parallel; n = 3 keeps them sequential.
    for (n, samples) in [(3, 8), (5000, 16)] {
        for config in configurations() {
            let sequential = run(config, false, 7, n, samples, 3);
            for threads in [1, 2, 4] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let parallel = pool.install(|| run(config, true, 7, n, samples, 3));
                assert_eq!(parallel, sequential, "{config:?} n={n} threads={threads}");
                // Sequential evaluation inside a pool is the same as well.
                let inside = pool.install(|| run(config, false, 7, n, samples, 3));
                assert_eq!(inside, sequential, "{config:?} n={n} threads={threads}");
            }
        }
    }
}

#[test]
fn optimisation_runs_repeat_exactly() {
    assert_repeats_sequential_and_parallel(
        || PlateauFreeGradient::new(tilted_2d).samples(8).seed(7),
        |grad| {
            let mut opt =
                Optimizer::new(Adam::new(0.02).unwrap(), Annealer::paper(0.5, 50).unwrap());
            opt.minimize(grad, &[1.0, 1.0]).unwrap()
        },
    );
}

/// Records `(point, seed)` of every call, in call order.
type Log = Mutex<Vec<(Vec<f64>, u64)>>;

fn seeds_of(log: &Log) -> Vec<u64> {
    log.lock().unwrap().iter().map(|(_, s)| *s).collect()
}

/// The seeded objective `x[0]` that records every call in `log`.
fn logged(log: &Log) -> Seeded<impl Fn(&[f64], u64) -> f64 + Sync + '_> {
    Seeded(move |x: &[f64], seed: u64| {
        log.lock().unwrap().push((x.to_vec(), seed));
        x[0]
    })
}

#[test]
fn seeded_objective_gets_one_seed_per_pair() {
    for (sampling, _, orthogonal) in configurations() {
        let log: Log = Mutex::new(Vec::new());
        let mut est = PlateauFreeGradient::new(logged(&log))
            .sampling(sampling)
            .orthogonal(orthogonal)
            .samples(8)
            .seed(3);
        let theta = [0.5, -0.5, 0.25];
        est.estimate(&theta, 0.1).unwrap();
        let first = seeds_of(&log);
        let points: Vec<Vec<f64>> = log.lock().unwrap().iter().map(|(p, _)| p.clone()).collect();
        assert_eq!(first.len(), 8);
        for k in 0..4 {
            // Rows 2k and 2k+1 are theta + tau and theta - tau, and share their seed.
            assert_eq!(first[2 * k], first[2 * k + 1], "pair {k}");
            for i in 0..3 {
                let mid = 0.5 * (points[2 * k][i] + points[2 * k + 1][i]);
                assert!((mid - theta[i]).abs() < 1e-15);
            }
        }
        let per_pair: HashSet<u64> = first.iter().copied().collect();
        assert_eq!(per_pair.len(), 4, "pairs must not share seeds");

        log.lock().unwrap().clear();
        est.estimate(&theta, 0.1).unwrap();
        let second: HashSet<u64> = seeds_of(&log).into_iter().collect();
        assert_eq!(second.len(), 4);
        assert!(
            second.is_disjoint(&per_pair),
            "seeds repeat across estimates"
        );
    }
}

#[test]
fn without_pairs_every_evaluation_has_its_own_seed() {
    let log: Log = Mutex::new(Vec::new());
    let mut est = PlateauFreeGradient::new(logged(&log))
        .antithetic(false)
        .samples(7)
        .seed(3);
    est.estimate(&[0.0], 1.0).unwrap();
    let seeds: HashSet<u64> = seeds_of(&log).into_iter().collect();
    assert_eq!(seeds.len(), 7);
}

#[test]
fn seeds_are_the_same_in_parallel_and_in_a_batch() {
    let sequential: Log = Mutex::new(Vec::new());
    let parallel: Log = Mutex::new(Vec::new());
    let batch: Log = Mutex::new(Vec::new());
    let theta = [0.1, 0.2];
    PlateauFreeGradient::new(logged(&sequential))
        .samples(16)
        .seed(9)
        .estimate(&theta, 0.5)
        .unwrap();
    PlateauFreeGradient::new(logged(&parallel))
        .samples(16)
        .seed(9)
        .parallel(true)
        .estimate(&theta, 0.5)
        .unwrap();
    PlateauFreeGradient::new(Batch(|p: Points<'_>, s: &[u64], out: &mut [f64]| {
        let mut log = batch.lock().unwrap();
        for (i, o) in out.iter_mut().enumerate() {
            log.push((p.get(i).to_vec(), s[i]));
            *o = p.get(i)[0];
        }
    }))
    .samples(16)
    .seed(9)
    .estimate(&theta, 0.5)
    .unwrap();
    let sequential = sequential.into_inner().unwrap();
    let mut parallel = parallel.into_inner().unwrap();
    let batch = batch.into_inner().unwrap();
    assert_eq!(batch, sequential);
    // Parallel calls arrive in any order; as a set of (point, seed) they are the same.
    let key = |e: &(Vec<f64>, u64)| (bits(&e.0), e.1);
    parallel.sort_by_key(key);
    let mut sorted = sequential.clone();
    sorted.sort_by_key(key);
    assert_eq!(parallel, sorted);
}
