//! When a run writes its checkpoint.

/// About every this many seconds of optimisation a run writes its checkpoint (the default
/// of `--checkpoint-every`).
pub const SECONDS_BETWEEN: f64 = 30.0;

/// When a run writes its checkpoint (besides at the end and on Ctrl-C, always).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Every {
    /// About every [`SECONDS_BETWEEN`] seconds: every K iterations, K from the measured
    /// seconds per iteration so far.
    #[default]
    Auto,
    /// Every this many iterations (at least 1).
    Iterations(usize),
    /// Only at the end and on Ctrl-C (`--checkpoint-every 0`).
    End,
}

impl Every {
    /// `--checkpoint-every N`: 0 for [`Every::End`], else every N iterations.
    pub fn from_option(n: Option<usize>) -> Self {
        match n {
            None => Every::Auto,
            Some(0) => Every::End,
            Some(n) => Every::Iterations(n),
        }
    }

    /// The iterations to run after `done` before the next checkpoint, given the seconds per
    /// iteration measured so far (`None` for never, until the end).
    ///
    /// ```
    /// use pathtracer::run::Every;
    /// assert_eq!(Every::Auto.next_after(0, 0.0), Some(1)); // measure one iteration first
    /// assert_eq!(Every::Auto.next_after(5, 0.25), Some(120)); // then about 30 s worth
    /// assert_eq!(Every::from_option(Some(0)).next_after(5, 0.25), None); // only at the end
    /// ```
    pub fn next_after(self, done: usize, seconds_per_iteration: f64) -> Option<usize> {
        match self {
            Every::End => None,
            Every::Iterations(k) => Some(k.max(1)),
            Every::Auto => {
                let measured = seconds_per_iteration > 0.0; // false for NaN too
                let k = if done == 0 || !measured {
                    // Nothing measured yet: one iteration, then measure.
                    1.0
                } else {
                    (SECONDS_BETWEEN / seconds_per_iteration).floor()
                };
                Some((k as usize).max(1))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The automatic cadence: one iteration to measure, then about 30 s worth.
    #[test]
    fn the_cadence_follows_the_measured_cost() {
        assert_eq!(Every::Auto.next_after(0, 0.0), Some(1));
        assert_eq!(Every::Auto.next_after(1, 0.5), Some(60));
        assert_eq!(Every::Auto.next_after(10, 45.0), Some(1));
        assert_eq!(Every::Iterations(7).next_after(3, 1.0), Some(7));
        assert_eq!(Every::End.next_after(3, 1.0), None);
        assert_eq!(Every::from_option(Some(0)), Every::End);
    }
}
