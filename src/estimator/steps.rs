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

/// The bits of `x * 0.0`: those of a signed zero (at most the sign bit) when `x` is
/// finite, those of a NaN when it is not. OR-ed over a pass, they test every value of the
/// pass for finiteness with two operations per value, in an integer reduction that the
/// compiler vectorises (a test per value was five operations; a branch would stop the
/// vectorisation).
#[inline(always)]
fn nonfinite_bits(x: f64) -> u64 {
    (x * 0.0).to_bits()
}

/// Whether an OR of [`nonfinite_bits`] saw only finite values.
#[inline(always)]
fn all_finite(bits: u64) -> bool {
    bits & !(1 << 63) == 0
}

/// Whether an estimate of `settings` has a single draw whose weight is a multiple of its
/// raw row (radial, Gaussian, and either of them orthogonal): then [`write_points`] replaces
/// the raw row by its quotients ([`quotient`]) and [`accumulate`] only multiplies.
pub(super) fn single_quotients(settings: &Settings, scales: &[Scales]) -> bool {
    settings.draws() == 1 && scales[0].weight.is_some()
}

/// Writes the perturbed points, `theta + spreads * z_k` (and `theta - spreads * z_k` in the
/// next row with antithetic pairs), in one pass per draw that expands the compact draw on
/// the fly.
///
/// With a single draw whose weight is `ws * raw` ([`single_quotients`]), the same pass
/// overwrites `first` with the quotients `q_i = (ws * raw_i) / spreads_i` that the gradient
/// needs: the division, the slowest step of the gradient, runs here beside the stores of
/// the points instead of in a pass of its own after `f`.
///
/// # Errors
/// The first non-finite point, if any.
pub(super) fn write_points<S: Spreads>(
    settings: &Settings,
    theta: &[f64],
    spreads: S,
    first: &mut [f64],
    b: &mut Buffers,
) -> Result<(), Error> {
    let n = theta.len();
    let spreads = spreads.fit(n);
    // `p - m` is not finite if either point is not: one test for the two.
    let mut bits = 0u64;
    // Indexed loops over slices of a known length `n`: the bounds checks drop out and the
    // loops vectorise (zipping with a repeated scalar spread did not).
    if single_quotients(settings, &b.scales) {
        let scale = b.scales[0];
        let (zs, ws) = (scale.offset, scale.weight.unwrap_or(1.0));
        let raw = &mut first[..n];
        let (plus, minus) = b.points.split_at_mut(n);
        if settings.antithetic {
            let minus = &mut minus[..n];
            for i in 0..n {
                let (r, s) = (raw[i], spreads.at(i));
                let tau = s * (zs * r);
                let (p, m) = (theta[i] + tau, theta[i] - tau);
                plus[i] = p;
                minus[i] = m;
                raw[i] = quotient(ws, r, s);
                bits |= nonfinite_bits(p - m);
            }
        } else {
            for i in 0..n {
                let (r, s) = (raw[i], spreads.at(i));
                let p = theta[i] + s * (zs * r);
                plus[i] = p;
                raw[i] = quotient(ws, r, s);
                bits |= nonfinite_bits(p);
            }
        }
    } else {
        let rows = b.points.chunks_exact_mut(settings.per_draw() * n);
        let draws = std::iter::once(&*first).chain(b.raw.chunks_exact(n));
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
                    bits |= nonfinite_bits(p - m);
                }
            } else {
                for i in 0..n {
                    let p = theta[i] + spreads.at(i) * (zs * raw[i]);
                    plus[i] = p;
                    bits |= nonfinite_bits(p);
                }
            }
        }
    }
    if all_finite(bits) {
        Ok(())
    } else {
        // `p - m` may overflow for finite points: the exact check decides.
        check::points(&b.points, n)
    }
}

/// The quotient `(ws * raw) / spread` of one coordinate of a single draw. A zero weight
/// `ws * raw` gives NaN instead of a signed zero: the gradient's sum starts at `+0.0`, so
/// that coordinate of the gradient is `+0.0` whatever the sign of the difference, which a
/// product `q * d` cannot give; [`accumulate`] finds the NaN and writes `+0.0`.
#[inline(always)]
fn quotient(ws: f64, raw: f64, spread: f64) -> f64 {
    let y = ws * raw;
    let q = y / spread;
    if y == 0.0 {
        f64::NAN
    } else {
        q
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
    if single_quotients(settings, &b.scales) {
        return from_quotients(gradient, b.diffs[0]);
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

/// The gradient of a single draw from the quotients `q_i` that [`write_points`] left in
/// `gradient`. The general form is `g_i = ((0.0 + (d / |d|) (ws raw_i)) / s_i) |d|` (the sum
/// starts at `+0.0`, `common` is `|d| / 1`). `d / |d|` is exactly `+-1` and rounding is
/// symmetric in sign, so `g_i = q_i d` to the last bit, computed with one multiplication;
/// except for a zero weight, where the general form gives `+0.0` and `q_i` is NaN.
///
/// # Errors
/// [`Error::NonFiniteGradient`] if the gradient overflows.
fn from_quotients(mut gradient: Vec<f64>, d: f64) -> Result<Vec<f64>, Error> {
    let n = gradient.len();
    let g = &mut gradient[..n];
    let mut bits = 0u64;
    for x in g.iter_mut() {
        *x *= d;
        bits |= nonfinite_bits(*x);
    }
    if !all_finite(bits) {
        for x in g.iter_mut().filter(|x| x.is_nan()) {
            *x = 0.0;
        }
        check::gradient(g)?;
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
            let mut bits = 0u64;
            for (i, gi) in g.iter_mut().enumerate() {
                let (sum, w) = term(*gi, i);
                let x = (sum + d * w) / spreads.at(i) * common;
                *gi = x;
                bits |= nonfinite_bits(x);
            }
            all_finite(bits)
        } else {
            for (i, gi) in g.iter_mut().enumerate() {
                let (sum, w) = term(*gi, i);
                *gi = sum + d * w;
            }
            true
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimator::Core;

    /// The single draw's quotients give the general accumulation's bits, signed zeros and
    /// underflows included: `((0.0 + (d / |d|) (ws raw_i)) / s) |d|`.
    #[test]
    fn quotients_match_the_general_accumulation_bit_for_bit() {
        let settings = Core::default().settings; // radial, antithetic, N = 2: one draw
        let raw = [0.0, -0.0, 1.0, -2.5, 1e-310, -3e-320, 7.25, 1e300];
        let n = raw.len();
        let theta = vec![0.25; n];
        let ws = 0.75;
        let mut checked = 0;
        for spread in [0.7, 3.0, 1e308, 1e-300] {
            for d in [1.0, -1.0, 3.5, -1e-320, 5e-324, -2e300] {
                let mut b = Buffers::default();
                b.resize(settings.draws(), settings.samples, n);
                b.scales[0] = Scales {
                    offset: 0.5,
                    weight: Some(ws),
                };
                // Values whose half difference is `d` exactly.
                b.values.copy_from_slice(&[2.0 * d, 0.0]);
                let mut first = raw.to_vec();
                let points = write_points(&settings, &theta, Uniform(spread), &mut first, &mut b);
                if points.is_err() {
                    continue; // 1e300 * 0.5 * 1e308 overflows: no gradient to compare
                }
                let got = accumulate(&settings, Uniform(spread), first, &mut b);
                let expected: Vec<f64> = raw
                    .iter()
                    .map(|r| (0.0 + (d / d.abs()) * (ws * r)) / spread * d.abs())
                    .collect();
                match got {
                    Ok(g) => {
                        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                        assert_eq!(bits(&g), bits(&expected), "spread {spread}, d {d}");
                        checked += 1;
                    }
                    Err(e) => {
                        assert!(
                            expected.iter().any(|x| !x.is_finite()),
                            "spread {spread}, d {d}: {e}"
                        );
                    }
                }
            }
        }
        assert!(checked >= 10, "{checked}");
    }
}
