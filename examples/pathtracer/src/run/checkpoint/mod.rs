//! A run's checkpoint, `checkpoint.json`: written by the library's
//! [`plateau_free::lifecycle::Checkpoint`] (its header line: the format, the library's
//! version and the run's identity, compared on resume; its atomic replace; its cadence),
//! the state after it being a [`Checkpoint`]: the method's own saved run and what the path
//! tracer keeps besides.
//!
//! What the state holds: the task, the settings asked for on the command line and those the
//! run uses (they differ only when `--budget` planned them), the method (the library's
//! `PaperAskTell` for the paper's loop, `AskTell` for the adaptive search and the polished
//! loop, `BaselineAskTell` for finite differences and SPSA), the history so far,
//! the progress strip's points, every value told (for the stop rule's study), the renders and
//! the times spent. The identity adds the executable's hash: a run continued by another build
//! could differ in any bit (a changed renderer, estimator or compiler), and nothing short of
//! the binary itself says reliably that the code is the same.
//!
//! One file per job: `cadence.rs` (when a run writes it), `build.rs` (the executable's hash,
//! one-line messages), `error.rs` (why one is refused), `checks.rs` (whether its parts fit
//! together and fit the run asked for); this file holds the contents and their reading.

mod build;
mod cadence;
mod checks;
mod error;

pub(crate) use build::executable;
pub use build::{executable_hash, fnv1a, one_line, ONE_LINE_MAX};
pub use cadence::Every;
pub use error::CheckpointError;

use std::path::Path;

use plateau_free::baseline::BaselineAskTell;
use plateau_free::{vector::LeastSquaresAskTell, AskTell, PaperAskTell};
use serde::{Deserialize, Serialize};

use super::{Row, Settings};

/// The checkpoint's file name inside a run's directory.
pub const FILE: &str = "checkpoint.json";

/// The method's own saved run.
#[derive(Debug, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Progress {
    /// The paper's loop (`--method plateau`): the library's ask-and-tell loop.
    Loop(Box<PaperAskTell>),
    /// Finite differences and SPSA: the library's ask-and-tell loop with a baseline.
    Baseline(Box<BaselineAskTell>),
    /// The adaptive search and the polished loop: the library's ask-and-tell run.
    Adaptive(Box<AskTell>),
    /// The image method: the library's least-squares run asked and told.
    Image(Box<LeastSquaresAskTell>),
}

/// The state of `checkpoint.json`, after the library's header line.
#[derive(Debug, Serialize, Deserialize)]
pub struct Checkpoint {
    /// The task's name.
    pub task: String,
    /// The settings the command line asked for.
    pub requested: Settings,
    /// The settings the run uses (after `--budget`'s plan).
    pub settings: Settings,
    /// Whether the run has ended (all iterations, its time budget spent, its stop rule).
    pub finished: bool,
    /// The method's run.
    pub progress: Progress,
    /// `history.csv` so far: one row per completed iteration.
    pub history: Vec<Row>,
    /// The progress strip's points so far: the loop's theta at the strip's moments, the
    /// search's best point after every iteration (small tasks only).
    pub snapshots: Vec<Vec<f64>>,
    /// Every value told, in order (the adaptive search and the polished loop).
    pub values: Vec<f64>,
    /// The best value told so far (`None` before a finite one; the searches).
    pub best_value: Option<f64>,
    /// The best point so far (the start before any value; the searches).
    pub best_point: Vec<f64>,
    /// Renders of the objective so far.
    pub renders: usize,
    /// Optimisation time so far, seconds.
    pub optimisation_seconds: f64,
    /// Of which rendering for the loss, seconds.
    pub render_seconds: f64,
}

impl Checkpoint {
    /// Reads the checkpoint at `path` (the library's header, the state after it) and checks
    /// it whole: the library's format and version, the build, and that its parts fit
    /// together. Never panics, whatever the bytes.
    ///
    /// # Errors
    /// A [`CheckpointError`] naming the file and what is wrong.
    pub fn load(path: &Path) -> Result<Checkpoint, CheckpointError> {
        Checkpoint::read(path, true)
    }

    /// [`Checkpoint::load`] without the check of the build: to look into a finished run's
    /// record (the stop rule's study reads the values told).
    ///
    /// # Errors
    /// As [`Checkpoint::load`], but never [`CheckpointError::OtherBuild`].
    pub fn load_any_build(path: &Path) -> Result<Checkpoint, CheckpointError> {
        Checkpoint::read(path, false)
    }

    fn read(path: &Path, check_build: bool) -> Result<Checkpoint, CheckpointError> {
        let file = plateau_free::lifecycle::Checkpoint::new(path);
        let (identity, state) = match file.read_state() {
            Ok(Some(read)) => read,
            Ok(None) => {
                let error = std::io::Error::from(std::io::ErrorKind::NotFound);
                return Err(CheckpointError::Unreadable {
                    path: path.into(),
                    error,
                });
            }
            Err(e) => {
                return Err(CheckpointError::Damaged {
                    path: path.into(),
                    error: e.to_string(),
                })
            }
        };
        let found = identity
            .iter()
            .find(|(name, _)| name == "executable")
            .map_or_else(|| "absent".to_string(), |(_, v)| v.clone());
        let here = build::executable();
        if check_build && (found != here || here == "unknown") {
            return Err(CheckpointError::OtherBuild {
                path: path.into(),
                found,
            });
        }
        Checkpoint::parse(&state, path)
    }

    /// The state's bytes (what follows the library's header line), parsed and checked for
    /// consistency, the build not checked (to inspect a checkpoint, and for the fuzzer, whose
    /// inputs cannot know the executable's hash); `path` names them in errors.
    ///
    /// # Errors
    /// As [`Checkpoint::load`], but never [`CheckpointError::OtherBuild`].
    pub fn parse(bytes: &[u8], path: &Path) -> Result<Checkpoint, CheckpointError> {
        let c: Checkpoint =
            serde_json::from_slice(bytes).map_err(|e| CheckpointError::Damaged {
                path: path.into(),
                error: e.to_string(),
            })?;
        c.check_consistent()
            .map_err(|reason| CheckpointError::Inconsistent {
                path: path.into(),
                reason,
            })?;
        Ok(c)
    }
}

/// The fuzzers' one body, shared by the cargo-fuzz target (`fuzz/fuzz_targets/checkpoint.rs`)
/// and the bounded run in the ordinary tests (`tests/checkpoint.rs`): the loader on `bytes`
/// (as the state of the file `fuzz/checkpoint.json`, after the library's header), then what `--resume` does with a checkpoint that
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
    let c = match Checkpoint::parse(bytes, path) {
        Ok(c) => c,
        Err(e) => {
            clean(&e);
            return false;
        }
    };
    // What `Checkpoint::load` says of another build (the file's, any text).
    clean(&CheckpointError::OtherBuild {
        path: path.into(),
        found: c.task.clone(),
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
    match Checkpoint::parse(&again, path) {
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
