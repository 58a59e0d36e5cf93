//! The adaptive search's distribution: a Gaussian whose mean, spread and covariance follow
//! the function, its draws and its update (one generation of the search, `mod.rs`).
//!
//! Each generation draws `lambda` points `x_k = m + sigma * y_k`, `y_k ~ N(0, C)`, ranks them by
//! `f`, and moves the mean along the rank-weighted sum of the best offsets. That sum is the
//! natural gradient of the Gaussian-smoothed, rank-transformed objective
//! `E_{x ~ N(m, sigma^2 C)} w(f(x))` with respect to `m` (the information-geometric view of
//! evolution strategies: Ollivier, Arnold, Auger and Hansen, "Information-Geometric Optimization
//! Algorithms", JMLR 18, 2017): the plateau-free gradient of this crate, with ranks in place of
//! values so that the scale of `f` does not matter, and with a smoothing kernel that adapts.
//!
//! The spread and the metric follow the published CMA-ES update rules (Hansen, "The CMA
//! Evolution Strategy: A Tutorial", arXiv:1604.00772, 2016, with the active update with
//! negative weights of Jastrebski and Arnold, CEC 2006): cumulative step-size adaptation
//! shrinks `sigma` while successive steps cancel (progress made, optimum near) and grows it
//! while they align; the covariance learns the function's metric from the selected steps,
//! which is what ill-conditioned and rotated problems need. There is no floor on `sigma`, but one on the
//! spread along a discrete coordinate ([`crate::Minimizer::steps`], `floor.rs`).
//! With the diagonal metric (large n) each run opens with a warm-up of two-point step-size
//! adaptation that shrinks a start spread far too wide in `O(ln n)` generations per e-fold
//! ([`Tpa`]), then CSA as above; a run whose warm-up drew nothing better than the best value
//! seen before it goes on from its start point with the spread found (`mod.rs`).
//!
//! Two rules are this crate's own, for plateaus:
//! - **flat generation**: when the best quarter of a generation ties with its best value, the
//!   points cannot be told apart; `sigma` grows by `exp(0.2 + c_sigma / d_sigma)` so that the
//!   smoothing widens until it feels a change of `f` (the paper's large `sigma_0`, found
//!   automatically instead of guessed). Not at a flat bottom: ties at the search's best
//!   level with worse points around are the floor of a flat region, where growth would not
//!   stop; three such generations end the run (`gaussian/ends.rs`).
//! - **restarts from `x0`** with a doubled population (IPOP: Auger and Hansen, CEC 2005)
//!   when a run has converged or stalls; a larger population is a smoother, more global
//!   estimate of the smoothed function's gradient, which multimodal functions need, and a
//!   fresh start searches the whole region again instead of the basin the run left.
//! - **resolution**: a flat generation at a spread below `1e-6` of the mean (`max(1, |m|)`)
//!   is the objective's resolution (single-precision geometry in a renderer), not a plateau:
//!   the run ends and restarts instead of growing `sigma` into a random walk on rounding noise.
//!
//! Implemented here from the published formulas; no code is taken from any other project.

use std::borrow::Cow;

use nalgebra::{DMatrix, DVector, SymmetricEigen};
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;

mod decoding;
mod ends;
mod floor;
mod lowrank;
mod tpa;

use decoding::Decoding;
pub(crate) use ends::RunEnd;
pub(crate) use floor::floors;
use lowrank::LowRank;
use tpa::Tpa;

/// The strategy parameters for a dimension and population size (Hansen 2016, Table 1).
#[derive(Debug, Clone)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub(crate) struct Params {
    pub lambda: usize,
    pub mu: usize,
    /// `lambda` weights: positive for the best `mu`, negative (active update) for the rest.
    pub weights: Vec<f64>,
    pub mueff: f64,
    pub cc: f64,
    pub cs: f64,
    pub c1: f64,
    pub cmu: f64,
    pub ds: f64,
    /// `E ||N(0, I)||`.
    pub chi_n: f64,
}

impl Params {
    pub fn new(n: usize, lambda: usize) -> Params {
        let nf = n as f64;
        let lambda = lambda.max(2);
        let mueff = Params::mueff(lambda);
        let cc = (4.0 + mueff / nf) / (nf + 4.0 + 2.0 * mueff / nf);
        let cs = (mueff + 2.0) / (nf + mueff + 5.0);
        let c1 = 2.0 / ((nf + 1.3).powi(2) + mueff);
        let cmu = (2.0 * (mueff - 2.0 + 1.0 / mueff) / ((nf + 2.0).powi(2) + mueff))
            .min(1.0 - c1)
            .max(0.0);
        let ds = 1.0 + 2.0 * (((mueff - 1.0) / (nf + 1.0)).sqrt() - 1.0).max(0.0) + cs;
        let chi_n = nf.sqrt() * (1.0 - 1.0 / (4.0 * nf) + 1.0 / (21.0 * nf * nf));
        Params {
            lambda,
            mu: lambda / 2,
            weights: Vec::new(),
            mueff,
            cc,
            cs,
            c1,
            cmu,
            ds,
            chi_n,
        }
        .with_rates(n, c1, cmu)
    }

    /// The log-rank weights before scaling: positive for the best half.
    fn raw_weights(lambda: usize) -> Vec<f64> {
        (0..lambda)
            .map(|i| ((lambda as f64 + 1.0) / 2.0).ln() - ((i + 1) as f64).ln())
            .collect()
    }

    /// The variance-effective selection mass of the positive weights.
    fn mueff(lambda: usize) -> f64 {
        let raw = Params::raw_weights(lambda);
        let pos = &raw[..lambda / 2];
        let sum: f64 = pos.iter().sum();
        sum * sum / pos.iter().map(|w| w * w).sum::<f64>()
    }

    /// The same with the covariance's rank-one and rank-mu rates `c1` and `cmu`, and the
    /// active update's negative weights sized for them (Hansen 2016, Table 1).
    pub fn with_rates(mut self, n: usize, c1: f64, cmu: f64) -> Params {
        let raw = Params::raw_weights(self.lambda);
        let mu = self.mu;
        let pos_sum: f64 = raw[..mu].iter().sum();
        let neg: Vec<f64> = raw[mu..].iter().copied().filter(|w| *w < 0.0).collect();
        let neg_sum: f64 = neg.iter().sum();
        let neg_sq: f64 = neg.iter().map(|w| w * w).sum();
        let mueff_neg = if neg_sq > 0.0 {
            neg_sum * neg_sum / neg_sq
        } else {
            0.0
        };
        let neg_scale = if neg_sum < 0.0 && cmu > 0.0 {
            let alpha_mu = 1.0 + c1 / cmu;
            let alpha_mueff = 1.0 + 2.0 * mueff_neg / (self.mueff + 2.0);
            let alpha_posdef = (1.0 - c1 - cmu) / (n as f64 * cmu);
            alpha_mu.min(alpha_mueff).min(alpha_posdef) / -neg_sum
        } else {
            0.0
        };
        self.weights = raw[..mu].iter().map(|w| w / pos_sum).collect();
        self.weights
            .extend(raw[mu..].iter().map(|w| w.min(0.0) * neg_scale));
        (self.c1, self.cmu) = (c1, cmu);
        self
    }

    /// The default population: `4 + floor(3 ln n)`.
    pub fn default_lambda(n: usize) -> usize {
        4 + (3.0 * (n as f64).ln()).floor() as usize
    }
}

/// One run: a Gaussian `N(m, sigma^2 C)` and its evolution paths.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub(crate) struct SearchGaussian {
    pub n: usize,
    pub p: Params,
    pub mean: DVector<f64>,
    pub sigma: f64,
    sigma_start: f64,
    /// The full covariance and its eigenvectors (columns), or `None` for a diagonal one
    /// (whose variances are `d^2`). With diagonal decoding it is `C` of `D C D`.
    full: Option<(DMatrix<f64>, DMatrix<f64>)>,
    /// The learning rates of the covariance (scaled up for a diagonal one).
    c1: f64,
    cmu: f64,
    /// Square roots of the eigenvalues of `cov`.
    d: DVector<f64>,
    ps: DVector<f64>,
    pc: DVector<f64>,
    pub generation: usize,
    eigen_generation: usize,
    /// The best value of every generation of this run (infinite for a generation whose
    /// every point failed).
    #[cfg_attr(feature = "serde", serde(with = "crate::saved::floats"))]
    best_history: Vec<f64>,
    /// The median value of every generation of this run.
    #[cfg_attr(feature = "serde", serde(with = "crate::saved::floats"))]
    median_history: Vec<f64>,
    /// Mirror every other draw (`y_{2k+1} = -y_{2k}`): the antithetic pairs of the paper.
    pub mirrored: bool,
    /// Grow sigma on flat generations.
    pub flat_growth: bool,
    /// The two-point step-size adaptation's warm-up (diagonal metric only): see [`Tpa`].
    #[cfg_attr(feature = "serde", serde(default))]
    tpa: Tpa,
    /// The range of the finite values of the run's first generation that had two different
    /// ones: the run's scale of `f` for TolFun (`None` before: scale 1).
    #[cfg_attr(feature = "serde", serde(default, with = "crate::saved::float_option"))]
    first_range: Option<f64>,
    /// Flat generations in a row at the run's best level with worse points around: the
    /// bottom of a flat region, seen from inside.
    #[cfg_attr(feature = "serde", serde(default))]
    flat_bottom: usize,
    /// Whether a generation of this run was flat (its values tie).
    #[cfg_attr(feature = "serde", serde(default))]
    pub ties: bool,
    /// The directions of the low-rank-plus-diagonal metric (`lowrank.rs`), on top of the
    /// diagonal one; `None` for a full or a purely diagonal metric.
    #[cfg_attr(feature = "serde", serde(default))]
    low_rank: Option<LowRank>,
    /// The least standard deviation of each coordinate (`floor.rs`): positive on the discrete
    /// coordinates of [`crate::Minimizer::steps`], empty when there are none.
    #[cfg_attr(feature = "serde", serde(default))]
    pub floors: Vec<f64>,
    /// The full metric's diagonal decoding (`decoding.rs`): the covariance is `D C D`;
    /// `None` for a plain full metric (and for the others).
    #[cfg_attr(feature = "serde", serde(default))]
    decoding: Option<Decoding>,
}

/// What a generation's update reads with diagonal decoding ([`SearchGaussian::decode`]).
struct Decoded {
    white_path: DVector<f64>,
    white_selected: Vec<(f64, DVector<f64>)>,
    pc: DVector<f64>,
    ys: Vec<DVector<f64>>,
}

/// One generation's draws: `ys` are the offsets `y_k` (so that `x_k = m + sigma y_k`).
pub(crate) struct Generation {
    pub ys: Vec<DVector<f64>>,
}

impl SearchGaussian {
    /// A read-back distribution's sizes against the dimension `n`.
    #[cfg(feature = "serde")]
    pub fn check(&self, n: usize) -> Result<(), crate::error::Error> {
        use crate::check::len;
        len("search dimension", self.n, n)?;
        for (what, v) in [
            ("search mean", &self.mean),
            ("search scales", &self.d),
            ("search path ps", &self.ps),
            ("search path pc", &self.pc),
        ] {
            len(what, v.len(), n)?;
        }
        if let Some(shift) = &self.tpa.shift {
            len("search mean shift", shift.len(), n)?;
        }
        if let Some(low_rank) = &self.low_rank {
            low_rank.check(n)?;
        }
        if let Some(decoding) = &self.decoding {
            decoding.check(n)?;
        }
        if !self.floors.is_empty() {
            len("search floors", self.floors.len(), n)?;
        }
        if let Some((cov, b)) = &self.full {
            len("search covariance", cov.nrows() * cov.ncols(), n * n)?;
            len("search eigenvectors", b.nrows() * b.ncols(), n * n)?;
            len("search covariance rows", cov.nrows(), n)?;
            len("search eigenvector rows", b.nrows(), n)?;
        }
        let p = &self.p;
        len("search weights", p.weights.len(), p.lambda)?;
        if p.lambda < 2 || p.mu == 0 || p.mu > p.lambda {
            return Err(crate::error::Error::InvalidParameter {
                name: "population",
                value: p.lambda.into(),
                reason: "must be at least 2, with 1 <= mu <= population",
            });
        }
        Ok(())
    }

    /// A run at `mean` with spread `sigma` and a covariance `diag(scales^2)` to start with,
    /// full (learns any metric) or diagonal (learns per-coordinate scales only, `O(n)` per
    /// sample: separable CMA-ES, Ros and Hansen, PPSN 2008, with its rates `(n + 2) / 3`
    /// times the full metric's).
    pub fn new(
        mean: &[f64],
        sigma: f64,
        scales: &[f64],
        lambda: usize,
        full: bool,
    ) -> SearchGaussian {
        let n = mean.len();
        let p = Params::new(n, lambda);
        let d = DVector::from_column_slice(scales);
        let (c1, cmu, full) = if full {
            let cov = DMatrix::from_diagonal(&d.map(|s| s * s));
            (p.c1, p.cmu, Some((cov, DMatrix::identity(n, n))))
        } else {
            let (c1, cmu) = diagonal_rates(&p, (n as f64 + 2.0) / 3.0);
            (c1, cmu, None)
        };
        SearchGaussian {
            n,
            p,
            mean: DVector::from_column_slice(mean),
            sigma,
            sigma_start: sigma,
            full,
            c1,
            cmu,
            d,
            ps: DVector::zeros(n),
            pc: DVector::zeros(n),
            generation: 0,
            eigen_generation: 0,
            best_history: Vec::new(),
            median_history: Vec::new(),
            mirrored: false,
            flat_growth: true,
            tpa: Tpa::default(),
            first_range: None,
            flat_bottom: 0,
            ties: false,
            low_rank: None,
            floors: Vec::new(),
            decoding: None,
        }
    }

    /// The same run with the full metric diagonally decoded ([`crate::run::Metric::Decoded`],
    /// `decoding.rs`): the start scales become `D` and `C` the identity. A diagonal metric
    /// stays as it is.
    pub fn with_decoding(mut self) -> SearchGaussian {
        if let Some((cov, b)) = &mut self.full {
            self.decoding = Some(Decoding::new(&self.d, &self.p));
            let (c1, cmu) = decoding::correlation_rates(&self.p, self.n);
            self.p = self.p.clone().with_rates(self.n, c1, cmu);
            (self.c1, self.cmu) = (c1, cmu);
            *cov = DMatrix::identity(self.n, self.n);
            *b = DMatrix::identity(self.n, self.n);
            self.d.fill(1.0);
        }
        self
    }

    /// The same run with the low-rank-plus-diagonal metric ([`crate::run::Metric::LowRank`]): the
    /// diagonal one, at the full metric's rates, and LM-MA-ES's directions (`lowrank.rs`). A
    /// full metric stays full.
    pub fn with_low_rank(mut self) -> SearchGaussian {
        if self.full.is_none() {
            self.low_rank = Some(LowRank::new(self.n, self.p.lambda));
            // The diagonal under the directions learns at the full metric's rates: at separable
            // CMA-ES's it takes up the stretch the directions should learn, and the rotated
            // ellipsoid of tests/low_rank.rs ends far higher.
            (self.c1, self.cmu) = diagonal_rates(&self.p, 1.0);
        }
        self
    }

    /// Draws a generation's offsets.
    pub fn sample(&self, rng: &mut Xoshiro256PlusPlus) -> Generation {
        let n = self.n;
        let mut ys = Vec::with_capacity(self.p.lambda);
        let pair = self.tpa_pair();
        for k in 0..self.p.lambda {
            if let (Some(dir), 0) = (&pair, k) {
                // The forward point's length is an ordinary draw's, so that its rank against
                // the others is decided by its direction, not its length.
                let z = DVector::from_fn(n, |_, _| -> f64 { StandardNormal.sample(rng) });
                ys.push(dir * z.norm());
                continue;
            }
            if pair.is_some() && k == 1 {
                let back = -&ys[0];
                ys.push(back);
                continue;
            }
            if self.mirrored && k % 2 == 1 {
                let prev: &DVector<f64> = &ys[k - 1];
                ys.push(-prev);
                continue;
            }
            if let Some(low_rank) = &self.low_rank {
                let mut u = DVector::from_fn(n, |_, _| -> f64 { StandardNormal.sample(rng) });
                low_rank.apply(&mut u);
                ys.push(u.component_mul(&self.d));
                continue;
            }
            let z = DVector::from_fn(n, |i, _| {
                let v: f64 = StandardNormal.sample(rng);
                v * self.d[i]
            });
            match (&self.full, &self.decoding) {
                (Some((_, b)), Some(decoding)) => ys.push((b * z).component_mul(&decoding.scale)),
                (Some((_, b)), None) => ys.push(b * z),
                (None, _) => ys.push(z),
            }
        }
        Generation { ys }
    }

    /// Moves the mean to `x` with the spread and scales learned so far; the evolution paths
    /// and the last mean shift led to the old mean, so they are cleared.
    pub fn recentre(&mut self, x: &[f64]) {
        self.mean = DVector::from_column_slice(x);
        self.ps.fill(0.0);
        self.pc.fill(0.0);
        self.tpa.shift = None;
        if let Some(decoding) = &mut self.decoding {
            decoding.clear_path();
        }
    }

    /// The point of offset `y`.
    pub fn point(&self, y: &DVector<f64>) -> DVector<f64> {
        &self.mean + y * self.sigma
    }

    /// `C^{-1/2} y` (with diagonal decoding `C^{-1/2} D^{-1} y`, with the low-rank metric
    /// `M^{-1} D^{-1} y`: the draw's `z`).
    fn inv_sqrt(&self, y: &DVector<f64>) -> DVector<f64> {
        match (&self.full, &self.low_rank) {
            (Some((_, b)), _) => {
                let mut t = match &self.decoding {
                    Some(decoding) => b.tr_mul(&y.component_div(&decoding.scale)),
                    None => b.tr_mul(y),
                };
                for (ti, di) in t.iter_mut().zip(self.d.iter()) {
                    *ti /= *di;
                }
                b * t
            }
            (None, Some(low_rank)) => {
                let mut z = y.component_div(&self.d);
                low_rank.apply_inverse(&mut z);
                z
            }
            (None, None) => y.component_div(&self.d),
        }
    }

    /// The offsets the diagonal metric learns from: the draws themselves, or with the
    /// low-rank metric their `D z` (what the directions leave); and the mean shift's.
    fn diagonal_offsets<'a>(
        &self,
        ys: &'a [DVector<f64>],
        yw: &'a DVector<f64>,
        zw: &DVector<f64>,
    ) -> (Cow<'a, [DVector<f64>]>, Cow<'a, DVector<f64>>) {
        if self.low_rank.is_none() {
            return (Cow::Borrowed(ys), Cow::Borrowed(yw));
        }
        let dz = |z: DVector<f64>| z.component_mul(&self.d);
        let each = ys.iter().map(|y| dz(self.inv_sqrt(y))).collect();
        (Cow::Owned(each), Cow::Owned(dz(zw.clone())))
    }

    /// With diagonal decoding, what a generation's update needs besides the plain full
    /// metric's: `D`'s path moved along `yw` and whitened, the selected draws whitened with
    /// their weights (for `D`), and the path `pc` and the offsets decoded by `D` (for `C`).
    fn decode(
        &mut self,
        ys: &[DVector<f64>],
        order: &[usize],
        yw: &DVector<f64>,
        hs: f64,
    ) -> Option<Decoded> {
        let mueff = self.p.mueff;
        self.decoding.as_mut()?.follow(yw, hs, mueff);
        let decoding = self.decoding.as_ref()?;
        let white_selected = order
            .iter()
            .zip(&self.p.weights)
            .take_while(|(_, &w)| w > 0.0)
            .map(|(&k, &w)| (w, self.inv_sqrt(&ys[k])))
            .collect();
        Some(Decoded {
            white_path: self.inv_sqrt(decoding.path()),
            white_selected,
            pc: self.pc.component_div(&decoding.scale),
            ys: ys
                .iter()
                .map(|y| y.component_div(&decoding.scale))
                .collect(),
        })
    }

    /// The variance of coordinate `i` (before `sigma^2`).
    fn variance(&self, i: usize) -> f64 {
        let scale = self.decoding.as_ref().map_or(1.0, |dd| dd.scale[i]);
        match &self.full {
            Some((cov, _)) => scale * scale * cov[(i, i)],
            None => self.d[i] * self.d[i],
        }
    }

    /// The largest and the smallest scale of `D` (1 without diagonal decoding).
    fn decoding_range(&self) -> (f64, f64) {
        self.decoding
            .as_ref()
            .map_or((1.0, 1.0), |dd| (dd.scale.max(), dd.scale.min()))
    }

    /// Updates the distribution from a generation's offsets (already repaired to the points
    /// actually evaluated) and their values, a failed point's value `+inf` (at least one
    /// finite); `level` is the best value the whole search has seen, this generation
    /// included. Returns why the run should end, if it should.
    pub fn update(&mut self, ys: &[DVector<f64>], values: &[f64], level: f64) -> Option<RunEnd> {
        let n = self.n;
        let nf = n as f64;
        let p = &self.p;
        let lambda = ys.len();
        let mut order: Vec<usize> = (0..lambda).collect();
        order.sort_by(|&a, &b| values[a].total_cmp(&values[b]));
        let best = values[order[0]];
        // The worst finite value (failures rank below it).
        let worst = order
            .iter()
            .rev()
            .map(|&k| values[k])
            .find(|v| v.is_finite());
        let worst = worst.unwrap_or(best);
        if self.first_range.is_none() && worst > best {
            self.first_range = Some(worst - best);
        }
        // A flat generation: the best quarter ties (measured against half and a tenth, and
        // against counting distinct values: docs/convergence.md).
        let flat = values[order[lambda / 4]] == best;
        self.ties |= flat;
        // Ties are a plateau to cross when they lie above the search's best level, or when
        // every point ties (nothing but the plateau in sight). Ties at the best level with
        // worse points around are the bottom of a flat region (the optimum's, or a step's of
        // the best value): growing sigma there grows it without bound (the staircase's
        // optimum), so it does not grow, and three such generations in a row end the run.
        let bottom = flat && best <= level && worst > best;
        self.flat_bottom = if bottom { self.flat_bottom + 1 } else { 0 };

        // Mean: the rank-weighted natural-gradient step.
        let mut yw = DVector::zeros(n);
        for (rank, &k) in order.iter().take(p.mu).enumerate() {
            yw.axpy(p.weights[rank], &ys[k], 1.0);
        }
        self.mean.axpy(self.sigma, &yw, 1.0);
        let paired = self.tpa_pair().is_some();

        // Evolution paths.
        let cs = p.cs;
        let inv = self.inv_sqrt(&yw);
        let (ds, dw) = self.diagonal_offsets(ys, &yw, &inv);
        self.ps
            .axpy((cs * (2.0 - cs) * p.mueff).sqrt(), &inv, 1.0 - cs);
        let ps_norm = self.ps.norm();
        let g1 = (self.generation + 1) as f64;
        let hsig =
            ps_norm / (1.0 - (1.0 - cs).powf(2.0 * g1)).sqrt() < (1.4 + 2.0 / (nf + 1.0)) * p.chi_n;
        let hs = if hsig { 1.0 } else { 0.0 };
        let cc = p.cc;
        self.pc
            .axpy(hs * (cc * (2.0 - cc) * p.mueff).sqrt(), &dw, 1.0 - cc);
        let decoded = self.decode(ys, &order, &yw, hs);
        let p = &self.p;

        // Covariance: rank-one, rank-mu and the active (negative) update.
        let (c1, cmu) = (self.c1, self.cmu);
        // The active update's weights are sized for the full metric's rates; the diagonal one
        // (rates (n + 2) / 3 times larger) uses positive weights only, as separable CMA-ES does
        // (with them it lost positive definiteness on a 2-D rotated ellipse: tests/minimize.rs).
        // The decay sums the weights used: counting skipped ones would inflate every variance.
        let full = self.full.is_some();
        let used = |w: f64| w > 0.0 || (w < 0.0 && full);
        let wsum: f64 = p.weights.iter().take(lambda).filter(|&&w| used(w)).sum();
        let decay = 1.0 + c1 * (1.0 - hs) * cc * (2.0 - cc) - c1 - cmu * wsum;
        let mut terms = Vec::with_capacity(lambda);
        for (rank, &k) in order.iter().enumerate() {
            let mut w = p.weights[rank];
            if !used(w) {
                continue;
            }
            if w < 0.0 {
                let norm2 = self.inv_sqrt(&ys[k]).norm_squared();
                if norm2 > 0.0 {
                    w *= nf / norm2;
                }
            }
            terms.push((cmu * w, k));
        }
        match &mut self.full {
            Some((cov, _)) => {
                let (pc, ys) = match &decoded {
                    Some(dec) => (&dec.pc, dec.ys.as_slice()),
                    None => (&self.pc, ys),
                };
                *cov *= decay;
                cov.ger(c1, pc, pc, 1.0);
                for &(w, k) in &terms {
                    cov.ger(w, &ys[k], &ys[k], 1.0);
                }
            }
            None => {
                let mut var = self.d.map(|d| d * d * decay);
                var.zip_apply(&self.pc, |v, p| *v += c1 * p * p);
                for &(w, k) in &terms {
                    var.zip_apply(&ds[k], |v, y| *v += w * y * y);
                }
                let floor = var.max().abs() * 1e-20 + f64::MIN_POSITIVE;
                self.d = var.map(|v| v.max(floor).sqrt());
            }
        }
        if let Some(low_rank) = &mut self.low_rank {
            low_rank.update(&inv, self.p.mueff);
        }
        if let (Some(decoding), Some(dec)) = (&mut self.decoding, decoded) {
            let cond_sqrt = self.d.max() / self.d.min();
            decoding.update(&dec.white_path, &dec.white_selected, cond_sqrt);
        }

        // Step size: TPA's warm-up (diagonal metric), then cumulative step-size adaptation;
        // and growth on flat generations.
        let csa = (cs / self.p.ds * (ps_norm / self.p.chi_n - 1.0)).min(1.0);
        let step = self.log_step(csa, paired, values, yw);
        self.sigma *= step.exp();
        if flat && !bottom && self.flat_growth {
            self.sigma *= (0.2 + cs / self.p.ds).exp();
        }
        self.apply_floors();
        self.generation += 1;

        // Eigendecomposition, lazily (every ~1/(10 n (c1 + cmu)) generations).
        // At least every n/10 (and n^2/400) generations: at n = 100 the tutorial's gap is ~1
        // generation and the O(n^3) decomposition would dominate the run.
        let gap = (1.0 / (10.0 * nf * (c1 + cmu)))
            .max(nf / 10.0)
            .max(nf * nf / 400.0)
            .floor()
            .max(1.0) as usize;
        if self.full.is_some() && self.generation - self.eigen_generation >= gap {
            self.decompose();
        }

        self.best_history.push(best);
        self.median_history.push(values[order[lambda / 2]]);
        self.check_end(flat, best, worst)
    }

    /// A generation in which every point failed: no value to rank, so the mean stays and
    /// sigma halves (the points were drawn too far into the region where `f` fails). The
    /// run ends when the spread has collapsed.
    pub fn failed_generation(&mut self) -> Option<RunEnd> {
        self.sigma *= 0.5;
        self.generation += 1;
        let widest = (0..self.n).map(|i| self.variance(i)).fold(0.0, f64::max);
        (self.sigma * widest.sqrt() < 1e-12 * self.sigma_start).then_some(RunEnd::TolX)
    }

    fn decompose(&mut self) {
        self.eigen_generation = self.generation;
        let Some((cov, b)) = &mut self.full else {
            return;
        };
        if let Some(decoding) = &mut self.decoding {
            decoding.absorb(cov);
        }
        let sym = (&*cov + cov.transpose()) * 0.5;
        let eig = SymmetricEigen::new(sym);
        let floor = eig.eigenvalues.max().abs() * 1e-20 + f64::MIN_POSITIVE;
        self.d = eig.eigenvalues.map(|e| e.max(floor).sqrt());
        *b = eig.eigenvectors;
        *cov = &*b * DMatrix::from_diagonal(&self.d.map(|d| d * d)) * b.transpose();
    }
}

/// The diagonal metric's rank-one and rank-mu rates: the full metric's times `k`, kept below
/// a decay of 1 (separable CMA-ES's bounds).
fn diagonal_rates(p: &Params, k: f64) -> (f64, f64) {
    let c1 = (p.c1 * k).min(0.5);
    (c1, (p.cmu * k).min(1.0 - c1 - 1e-3).max(0.0))
}

/// A generator for a run's seed.
pub(crate) fn rng(seed: u64) -> Xoshiro256PlusPlus {
    Xoshiro256PlusPlus::seed_from_u64(seed)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_sum_to_one_and_are_sorted() {
        for n in [1, 2, 10, 100] {
            let p = Params::new(n, Params::default_lambda(n));
            let pos: f64 = p.weights[..p.mu].iter().sum();
            assert!((pos - 1.0).abs() < 1e-12);
            assert!(p.weights.windows(2).all(|w| w[0] >= w[1]));
            assert!(p.cmu > 0.0 && p.c1 > 0.0 && p.c1 + p.cmu <= 1.0);
        }
    }
}
