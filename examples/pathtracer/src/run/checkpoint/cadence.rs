//! When a run writes its checkpoint: the command line's choice, as the library's cadence.

use std::path::Path;

use plateau_free::lifecycle::Checkpoint;

/// When a run writes its checkpoint (besides at the end and on Ctrl-C, always).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Every {
    /// About every [`plateau_free::lifecycle::CHECKPOINT_SECONDS`] seconds.
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

    /// The library's checkpoint at `path`, written at this cadence.
    ///
    /// ```
    /// use pathtracer::run::Every;
    /// let c = Every::from_option(Some(7)).checkpoint("run/checkpoint.json".as_ref());
    /// assert_eq!(c.path(), std::path::Path::new("run/checkpoint.json"));
    /// ```
    pub fn checkpoint(self, path: &Path) -> Checkpoint {
        let checkpoint = Checkpoint::new(path);
        match self {
            Every::Auto => checkpoint,
            Every::Iterations(k) => checkpoint.every_iterations(k.max(1)),
            Every::End => checkpoint.every_iterations(0),
        }
    }
}
