//! What an earlier run left at a checkpoint file, for the commands that make many runs.

use std::path::Path;

use super::{Checkpoint, CheckpointError, Settings};
use crate::tasks::Task;

/// What an earlier run left at a checkpoint file, for the commands that make many runs
/// (`all`, the experiments): a finished run (kept), a run to continue, or nothing usable.
pub enum Earlier {
    /// The checkpoint of a finished run of this task and these settings.
    Finished(Box<Checkpoint>),
    /// The checkpoint of an unfinished run of this task and these settings.
    Unfinished(Box<Checkpoint>),
    /// No checkpoint, or one that is refused (the reason, if there was a file): start over.
    None(Option<CheckpointError>),
}

impl Earlier {
    /// Reads and checks the checkpoint at `path` for a run of `task` with the settings
    /// `requested`.
    pub fn at(path: &Path, task: &Task, requested: &Settings) -> Earlier {
        let checked =
            Checkpoint::load(path).and_then(|c| c.check_matches(task, requested, path).map(|()| c));
        match checked {
            Ok(c) if c.finished => Earlier::Finished(Box::new(c)),
            Ok(c) => Earlier::Unfinished(Box::new(c)),
            Err(CheckpointError::Unreadable { error, .. })
                if error.kind() == std::io::ErrorKind::NotFound =>
            {
                Earlier::None(None)
            }
            Err(e) => Earlier::None(Some(e)),
        }
    }

    /// The run to continue (`None`: start over) and the settings to run with: the
    /// checkpoint's, else `requested`. Says which on stderr, naming the run `label`.
    pub fn resume(self, label: &str, requested: &Settings) -> (Option<Checkpoint>, Settings) {
        let resume = match self {
            Earlier::Finished(c) | Earlier::Unfinished(c) => {
                eprintln!("{label}: resuming from iteration {}", c.history.len());
                Some(*c)
            }
            Earlier::None(None) => None,
            Earlier::None(Some(why)) => {
                eprintln!("{label}: starting over ({why})");
                None
            }
        };
        let settings = resume
            .as_ref()
            .map_or_else(|| requested.clone(), |c| c.settings.clone());
        (resume, settings)
    }
}
