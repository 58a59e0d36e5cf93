//! When a run writes its checkpoint.

use std::time::Duration;

/// About every this many seconds of optimisation a run writes its checkpoint (the default
/// of `--checkpoint-every`): the library's cadence.
pub const SECONDS_BETWEEN: f64 = plateau_free::lifecycle::CHECKPOINT_SECONDS;

/// When a run writes its checkpoint (besides at the end and on Ctrl-C, always).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Every {
    /// About every [`SECONDS_BETWEEN`] seconds of optimisation.
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

    /// Whether a checkpoint is due `iterations` iterations and `spent` of optimisation time
    /// after the last one.
    ///
    /// ```
    /// use std::time::Duration;
    /// use pathtracer::run::Every;
    /// assert!(!Every::Auto.is_due(100, Duration::from_secs(29)));
    /// assert!(Every::Auto.is_due(1, Duration::from_secs(30)));
    /// assert!(Every::Iterations(7).is_due(7, Duration::ZERO));
    /// assert!(!Every::from_option(Some(0)).is_due(1000, Duration::from_secs(3600)));
    /// ```
    pub fn is_due(self, iterations: usize, spent: Duration) -> bool {
        match self {
            Every::End => false,
            Every::Iterations(k) => iterations >= k.max(1),
            Every::Auto => spent.as_secs_f64() >= SECONDS_BETWEEN,
        }
    }
}
