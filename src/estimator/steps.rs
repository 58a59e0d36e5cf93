//! The steps of one estimate after its checks: draw the perturbations ([`Stream`]), write
//! the perturbed points ([`write_points`]), and turn the values into the gradient
//! ([`accumulate`]).

use rayon::prelude::*;

use super::{Buffers, Settings};
use crate::check;
use crate::error::Error;
use crate::sampling::{fill_normal_local, Sampling, Scales};
use crate::seeding::{stream_rng, stream_seed, OBJECTIVE_STREAM, ORTHOGONAL_STREAM};

/// The spreads of an estimate, one per coordinate: a slice, or one scalar for all (which
/// saves writing and reading a vector of `n` copies).
pub(super) trait Spreads: Copy {
    /// The same spreads, for a vector of length `n` (a slice is cut to `n`, so that the
    /// compiler sees the length of every loop over it).
    fn fit(self, n: usize) -> Self;
    /// The spread of coordinate `i`.
    fn at(self, i: usize) -> f64;
}

impl Spreads for &[f64] {
    fn fit(self, n: usize) -> Self {
        &self[..n]
    }
    fn at(self, i: usize) -> f64 {
        self[i]
    }
}

/// One spread for every coordinate.
#[derive(Debug, Clone, Copy)]
pub(super) struct Uniform(pub(super) f64);

impl Spreads for Uniform {
    fn fit(self, _n: usize) -> Self {
        self
    }
    fn at(self, _i: usize) -> f64 {
        self.0
    }
}

/// Below this many coordinates in all, drawing on several threads costs more than it saves.
pub(super) const PARALLEL_DRAW_MIN: usize = 1 << 15;

/// One draw's compact row, stored weights and scales, as the draw loop sees them.
pub(super) type RowMut<'a> = ((&'a mut [f64], &'a mut [f64]), &'a mut Scales);

/// Draws 1, 2, ... of an estimate: their compact rows, stored weights and scales.
pub(super) struct Rows<'a> {
    raw: &'a mut [f64],
    weights: &'a mut [f64],
    scales: &'a mut [Scales],
}

/// The random streams of one estimate: `index` of the estimator seeded with `seed`.
#[derive(Debug, Clone, Copy)]
pub(super) struct Stream {
    pub(super) seed: u64,
    pub(super) index: u64,
}

impl Stream {
    /// Makes the estimate's draws: returns draw 0, writes the others into `b.raw`, every
    /// draw's scales into `b.scales` and stored weights into `b.weights`.
    pub(super) fn draw(
        &self,
        settings: &Settings,
        c_n: f64,
        n: usize,
        b: &mut Buffers,
    ) -> Vec<f64> {
        let sampling = settings.sampling;
        if settings.orthogonal {
            b.block.resize(b.scales.len() * n, 0.0);
            let mut rng = stream_rng(self.seed, self.index, ORTHOGONAL_STREAM);
            sampling.draw_orthogonal(&mut rng, c_n, n, &mut b.block, &mut b.scales);
            let (first, rest) = b.block.split_at(n);
            b.raw.copy_from_slice(rest);
            return first.to_vec();
        }
        let (w0, w_rest) = b.weights.split_at_mut(n);
        let (s0, s_rest) = b.scales.split_at_mut(1);
        let mut draw_first = || {
            let mut rng = stream_rng(self.seed, self.index, 0);
            let (first, scales) = sampling.draw_fresh(&mut rng, fill_normal_local, c_n, w0);
            s0[0] = scales;
            first
        };
        let rest = Rows {
            raw: &mut b.raw,
            weights: w_rest,
            scales: s_rest,
        };
        if !rest.scales.is_empty() && (rest.raw.len() + n) >= PARALLEL_DRAW_MIN {
            rayon::join(draw_first, || self.draw_rest(sampling, c_n, n, rest, true)).0
        } else {
            let first = draw_first();
            self.draw_rest(sampling, c_n, n, rest, false);
            first
        }
    }

    /// Draws 1, 2, ..., draw `k` from its own stream `k`, so that the draws may run on any
    /// thread in any order.
    fn draw_rest(&self, sampling: Sampling, c_n: f64, n: usize, rows: Rows<'_>, parallel: bool) {
        let draw_one = |(k, ((z, w), scale)): (usize, RowMut<'_>)| {
            let mut rng = stream_rng(self.seed, self.index, k as u64 + 1);
            *scale = sampling.draw_raw(&mut rng, fill_normal_local, c_n, z, w);
        };
        if parallel {
            rows.raw
                .par_chunks_exact_mut(n)
                .zip(rows.weights.par_chunks_exact_mut(n))
                .zip(rows.scales.par_iter_mut())
                .enumerate()
                .for_each(draw_one);
        } else {
            rows.raw
                .chunks_exact_mut(n)
                .zip(rows.weights.chunks_exact_mut(n))
                .zip(rows.scales.iter_mut())
                .enumerate()
                .for_each(draw_one);
        }
    }

    /// The objective's seeds: one per pair (or per draw), shared by both members of a pair.
    #[inline]
    pub(super) fn objective_seeds(&self, settings: &Settings, seeds: &mut [u64]) {
        for (k, pair) in seeds.chunks_exact_mut(settings.per_draw()).enumerate() {
            pair.fill(stream_seed(
                self.seed,
                self.index,
                k as u64 ^ OBJECTIVE_STREAM,
            ));
        }
    }
}

/// Writes the perturbed points, `theta + spreads * z_k` (and `theta - spreads * z_k` in the
/// next row with antithetic pairs), in one pass per draw that expands the compact draw on
/// the fly.
///
/// # Errors
/// The first non-finite point, if any.
pub(super) fn write_points<S: Spreads>(
    settings: &Settings,
    theta: &[f64],
    spreads: S,
    first: &[f64],
    b: &mut Buffers,
) -> Result<(), Error> {
    let n = theta.len();
    let spreads = spreads.fit(n);
    let mut all_finite = true;
    let rows = b.points.chunks_exact_mut(settings.per_draw() * n);
    // Indexed loops over slices of a known length `n`: the bounds checks drop out and the
    // loops vectorise (zipping with a repeated scalar spread did not).
    let draws = std::iter::once(first).chain(b.raw.chunks_exact(n));
    for ((raw, scale), rows) in draws.zip(&b.scales).zip(rows) {
        let raw = &raw[..n];
        let zs = scale.offset;
        let (plus, minus) = rows.split_at_mut(n);
        if settings.antithetic {
            let minus = &mut minus[..n];
            for i in 0..n {
                let tau = spreads.at(i) * (zs * raw[i]);
                let (p, m) = (theta[i] + tau, theta[i] - tau);
                plus[i] = p;
                minus[i] = m;
                // `&` rather than `&&`: branch-free, so that the pass vectorises. `p - m`
                // is not finite if either point is not: one test for the two.
                all_finite &= (p - m).is_finite();
            }
        } else {
            for i in 0..n {
                let p = theta[i] + spreads.at(i) * (zs * raw[i]);
                plus[i] = p;
                all_finite &= p.is_finite();
            }
        }
    }
    if all_finite {
        Ok(())
    } else {
        check::points(&b.points, n)
    }
}

/// The gradient `g_i = 1/P sum_k d_k w_ki / spreads_i` from the evaluated values, with
/// `d_k` the pair's half difference (or the value without pairs), written over `first`
/// (which holds draw 0).
///
/// # Errors
/// [`Error::NonFiniteGradient`] if the gradient overflows.
pub(super) fn accumulate<S: Spreads>(
    settings: &Settings,
    spreads: S,
    mut gradient: Vec<f64>,
    b: &mut Buffers,
) -> Result<Vec<f64>, Error> {
    let n = gradient.len();
    let draws = b.scales.len();
    // Halving before subtracting keeps f near +-f64::MAX from overflowing the difference.
    for (d, v) in b
        .diffs
        .iter_mut()
        .zip(b.values.chunks_exact(settings.per_draw()))
    {
        *d = if settings.antithetic {
            0.5 * v[0] - 0.5 * v[1]
        } else {
            v[0]
        };
    }
    // Accumulate in units of the largest |d| so that huge values of f overflow only if the
    // gradient itself does.
    let scale = b.diffs.iter().fold(0.0f64, |m, d| m.max(d.abs()));
    if scale == 0.0 {
        gradient.fill(0.0);
        return Ok(gradient);
    }
    let common = scale / draws as f64;
    let mut finite = true;
    for (k, (draw, d)) in b.scales.iter().zip(&b.diffs).enumerate() {
        let step = Step {
            d: d / scale,
            common,
            last: k + 1 == draws,
        };
        let stored = &b.weights[k * n..(k + 1) * n];
        // Weight i of draw k, given the gradient's current g_i: the sum so far and the
        // weight. Draw 0's raw row is g itself, and the sum starts at +0.0 (so that a
        // product of -0.0 gives +0.0, as the accumulation always has).
        finite = match (k, draw.weight) {
            (0, Some(ws)) => step.apply(&mut gradient, spreads, |g, _| (0.0, ws * g)),
            (0, None) => step.apply(&mut gradient, spreads, |_, i| (0.0, stored[i])),
            (_, Some(ws)) => {
                let raw = &b.raw[(k - 1) * n..k * n];
                step.apply(&mut gradient, spreads, |g, i| (g, ws * raw[i]))
            }
            (_, None) => step.apply(&mut gradient, spreads, |g, i| (g, stored[i])),
        };
    }
    if !finite {
        check::gradient(&gradient)?;
    }
    Ok(gradient)
}

/// One draw's contribution to the gradient, `g += d w`, finishing with
/// `g / spreads * common` at the last draw, all in one pass.
#[derive(Debug, Clone, Copy)]
pub(super) struct Step {
    d: f64,
    common: f64,
    last: bool,
}

impl Step {
    /// Applies the step; `term(g_i, i)` gives the sum so far and the weight of coordinate
    /// `i`. Returns whether every coordinate it wrote is finite (checked in the same pass,
    /// branch-free, so that no second pass is needed).
    fn apply<S: Spreads>(
        self,
        g: &mut [f64],
        spreads: S,
        term: impl Fn(f64, usize) -> (f64, f64),
    ) -> bool {
        let Step { d, common, last } = self;
        let n = g.len();
        let spreads = spreads.fit(n);
        if last {
            let mut finite = true;
            for (i, gi) in g.iter_mut().enumerate() {
                let (sum, w) = term(*gi, i);
                let x = (sum + d * w) / spreads.at(i) * common;
                *gi = x;
                finite &= x.is_finite();
            }
            finite
        } else {
            for (i, gi) in g.iter_mut().enumerate() {
                let (sum, w) = term(*gi, i);
                *gi = sum + d * w;
            }
            true
        }
    }
}
