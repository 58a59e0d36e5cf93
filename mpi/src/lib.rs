//! # plateau-free-mpi
//!
//! plateau-free's objective over MPI: rank 0 runs the optimiser, the other ranks evaluate.
//!
//! Every estimate of plateau hands all its points to [`plateau_free::Objective::evaluate_batch`] at
//! once. [`MpiBatch`] is an [`Objective`] that, on rank 0, cuts those points into contiguous
//! chunks, one per worker rank ([`chunk`]), sends each worker its chunk and the chunk's seeds,
//! and receives the values straight into their places in the output. The worker ranks run
//! [`serve`] with the real objective: evaluate the chunks they are sent until rank 0 says
//! stop.
//!
//! ```no_run
//! // Run as `mpirun -n 3 program`: rank 0 optimises, ranks 1 and 2 evaluate. (`no_run`:
//! // a doctest is one process; it cannot be started by mpirun.)
//! use mpi::traits::Communicator;
//! use plateau_free::{Minimizer, objective::Seeded};
//!
//! let f = Seeded(|x: &[f64], seed: u64| x.iter().map(|v| v.round().abs()).sum::<f64>()
//!     + (seed % 3) as f64 * 1e-3);
//! let universe = mpi::initialize().expect("MPI initialised twice");
//! let world = universe.world();
//! if world.rank() == 0 {
//!     let remote = plateau_free_mpi::MpiBatch::new(&world)?;
//!     let best = Minimizer::new(&remote).budget(2000).seed(1).run(&[3.0, -2.0])?;
//!     remote.finish(); // the workers leave `serve`
//!     println!("{:?} {}", best.x, best.fun);
//! } else {
//!     plateau_free_mpi::serve(&world, &f)?;
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! ## What stays the same
//! The result is the sequential run's, bit for bit, for any number of workers: the points
//! and seeds travel as they are, every value is written at its point's index (nothing
//! depends on the order in which replies arrive), and the optimiser on rank 0 is the one
//! that would run alone. Non-finite values pass through unchanged, so the estimator's
//! failure policy ([`plateau_free::estimator::OnFailure`]) sees them as it would locally.
//!
//! ## When something fails
//! - A worker's objective panics: the worker catches the panic, reports its message to rank
//!   0 and keeps serving. Rank 0 receives every other worker's reply (so no message is left
//!   in flight) and then panics with the worker's rank, the points and the message. Under
//!   [`plateau_free::PlateauFreeGradient::catch_panics`] that is [`plateau_free::Error::ObjectivePanicked`]
//!   like a local panic; otherwise it unwinds, [`MpiBatch`]'s `Drop` stops the workers, and
//!   every rank ends normally.
//! - A worker process dies (a segfault, an abort, `panic = "abort"`, a lost node): MPI's
//!   default error handler ends the job; with Open MPI, `mpirun` kills the other ranks and
//!   exits non-zero with the rank that failed. Nothing hangs, but rank 0 cannot recover.
//!
//! ## Threads
//! Only the thread that created the [`MpiBatch`] (and the one running [`serve`]) calls MPI.
//! An objective may use threads of its own (a renderer on rayon's pool); initialise with
//! `mpi::initialize_with_threading(mpi::Threading::Funneled)` to say so.

#![warn(missing_docs, missing_debug_implementations)]

use std::any::Any;
use std::fmt;
use std::ops::Range;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::time::{Duration, Instant};

use mpi::datatype::Equivalence;
use mpi::point_to_point::{Destination, MatchedReceiveVec, Message, Source, Status};
use mpi::topology::{Communicator, Process, Rank};
use mpi::Tag;
use plateau_free::{objective::Points, Objective};

/// Rank 0 to a worker: a chunk's header, `[dim, count, seed_0, ..., seed_{count-1}]`.
const TAG_WORK: Tag = 1;
/// Rank 0 to a worker: a chunk's points, `count * dim` values row after row (after `TAG_WORK`).
const TAG_POINTS: Tag = 2;
/// Rank 0 to a worker: leave [`serve`].
const TAG_STOP: Tag = 3;
/// A worker to rank 0: the chunk's `count` values.
const TAG_VALUES: Tag = 4;
/// A worker to rank 0: the objective panicked on the chunk; the message as UTF-8.
const TAG_PANICKED: Tag = 5;

/// The rank that runs the optimiser and hands out the points.
pub const ROOT: Rank = 0;

/// How a rank waits for its next message: rank 0 for the workers' values, a worker for its
/// next chunk.
///
/// MPI's blocking receive polls in a loop and keeps a core busy while it waits, which costs
/// nothing when every rank has a core of its own, and slows the job down when ranks share
/// cores (rank 0 beside the workers of its node, more ranks than cores): the waiting rank
/// takes the core a renderer's thread could use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Wait {
    /// Poll, then sleep: spin for the first 100 microseconds, then sleep a twentieth of the
    /// time waited so far (at most a millisecond) between polls. A reply arrives at most
    /// about 5% (or 1 ms) later than with [`Wait::Spin`]; a waiting rank uses almost no CPU.
    #[default]
    Backoff,
    /// MPI's blocking probe: the lowest latency, one core busy while waiting. For ranks with
    /// a core each.
    Spin,
}

/// The spinning phase of [`Wait::Backoff`].
const SPIN: Duration = Duration::from_micros(100);
/// The longest sleep of [`Wait::Backoff`].
const MAX_SLEEP: Duration = Duration::from_millis(1);

impl Wait {
    /// The next message from `process`, with any tag.
    fn probe(self, process: &Process<'_>) -> (Message, Status) {
        match self {
            Wait::Spin => process.matched_probe(),
            Wait::Backoff => {
                let started = Instant::now();
                loop {
                    if let Some(found) = process.immediate_matched_probe() {
                        return found;
                    }
                    let waited = started.elapsed();
                    if waited < SPIN {
                        std::hint::spin_loop();
                    } else {
                        std::thread::sleep((waited / 20).min(MAX_SLEEP));
                    }
                }
            }
        }
    }
}

/// Everything that can go wrong in setting up or serving, short of a process dying.
#[derive(Debug, thiserror::Error, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub enum Error {
    /// [`MpiBatch::new`] was called on a rank other than [`ROOT`].
    #[error("MpiBatch runs on rank 0 (the optimiser's), this is rank {rank}; the other ranks call plateau_free_mpi::serve")]
    NotRoot {
        /// The caller's rank.
        rank: Rank,
    },
    /// [`serve`] was called on [`ROOT`].
    #[error("plateau_free_mpi::serve runs on the worker ranks (1 and above); rank 0 runs the optimiser with an MpiBatch")]
    ServeOnRoot,
    /// The communicator has no rank besides [`ROOT`] to evaluate on.
    #[error("the communicator has {size} rank(s): an MpiBatch needs at least one worker besides rank 0 (start with mpirun -n 2 or more)")]
    NoWorkers {
        /// The communicator's size.
        size: Rank,
    },
    /// A worker received a message that does not follow this crate's protocol (another
    /// library sending on the same communicator, or a different version on rank 0).
    #[error("rank {rank} received a malformed message from rank 0 (tag {tag}): {what}")]
    Protocol {
        /// The worker's rank.
        rank: Rank,
        /// The message's tag.
        tag: Tag,
        /// What was wrong with it.
        what: String,
    },
}

/// The points worker `worker` (0-based: rank `worker + 1`) evaluates when an estimate of
/// `len` points is shared among `workers` workers: `worker * len / workers` up to
/// `(worker + 1) * len / workers`. The chunks are contiguous, cover `0..len` in order, differ
/// in length by at most one, and depend on nothing but the three numbers; with more workers
/// than points, some chunks are empty (those workers are not sent anything).
///
/// ```
/// let chunks: Vec<_> = (0..3).map(|k| plateau_free_mpi::chunk(8, 3, k)).collect();
/// assert_eq!(chunks, [0..2, 2..5, 5..8]);
/// assert_eq!(plateau_free_mpi::chunk(2, 3, 0), 0..0);
/// ```
///
/// # Panics
/// If `workers` is zero or `worker >= workers`.
pub fn chunk(len: usize, workers: usize, worker: usize) -> Range<usize> {
    assert!(
        worker < workers,
        "worker {worker} of {workers}: no such worker"
    );
    // u128: `worker * len` must not overflow for any usize inputs.
    let at = |k: usize| (k as u128 * len as u128 / workers as u128) as usize;
    at(worker)..at(worker + 1)
}

/// An [`Objective`] on rank 0 whose evaluations run on the other ranks of a communicator,
/// which are in [`serve`].
///
/// Each [`Objective::evaluate_batch`] sends worker `k` (rank `k + 1`) the points
/// [`chunk`]`(len, workers, k)` and their seeds, and receives its values into the same
/// places of `out`; [`Objective::evaluate`] sends its one point to rank 1. Hand it to any
/// of plateau-free's estimators or to [`plateau_free::Minimizer`] by reference (`&MpiBatch` is an
/// [`Objective`] too). End with [`MpiBatch::finish`] (or let it drop), which tells every
/// worker to leave [`serve`].
///
/// See the [crate documentation](crate) for an example.
pub struct MpiBatch<'c, C: Communicator> {
    comm: &'c C,
    workers: usize,
    wait: Wait,
}

impl<C: Communicator> fmt::Debug for MpiBatch<'_, C> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("MpiBatch")
            .field("workers", &self.workers)
            .field("wait", &self.wait)
            .finish()
    }
}

impl<'c, C: Communicator> MpiBatch<'c, C> {
    /// The objective on rank 0 of `comm`, whose ranks `1..size` are (or will be) in [`serve`].
    ///
    /// # Errors
    /// [`Error::NotRoot`] on any rank but 0; [`Error::NoWorkers`] if `comm` has one rank.
    pub fn new(comm: &'c C) -> Result<Self, Error> {
        let rank = comm.rank();
        if rank != ROOT {
            return Err(Error::NotRoot { rank });
        }
        let size = comm.size();
        if size < 2 {
            return Err(Error::NoWorkers { size });
        }
        Ok(MpiBatch {
            comm,
            workers: (size - 1) as usize,
            wait: Wait::default(),
        })
    }

    /// How rank 0 waits for the workers' values ([`Wait::Backoff`] unless set).
    pub fn wait(mut self, wait: Wait) -> Self {
        self.wait = wait;
        self
    }

    /// The number of worker ranks (the communicator's size less one).
    pub fn workers(&self) -> usize {
        self.workers
    }

    /// Tells every worker to leave [`serve`]. Dropping the `MpiBatch` does the same; `finish`
    /// says where it happens.
    pub fn finish(self) {
        // Drop sends the stop messages.
    }

    /// Sends every worker its chunk, then receives the values in order of rank. Returns the
    /// first panic a worker reported, after every reply is in.
    fn scatter_gather(
        &self,
        points: Points<'_>,
        seeds: &[u64],
        out: &mut [f64],
    ) -> Option<(Rank, Range<usize>, String)> {
        let len = points.len();
        assert!(
            seeds.len() == len && out.len() == len,
            "evaluate_batch: {len} points, {} seeds and {} outputs",
            seeds.len(),
            out.len()
        );
        let dim = points.dim();
        let flat = points.as_flat();
        let mut header = Vec::with_capacity(2 + len.div_ceil(self.workers));
        for k in 0..self.workers {
            let range = chunk(len, self.workers, k);
            if range.is_empty() {
                continue;
            }
            header.clear();
            header.extend([dim as u64, range.len() as u64]);
            header.extend_from_slice(&seeds[range.clone()]);
            let worker = self.comm.process_at_rank(k as Rank + 1);
            worker.send_with_tag(&header[..], TAG_WORK);
            worker.send_with_tag(&flat[range.start * dim..range.end * dim], TAG_POINTS);
        }
        let mut panicked = None;
        for k in 0..self.workers {
            let range = chunk(len, self.workers, k);
            if range.is_empty() {
                continue;
            }
            let rank = k as Rank + 1;
            let (message, status) = self.wait.probe(&self.comm.process_at_rank(rank));
            if status.tag() == TAG_PANICKED {
                let (text, _) = (message, status).matched_receive_vec::<u8>();
                panicked.get_or_insert((rank, range, String::from_utf8_lossy(&text).into_owned()));
            } else {
                let status = message.matched_receive_into(&mut out[range.clone()]);
                let got = status.count(f64::equivalent_datatype()) as usize;
                assert!(
                    status.tag() == TAG_VALUES && got == range.len(),
                    "rank {rank} replied with tag {} and {got} values to {} points: is every other rank in plateau_free_mpi::serve?",
                    status.tag(),
                    range.len()
                );
            }
        }
        panicked
    }
}

impl<C: Communicator> Objective for MpiBatch<'_, C> {
    /// Evaluates `point` on rank 1.
    fn evaluate(&self, point: &[f64], seed: u64) -> f64 {
        let mut out = [0.0];
        self.evaluate_batch(Points::new(point, point.len()), &[seed], &mut out);
        out[0]
    }

    /// Evaluates the points on the workers, [`chunk`] by chunk.
    ///
    /// # Panics
    /// If a worker's objective panicked (after every worker has replied), with the rank,
    /// the points and the worker's message.
    fn evaluate_batch(&self, points: Points<'_>, seeds: &[u64], out: &mut [f64]) {
        if let Some((rank, range, message)) = self.scatter_gather(points, seeds, out) {
            panic!(
                "the objective panicked on rank {rank} (points {}..{} of {}): {message}",
                range.start,
                range.end,
                points.len()
            );
        }
    }
}

/// The same objective by reference, so that rank 0 keeps the `MpiBatch` to
/// [`finish`](MpiBatch::finish) after the estimator or minimiser that borrowed it.
impl<C: Communicator> Objective for &MpiBatch<'_, C> {
    fn evaluate(&self, point: &[f64], seed: u64) -> f64 {
        (**self).evaluate(point, seed)
    }

    fn evaluate_batch(&self, points: Points<'_>, seeds: &[u64], out: &mut [f64]) {
        (**self).evaluate_batch(points, seeds, out)
    }
}

impl<C: Communicator> Drop for MpiBatch<'_, C> {
    fn drop(&mut self) {
        for k in 0..self.workers {
            self.comm
                .process_at_rank(k as Rank + 1)
                .send_with_tag(&[0u64][..], TAG_STOP);
        }
    }
}

/// What a worker did in [`serve`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Served {
    /// Chunks received.
    pub chunks: usize,
    /// Points evaluated.
    pub points: usize,
    /// Chunks on which the objective panicked (each reported to rank 0).
    pub panics: usize,
}

/// Evaluates, on a worker rank, the chunks rank 0's [`MpiBatch`] sends, with `objective`'s
/// [`Objective::evaluate_batch`], until rank 0 finishes its `MpiBatch`; returns what it did.
/// Waits for each chunk with [`Wait::Backoff`] ([`serve_with`] chooses).
///
/// A panic of `objective` is caught, reported to rank 0 (whose `MpiBatch` panics with it) and
/// counted; the worker goes on serving. See the [crate documentation](crate) for an example.
///
/// # Errors
/// [`Error::ServeOnRoot`] on rank 0; [`Error::Protocol`] if a message from rank 0 does not
/// follow the protocol (the worker stops serving then, and rank 0 would wait for its reply:
/// end the job, e.g. with `world.abort(1)`).
pub fn serve<C, O>(comm: &C, objective: &O) -> Result<Served, Error>
where
    C: Communicator,
    O: Objective + ?Sized,
{
    serve_with(comm, objective, Wait::default())
}

/// [`serve`], waiting for each chunk as `wait` says.
///
/// # Errors
/// As [`serve`].
pub fn serve_with<C, O>(comm: &C, objective: &O, wait: Wait) -> Result<Served, Error>
where
    C: Communicator,
    O: Objective + ?Sized,
{
    let rank = comm.rank();
    if rank == ROOT {
        return Err(Error::ServeOnRoot);
    }
    let root = comm.process_at_rank(ROOT);
    let mut served = Served::default();
    let (mut points, mut values) = (Vec::new(), Vec::new());
    loop {
        let (message, status) = wait.probe(&root);
        let tag = status.tag();
        let (header, _) = (message, status).matched_receive_vec::<u64>();
        let protocol = |what: String| Error::Protocol { rank, tag, what };
        match tag {
            TAG_STOP => return Ok(served),
            TAG_WORK => {}
            _ => return Err(protocol("expected a chunk or a stop".into())),
        }
        let (dim, count) = match header[..] {
            [dim, count, ..] if dim > 0 && header.len() as u64 == 2 + count => {
                (dim as usize, count as usize)
            }
            _ => {
                return Err(protocol(format!(
                    "a header of {} words is not [dim > 0, count, count seeds]",
                    header.len()
                )))
            }
        };
        let seeds = &header[2..];
        points.resize(count * dim, 0.0);
        let status = root.receive_into_with_tag(&mut points[..], TAG_POINTS);
        let got = status.count(f64::equivalent_datatype()) as usize;
        if got != count * dim {
            return Err(Error::Protocol {
                rank,
                tag: TAG_POINTS,
                what: format!("{got} coordinates for {count} points of dimension {dim}"),
            });
        }
        values.clear();
        values.resize(count, 0.0);
        served.chunks += 1;
        served.points += count;
        let run = catch_unwind(AssertUnwindSafe(|| {
            objective.evaluate_batch(Points::new(&points, dim), seeds, &mut values)
        }));
        match run {
            Ok(()) => root.send_with_tag(&values[..], TAG_VALUES),
            Err(payload) => {
                served.panics += 1;
                root.send_with_tag(panic_message(&*payload).as_bytes(), TAG_PANICKED);
            }
        }
    }
}

/// The text of a panic's payload (`panic!` with a literal or a format), or a placeholder.
fn panic_message(payload: &(dyn Any + Send)) -> &str {
    if let Some(s) = payload.downcast_ref::<&str>() {
        s
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s
    } else {
        "(a panic with a payload that is not a string)"
    }
}
