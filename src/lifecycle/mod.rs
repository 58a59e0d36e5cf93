//! A run's lifecycle, written once for every method: a [`Driver`] runs any ask-and-tell
//! method ([`AskAndTell`]: [`crate::AskTell`], [`crate::PaperAskTell`],
//! [`crate::vector::LeastSquaresAskTell`]) with an objective. Each turn it checks the
//! [`Interrupt`], asks, evaluates the points (on [`Workers`]), tells, shows the
//! [`Observer`]s and, with the `serde` feature, writes the [`Checkpoint`] when it is due.
//!
//! - `method.rs`: [`AskAndTell`], what the driver needs of a method;
//! - `driver.rs`: [`Driver`] and [`Failure`], the error that carries the result so far;
//! - `interrupt.rs`: [`Interrupt`], a stop asked from anywhere (a Ctrl-C handler, a thread);
//! - `observe.rs`: [`Observer`], [`Progress`] and [`ProgressLine`], a plain progress line;
//! - `trace.rs`: [`Trace`], a bounded history of the run;
//! - `workers.rs`: [`Workers`], an ask's points evaluated on threads, bit-identical to one;
//! - `checkpoint.rs` (feature `serde`): [`Checkpoint`] and [`replace_file`].
//!
//! ```
//! use plateau_free::lifecycle::{Driver, Trace};
//! use plateau_free::{Minimizer, Stop};
//!
//! let f = |x: &[f64]| x.iter().map(|v| v * v).sum::<f64>();
//! let mut trace = Trace::new(100);
//! let best = Minimizer::new(f)
//!     .budget(2000)
//!     .target(1e-12)
//!     .run_with(&[1.0, -2.0], Driver::new().workers(2).observe(&mut trace))?;
//! assert_eq!(best.stop, Stop::Target);
//! assert_eq!(trace.rows().last().unwrap().evaluations, best.evaluations);
//! # Ok::<(), plateau_free::lifecycle::Failure<plateau_free::Minimum>>(())
//! ```

#[cfg(feature = "serde")]
mod checkpoint;
mod driver;
mod interrupt;
mod method;
mod observe;
mod trace;
mod workers;

#[cfg(feature = "serde")]
pub use checkpoint::{replace_file, Checkpoint, CHECKPOINT_SECONDS};
pub use driver::{Driver, Failure};
pub use interrupt::Interrupt;
pub use method::AskAndTell;
pub use observe::{Observer, Progress, ProgressLine, PROGRESS_SECONDS};
pub use trace::{Trace, TraceRow};
pub use workers::Workers;
