//! [`Strategy::Paper`] in a [`Minimizer`] run, written once: after the start, the paper's
//! loop (`paper/`, asked and told), one evaluation at its last iterate, and, with
//! [`Minimizer::polish`], the hand-over to the adaptive search (`adaptive/`) from the best
//! point seen with the loop's last spread.

use super::adaptive::Adaptive;
use super::paper::{Optimizer, PaperAskTell};
use crate::adam::Adam;
use crate::anneal::Annealer;
use crate::error::Error;
use crate::estimator::{OnFailure, PlateauFreeGradient};
use crate::objective::Points;
use crate::run::{Ask, FailurePolicy, Ledger, Minimum, Options, Stop};
// For the documentation's links only.
#[cfg(doc)]
use crate::{run::Strategy, Minimizer};

/// Mixed into the seed for the polish's random stream, so that it is not the loop's.
const POLISH_STREAM: u64 = 0x706f_6c69_7368_0001;

/// Under [`FailurePolicy::Continue`], how many times an estimate whose every point failed
/// (NaN or an infinity) is redrawn before the loop ends at its last iterate (and the polish,
/// if any, goes on from the best point): a loop whose estimates keep failing stands where
/// `f` fails all around it, and the adaptive search, which ranks failures, is the better
/// tool there.
pub(crate) const FAILURE_REDRAWS: usize = 10;

/// [`Strategy::Paper`] between asks: the loop, one evaluation at its last iterate, then the
/// polish, if any.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub(crate) struct Polished {
    /// `None` when the budget allows no iteration.
    run: Option<PaperAskTell>,
    iterations: usize,
    /// The spread of the last iteration.
    sigma: f64,
    /// The final evaluation's point (the loop's last iterate) and seed.
    last_point: Vec<f64>,
    last_seed: [u64; 1],
    final_asked: bool,
    /// The adaptive search after the loop ([`Minimizer::polish`]), once it has begun.
    polish: Option<Box<Adaptive>>,
    /// The loop ended before its schedule: an estimate failed beyond its redraws, or the
    /// redraws spent its share of the budget.
    #[cfg_attr(feature = "serde", serde(default))]
    loop_ended: bool,
    /// The loop's share of the budget (the final evaluation included) and the evaluations
    /// of one estimate: an estimate is asked only while it fits.
    #[cfg_attr(feature = "serde", serde(default))]
    share: Option<(usize, usize)>,
}

impl Polished {
    /// The loop from `x0` with [`Strategy::Paper`]'s settings and its share of the `budget`
    /// (the rest polishes).
    pub(crate) fn new(
        o: &Options,
        x0: &[f64],
        budget: usize,
        samples: usize,
        lr: f64,
        sigma0: f64,
    ) -> Result<Polished, Error> {
        let budget = budget - (budget as f64 * o.polish()).floor() as usize;
        // The start and the final evaluation (at the loop's last iterate) around the
        // iterations; with no iteration, the start alone.
        let iterations = budget.saturating_sub(2) / samples;
        let mut adam = Adam::new(lr)?;
        if let Some((lo, hi)) = &o.bounds {
            adam = adam.bounds(lo.clone(), hi.clone())?;
        }
        let (run, sigma) = if iterations > 0 {
            let annealer = Annealer::paper(sigma0, iterations)?;
            let sigma = annealer.sigma(iterations - 1);
            let mut grad = PlateauFreeGradient::without_objective()
                .samples(samples)
                .seed(o.seed);
            if o.on_failure == FailurePolicy::Continue {
                grad = grad.on_failure(OnFailure::Resample {
                    limit: FAILURE_REDRAWS,
                });
            }
            let opt = Optimizer::new(adam, annealer).record_theta(false);
            (Some(opt.ask_tell(grad, x0)?), sigma)
        } else {
            (None, sigma0)
        };
        Ok(Polished {
            run,
            iterations,
            sigma,
            last_point: x0.to_vec(),
            last_seed: [o.seed],
            final_asked: false,
            polish: None,
            loop_ended: false,
            share: Some((budget, samples)),
        })
    }

    /// A read-back run's vectors against the run's dimension `n`.
    #[cfg(feature = "serde")]
    pub(crate) fn check(&self, n: usize) -> Result<(), Error> {
        crate::check::len("final point", self.last_point.len(), n)?;
        if let Some(run) = &self.run {
            run.check(n)?;
        }
        match &self.polish {
            Some(polish) => polish.check(n),
            None => Ok(()),
        }
    }

    /// The spread of the first iteration.
    pub(crate) fn start_sigma(&self) -> f64 {
        match &self.run {
            Some(run) => run.optimizer().annealer().sigma(0),
            None => self.sigma,
        }
    }

    /// Iterations and restarts so far, and the spread of the next iteration.
    pub(crate) fn progress(&self) -> (usize, usize, f64) {
        match (&self.polish, &self.run) {
            (Some(polish), _) => polish.progress(),
            (None, Some(run)) => (run.iteration(), 0, run.sigma().unwrap_or(self.sigma)),
            (None, None) => (0, 0, self.sigma),
        }
    }

    /// Whether the budget allows the loop an iteration.
    pub(crate) fn has_iterations(&self) -> bool {
        self.run.is_some()
    }

    /// Whether the polish has begun.
    pub(crate) fn polishing(&self) -> bool {
        self.polish.is_some()
    }

    /// The loop's next estimate's points, else the final point, else the polish's.
    pub(crate) fn ask(&mut self, ledger: &Ledger) -> Result<Option<Ask<'_>>, Error> {
        if let Some(polish) = &mut self.polish {
            return polish.ask(ledger).map(Some);
        }
        // Redraws of failed estimates spend evaluations the schedule did not plan: the loop
        // ends when the next estimate and the final evaluation no longer fit its share.
        let fits = |(share, samples): (usize, usize)| ledger.evaluations + samples < share;
        if !self.loop_ended && self.run.as_ref().is_some_and(|run| !run.is_done()) {
            if self.share.is_none_or(fits) {
                return match &mut self.run {
                    Some(run) => run.ask(),
                    None => Ok(None),
                };
            }
            self.loop_ended = true;
            if let Some(sigma) = self.run.as_ref().and_then(PaperAskTell::sigma) {
                self.sigma = sigma;
            }
        }
        if self.final_asked {
            return Err(Error::AskPending);
        }
        if let Some(run) = &self.run {
            self.last_point.copy_from_slice(run.theta());
        }
        self.final_asked = true;
        let n = self.last_point.len();
        Ok(Some(Ask::new(
            Points::new(&self.last_point, n),
            &self.last_seed,
        )))
    }

    /// Takes the values of the asked points; the loop's end (a [`Minimum`]) after the final
    /// point's value, the run's end in the polish.
    pub(crate) fn tell(
        &mut self,
        ledger: &mut Ledger,
        values: &[f64],
    ) -> Result<Option<Minimum>, Error> {
        if let Some(polish) = &mut self.polish {
            return polish.tell(ledger, values);
        }
        let n = self.last_point.len();
        if self.final_asked {
            ledger.take(Points::new(&self.last_point, n), values)?;
            let stop = if ledger.target_reached() {
                Stop::Target
            } else {
                Stop::Budget
            };
            let iterations = match &self.run {
                Some(run) if self.loop_ended => run.iteration(),
                _ => self.iterations,
            };
            return Ok(Some(ledger.minimum(iterations, 0, self.sigma, stop)));
        }
        let Some(run) = &mut self.run else {
            return Err(Error::NothingAsked);
        };
        let sigma = run.sigma().unwrap_or(self.sigma);
        let ranked = ranked_values(&ledger.options, values, run.core.seeds());
        match run.tell(ranked.as_deref().unwrap_or(values)) {
            Ok(()) => {}
            Err(Error::NonFiniteValue { .. })
                if ledger.options.on_failure == FailurePolicy::Continue =>
            {
                // Failed beyond the redraws: the loop ends at its last iterate.
                ledger.count(run.core.points(n), values);
                self.loop_ended = true;
                self.sigma = sigma;
                return Ok(None);
            }
            Err(error) => return Err(error),
        }
        // The told points are still in the estimator's buffers.
        ledger.count(run.core.points(n), values);
        // As the adaptive search: the run ends after the iteration that saw a value at or
        // below the target, with no final evaluation and no polish.
        if ledger.target_reached() {
            let end = ledger.minimum(run.iteration(), 0, sigma, Stop::Target);
            return Ok(Some(end));
        }
        Ok(None)
    }

    /// The run's result at the loop's `end`, or `None` when the polish takes over: a search
    /// from the loop's best point whose spread starts at the loop's last one, with its own
    /// random stream, counting iterations on from the loop's.
    pub(crate) fn hand_over(&mut self, ledger: &Ledger, end: Minimum) -> Option<Minimum> {
        let o = &ledger.options;
        let polishes = self.polish.is_none()
            && o.polish() > 0.0
            && end.stop == Stop::Budget
            && ledger.evaluations < ledger.budget;
        if !polishes {
            return Some(end);
        }
        let mut start = o.clone();
        start.sigma0 = Some(end.sigma);
        start.sigma0_each = None;
        start.seed = o.seed ^ POLISH_STREAM;
        let polish = Adaptive::new(&start, &ledger.best.x).counting_from(end.iterations);
        let polish = polish.judged(o, ledger.budget);
        self.polish = Some(Box::new(polish));
        None
    }
}

/// Under [`FailurePolicy::Continue`], an estimate's values with its failed points (NaN or an
/// infinity) left out: a failed point takes its antithetic partner's value (a pair shares
/// its seed), so that the pair's difference, its whole share of the gradient, is zero; a
/// pair that failed twice takes the mean of the finite values. The schedule then spends no
/// evaluation on redraws. `None` when nothing failed, or when every point did (then the
/// estimate is redrawn).
fn ranked_values(o: &Options, values: &[f64], seeds: &[u64]) -> Option<Vec<f64>> {
    if o.on_failure != FailurePolicy::Continue || values.iter().all(|v| v.is_finite()) {
        return None;
    }
    let finite: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    if finite.is_empty() {
        return None;
    }
    let mean = crate::estimator::mean(&finite);
    let partner = |k: usize| {
        let j = k ^ 1;
        (j < values.len() && seeds[j] == seeds[k] && values[j].is_finite()).then(|| values[j])
    };
    let kept = |(k, &v): (usize, &f64)| {
        if v.is_finite() {
            v
        } else {
            partner(k).unwrap_or(mean)
        }
    };
    Some(values.iter().enumerate().map(kept).collect())
}
