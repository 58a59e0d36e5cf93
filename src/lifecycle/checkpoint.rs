//! [`Checkpoint`]: a run saved to a file when due and at every end, and resumed from it
//! after the identity check; [`replace_file`], the atomic write it uses.

use std::fmt;
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use super::method::AskAndTell;
use crate::error::Error;

/// How often a [`Checkpoint`] writes by default, in seconds.
pub const CHECKPOINT_SECONDS: f64 = 30.0;

/// The version of the file's layout.
const FORMAT: u32 = 2;

/// The file's first line: what the state that follows belongs to.
#[derive(serde::Serialize, serde::Deserialize)]
struct Header {
    format: u32,
    version: String,
    identity: Vec<(String, String)>,
    /// The state's checksum ([`checksum`]): a file damaged after it was written is refused,
    /// never resumed with a state that is valid JSON but not the run's.
    checksum: String,
}

/// FNV-1a over `bytes`, in hex: enough to tell a damaged state from the one written.
fn checksum(bytes: &[u8]) -> String {
    let hash = bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3)
    });
    format!("{hash:016x}")
}

/// When a checkpoint is due.
#[derive(Debug, Clone, Copy)]
enum Every {
    Time(Duration),
    Iterations(usize),
}

/// A run saved to a file (feature `serde`): by a [`crate::lifecycle::Driver`], at the start
/// (so that a path that cannot be written fails before any evaluation), every
/// [`CHECKPOINT_SECONDS`] (or every `k` iterations) and at every end (done, interrupted),
/// atomically ([`replace_file`]). A write that fails during the run is told to the
/// observers ([`crate::lifecycle::Observer::not_saved`]) and the run goes on. When the driver starts and the file exists, the run
/// resumes from it: the file's settings are compared with the run given
/// ([`AskAndTell::identity`]: `x0`, `budget`, `seed`, `strategy`, the other options) and
/// the first that differs is an [`Error::CheckpointMismatch`] naming it. A resumed run goes
/// on bit for bit as the run left alone. A run that fails keeps the last file written.
///
/// The file is a line of JSON (the format, the library's version, the run's settings) and
/// the run's state in JSON ([`AskAndTell::save`]); it belongs to this library's version.
///
/// ```
/// use plateau_free::lifecycle::{Checkpoint, Driver, Interrupt, Observer, Progress};
/// use plateau_free::{Minimizer, Stop};
///
/// let path = std::env::temp_dir().join(format!("plateau-free-doc-{}.json", std::process::id()));
/// let f = |x: &[f64]| x.iter().map(|v| (v.round() - 1.0).powi(2)).sum::<f64>();
/// let m = Minimizer::new(f).budget(600).seed(3);
///
/// // Interrupted after 10 iterations (an observer triggers the stop): the file holds the run.
/// struct StopAt(usize, Interrupt);
/// impl Observer for StopAt {
///     fn observe(&mut self, p: &Progress) {
///         if p.iteration == self.0 { self.1.trigger() }
///     }
/// }
/// let stop = Interrupt::new();
/// let driver = Driver::new().interrupt(stop.clone()).observe(StopAt(10, stop));
/// let first = m.run_with(&[0.0; 3], driver.checkpoint(Checkpoint::new(&path)))?;
/// assert_eq!(first.stop, Stop::Interrupted);
///
/// // Resumed: the run left alone, bit for bit.
/// let resumed = m.run_with(&[0.0; 3], Driver::new().checkpoint(Checkpoint::new(&path)))?;
/// assert_eq!(resumed, m.run(&[0.0; 3])?);
///
/// // Another seed is another run.
/// let other = Minimizer::new(f).budget(600).seed(4);
/// let e = other.run_with(&[0.0; 3], Driver::new().checkpoint(Checkpoint::new(&path))).unwrap_err();
/// assert!(e.to_string().contains("seed is 3 there, 4 here"), "{e}");
/// std::fs::remove_file(&path)?;
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct Checkpoint {
    path: PathBuf,
    every: Every,
    /// The settings of the run the file holds (read from it, or taken from the run given).
    identity: Option<Vec<(String, String)>>,
    last_save: Instant,
    last_iteration: usize,
    resumed: bool,
    /// The state at the end of the last turn and its iteration ([`Checkpoint::remember`]).
    remembered: Option<(Vec<u8>, usize)>,
}

impl fmt::Debug for Checkpoint {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Checkpoint")
            .field("path", &self.path)
            .field("every", &self.every)
            .field("resumed", &self.resumed)
            .finish_non_exhaustive()
    }
}

impl Checkpoint {
    /// A checkpoint at `path`, written every [`CHECKPOINT_SECONDS`] and at every end.
    pub fn new(path: impl Into<PathBuf>) -> Checkpoint {
        Checkpoint {
            path: path.into(),
            every: Every::Time(Duration::from_secs_f64(CHECKPOINT_SECONDS)),
            identity: None,
            last_save: Instant::now(),
            last_iteration: 0,
            resumed: false,
            remembered: None,
        }
    }

    /// Written at most once per `every` (and at every end).
    #[must_use]
    pub fn every(mut self, every: Duration) -> Checkpoint {
        self.every = Every::Time(every);
        self
    }

    /// Written every `k` iterations instead of on a timer (and at every end; 0: only at the
    /// ends).
    ///
    /// ```
    /// use plateau_free::lifecycle::{Checkpoint, CHECKPOINT_SECONDS};
    /// let c = Checkpoint::new("run.json").every_iterations(100);
    /// assert_eq!(c.path(), std::path::Path::new("run.json"));
    /// assert!(!c.resumed());
    /// assert_eq!(CHECKPOINT_SECONDS, 30.0);
    /// ```
    #[must_use]
    pub fn every_iterations(mut self, k: usize) -> Checkpoint {
        self.every = Every::Iterations(k);
        self
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Whether the last run began from the file.
    pub fn resumed(&self) -> bool {
        self.resumed
    }

    /// Restores `run` (a fresh run) from the file, after checking the file's settings
    /// against the run's; `false` when the file does not exist (`run` unchanged).
    ///
    /// # Errors
    /// [`Error::Checkpoint`] for a file that cannot be read or is damaged, or of another
    /// format or library version; [`Error::CheckpointMismatch`] for another run's file.
    pub fn read<M: AskAndTell>(&self, run: &mut M) -> Result<bool, Error> {
        let Some((identity, state)) = self.read_state()? else {
            return Ok(false);
        };
        self.compare(&identity, &run.identity())?;
        run.restore(&state)
            .map(|()| true)
            .map_err(|e| self.error(inner_reason(e)))
    }

    /// The file's settings ([`AskAndTell::identity`], as saved) and the run's state (the
    /// bytes of [`AskAndTell::save`]), after the checks of the file's format, library
    /// version and checksum but with no run to compare with: to look into a checkpoint
    /// (which run it holds, how far it went) before making the run that resumes it. `None`
    /// when the file does not exist.
    ///
    /// ```
    /// use plateau_free::lifecycle::{AskAndTell, Checkpoint, Driver};
    /// use plateau_free::Minimizer;
    ///
    /// let path = std::env::temp_dir().join(format!("plateau-free-state-{}.json", std::process::id()));
    /// let checkpoint = Checkpoint::new(&path);
    /// assert!(checkpoint.read_state()?.is_none());
    /// let m = Minimizer::new(|x: &[f64]| x[0] * x[0]).budget(40).seed(5);
    /// m.run_with(&[1.0], Driver::new().checkpoint(Checkpoint::new(&path)))?;
    /// let (identity, state) = checkpoint.read_state()?.unwrap();
    /// assert!(identity.contains(&("seed".to_string(), "5".to_string())));
    /// let mut run = Minimizer::without_objective().budget(40).seed(5).ask_tell(&[1.0])?;
    /// run.restore(&state)?;
    /// assert_eq!(AskAndTell::evaluations(&run), 40);
    /// std::fs::remove_file(&path)?;
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    ///
    /// # Errors
    /// [`Error::Checkpoint`] for a file that cannot be read, is damaged (its header, or a
    /// state that does not match its checksum), or of another format or library version.
    #[allow(clippy::type_complexity)]
    pub fn read_state(&self) -> Result<Option<(Vec<(String, String)>, Vec<u8>)>, Error> {
        let mut bytes = match std::fs::read(&self.path) {
            Ok(bytes) => bytes,
            Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(None),
            Err(e) => return Err(self.error(format!("cannot be read: {e}"))),
        };
        let cut = bytes
            .iter()
            .position(|&b| b == b'\n')
            .unwrap_or(bytes.len());
        let header: Header = serde_json::from_slice(&bytes[..cut])
            .map_err(|e| self.error(format!("damaged header: {e}")))?;
        if header.format != FORMAT {
            let why = format!("has format {}, this version reads {FORMAT}", header.format);
            return Err(self.error(why));
        }
        let version = env!("CARGO_PKG_VERSION");
        if header.version != version {
            let why = format!(
                "written by plateau-free {}, this is {version}",
                header.version
            );
            return Err(self.error(why));
        }
        bytes.drain(..(cut + 1).min(bytes.len()));
        if checksum(&bytes) != header.checksum {
            return Err(self.error("damaged: the state does not match its checksum".into()));
        }
        Ok(Some((header.identity, bytes)))
    }

    /// The first setting of `given` that `saved` has otherwise.
    fn compare(&self, saved: &[(String, String)], given: &[(&str, String)]) -> Result<(), Error> {
        for (name, value) in given {
            let found = saved.iter().find(|(n, _)| n == name).map(|(_, v)| v);
            if found != Some(value) {
                return Err(Error::CheckpointMismatch {
                    path: self.path.display().to_string(),
                    field: (*name).to_string(),
                    saved: found.cloned().unwrap_or_else(|| "absent".into()),
                    given: value.clone(),
                });
            }
        }
        Ok(())
    }

    /// Writes `method`'s state now, atomically.
    ///
    /// # Errors
    /// [`Error::Checkpoint`] when the state or the file cannot be written (the file is then
    /// as before).
    pub fn save<M: AskAndTell>(&mut self, method: &M) -> Result<(), Error> {
        self.remember(method)?;
        self.write_remembered()
    }

    /// Keeps `method`'s state in memory (after a turn): what the file gets when it is due,
    /// and when the next turn fails halfway (an error or Ctrl-C inside an evaluation), so
    /// that the file always holds a whole turn's end.
    pub(crate) fn remember<M: AskAndTell>(&mut self, method: &M) -> Result<(), Error> {
        let mut state = Vec::new();
        method
            .save(&mut state)
            .map_err(|e| self.error(inner_reason(e)))?;
        self.identity
            .get_or_insert_with(|| owned(method.identity()));
        self.remembered = Some((state, method.iteration()));
        Ok(())
    }

    /// Writes the state [`Checkpoint::remember`] kept, if any, atomically.
    pub(crate) fn write_remembered(&mut self) -> Result<(), Error> {
        let (Some((state, iteration)), Some(identity)) = (&self.remembered, &self.identity) else {
            return Ok(());
        };
        let header = Header {
            format: FORMAT,
            version: env!("CARGO_PKG_VERSION").into(),
            identity: identity.clone(),
            checksum: checksum(state),
        };
        let mut bytes = serde_json::to_vec(&header).map_err(|e| self.error(e.to_string()))?;
        bytes.push(b'\n');
        bytes.extend_from_slice(state);
        // A write that fails is tried again when the next one is due, not at every turn.
        self.last_save = Instant::now();
        self.last_iteration = *iteration;
        replace_file(&self.path, &bytes).map_err(|e| self.error(format!("not written: {e}")))
    }

    /// The run to drive: the file's, when it exists, else `fresh`.
    pub(crate) fn begin<M: AskAndTell>(&mut self, fresh: M) -> Result<M, Error> {
        self.last_save = Instant::now();
        let identity = fresh.identity();
        if identity.is_empty() {
            return Err(self.error("this method's state cannot be saved".into()));
        }
        self.identity = Some(owned(identity));
        let mut run = fresh;
        self.resumed = self.read(&mut run)?;
        self.last_iteration = run.iteration();
        self.remember(&run)?;
        if !self.resumed {
            // A file that cannot be written fails the run now, before any evaluation.
            self.write_remembered()?;
        }
        Ok(run)
    }

    /// Whether a write is due after `iteration`.
    pub(crate) fn due(&self, iteration: usize) -> bool {
        match self.every {
            Every::Time(every) => self.last_save.elapsed() >= every,
            Every::Iterations(0) => false,
            Every::Iterations(k) => iteration >= self.last_iteration + k,
        }
    }

    fn error(&self, reason: String) -> Error {
        Error::Checkpoint {
            path: self.path.display().to_string(),
            reason,
        }
    }
}

/// The reason of a method's [`Error::Checkpoint`] (which names no path), else the error.
fn inner_reason(e: Error) -> String {
    match e {
        Error::Checkpoint { reason, .. } => reason,
        e => e.to_string(),
    }
}

fn owned(identity: Vec<(&'static str, String)>) -> Vec<(String, String)> {
    identity
        .into_iter()
        .map(|(n, v)| (n.to_string(), v))
        .collect()
}

/// Replaces `path` by `bytes` atomically: writes a temporary file beside it, syncs it to
/// disk, renames it over `path` and syncs the directory. A reader sees the old file or the
/// new one, never half of one; on error `path` is as before and no temporary file is left.
///
/// ```
/// let path = std::env::temp_dir().join(format!("plateau-free-replace-{}", std::process::id()));
/// plateau_free::lifecycle::replace_file(&path, b"one")?;
/// plateau_free::lifecycle::replace_file(&path, b"two")?;
/// assert_eq!(std::fs::read(&path)?, b"two");
/// std::fs::remove_file(&path)?;
/// # Ok::<(), std::io::Error>(())
/// ```
///
/// # Errors
/// The system's, when the directory cannot be written.
pub fn replace_file(path: &Path, bytes: &[u8]) -> io::Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let name = path
        .file_name()
        .map_or_else(|| "checkpoint".into(), |n| n.to_string_lossy().into_owned());
    let tmp = dir.join(format!(".{name}.tmp{}", std::process::id()));
    let result = (|| {
        let mut file = std::fs::File::create(&tmp)?;
        file.write_all(bytes)?;
        file.sync_all()?;
        drop(file);
        std::fs::rename(&tmp, path)?;
        // The rename itself on disk; some systems cannot sync a directory.
        if let Ok(d) = std::fs::File::open(dir) {
            let _ = d.sync_all();
        }
        Ok(())
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}
