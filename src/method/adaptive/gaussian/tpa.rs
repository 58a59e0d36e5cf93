//! The two-point step-size adaptation's warm-up of a run with the diagonal metric: [`Tpa`]
//! and the generation steps that read and update it.

use nalgebra::DVector;

use super::SearchGaussian;

/// A warm-up of two-point step-size adaptation (TPA: Hansen, "CMA-ES with Two-Point Step-Size
/// Adaptation", INRIA RR-6527, 2008; its damping as pycma 4.5 sets it) at the start of each run
/// with the diagonal metric, before cumulative step-size adaptation (CSA) takes over.
///
/// Why: CSA moves `ln sigma` by at most `c_sigma / d_sigma ~ mueff / n` per generation, so at
/// n = 49,152 one e-fold costs ~145,000 evaluations and a start spread ten times too wide is
/// never corrected within 10^5 (docs/results/large-scale.md). TPA draws the first two points
/// of each generation at `m +- sigma * l * dm / |dm|_C`, along the last mean shift `dm` with
/// the Mahalanobis length `l` of an ordinary draw, and shrinks `sigma` when the backward point
/// ranks better (the last step overshot), grows it when the forward one does; its damping is
/// `O(ln n)` generations per e-fold, not `O(n / mueff)`. But TPA throughout (and CSA only
/// accelerated where both rules agreed) shrank `sigma` onto Rastrigin's local basins at
/// n = 320 and lost its target, as the median success rule had. So TPA only shrinks a spread
/// that is too large: the first generation in which its smoothed rank difference turns
/// positive (the forward point better: `sigma` no longer too large) ends the warm-up for the
/// rest of the run, and CSA, whose slowness keeps `sigma` wide on multimodal functions, goes
/// on from there. The two points stay in every generation: without them after the warm-up
/// (measured at n = 3,072, seed 0) the texture task ends at 7.1e-5 instead of 9.7e-7 with
/// 10^5 evaluations; with them, separable and Rosenbrock-like functions at n = 320 (bbob f2,
/// f8, f10) end higher than under CSA alone (docs/results/large-scale.md).
#[derive(Debug, Clone, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub(crate) struct Tpa {
    /// The smoothed rank difference, in `[-1, 1]`.
    s: f64,
    /// The last mean shift, when the next generation is to open with the two points along
    /// it (none in a run's first generation, or after a mean that did not move).
    pub(super) shift: Option<DVector<f64>>,
    /// The warm-up has ended: `sigma` follows CSA for the rest of the run.
    #[cfg_attr(feature = "serde", serde(default))]
    warmed: bool,
    /// The warm-up ended with the last update, until [`SearchGaussian::warm_up_ended`] reads
    /// it.
    #[cfg_attr(feature = "serde", serde(default))]
    ended: bool,
}

/// TPA's smoothing weight of the newest rank difference.
const TPA_C: f64 = 0.3;

impl SearchGaussian {
    /// Whether the run draws TPA's two points and starts with its warm-up (the diagonal
    /// metric; the full one, n <= 200 by default, keeps CSA alone, bit for bit).
    pub(super) fn uses_tpa(&self) -> bool {
        self.full.is_none() && self.p.lambda >= 4
    }

    /// TPA's damping: `0.7 + 2 ln n`, more when the population exceeds the dimension
    /// (pycma's setting for its TPA: an e-fold of `sigma` in about 22 generations at
    /// n = 49,152).
    fn tpa_damping(&self) -> f64 {
        let (nf, lf) = (self.n as f64, self.p.lambda as f64);
        0.7 + 2.0 * nf.ln().max(0.0) + 2.0 * (lf - nf).max(1.0).ln()
    }

    /// The unit (in the metric's norm) direction of the last mean shift, when this
    /// generation opens with TPA's two points.
    pub(super) fn tpa_pair(&self) -> Option<DVector<f64>> {
        if !self.uses_tpa() {
            return None;
        }
        let shift = self.tpa.shift.as_ref()?;
        let len = self.inv_sqrt(shift).norm();
        (len > 0.0 && len.is_finite()).then(|| shift / len)
    }

    /// TPA's update of `sigma` from a generation that opened with its two points: the rank
    /// difference `z` of the backward and the forward point over `lambda - 1` (positive when
    /// the forward one is better), smoothed as `sign(z) sqrt(|z|)` (which enlarges small
    /// differences, as pycma does with large populations).
    fn tpa_step(&mut self, values: &[f64]) -> f64 {
        let lambda = values.len();
        let below = |v: f64| values.iter().filter(|&&w| w < v).count() as f64;
        let z = (below(values[1]) - below(values[0])) / (lambda - 1) as f64;
        self.tpa.s = (1.0 - TPA_C) * self.tpa.s + TPA_C * z.signum() * z.abs().sqrt();
        self.tpa.s / self.tpa_damping()
    }

    /// The change of `ln sigma` after a generation: TPA's while the warm-up lasts, CSA's
    /// (`csa`) after it and with the full metric. Keeps the mean shift `yw` (in units of
    /// sigma) for the next generation's two points.
    pub(super) fn log_step(
        &mut self,
        csa: f64,
        paired: bool,
        values: &[f64],
        yw: DVector<f64>,
    ) -> f64 {
        if !self.uses_tpa() {
            return csa;
        }
        let tpa = if paired && values.len() == self.p.lambda {
            self.tpa_step(values)
        } else {
            0.0
        };
        self.tpa.shift = Some(yw);
        // The warm-up ends for good the first time the forward point ranks better on
        // average: sigma is no longer too large, and CSA, slower, keeps it wide on
        // multimodal functions from there on (TPA alone lost Rastrigin's target).
        if self.tpa.s > 0.0 && !self.tpa.warmed {
            self.tpa.warmed = true;
            self.tpa.ended = true;
        }
        if self.tpa.warmed {
            csa
        } else {
            tpa
        }
    }

    /// Whether the warm-up ended with the last update (true once).
    pub fn warm_up_ended(&mut self) -> bool {
        std::mem::take(&mut self.tpa.ended)
    }
}
