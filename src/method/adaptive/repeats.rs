//! The rule that ends the whole adaptive search before its budget ([`crate::Stop::Done`]):
//! a converged run is not yet a finished search on a multimodal function, but restarts that
//! keep converging back at the best point seen before them show that more budget buys
//! nothing ([`crate::Minimizer::patience`]).

use super::gaussian::{RunEnd, SearchGaussian};

/// How far, in standard deviations of the search distribution, a converged run's mean may
/// lie from the best point seen before it and still count as the same point.
const SAME_POINT_DEVIATIONS: f64 = 10.0;

/// The search's record of its converged runs, for the rule.
#[derive(Debug, Clone, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub(crate) struct Repeats {
    /// The best point seen when the run in progress began.
    reference: Vec<f64>,
    /// The spread (standard deviation of every coordinate) of the last converged run at its
    /// end: how precisely that run placed the best point.
    last_spread: Option<Vec<f64>>,
    /// Converged runs in a row that found the best point again.
    found: usize,
    /// Whether a generation of any run was flat: the objective's values tie.
    ties: bool,
}

impl Repeats {
    /// A read-back record's vectors against the run's dimension `n` (the reference is empty
    /// before the first run).
    #[cfg(feature = "serde")]
    pub(crate) fn check(&self, n: usize) -> Result<(), crate::error::Error> {
        use crate::check::len;
        if !self.reference.is_empty() {
            len("patience reference point", self.reference.len(), n)?;
        }
        match &self.last_spread {
            Some(spread) => len("patience spread", spread.len(), n),
            None => Ok(()),
        }
    }

    /// Whether the last converged run found the best point again (a repeat is under way).
    pub(crate) fn found_again(&self) -> bool {
        self.found > 0
    }

    /// A run begins, with `best` the best point seen so far.
    pub(crate) fn begin(&mut self, best: &[f64]) {
        self.reference.clear();
        self.reference.extend_from_slice(best);
    }

    /// Judges a run that ended with `end`, `reference` the best value seen when it began:
    /// whether `patience` runs in a row (two more on an objective whose values tie, where a
    /// run can end on a step of the best value that is not the best step, and restarts with
    /// larger populations still find lower steps) converged at the
    /// same value, within the run's own precision, and at the same point, within a few of
    /// its standard deviations (or of the run's before it, which placed the point).
    pub(crate) fn judge(
        &mut self,
        end: RunEnd,
        dist: &SearchGaussian,
        reference: f64,
        patience: usize,
    ) -> bool {
        self.ties |= dist.ties;
        if !end.converged() {
            self.found = 0;
            return false;
        }
        // A flat bottom's values tie: the same value is the same number.
        let precision = match end {
            RunEnd::FlatBottom => 0.0,
            _ => dist.precision(),
        };
        let same_value = (dist.run_best() - reference).abs() <= precision;
        let spread = dist.spread();
        let last = self.last_spread.as_deref().unwrap_or(&spread);
        let same_point = self.reference.len() == spread.len()
            && (0..spread.len()).all(|i| {
                let deviation = spread[i].max(last[i]);
                (dist.mean[i] - self.reference[i]).abs() <= SAME_POINT_DEVIATIONS * deviation
            });
        self.found = if same_value && same_point {
            self.found + 1
        } else {
            0
        };
        self.last_spread = Some(spread);
        patience > 0 && self.found >= patience + 2 * usize::from(self.ties)
    }
}
