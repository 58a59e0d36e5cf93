//! Why a checkpoint cannot be used.

use std::fmt;
use std::io;
use std::path::PathBuf;

use super::one_line;

/// Why a checkpoint cannot be used. Each says what differs or is wrong, and where.
#[derive(Debug)]
pub enum CheckpointError {
    /// The file cannot be read (missing, a directory, no permission).
    Unreadable {
        /// The file.
        path: PathBuf,
        /// What the system said.
        error: io::Error,
    },
    /// The file is not a checkpoint (truncated, corrupted, not JSON, fields missing, of
    /// another layout or library version).
    Damaged {
        /// The file.
        path: PathBuf,
        /// What the parser said (with the line and column).
        error: String,
    },
    /// Written by another build.
    OtherBuild {
        /// The file.
        path: PathBuf,
        /// The hash of the executable that wrote it.
        found: String,
    },
    /// Of another task or other settings.
    Mismatch {
        /// The file.
        path: PathBuf,
        /// The setting (`task`, `spp`, ...).
        setting: String,
        /// Its value in the file.
        found: String,
        /// Its value here.
        here: String,
    },
    /// Parses, but its parts do not fit together (a hand-edited or damaged file).
    Inconsistent {
        /// The file.
        path: PathBuf,
        /// What does not fit.
        reason: String,
    },
}

impl fmt::Display for CheckpointError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CheckpointError::Unreadable { path, error } => {
                write!(f, "checkpoint {} cannot be read: {error}", path.display())
            }
            CheckpointError::Damaged { path, error } => {
                let error = one_line(error);
                write!(f, "checkpoint {} is damaged: {error}", path.display())
            }
            CheckpointError::OtherBuild { path, found } => write!(
                f,
                "checkpoint {} was written by another build, pathtracer executable {}; this is {}",
                path.display(),
                one_line(found),
                super::build::executable()
            ),
            CheckpointError::Mismatch {
                path,
                setting,
                found,
                here,
            } => write!(
                f,
                "checkpoint: {} is {} in {}, {} here",
                one_line(setting),
                one_line(found),
                path.display(),
                one_line(here)
            ),
            CheckpointError::Inconsistent { path, reason } => {
                let reason = one_line(reason);
                write!(f, "checkpoint {} is inconsistent: {reason}", path.display())
            }
        }
    }
}

impl std::error::Error for CheckpointError {}
