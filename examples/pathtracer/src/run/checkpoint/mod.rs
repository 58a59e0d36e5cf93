//! A run's checkpoint, `checkpoint.json`: everything needed to continue the run bit for bit,
//! written atomically, and refused whole when it does not fit the run asked for.
//!
//! What it holds: a format version, the build that wrote it (the crate's version and a hash of
//! the executable), the task, the settings asked for on the command line and those the run
//! uses (they differ only when `--budget` planned them), the loop's state (theta, Adam's
//! moments, the iteration, hence the annealer's sigma, the estimator's stream position,
//! hence every random stream), the history so far, the progress strip's snapshots and the
//! times spent. For `--method adaptive` and `polished`, instead of the loop's state, the
//! library's ask-and-tell run (`plateau_free::AskTell`, serialised), read back on resume, and
//! the value of every evaluation so far (for the stop rule's study).
//!
//! Why the executable's hash: a run continued by another build could differ in any bit (a
//! changed renderer, estimator or compiler), and nothing short of the binary itself says
//! reliably that the code is the same (a git commit misses uncommitted edits and is absent
//! from a source archive). The price: a rebuild after any change refuses the old checkpoints.
//!
//! One file per job: `cadence.rs` (when a run writes it), `build.rs` (the build that wrote
//! it), `error.rs` (why one is refused), `checks.rs` (whether its parts fit together and fit
//! the run asked for); this file holds the contents, reading and writing (atomically, with
//! the library's `replace_file`).

mod build;
mod cadence;
mod checks;
mod error;

pub use build::{executable_hash, fnv1a, one_line, Build, ONE_LINE_MAX};
pub use cadence::{Every, SECONDS_BETWEEN};
pub use error::CheckpointError;

use std::fs;
use std::io;
use std::path::Path;

use plateau_free::lifecycle::replace_file;
use plateau_free::OptimizerState;
use serde::{Deserialize, Serialize};

use super::{Row, Settings};

/// The checkpoint's file name inside a run's directory.
pub const FILE: &str = "checkpoint.json";

/// The version of the file's layout; a file of another version is refused.
pub const FORMAT: u32 = 1;

/// Where the run's loop stands.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum Progress {
    /// The paper's loop (plateau, fd, spsa): the library's state.
    Loop {
        /// Theta, Adam's moments, the iteration, the stream position, the loop's history.
        state: OptimizerState,
    },
    /// The adaptive search (and the polished loop): the library's run, and every value.
    Adaptive {
        /// The library's `plateau_free::AskTell`, serialised: its options, state and random
        /// generators.
        state: serde_json::Value,
        /// The values of the evaluations, in the order the search asked for them.
        values: Vec<f64>,
        /// The best value so far (`None` before the first finite one).
        best_value: Option<f64>,
        /// The best point so far.
        best_point: Vec<f64>,
        /// The best point after every iteration (small tasks only).
        bests: Vec<Vec<f64>>,
    },
}

/// The contents of `checkpoint.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Checkpoint {
    /// [`FORMAT`] of the build that wrote it.
    pub format: u32,
    /// The build that wrote it.
    pub build: Build,
    /// The task's name.
    pub task: String,
    /// The settings the command line asked for.
    pub requested: Settings,
    /// The settings the run uses (after `--budget`'s plan).
    pub settings: Settings,
    /// Whether the run has ended (all iterations, or its time budget spent).
    pub finished: bool,
    /// Where the loop stands.
    pub progress: Progress,
    /// `history.csv` so far: one row per completed iteration.
    pub history: Vec<Row>,
    /// Theta at the progress strip's moments so far (the paper's loop).
    pub snapshots: Vec<Vec<f64>>,
    /// Optimisation time so far, seconds.
    pub optimisation_seconds: f64,
    /// Of which rendering for the loss, seconds.
    pub render_seconds: f64,
}

impl Checkpoint {
    /// Reads the checkpoint at `path` and checks it whole: the format, the build, and that
    /// its parts fit together. Never panics, whatever the bytes.
    ///
    /// # Errors
    /// A [`CheckpointError`] naming the file and what is wrong.
    pub fn load(path: &Path) -> Result<Checkpoint, CheckpointError> {
        let bytes = fs::read(path).map_err(|error| CheckpointError::Unreadable {
            path: path.into(),
            error,
        })?;
        Checkpoint::parse(&bytes, path)
    }

    /// [`Checkpoint::load`] on bytes already read; `path` names them in errors.
    ///
    /// # Errors
    /// As [`Checkpoint::load`].
    pub fn parse(bytes: &[u8], path: &Path) -> Result<Checkpoint, CheckpointError> {
        let c = Checkpoint::parse_any_build(bytes, path)?;
        let current = Build::current();
        if c.build != current || current.executable == "unknown" {
            return Err(CheckpointError::OtherBuild {
                path: path.into(),
                found: c.build,
            });
        }
        Ok(c)
    }

    /// [`Checkpoint::parse`] without the check of the build: the format, the JSON and the
    /// consistency of the parts (to inspect a checkpoint, and for the fuzzer, whose inputs
    /// cannot know the executable's hash).
    ///
    /// # Errors
    /// As [`Checkpoint::load`], but never [`CheckpointError::OtherBuild`].
    pub fn parse_any_build(bytes: &[u8], path: &Path) -> Result<Checkpoint, CheckpointError> {
        // The format first, so that a file of another layout says so rather than "damaged".
        #[derive(Deserialize)]
        struct Head {
            format: u32,
        }
        let damaged = |e: serde_json::Error| CheckpointError::Damaged {
            path: path.into(),
            error: e.to_string(),
        };
        let head: Head = serde_json::from_slice(bytes).map_err(damaged)?;
        if head.format != FORMAT {
            return Err(CheckpointError::Format {
                path: path.into(),
                found: head.format,
            });
        }
        let c: Checkpoint = serde_json::from_slice(bytes).map_err(damaged)?;
        c.check_consistent()
            .map_err(|reason| CheckpointError::Inconsistent {
                path: path.into(),
                reason,
            })?;
        Ok(c)
    }

    /// Writes the checkpoint to `path` atomically ([`replace_file`]).
    ///
    /// # Errors
    /// Whatever the file system reports (a full disk, a missing directory); the file at
    /// `path`, if any, is then as before.
    pub fn save(&self, path: &Path) -> io::Result<()> {
        let bytes = serde_json::to_vec(self).map_err(io::Error::other)?;
        replace_file(path, &bytes)
    }
}

/// The fuzzers' one body, shared by the cargo-fuzz target (`fuzz/fuzz_targets/checkpoint.rs`)
/// and the bounded run in the ordinary tests (`tests/checkpoint.rs`): the loader on `bytes`
/// (as the file `fuzz/checkpoint.json`), then what `--resume` does with a checkpoint that
/// loads. Returns whether it loaded; panics (the fuzzers' crash) when the contract breaks:
///
/// - the loader never panics, and refuses with one line naming the file;
/// - a checkpoint that loads is matched against its task, with the task's defaults and with
///   its own settings (what `--resume` does; the CLI then checks the options given against
///   its settings), without a panic, any refusal again one line naming the file;
/// - a checkpoint that loads, written again (as the resumed run writes it), loads again, the
///   same: a run continued from it can be continued again.
#[doc(hidden)]
pub fn fuzz_checkpoint(bytes: &[u8]) -> bool {
    let path = Path::new("fuzz/checkpoint.json");
    let clean = |e: &CheckpointError| {
        let message = e.to_string();
        assert!(
            message.contains("fuzz/checkpoint.json") && !message.contains('\n'),
            "not one line naming the file: {message}"
        );
    };
    let c = match Checkpoint::parse_any_build(bytes, path) {
        Ok(c) => c,
        Err(e) => {
            clean(&e);
            return false;
        }
    };
    // What `Checkpoint::parse` says of another build (the file's build, any text).
    clean(&CheckpointError::OtherBuild {
        path: path.into(),
        found: c.build.clone(),
    });
    // `optimize --resume` (the checkpoint's task) and `optimize shadow --resume` (any).
    let tasks = [
        crate::tasks::by_name(&c.task),
        crate::tasks::by_name("shadow"),
    ];
    for task in tasks.into_iter().flatten() {
        for requested in [Settings::defaults(&task), c.requested.clone()] {
            if let Err(e) = c.check_matches(&task, &requested, path) {
                clean(&e);
            }
        }
    }
    let again = serde_json::to_vec(&c).expect("a checkpoint that loads serialises");
    match Checkpoint::parse_any_build(&again, path) {
        Ok(d) => assert_eq!(
            serde_json::to_vec(&d).ok().as_ref(),
            Some(&again),
            "written again, it loads as another checkpoint"
        ),
        Err(e) => panic!("written again, it no longer loads: {e}"),
    }
    true
}

/// A setting's value as the user would write it (`16`, `0.5`, `none`, `radial`).
pub(crate) fn show(value: &serde_json::Value) -> String {
    match value {
        serde_json::Value::Null => "none".into(),
        serde_json::Value::String(s) => s.clone(),
        v => v.to_string(),
    }
}
