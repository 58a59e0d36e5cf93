//! The three samplers of perturbations and their weights.
//!
//! A draw writes two vectors into caller-owned buffers: the offset `z` in units of the spread
//! (the evaluated point is `theta_i + sigma_i z_i`) and the weight `w`, such that for every
//! integrable `f`
//!
//! ```text
//! E[ f(theta + sigma z) w_i ] / sigma_i = d/dtheta_i  E_{tau ~ N(0, diag sigma^2)} f(theta + tau)
//! ```
//!
//! (for [`Sampling::PerCoordinate`] only when `n = 1` or `f` is additively separable). With an
//! antithetic pair the estimator uses `(f(theta + sigma z) - f(theta - sigma z)) / 2` in place
//! of `f(theta + sigma z)`; every weight here is odd in `z`, so the pair is unbiased too.

use std::f64::consts::PI;
use std::fmt;

use rand::{Rng, RngExt};
use rand_distr::{ChiSquared, Distribution, StandardNormal};

use crate::kernel::{chi_mean, rayleigh_inverse_cdf, unit_open_closed};

/// How the perturbations of one estimate are drawn.
///
/// Its name, as a command line or a CSV file spells it, is one of `radial`,
/// `per-coordinate`, `gaussian`: [`Display`](fmt::Display) writes it, [`FromStr`](std::str::FromStr) reads it
/// (ignoring ASCII case), and with the `serde` feature it is the serialised form too.
///
/// ```
/// use plateau_free::Sampling;
/// assert_eq!(Sampling::PerCoordinate.to_string(), "per-coordinate");
/// assert_eq!("Radial".parse::<Sampling>()?, Sampling::Radial);
/// assert!("percoordinate".parse::<Sampling>().is_err());
/// # Ok::<(), plateau_free::Error>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(rename_all = "kebab-case")
)]
pub enum Sampling {
    /// Direction `u` uniform on the sphere, radius `r ~ chi_{n+1}`, `z = r u`, weight `c_n u`.
    /// Importance-samples the radial part of the Gaussian's derivative exactly: unbiased for
    /// the Gaussian-smoothed gradient in every dimension and for every `f`. For `n = 1` it is
    /// the paper's estimator. The default.
    #[default]
    Radial,
    /// The paper's reference sampler: every coordinate independently `z_i = s_i rho_i` with
    /// `rho_i ~ Rayleigh(1)` and a random sign, weight `s_i sqrt(2/pi)`. Exact for `n = 1` and
    /// for additively separable `f`; for other `f` each coordinate of its mean is the
    /// derivative of a differently smoothed function (the other coordinates are perturbed by
    /// the two-sided Rayleigh density, not a Gaussian), so it is biased: on a 3-D tilted step
    /// its mean is tens of percent away from the smoothed gradient. Kept to reproduce the paper.
    PerCoordinate,
    /// Plain Gaussian perturbations `z = eps ~ N(0, I)`, weight `eps`: the evolution-strategies
    /// estimator, the paper's "no importance sampling" ablation. Unbiased, higher variance.
    Gaussian,
}

impl Sampling {
    /// Every sampler, in the order of the documentation.
    pub const ALL: [Sampling; 3] = [
        Sampling::Radial,
        Sampling::PerCoordinate,
        Sampling::Gaussian,
    ];

    /// The sampler's one spelling: `radial`, `per-coordinate` or `gaussian`.
    ///
    /// ```
    /// assert_eq!(plateau_free::Sampling::Gaussian.name(), "gaussian");
    /// ```
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Sampling::Radial => "radial",
            Sampling::PerCoordinate => "per-coordinate",
            Sampling::Gaussian => "gaussian",
        }
    }

    /// Draws one perturbation in units of the spread into `offset` and its weight into
    /// `weight` (both of the same length `n >= 1`), in the manner of a `rand` distribution: the
    /// generator is passed in.
    ///
    /// ```
    /// use plateau_free::Sampling;
    /// use rand::SeedableRng;
    ///
    /// let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(1);
    /// let (mut z, mut w) = (vec![0.0; 3], vec![0.0; 3]);
    /// Sampling::Radial.sample_into(&mut rng, &mut z, &mut w);
    /// // The radial weight is c_n times the unit direction of the offset.
    /// let r = z.iter().map(|x| x * x).sum::<f64>().sqrt();
    /// let c3 = plateau_free::kernel::chi_mean(3);
    /// assert!((w[0] - c3 * z[0] / r).abs() < 1e-12);
    /// ```
    ///
    /// # Panics
    /// If the two buffers differ in length or are empty (this is the low-level building
    /// block; [`crate::PlateauFreeGradient`] validates its input and never panics).
    pub fn sample_into<R: Rng + ?Sized>(
        &self,
        rng: &mut R,
        offset: &mut [f64],
        weight: &mut [f64],
    ) {
        assert_eq!(
            offset.len(),
            weight.len(),
            "offset and weight lengths differ"
        );
        assert!(!offset.is_empty(), "cannot sample an empty perturbation");
        let c_n = chi_mean(offset.len());
        let scales = self.draw_raw(rng, fill_normal::<R>, c_n, offset, weight);
        scales.expand(offset, weight);
    }

    /// Draws one perturbation in its compact form: `raw` and the returned [`Scales`] give
    /// the offset `z_i = scales.offset * raw_i` and the weight `w_i = scales.weight * raw_i`,
    /// or `w_i = weights_i` where the sampler writes its weights (per-coordinate). The
    /// estimator never materialises `z` and `w`: it applies the two scalars in the passes
    /// that write the points and accumulate the gradient, which saves two passes over `n`.
    pub(crate) fn draw_raw<R: Rng + ?Sized>(
        &self,
        rng: &mut R,
        fill: Fill<R>,
        c_n: f64,
        raw: &mut [f64],
        weights: &mut [f64],
    ) -> Scales {
        match self {
            Sampling::Radial => {
                fill(rng, raw);
                let r = chi_radius(rng, raw.len());
                let norm = lane_norm(raw);
                direction_scales(norm, r, c_n)
            }
            Sampling::PerCoordinate => {
                per_coordinate(rng, raw, weights);
                Scales {
                    offset: 1.0,
                    weight: None,
                }
            }
            Sampling::Gaussian => {
                fill(rng, raw);
                GAUSSIAN_SCALES
            }
        }
    }

    /// As [`Sampling::draw_raw`] into a new vector of the length of `weights`.
    pub(crate) fn draw_fresh<R: Rng + ?Sized>(
        &self,
        rng: &mut R,
        fill: Fill<R>,
        c_n: f64,
        weights: &mut [f64],
    ) -> (Vec<f64>, Scales) {
        let n = weights.len();
        match self {
            Sampling::Radial | Sampling::Gaussian => {
                // Zeroed, then filled: a `collect` from the generator would skip the zeroing
                // but its loop is slower than the plain fill by more than the zeroing costs.
                let mut raw = vec![0.0; n];
                fill(rng, &mut raw);
                let scales = match self {
                    Sampling::Radial => {
                        let r = chi_radius(rng, n);
                        direction_scales(lane_norm(&raw), r, c_n)
                    }
                    _ => GAUSSIAN_SCALES,
                };
                (raw, scales)
            }
            Sampling::PerCoordinate => {
                let mut raw = vec![0.0; n];
                let scales = self.draw_raw(rng, fill, c_n, &mut raw, weights);
                (raw, scales)
            }
        }
    }

    /// Draws `count` perturbations whose directions are mutually orthogonal (in blocks of
    /// `n` when `count > n`), each with an independent radius: `chi_{n+1}` for
    /// [`Sampling::Radial`], `chi_n` for [`Sampling::Gaussian`]. Every single draw keeps its
    /// marginal law, so estimates stay unbiased; the directions no longer repeat each other.
    /// `z` receives `count` unit directions of length `n` in the compact form of
    /// [`Sampling::draw_raw`], `scales` one entry per direction.
    pub(crate) fn draw_orthogonal<R: Rng + ?Sized>(
        &self,
        rng: &mut R,
        c_n: f64,
        n: usize,
        z: &mut [f64],
        scales: &mut [Scales],
    ) {
        let count = z.len() / n;
        for block_start in (0..count).step_by(n) {
            let block_end = (block_start + n).min(count);
            for k in block_start..block_end {
                let (done, rest) = z.split_at_mut(k * n);
                let row = &mut rest[..n];
                // Gram-Schmidt against the earlier rows of this block; a fresh Gaussian row
                // is almost surely independent of them, and re-drawing handles the null event.
                loop {
                    fill_normal(rng, row);
                    for j in block_start..k {
                        let prev = &done[j * n..(j + 1) * n];
                        let dot: f64 = row.iter().zip(prev).map(|(a, b)| a * b).sum();
                        row.iter_mut().zip(prev).for_each(|(a, b)| *a -= dot * b);
                    }
                    let norm = norm2(row);
                    if norm > 1e-8 {
                        row.iter_mut().for_each(|a| *a /= norm);
                        break;
                    }
                }
            }
        }
        for (scale, _) in scales.iter_mut().zip(z.chunks_exact(n)) {
            *scale = match self {
                // z = w = r u, the Gaussian's chi_n length along a unit direction.
                Sampling::Gaussian => {
                    let r = ChiSquared::new(n as f64).map_or(1.0, |d| d.sample(rng).sqrt());
                    Scales {
                        offset: r,
                        weight: Some(r),
                    }
                }
                _ => direction_scales(1.0, chi_radius(rng, n), c_n),
            };
        }
    }
}

/// z = w = eps: multiplying by 1.0 is exact, so these scales change no bit.
const GAUSSIAN_SCALES: Scales = Scales {
    offset: 1.0,
    weight: Some(1.0),
};

/// How a compact draw (see [`Sampling::draw_raw`]) expands into its offset and weight.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub(crate) struct Scales {
    /// `z_i = offset * raw_i`.
    pub(crate) offset: f64,
    /// `w_i = weight * raw_i`; `None` when the sampler wrote every `w_i` itself.
    pub(crate) weight: Option<f64>,
}

impl Default for Scales {
    fn default() -> Self {
        Scales {
            offset: 1.0,
            weight: Some(1.0),
        }
    }
}

impl Scales {
    /// Writes the offset over `raw` and the weight into `weights`.
    fn expand(self, raw: &mut [f64], weights: &mut [f64]) {
        match self.weight {
            Some(ws) => {
                for (zi, wi) in raw.iter_mut().zip(weights.iter_mut()) {
                    let u = *zi;
                    *zi = self.offset * u;
                    *wi = ws * u;
                }
            }
            None => raw.iter_mut().for_each(|zi| *zi *= self.offset),
        }
    }
}

impl fmt::Display for Sampling {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Fills `z` with standard normals.
///
fn fill_normal<R: Rng + ?Sized>(rng: &mut R, z: &mut [f64]) {
    for zi in z.iter_mut() {
        *zi = StandardNormal.sample(rng);
    }
}

/// As [`fill_normal`], the same draws, on a copy of the generator that is written back at
/// the end. Through the `&mut` the compiler stored the generator's state to memory after
/// every draw, and the loop took about 1.3x the time of the same loop on a local generator.
pub(crate) fn fill_normal_local<R: Rng + Clone>(rng: &mut R, z: &mut [f64]) {
    let mut local = rng.clone();
    for zi in z.iter_mut() {
        *zi = StandardNormal.sample(&mut local);
    }
    *rng = local;
}

/// How a draw fills a row with standard normals: [`fill_normal`] for any generator,
/// [`fill_normal_local`] for one that can be copied (the estimator's).
pub(crate) type Fill<R> = fn(&mut R, &mut [f64]);

/// The Euclidean norm of `v`, summed in eight interleaved lanes. Summing in order would be
/// a chain of `n` dependent additions (about 50 us at n = 49,152, a third of the time the
/// normals take to draw); eight independent chains vectorise and overlap. The order is
/// fixed, so the result is deterministic.
fn lane_norm(v: &[f64]) -> f64 {
    const LANES: usize = 8;
    let mut lanes = [0.0f64; LANES];
    let chunks = v.chunks_exact(LANES);
    let rest = chunks.remainder();
    for chunk in chunks {
        for (acc, x) in lanes.iter_mut().zip(chunk) {
            *acc += x * x;
        }
    }
    let [a, b, c, d, e, f, g, h] = lanes;
    let mut total = ((a + b) + (c + d)) + ((e + f) + (g + h));
    for x in rest {
        total += x * x;
    }
    total.sqrt()
}

/// A `chi_{n+1}` radius: the law of `|tau| / sigma` under the importance density
/// `|tau| N(tau; 0, sigma^2 I)` in `n` dimensions.
fn chi_radius<R: Rng + ?Sized>(rng: &mut R, n: usize) -> f64 {
    if n == 1 {
        // chi_2 is Rayleigh(1): the paper's inverse CDF, exact and cheaper than a gamma draw.
        rayleigh_inverse_cdf(unit_open_closed(rng.random()), 1.0)
    } else {
        // `ChiSquared::new` only fails for a non-positive or NaN degree of freedom.
        ChiSquared::new((n + 1) as f64).map_or(0.0, |d| d.sample(rng).sqrt())
    }
}

/// The scales that turn a raw vector of norm `norm` into the offset `r u` and the weight
/// `c_n u` of its unit direction `u`.
fn direction_scales(norm: f64, r: f64, c_n: f64) -> Scales {
    // A zero vector has probability zero; if it happens the draw contributes nothing.
    let inv = if norm > 0.0 { 1.0 / norm } else { 0.0 };
    Scales {
        offset: r * inv,
        weight: Some(c_n * inv),
    }
}

/// The paper's per-coordinate draw: `z_i = s_i rho_i`, `w_i = s_i sqrt(2/pi)`.
fn per_coordinate<R: Rng + ?Sized>(rng: &mut R, z: &mut [f64], w: &mut [f64]) {
    let weight = (2.0 / PI).sqrt();
    for (zi, wi) in z.iter_mut().zip(w.iter_mut()) {
        let bits: u64 = rng.random();
        // The top bit is the sign; the rest (shifted in) is the uniform. Using one
        // 64-bit draw for both halves the generator's work per coordinate.
        *wi = if bits >> 63 == 1 { -weight } else { weight };
        *zi = unit_open_closed(bits << 1);
    }
    // The radius in passes of its own: the logarithm is a call that the loop above would
    // wait on, while this square root and sign vectorise. Same operations as
    // `rayleigh_inverse_cdf(xi, 1.0)` times the sign, bit for bit.
    for zi in z.iter_mut() {
        *zi = zi.ln();
    }
    for (zi, wi) in z.iter_mut().zip(w.iter()) {
        let rho = (-2.0 * *zi).sqrt();
        *zi = if *wi < 0.0 { -rho } else { rho };
    }
}

fn norm2(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_xoshiro::Xoshiro256PlusPlus;

    #[test]
    fn orthogonal_rows_are_orthonormal_directions() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(3);
        let n = 5;
        let count = 7; // one full block of 5 and a block of 2
        let (mut z, mut w) = (vec![0.0; n * count], vec![0.0; n * count]);
        let mut scales = vec![Scales::default(); count];
        Sampling::Radial.draw_orthogonal(&mut rng, chi_mean(n), n, &mut z, &mut scales);
        for ((zk, wk), scale) in z
            .chunks_exact_mut(n)
            .zip(w.chunks_exact_mut(n))
            .zip(&scales)
        {
            scale.expand(zk, wk);
        }
        let unit = |k: usize| {
            let row = &w[k * n..(k + 1) * n];
            let norm = norm2(row);
            row.iter().map(|x| x / norm).collect::<Vec<_>>()
        };
        for a in 0..n {
            for b in 0..n {
                let dot: f64 = unit(a).iter().zip(unit(b)).map(|(x, y)| x * y).sum();
                let expected = if a == b { 1.0 } else { 0.0 };
                assert!((dot - expected).abs() < 1e-12, "{a} {b} {dot}");
            }
        }
        for k in 0..count {
            assert!((norm2(&w[k * n..(k + 1) * n]) - chi_mean(n)).abs() < 1e-12);
        }
    }

    #[test]
    fn per_coordinate_signs_match_weights() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(9);
        let (mut z, mut w) = (vec![0.0; 1000], vec![0.0; 1000]);
        Sampling::PerCoordinate.sample_into(&mut rng, &mut z, &mut w);
        for (zi, wi) in z.iter().zip(&w) {
            assert_eq!(zi.is_sign_negative(), wi.is_sign_negative());
            assert!((wi.abs() - (2.0 / PI).sqrt()).abs() < 1e-15);
        }
        let negatives = w.iter().filter(|x| **x < 0.0).count();
        assert!((400..600).contains(&negatives), "{negatives}");
    }
}
