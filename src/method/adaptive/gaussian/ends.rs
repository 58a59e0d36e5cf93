//! Why one run of the search distribution ends ([`RunEnd`]), in the spirit of pycma's
//! termination criteria (Hansen 2016, appendix B.3): each rule names its reason, and the
//! converged ones tell the search (`../mod.rs`) how precisely the run knows its best value
//! and where it is, for the rule that ends the whole search when restarts keep finding the
//! same best point.

use super::SearchGaussian;

/// The largest condition number of the covariance a run goes on with (pycma's
/// `tolconditioncov`).
pub(super) const MAX_CONDITION: f64 = 1e14;

/// Why one run of the search distribution ended (and a restart is due).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum RunEnd {
    /// The spread became negligible next to the mean (converged to the working precision):
    /// pycma's tolx.
    TolX,
    /// A flat generation at a spread below `1e-6` of the mean: the objective's resolution.
    Resolution,
    /// The values of the last generations are all within `1e-12` of each other, in units of
    /// the run's first generation's range when that is below 1 (so that a tiny `f` is not
    /// converged at once): pycma's tolfun.
    TolFun,
    /// Three flat generations in a row at the search's best level, with worse points around:
    /// the run sits at the bottom of a flat region and sees its walls, pycma's tolflatfitness.
    FlatBottom,
    /// The covariance's condition number passed [`MAX_CONDITION`] (over the continuous
    /// coordinates when floors raise the discrete ones: `floor.rs`).
    Condition,
    /// The best value of a generation has not improved for a long window: pycma's
    /// tolstagnation.
    Stagnation,
    /// Over twice TolFun's window no generation improved on the run's best, and half of them
    /// drew the same best value as the last, which was not flat: the mean is parked in one
    /// cell of a staircase, its spread too wide for a flat generation and too narrow to reach
    /// a lower step (the step ellipsoid's rotated steps). Tolstagnation's verdict, reached
    /// sooner. A flat generation is a plateau to cross (the spread grows) and never parked.
    Parked,
    /// The spread grew beyond `1e8` times its start: the function looks flat everywhere.
    Flat,
}

impl RunEnd {
    /// Whether the run converged: it ended because it knows its best value and point to its
    /// own precision (not because it stalled, blew up, or lost its metric).
    pub(crate) fn converged(self) -> bool {
        matches!(
            self,
            RunEnd::TolX | RunEnd::Resolution | RunEnd::TolFun | RunEnd::FlatBottom
        )
    }
}

/// Flat generations in a row at the best level that end a run.
const FLAT_BOTTOM_GENERATIONS: usize = 3;

impl SearchGaussian {
    /// The TolFun window: `10 + 30 n / lambda` generations.
    fn tolfun_window(&self) -> usize {
        10 + (30.0 * self.n as f64 / self.p.lambda as f64).ceil() as usize
    }

    /// The run's best value so far (`+inf` before a finite one).
    pub(crate) fn run_best(&self) -> f64 {
        self.best_history
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min)
    }

    /// TolFun's tolerance at the value `lo`: `1e-12` in units of the run's first range when
    /// that is below 1, or `1e-15 |lo|` if larger.
    fn tolfun_tolerance(&self, lo: f64) -> f64 {
        let scale = self.first_range.unwrap_or(1.0).min(1.0);
        (1e-12 * scale).max(1e-15 * lo.abs())
    }

    /// How precisely the run knows its best value: the range of its generations' best values
    /// over the TolFun window (0 when they tie exactly, as at a flat bottom), or TolFun's
    /// tolerance if larger (values that TolFun calls flat are the same value). The range is
    /// in the units of `f`, so a rule comparing values with it is scale-free.
    pub(crate) fn precision(&self) -> f64 {
        let h = &self.best_history;
        let recent = &h[h.len().saturating_sub(self.tolfun_window())..];
        let finite = recent.iter().copied().filter(|v| v.is_finite());
        let (lo, hi) = finite.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
        if lo <= hi {
            (hi - lo).max(self.tolfun_tolerance(lo))
        } else {
            0.0
        }
    }

    /// The standard deviation of every coordinate of the search distribution.
    pub(crate) fn spread(&self) -> Vec<f64> {
        (0..self.n)
            .map(|i| self.sigma * self.variance(i).sqrt())
            .collect()
    }

    /// Whether the run is [`RunEnd::Parked`], `best` the last generation's best value. The
    /// history is scanned only when the last two generations' bests tie.
    fn parked(&self, best: f64) -> bool {
        let h = &self.best_history;
        let window = 2 * self.tolfun_window();
        if h.len() <= window || h[h.len() - 2] != best {
            return false;
        }
        let (earlier, recent) = h.split_at(h.len() - window);
        let before = earlier.iter().copied().fold(f64::INFINITY, f64::min);
        let improved = recent.iter().any(|&v| v < before);
        let repeats = recent.iter().filter(|&&v| v == best).count();
        !improved && 2 * repeats >= window
    }

    pub(super) fn check_end(&self, flat: bool, best: f64, worst: f64) -> Option<RunEnd> {
        let n = self.n;
        let max_d = self.d.max() * self.decoding_range().0;
        let diag_max = (0..n).map(|i| self.variance(i)).fold(0.0, f64::max).sqrt();
        if self.sigma * max_d > 1e8 * self.sigma_start {
            return Some(RunEnd::Flat);
        }
        if self.sigma * diag_max < 1e-12 * self.sigma_start
            || (0..n).all(|i| {
                let m = self.mean[i];
                m + 0.2 * self.sigma * self.variance(i).sqrt() == m
            })
        {
            return Some(RunEnd::TolX);
        }
        // A flat generation whose spread is below a millionth of the mean is not a plateau to
        // cross but the objective's resolution (a renderer computing in single precision
        // cannot tell such points apart): growing the spread there makes it random-walk on
        // rounding noise (seen on CUP: 150 generations at 1e-8 to 1e-6). The run has
        // converged; a restart (the best point stays the result's) is worth more.
        let m_scale = self.mean.iter().fold(1.0f64, |a, m| a.max(m.abs()));
        if flat && self.sigma * diag_max < 1e-6 * m_scale {
            return Some(RunEnd::Resolution);
        }
        if self.flat_bottom >= FLAT_BOTTOM_GENERATIONS {
            return Some(RunEnd::FlatBottom);
        }
        if self.condition(MAX_CONDITION) > MAX_CONDITION {
            return Some(RunEnd::Condition);
        }
        if !flat && self.parked(best) {
            return Some(RunEnd::Parked);
        }
        let window = self.tolfun_window();
        if !flat && self.best_history.len() >= window {
            let recent = &self.best_history[self.best_history.len() - window..];
            let hi = recent.iter().copied().fold(worst, f64::max);
            let lo = recent.iter().copied().fold(best, f64::min);
            if hi - lo <= self.tolfun_tolerance(lo) {
                return Some(RunEnd::TolFun);
            }
        }
        let lambda = self.p.lambda as f64;
        let stall = 120 + (30.0 * n as f64 / lambda).ceil() as usize;
        let median = |s: &[f64]| {
            let mut v = s.to_vec();
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        // Neither the generations' best nor their median values improved over the window.
        let stalled = |h: &[f64]| {
            h.len() >= stall + 20
                && median(&h[h.len() - 20..]) >= median(&h[h.len() - stall - 20..h.len() - stall])
        };
        if stalled(&self.best_history) && stalled(&self.median_history) {
            return Some(RunEnd::Stagnation);
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run at n = 2, lambda 6 (TolFun's window 20 generations, Parked's 40) with the given
    /// generations' best values.
    fn run_with(history: &[f64]) -> SearchGaussian {
        let mut run = SearchGaussian::new(&[0.0, 0.0], 1.0, &[1.0, 1.0], 6, true);
        run.best_history = history.to_vec();
        run
    }

    /// 10 generations descending to 7, then 40 in pairs of 7.2 and pairs of 7.5 (the cell the
    /// mean sits in), ending on a pair of 7.5.
    fn parked_history() -> Vec<f64> {
        let mut h: Vec<f64> = (0..10).map(|k| 16.0 - k as f64).collect();
        h.extend((0..40).map(|k| if k % 4 < 2 { 7.2 } else { 7.5 }));
        h
    }

    #[test]
    fn a_run_drawing_the_same_best_for_half_its_window_is_parked() {
        let run = run_with(&parked_history());
        assert_eq!(run.tolfun_window(), 20);
        assert!(run.parked(7.5));
        assert_eq!(run.check_end(false, 7.5, 9.0), Some(RunEnd::Parked));
        assert!(!RunEnd::Parked.converged());
    }

    #[test]
    fn a_flat_generation_is_never_parked() {
        let run = run_with(&parked_history());
        assert_ne!(run.check_end(true, 7.5, 9.0), Some(RunEnd::Parked));
    }

    #[test]
    fn an_improvement_a_changed_best_or_fewer_repeats_is_not_parked() {
        let mut improved = parked_history();
        improved[30] = 6.9;
        assert!(!run_with(&improved).parked(7.5));

        let mut changed = parked_history();
        *changed.last_mut().unwrap() = 7.3;
        assert!(!run_with(&changed).parked(7.3));

        let mut fewer = parked_history();
        fewer[12] = 7.4; // 19 of the 40 draw 7.5
        assert!(!run_with(&fewer).parked(7.5));

        let short = &parked_history()[..40];
        assert!(!run_with(short).parked(7.5));
    }
}
