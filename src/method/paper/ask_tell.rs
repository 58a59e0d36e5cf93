//! The paper's loop ([`Optimizer`] with a [`PlateauFreeGradient`]), asked and told: the
//! loop's engine (`mod.rs`) driven point by point, the estimator split into its draws and
//! its finish ([`Core`]) so that the points can be evaluated elsewhere.

use super::{Optimizer, Progress};
use crate::check;
use crate::error::Error;
use crate::estimator::{Core, Estimate, Pending, PlateauFreeGradient};
use crate::run::{count, Ask, History, OptimizerState, RunError};

/// The paper's loop ([`Optimizer`] with a [`PlateauFreeGradient`]), asked and told: each
/// iteration asks for the `N` points of one gradient estimate and takes the Adam step when
/// their values are told. Made by [`Optimizer::ask_tell`] or, from a saved state,
/// [`Optimizer::ask_tell_from`].
///
/// ```
/// use plateau_free::{Adam, Annealer, Optimizer, PlateauFreeGradient};
///
/// let f = |x: &[f64]| if x[0] + 2.0 * x[1] > 0.3 { 1.0 } else { 0.0 };
/// let new_opt = || Optimizer::new(Adam::new(0.02).unwrap(), Annealer::paper(0.5, 200).unwrap());
///
/// let grad = PlateauFreeGradient::without_objective().samples(8).seed(7);
/// let mut run = new_opt().ask_tell(grad, &[1.0, 1.0])?;
/// while let Some(ask) = run.ask()? {
///     let values: Vec<f64> = ask.points().iter().map(f).collect(); // anywhere, any order
///     run.tell(&values)?;
/// }
/// let told = run.finish();
///
/// // The callback form: the same run, bit for bit.
/// let mut grad = PlateauFreeGradient::new(f).samples(8).seed(7);
/// let called = new_opt().minimize(&mut grad, &[1.0, 1.0])?;
/// assert_eq!(told, called);
/// # Ok::<(), plateau_free::Error>(())
/// ```
///
/// With the `serde` feature it is `Serialize` and `Deserialize`, as [`crate::AskTell`] is: saved
/// after any tell or between an ask and its tell and read back, the run goes on bit for bit
/// (unlike [`PaperAskTell::state`], which repeats an iteration in progress). Reading back
/// checks the lengths of its vectors against theta's, as [`crate::AskTell`]'s does.
#[derive(Debug)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "serde", serde(try_from = "Unchecked"))]
pub struct PaperAskTell {
    optimizer: Optimizer,
    /// The estimator; [`crate::method::polished`] reads the told points from it.
    pub(crate) core: Core,
    progress: Progress,
    /// The iteration in progress: its spread and its estimate (drawn, or to be redrawn).
    current: Option<(f64, Pending)>,
    /// Whether the current iteration's points wait for their values.
    asked: bool,
    /// The estimate of the last completed iteration.
    last: Option<Estimate>,
}

/// [`PaperAskTell`]'s fields as read, before [`PaperAskTell::check`] of theta's dimension.
#[cfg(feature = "serde")]
#[derive(serde::Deserialize)]
struct Unchecked {
    optimizer: Optimizer,
    core: Core,
    progress: Progress,
    current: Option<(f64, Pending)>,
    asked: bool,
    last: Option<Estimate>,
}

#[cfg(feature = "serde")]
impl TryFrom<Unchecked> for PaperAskTell {
    type Error = Error;

    fn try_from(u: Unchecked) -> Result<PaperAskTell, Error> {
        let run = PaperAskTell {
            optimizer: u.optimizer,
            core: u.core,
            progress: u.progress,
            current: u.current,
            asked: u.asked,
            last: u.last,
        };
        run.check(run.progress.theta.len())?;
        Ok(run)
    }
}

impl Optimizer {
    /// An ask-and-tell run of this loop from `start`, with `estimator`'s configuration and
    /// stream position (its objective, if it has one, is not used: make it with
    /// [`PlateauFreeGradient::without_objective`]). Adam's moments start afresh, as in
    /// [`Optimizer::minimize`]. See [`PaperAskTell`].
    ///
    /// With bounds on Adam, `start` must lie inside the box, and every asked point lies
    /// inside it (the perturbations are clamped onto it, as in [`Optimizer::minimize`]).
    ///
    /// # Errors
    /// An empty or non-finite `start`, or one outside Adam's bounds
    /// ([`Error::OutsideBounds`]); an estimator configuration that
    /// [`PlateauFreeGradient::validate`] rejects.
    pub fn ask_tell<F>(
        self,
        estimator: PlateauFreeGradient<F>,
        start: &[f64],
    ) -> Result<PaperAskTell, Error> {
        let state = OptimizerState::new(start)?;
        self.ask_tell_from(estimator, state).map_err(Error::from)
    }

    /// [`Optimizer::ask_tell`] from a saved state (see [`OptimizerState`] and
    /// [`PaperAskTell::state`]): the continued run is bit for bit the uninterrupted one.
    ///
    /// # Errors
    /// A state that [`OptimizerState::validate`] rejects, or an estimator configuration
    /// that [`PlateauFreeGradient::validate`] rejects; the state comes back unused.
    pub fn ask_tell_from<F>(
        mut self,
        estimator: PlateauFreeGradient<F>,
        state: OptimizerState,
    ) -> Result<PaperAskTell, RunError> {
        let mut core = estimator.into_core();
        if let Err(error) = core.validate() {
            return Err(RunError {
                error,
                state: Box::new(state),
            });
        }
        let (progress, position) =
            self.begin(state, |lower, upper| core.set_bounds(lower, upper))?;
        if let Some(position) = position {
            core.set_position(position);
        }
        Ok(PaperAskTell {
            optimizer: self,
            core,
            progress,
            current: None,
            asked: false,
            last: None,
        })
    }
}

impl PaperAskTell {
    /// A read-back loop's parameters against the dimension `n`: theta (finite), Adam's
    /// moments and box, the estimator's box.
    #[cfg(feature = "serde")]
    pub(crate) fn check(&self, n: usize) -> Result<(), Error> {
        check::len("theta", self.progress.theta.len(), n)?;
        check::theta(&self.progress.theta)?;
        for theta in &self.progress.history.theta {
            check::len("history's theta", theta.len(), n)?;
        }
        if let Some((sigma, pending)) = &self.current {
            check::sigma(*sigma)?;
            pending.check(n)?;
        }
        self.optimizer.check(n)?;
        self.core.check(n, self.current.is_some())
    }

    /// The points of the next gradient estimate (`N` rows of theta's dimension) and their
    /// seeds (both members of an antithetic pair share one), or `None` once every iteration
    /// is done. After a [`PaperAskTell::tell`] whose values called for a redraw
    /// ([`crate::estimator::OnFailure::Resample`]), the same iteration's redrawn points.
    ///
    /// # Errors
    /// [`Error::AskPending`] if the last asked points still wait for their values; a
    /// perturbed point that overflows ([`Error::NonFinitePoint`]: then the run stays at the
    /// last completed iteration, and asks again draw the same points).
    pub fn ask(&mut self) -> Result<Option<Ask<'_>>, Error> {
        if self.asked {
            return Err(Error::AskPending);
        }
        let (sigma, mut pending) = match self.current.take() {
            Some(current) => current,
            None => {
                let Some(sigma) = self.optimizer.next_sigma(&self.progress) else {
                    return Ok(None);
                };
                check::sigma(sigma)?;
                (sigma, self.core.start(&self.progress.theta, false)?)
            }
        };
        let index = pending.index;
        if let Err(error) = self
            .core
            .draw_uniform(&self.progress.theta, sigma, &mut pending)
        {
            // As a failed iteration of the callback form: its streams are drawn again.
            self.core.set_position(index);
            return Err(error);
        }
        self.current = Some((sigma, pending));
        self.asked = true;
        let points = self.core.points(self.progress.theta.len());
        Ok(Some(Ask::new(points, self.core.seeds())))
    }

    /// Tells the values of the asked points, in their order: finishes the estimate and
    /// takes the Adam step (or, when a value is not finite and the estimator redraws,
    /// [`crate::estimator::OnFailure::Resample`], readies the redraw for the next ask).
    ///
    /// # Errors
    /// [`Error::NothingAsked`] without an ask waiting for values; [`Error::TellCount`] for
    /// the wrong number of values; [`Error::NonFiniteValue`] for a NaN or an infinity
    /// (beyond the estimator's redraws). After these the run is unchanged and the same
    /// points still wait for their values. An estimate or a step that overflows
    /// ([`Error::NonFiniteGradient`], [`Error::StepOverflow`]) leaves the run at the last
    /// completed iteration, as the callback form's [`RunError`] does: the next ask draws the
    /// same points again.
    pub fn tell(&mut self, values: &[f64]) -> Result<(), Error> {
        let (true, Some((sigma, pending))) = (self.asked, &mut self.current) else {
            return Err(Error::NothingAsked);
        };
        let sigma = *sigma;
        let index = pending.index;
        count(self.core.values_mut().len(), values.len())?;
        self.core.values_mut().copy_from_slice(values);
        let estimate = match self.core.finish_uniform(sigma, pending) {
            Ok(Some(estimate)) => estimate,
            Ok(None) => {
                self.asked = false; // the redraw waits for the next ask
                return Ok(());
            }
            Err(error) => {
                if !pending.is_drawn() {
                    // The draws are spent: the iteration starts over.
                    self.current = None;
                    self.asked = false;
                    self.core.set_position(index);
                }
                return Err(error);
            }
        };
        self.current = None;
        self.asked = false;
        if let Err(error) = self.optimizer.advance(&mut self.progress, sigma, &estimate) {
            self.core.set_position(index);
            return Err(error);
        }
        self.last = Some(estimate);
        Ok(())
    }

    /// Whether every iteration is done (the next ask gives `None`).
    pub fn is_done(&self) -> bool {
        self.optimizer.next_sigma(&self.progress).is_none()
    }

    /// Iterations completed.
    pub fn iteration(&self) -> usize {
        self.progress.iteration
    }

    /// The current parameters (after the last completed iteration's step).
    pub fn theta(&self) -> &[f64] {
        &self.progress.theta
    }

    /// The spread of the iteration in progress or the next one; `None` once done.
    pub fn sigma(&self) -> Option<f64> {
        match &self.current {
            Some((sigma, _)) => Some(*sigma),
            None => self.optimizer.next_sigma(&self.progress),
        }
    }

    /// The record of the completed iterations (with [`crate::run::HistoryKeep::Last`]`(k)`, of
    /// the last `k` to `2 k` of them while the run is in progress; [`PaperAskTell::finish`]
    /// and [`PaperAskTell::state`] keep exactly `k`).
    pub fn history(&self) -> &History {
        &self.progress.history
    }

    /// The gradient estimate of the last completed iteration (what the callback form's
    /// observer sees in [`crate::run::Step::estimate`]).
    pub fn last_estimate(&self) -> Option<&Estimate> {
        self.last.as_ref()
    }

    /// The optimiser (Adam with its moments so far, the annealer).
    pub fn optimizer(&self) -> &Optimizer {
        &self.optimizer
    }

    /// The state after the last completed iteration, to save and continue from
    /// ([`Optimizer::ask_tell_from`] or [`Optimizer::minimize_from`]); an iteration in
    /// progress is repeated by the continued run.
    pub fn state(&self) -> OptimizerState {
        let position = match &self.current {
            Some((_, pending)) => pending.index,
            None => self.core.position(),
        };
        self.optimizer
            .state_of(self.progress.clone(), Some(position))
    }

    /// Ends the run where it stands: the [`History`] that [`Optimizer::minimize`] returns
    /// (its last theta the point the run ended at; `stopped_early` if iterations remained).
    pub fn finish(self) -> History {
        self.optimizer.ended(self.progress)
    }

    /// The history as it stands, for a run ended early ([`PaperAskTell::finish`] without
    /// the end).
    pub(crate) fn so_far(&self) -> History {
        self.optimizer.ended(self.progress.clone())
    }
}
