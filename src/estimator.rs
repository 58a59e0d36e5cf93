//! `PlateauFreeGradient`: the Monte Carlo estimate of the Gaussian-smoothed gradient.

use rand::SeedableRng;
use rand_xoshiro::Xoshiro256PlusPlus;
use rayon::prelude::*;

use crate::error::{check_sigma, check_spreads, check_theta, Error};
use crate::kernel::chi_mean;
use crate::objective::{Objective, Points};
use crate::sampling::Sampling;

/// One gradient estimate.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    /// The estimated gradient of the smoothed objective, one entry per coordinate of theta.
    pub gradient: Vec<f64>,
    /// How many times `f` was evaluated.
    pub evaluations: usize,
    /// The mean of the evaluated values of `f` (at the perturbed points, not at theta): a
    /// noisy estimate of the smoothed objective itself.
    pub mean_value: f64,
}

/// Anything that turns `(theta, sigma)` into a gradient [`Estimate`]: the plateau-free
/// estimator and the baselines in [`crate::baseline`]. The optimisation loop
/// ([`crate::Optimizer`]) accepts any of them.
pub trait GradientEstimator {
    /// Estimates the gradient at `theta` for the spread `sigma`.
    fn estimate(&mut self, theta: &[f64], sigma: f64) -> Result<Estimate, Error>;
}

type Evaluator<F> = fn(&F, Points<'_>, &[u64], &mut [f64]);

/// The plateau-free gradient of an objective `f`: the gradient of `f` smoothed by a
/// Gaussian of spread `sigma` in parameter space, estimated from `samples` evaluations of `f`.
///
/// Builder-style configuration; defaults: [`Sampling::Radial`], antithetic pairs, 2 samples,
/// seed 0, sequential evaluation.
///
/// ```
/// use plateau::{PlateauFreeGradient, Sampling};
///
/// // A tilted step: zero gradient almost everywhere, yet the smoothed gradient points uphill.
/// let f = |x: &[f64]| if x[0] + 2.0 * x[1] > 0.3 { 1.0 } else { 0.0 };
/// let mut grad = PlateauFreeGradient::new(f).samples(8).sampling(Sampling::Radial).seed(7);
/// let est = grad.estimate(&[0.1, -0.2], 0.5)?;
/// assert_eq!(est.gradient.len(), 2);
/// assert_eq!(est.evaluations, 8);
/// # Ok::<(), plateau::Error>(())
/// ```
///
/// # Randomness and determinism
/// Estimate `e` (counted from 0 since construction or [`PlateauFreeGradient::reset`]) draws
/// its `k`-th perturbation from a generator seeded by `(seed, e, k)`, and hands the
/// objective the seed `(seed, e, k)` for both members of pair `k`. The result is a function of
/// the seed, the inputs and the estimate's index alone: bit-for-bit the same sequentially, in
/// parallel, and with any number of threads.
///
/// # When `f` panics
/// The panic is not caught: it unwinds out of [`PlateauFreeGradient::estimate`] (through
/// rayon's worker when evaluating in parallel, which re-raises it on the caller's thread).
/// The estimator stays usable afterwards; the estimate that panicked is lost but still
/// counted, so later estimates draw fresh perturbations.
pub struct PlateauFreeGradient<F> {
    objective: F,
    samples: usize,
    sampling: Sampling,
    antithetic: bool,
    orthogonal: bool,
    seed: u64,
    estimates: u64,
    evaluator: Evaluator<F>,
    buffers: Buffers,
}

/// Scratch space reused across estimates so that the hot path does not allocate.
#[derive(Default)]
struct Buffers {
    spreads: Vec<f64>,
    offsets: Vec<f64>,
    weights: Vec<f64>,
    points: Vec<f64>,
    seeds: Vec<u64>,
    values: Vec<f64>,
    diffs: Vec<f64>,
    /// `(n, c_n)` of the last estimate: two log-gammas per estimate are a noticeable share
    /// of the cost when `n` is small.
    chi_mean: Option<(usize, f64)>,
}

impl<F: Objective> PlateauFreeGradient<F> {
    /// The estimator for `objective`: any `Fn(&[f64]) -> f64`, a [`crate::Seeded`] or
    /// [`crate::Batch`] closure, or your own [`Objective`].
    pub fn new(objective: F) -> Self {
        PlateauFreeGradient {
            objective,
            samples: 2,
            sampling: Sampling::Radial,
            antithetic: true,
            orthogonal: false,
            seed: 0,
            estimates: 0,
            evaluator: evaluate_sequential::<F>,
            buffers: Buffers::default(),
        }
    }

    /// `N`, the number of evaluations of `f` per estimate (the paper's "number of
    /// samples"). With antithetic pairs it must be even: `N / 2` pairs.
    pub fn samples(mut self, samples: usize) -> Self {
        self.samples = samples;
        self
    }

    /// The sampler of perturbations.
    pub fn sampling(mut self, sampling: Sampling) -> Self {
        self.sampling = sampling;
        self
    }

    /// Whether every perturbation `tau` is paired with `-tau` (default: yes). The pair's
    /// difference cancels the even part of `f`, including its constant offset.
    pub fn antithetic(mut self, antithetic: bool) -> Self {
        self.antithetic = antithetic;
        self
    }

    /// Whether the directions within one estimate are drawn mutually orthogonal (for
    /// [`Sampling::Radial`] and [`Sampling::Gaussian`]; in blocks of `n` when there are more
    /// draws than dimensions). Still unbiased; lower variance when several draws share an
    /// estimate (see `docs/estimators.md`). Default: off.
    pub fn orthogonal(mut self, orthogonal: bool) -> Self {
        self.orthogonal = orthogonal;
        self
    }

    /// The seed of every random choice the estimator makes, and of the seeds it hands to
    /// the objective.
    pub fn seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// Restarts the count of estimates: the next estimate repeats the first one's draws.
    pub fn reset(&mut self) {
        self.estimates = 0;
    }

    /// The objective.
    pub fn objective(&self) -> &F {
        &self.objective
    }

    /// The number of estimates made since construction or the last reset.
    pub fn estimates_made(&self) -> u64 {
        self.estimates
    }

    /// Estimates the gradient of `f` smoothed by `N(0, sigma^2 I)` at `theta`.
    ///
    /// # Errors
    /// Empty or non-finite `theta`; `sigma` not finite and positive; zero samples; an odd
    /// sample count with antithetic pairs; orthogonal directions with the per-coordinate
    /// sampler; a perturbed point that overflows; `f` returning NaN or an infinity (the
    /// error names the evaluation and the point); a gradient too large to represent.
    pub fn estimate(&mut self, theta: &[f64], sigma: f64) -> Result<Estimate, Error> {
        check_sigma(sigma)?;
        check_theta(theta)?;
        let mut spreads = std::mem::take(&mut self.buffers.spreads);
        spreads.clear();
        spreads.resize(theta.len(), sigma);
        let result = self.estimate_checked(theta, &spreads);
        self.buffers.spreads = spreads;
        result
    }

    /// Estimates the gradient of `f` smoothed by `N(0, diag(spreads)^2)` at `theta`: one
    /// spread per coordinate, for parameters of different scales.
    ///
    /// # Errors
    /// As [`PlateauFreeGradient::estimate`], and `spreads` of the wrong length.
    pub fn estimate_with_spreads(
        &mut self,
        theta: &[f64],
        spreads: &[f64],
    ) -> Result<Estimate, Error> {
        check_theta(theta)?;
        check_spreads(spreads, theta.len())?;
        self.estimate_checked(theta, spreads)
    }

    fn estimate_checked(&mut self, theta: &[f64], spreads: &[f64]) -> Result<Estimate, Error> {
        let n = theta.len();
        let evaluations = self.samples;
        if evaluations == 0 {
            return Err(Error::ZeroSamples);
        }
        if self.antithetic && evaluations % 2 == 1 {
            return Err(Error::OddSamples(evaluations));
        }
        if self.orthogonal && self.sampling == Sampling::PerCoordinate {
            return Err(Error::OrthogonalUnsupported(self.sampling));
        }
        let draws = if self.antithetic {
            evaluations / 2
        } else {
            evaluations
        };
        let index = self.estimates;
        self.estimates += 1;

        let b = &mut self.buffers;
        b.offsets.resize(draws * n, 0.0);
        b.weights.resize(draws * n, 0.0);
        b.points.resize(evaluations * n, 0.0);
        b.seeds.resize(evaluations, 0);
        b.values.resize(evaluations, 0.0);
        b.diffs.resize(draws, 0.0);

        let c_n = match b.chi_mean {
            Some((dim, c)) if dim == n => c,
            _ => {
                let c = chi_mean(n);
                b.chi_mean = Some((n, c));
                c
            }
        };
        draw_all(
            self.sampling,
            self.orthogonal,
            self.seed,
            index,
            c_n,
            n,
            &mut b.offsets,
            &mut b.weights,
        );

        // Perturbed points: pair k occupies rows 2k (theta + tau) and 2k + 1 (theta - tau).
        let per_draw = if self.antithetic { 2 } else { 1 };
        let mut all_finite = true;
        for (k, z) in b.offsets.chunks_exact(n).enumerate() {
            let rows = &mut b.points[k * per_draw * n..(k + 1) * per_draw * n];
            let (plus, minus) = rows.split_at_mut(n);
            for i in 0..n {
                let tau = spreads[i] * z[i];
                let p = theta[i] + tau;
                plus[i] = p;
                all_finite &= p.is_finite();
            }
            if self.antithetic {
                for i in 0..n {
                    let m = theta[i] - spreads[i] * z[i];
                    minus[i] = m;
                    all_finite &= m.is_finite();
                }
            }
            let pair_seed = stream_seed(self.seed, index, k as u64 ^ OBJECTIVE_STREAM);
            b.seeds[k * per_draw..(k + 1) * per_draw].fill(pair_seed);
        }
        if !all_finite {
            let at = b.points.iter().position(|x| !x.is_finite()).unwrap_or(0);
            return Err(Error::NonFinitePoint {
                sample: at / n,
                index: at % n,
                value: b.points[at],
            });
        }

        (self.evaluator)(
            &self.objective,
            Points::new(&b.points, n),
            &b.seeds,
            &mut b.values,
        );

        if let Some(sample) = b.values.iter().position(|v| !v.is_finite()) {
            return Err(Error::NonFiniteValue {
                sample,
                value: b.values[sample],
                point: b.points[sample * n..(sample + 1) * n].to_vec(),
            });
        }

        // Halving before subtracting keeps f near +-f64::MAX from overflowing the difference.
        for (d, v) in b.diffs.iter_mut().zip(b.values.chunks_exact(per_draw)) {
            *d = if self.antithetic {
                0.5 * v[0] - 0.5 * v[1]
            } else {
                v[0]
            };
        }
        // Accumulate in units of the largest |d| so that huge values of f overflow only if the
        // gradient itself does.
        let scale = b.diffs.iter().fold(0.0f64, |m, d| m.max(d.abs()));
        let mut gradient = vec![0.0; n];
        if scale > 0.0 {
            for (d, w) in b.diffs.iter().zip(b.weights.chunks_exact(n)) {
                let d = d / scale;
                gradient.iter_mut().zip(w).for_each(|(g, wi)| *g += d * wi);
            }
            let common = scale / draws as f64;
            // Branch-free so that it vectorises; the rare overflow is located afterwards.
            let mut all_finite = true;
            for (g, s) in gradient.iter_mut().zip(spreads) {
                *g = *g / s * common;
                all_finite &= g.is_finite();
            }
            if !all_finite {
                let index = gradient.iter().position(|g| !g.is_finite()).unwrap_or(0);
                return Err(Error::NonFiniteGradient {
                    index,
                    value: gradient[index],
                });
            }
        }
        let mean_value = b.values.iter().map(|v| v / evaluations as f64).sum();
        Ok(Estimate {
            gradient,
            evaluations,
            mean_value,
        })
    }
}

impl<F: Objective + Sync> PlateauFreeGradient<F> {
    /// Whether the `N` evaluations of one estimate run in parallel on rayon's thread pool
    /// (default: off, since a renderer usually parallelises within one evaluation already).
    /// Results are bit-for-bit those of the sequential run. A [`crate::Batch`] objective is
    /// then called once per point; leave this off for batch objectives.
    pub fn parallel(mut self, parallel: bool) -> Self {
        self.evaluator = if parallel {
            evaluate_parallel::<F>
        } else {
            evaluate_sequential::<F>
        };
        self
    }
}

impl<F: Objective> GradientEstimator for PlateauFreeGradient<F> {
    fn estimate(&mut self, theta: &[f64], sigma: f64) -> Result<Estimate, Error> {
        PlateauFreeGradient::estimate(self, theta, sigma)
    }
}

fn evaluate_sequential<F: Objective>(f: &F, points: Points<'_>, seeds: &[u64], out: &mut [f64]) {
    f.evaluate_batch(points, seeds, out);
}

fn evaluate_parallel<F: Objective + Sync>(
    f: &F,
    points: Points<'_>,
    seeds: &[u64],
    out: &mut [f64],
) {
    out.par_iter_mut()
        .enumerate()
        .for_each(|(i, o)| *o = f.evaluate(points.get(i), seeds[i]));
}

/// Separates the objective's seeds from the sampler's streams.
const OBJECTIVE_STREAM: u64 = 0x8000_0000_0000_0000;
/// The stream of an estimate's orthogonal block draw.
const ORTHOGONAL_STREAM: u64 = 0x4000_0000_0000_0000;
/// Below this many coordinates in all, drawing on several threads costs more than it saves.
const PARALLEL_DRAW_MIN: usize = 1 << 15;

/// Fills `offsets` and `weights` (rows of length `n`) for estimate `index`.
#[allow(clippy::too_many_arguments)]
fn draw_all(
    sampling: Sampling,
    orthogonal: bool,
    seed: u64,
    index: u64,
    c_n: f64,
    n: usize,
    offsets: &mut [f64],
    weights: &mut [f64],
) {
    if orthogonal {
        let mut rng =
            Xoshiro256PlusPlus::seed_from_u64(stream_seed(seed, index, ORTHOGONAL_STREAM));
        sampling.draw_orthogonal(&mut rng, c_n, n, offsets, weights);
        return;
    }
    let draw_one = |(k, (z, w)): (usize, (&mut [f64], &mut [f64]))| {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(stream_seed(seed, index, k as u64));
        sampling.draw(&mut rng, c_n, z, w);
    };
    let draws = offsets.len() / n;
    if draws > 1 && offsets.len() >= PARALLEL_DRAW_MIN {
        offsets
            .par_chunks_exact_mut(n)
            .zip(weights.par_chunks_exact_mut(n))
            .enumerate()
            .for_each(draw_one);
    } else {
        offsets
            .chunks_exact_mut(n)
            .zip(weights.chunks_exact_mut(n))
            .enumerate()
            .for_each(draw_one);
    }
}

/// A well-mixed 64-bit seed for `(seed, estimate, stream)` (SplitMix64's finaliser applied
/// to each part in turn), so that neighbouring indices give unrelated streams.
pub(crate) fn stream_seed(seed: u64, estimate: u64, stream: u64) -> u64 {
    let mut h = mix(seed ^ 0x243F_6A88_85A3_08D3);
    h = mix(h ^ estimate);
    mix(h ^ stream)
}

fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}
