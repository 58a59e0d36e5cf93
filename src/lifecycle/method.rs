//! [`AskAndTell`]: what the driver needs of a method, and its implementations for the
//! crate's ask-and-tell runs.

use crate::baseline::BaselineAskTell;
use crate::error::Error;
use crate::method::{AskTell, PaperAskTell};
use crate::run::{Ask, History, Minimum};
use crate::vector::{LeastSquaresAskTell, VectorMinimum};

/// An ask-and-tell method, as a [`crate::lifecycle::Driver`] runs it: points out, values
/// in, until the method is done. [`AskTell`] (the adaptive search, the paper's loop and its
/// polish), [`PaperAskTell`] (the paper's loop alone), [`BaselineAskTell`] (the paper's loop
/// with a baseline estimator) and [`LeastSquaresAskTell`] (vector values) implement it; so
/// can any method of your own.
///
/// ```
/// use plateau_free::lifecycle::AskAndTell;
/// use plateau_free::Minimizer;
///
/// let mut run = Minimizer::without_objective().budget(50).ask_tell(&[1.0])?;
/// while let Some(ask) = AskAndTell::ask(&mut run)? {
///     let values: Vec<f64> = ask.iter().map(|(x, _)| x[0] * x[0]).collect();
///     AskAndTell::tell(&mut run, &values)?;
/// }
/// assert_eq!(AskAndTell::evaluations(&run), 50);
/// let best = AskAndTell::finish(run)?;
/// assert!(best.fun < 1.0);
/// # Ok::<(), plateau_free::Error>(())
/// ```
pub trait AskAndTell {
    /// What the run gives back ([`Minimum`], [`History`], [`VectorMinimum`]).
    type Output;

    /// The next points and their seeds; `None` once the run is done.
    ///
    /// # Errors
    /// The method's: a point that overflows, an ask while points wait for values.
    fn ask(&mut self) -> Result<Option<Ask<'_>>, Error>;

    /// The values of the asked points: [`AskAndTell::values_per_point`] per point, in the
    /// points' order, flat.
    ///
    /// # Errors
    /// The method's: the wrong count, a value it refuses.
    fn tell(&mut self, values: &[f64]) -> Result<(), Error>;

    /// Values told per point: 1, or a least-squares run's outputs.
    fn values_per_point(&self) -> usize {
        1
    }

    /// Evaluations told so far.
    fn evaluations(&self) -> usize;

    /// The budget of evaluations, if the method has one.
    fn budget(&self) -> Option<usize> {
        None
    }

    /// Iterations completed.
    fn iteration(&self) -> usize;

    /// The current spread (NaN when the method has none).
    fn sigma(&self) -> f64;

    /// The best value so far (infinite before any). The paper's loop keeps no best point:
    /// its value is the mean of the last estimate's values.
    fn best_value(&self) -> f64;

    /// The result, once [`AskAndTell::ask`] has given `None`.
    ///
    /// # Errors
    /// The method's: [`Error::Unfinished`] before the end.
    fn finish(self) -> Result<Self::Output, Error>
    where
        Self: Sized;

    /// The result as it stands, for a run ended early (an interrupt, an error): the best
    /// point so far ([`crate::Stop::Interrupted`] in a [`Minimum`]).
    fn so_far(&self) -> Self::Output;

    /// The settings that make the run this run, by name, first the ones a user is likeliest
    /// to change: a checkpoint compares them before it resumes and names the first that
    /// differs. Empty (the default) for a method that cannot be saved: a checkpoint
    /// refuses it before the run begins.
    fn identity(&self) -> Vec<(&'static str, String)> {
        Vec::new()
    }

    /// Appends the run's whole state (JSON) to `out`, for a checkpoint.
    ///
    /// # Errors
    /// [`Error::Checkpoint`] for a method that cannot be saved (the default), or without
    /// the `serde` feature.
    fn save(&self, out: &mut Vec<u8>) -> Result<(), Error> {
        let _ = out;
        Err(unsaved())
    }

    /// Replaces this run's state with the one [`AskAndTell::save`] wrote into `bytes`. The
    /// run given is the fresh one of the same settings, so a method that wraps another can
    /// keep what is not state (a handle, a callback) and restore the rest.
    ///
    /// # Errors
    /// [`Error::Checkpoint`] for bytes that are not such a state, or for a method that
    /// cannot be saved (the default); the run is then unchanged.
    fn restore(&mut self, bytes: &[u8]) -> Result<(), Error> {
        let _ = bytes;
        Err(unsaved())
    }

    /// Evaluations whose value was a failure (NaN, an infinity, an error the method counts),
    /// for the progress shown; 0 for a method that counts none.
    fn failures(&self) -> usize {
        0
    }
}

/// The error of a method with no saved form.
fn unsaved() -> Error {
    Error::Checkpoint {
        path: String::new(),
        reason: "this method's state cannot be saved (it needs the serde feature and a \
                 serialisable method: AskTell or PaperAskTell)"
            .into(),
    }
}

/// A vector for an identity: whole when short, else its dimension and a hash of its bits.
fn vector_identity(x: &[f64]) -> String {
    if x.len() <= 8 {
        return format!("{x:?}");
    }
    let bytes: Vec<u8> = x.iter().flat_map(|v| v.to_bits().to_le_bytes()).collect();
    format!("dimension {} (hash {:016x})", x.len(), fnv1a(&bytes))
}

/// FNV-1a over `bytes`: the same input, the same hash.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// `save` and `load` of a serialisable method, as JSON.
#[cfg(feature = "serde")]
macro_rules! saved_as_json {
    () => {
        fn save(&self, out: &mut Vec<u8>) -> Result<(), Error> {
            serde_json::to_writer(out, self).map_err(|e| Error::Checkpoint {
                path: String::new(),
                reason: format!("state not written: {e}"),
            })
        }

        fn restore(&mut self, bytes: &[u8]) -> Result<(), Error> {
            *self = serde_json::from_slice(bytes).map_err(|e| Error::Checkpoint {
                path: String::new(),
                reason: format!("damaged state: {e}"),
            })?;
            Ok(())
        }
    };
}

impl AskAndTell for AskTell {
    type Output = Minimum;

    fn ask(&mut self) -> Result<Option<Ask<'_>>, Error> {
        AskTell::ask(self)
    }

    fn tell(&mut self, values: &[f64]) -> Result<(), Error> {
        AskTell::tell(self, values)
    }

    fn evaluations(&self) -> usize {
        AskTell::evaluations(self)
    }

    fn budget(&self) -> Option<usize> {
        Some(AskTell::budget(self))
    }

    fn iteration(&self) -> usize {
        AskTell::iteration(self)
    }

    fn sigma(&self) -> f64 {
        AskTell::sigma(self)
    }

    fn best_value(&self) -> f64 {
        self.best().map_or(f64::INFINITY, |(_, v)| v)
    }

    fn failures(&self) -> usize {
        AskTell::failures(self)
    }

    fn finish(self) -> Result<Minimum, Error> {
        AskTell::finish(self)
    }

    fn so_far(&self) -> Minimum {
        AskTell::so_far(self)
    }

    fn identity(&self) -> Vec<(&'static str, String)> {
        let o = self.options();
        vec![
            ("x0", vector_identity(self.x0())),
            ("budget", self.budget().to_string()),
            ("seed", o.seed.to_string()),
            ("strategy", format!("{:?}", o.strategy)),
            ("sigma0", format!("{:?}", o.sigma0)),
            (
                "bounds",
                o.bounds.as_ref().map_or("None".into(), |(lo, hi)| {
                    format!("{} to {}", vector_identity(lo), vector_identity(hi))
                }),
            ),
            ("target", format!("{:?}", o.target)),
            ("population", format!("{:?}", o.population)),
            ("restarts", o.restarts.to_string()),
            ("mirrored", o.mirrored.to_string()),
            ("flat_growth", o.flat_growth.to_string()),
            ("steps", format!("{:?}", o.steps)),
            ("metric", format!("{:?}", o.metric)),
            ("restart_from_best", o.restart_from_best.to_string()),
            ("polish", format!("{:?}", o.polish)),
            ("stop_when_stalled", format!("{:?}", o.stall)),
            ("on_failure", format!("{:?}", o.on_failure)),
        ]
    }

    #[cfg(feature = "serde")]
    saved_as_json!();
}

/// [`AskAndTell`] for a run of the paper's loop ([`PaperAskTell`], [`BaselineAskTell`]):
/// the same inherent methods, the estimator's settings named by `$estimator`.
macro_rules! paper_loop {
    ($run:ty, $estimator:expr) => {
        impl AskAndTell for $run {
            type Output = History;

            fn ask(&mut self) -> Result<Option<Ask<'_>>, Error> {
                <$run>::ask(self)
            }

            fn tell(&mut self, values: &[f64]) -> Result<(), Error> {
                <$run>::tell(self, values)
            }

            fn evaluations(&self) -> usize {
                self.history().evaluations
            }

            fn iteration(&self) -> usize {
                <$run>::iteration(self)
            }

            fn sigma(&self) -> f64 {
                let next = self.optimizer().annealer().sigma(self.iteration());
                match self.is_done() {
                    false => next,
                    true => self.history().sigma.last().copied().unwrap_or(f64::NAN),
                }
            }

            fn best_value(&self) -> f64 {
                self.last_estimate().map_or(f64::INFINITY, |e| e.mean_value)
            }

            fn finish(self) -> Result<History, Error> {
                Ok(<$run>::finish(self))
            }

            fn so_far(&self) -> History {
                <$run>::so_far(self)
            }

            fn identity(&self) -> Vec<(&'static str, String)> {
                let estimator: fn(&$run) -> String = $estimator;
                vec![
                    ("start", vector_identity(self.theta())),
                    ("optimizer", format!("{:?}", self.optimizer())),
                    ("estimator", estimator(self)),
                ]
            }

            #[cfg(feature = "serde")]
            saved_as_json!();
        }
    };
}

paper_loop!(PaperAskTell, |run| format!("{:?}", run.core));
paper_loop!(BaselineAskTell, |run| format!("{:?}", run.baseline()));

impl AskAndTell for LeastSquaresAskTell {
    type Output = VectorMinimum;

    fn ask(&mut self) -> Result<Option<Ask<'_>>, Error> {
        LeastSquaresAskTell::ask(self)
    }

    fn tell(&mut self, values: &[f64]) -> Result<(), Error> {
        LeastSquaresAskTell::tell(self, values)
    }

    fn values_per_point(&self) -> usize {
        self.outputs()
    }

    fn evaluations(&self) -> usize {
        LeastSquaresAskTell::evaluations(self)
    }

    fn budget(&self) -> Option<usize> {
        Some(LeastSquaresAskTell::budget(self))
    }

    fn iteration(&self) -> usize {
        self.result().nit
    }

    fn sigma(&self) -> f64 {
        LeastSquaresAskTell::sigma(self)
    }

    fn best_value(&self) -> f64 {
        self.fun()
    }

    fn failures(&self) -> usize {
        LeastSquaresAskTell::failures(self)
    }

    fn finish(self) -> Result<VectorMinimum, Error> {
        LeastSquaresAskTell::finish(&self)
    }

    fn so_far(&self) -> VectorMinimum {
        self.result()
    }

    fn identity(&self) -> Vec<(&'static str, String)> {
        // The options include the sparsity pattern, of any size: long text goes by its hash.
        let options = format!("{:?}", self.options());
        let options = match options.len() {
            0..=400 => options,
            len => format!("{len} characters (hash {:016x})", fnv1a(options.as_bytes())),
        };
        vec![("x0", vector_identity(self.theta())), ("options", options)]
    }

    #[cfg(feature = "serde")]
    fn save(&self, out: &mut Vec<u8>) -> Result<(), Error> {
        serde_json::to_writer(out, self).map_err(|e| Error::Checkpoint {
            path: String::new(),
            reason: format!("state not written: {e}"),
        })
    }

    #[cfg(feature = "serde")]
    fn restore(&mut self, bytes: &[u8]) -> Result<(), Error> {
        let run: LeastSquaresAskTell =
            serde_json::from_slice(bytes).map_err(|e| Error::Checkpoint {
                path: String::new(),
                reason: format!("damaged state: {e}"),
            })?;
        run.check()?;
        *self = run;
        Ok(())
    }
}
