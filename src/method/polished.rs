//! [`Strategy::Paper`] in a [`Minimizer`] run, written once: after the start, the paper's
//! loop (`paper/`, asked and told), one evaluation at its last iterate, and, with
//! [`Minimizer::polish`], the hand-over to the adaptive search (`adaptive/`) from the best
//! point seen with the loop's last spread.

use super::adaptive::Adaptive;
use super::paper::{Optimizer, PaperAskTell};
use crate::adam::Adam;
use crate::anneal::Annealer;
use crate::error::Error;
use crate::estimator::PlateauFreeGradient;
use crate::objective::Points;
use crate::run::{Ask, Ledger, Minimum, Options, Stop};
// For the documentation's links only.
#[cfg(doc)]
use crate::{Minimizer, Strategy};

/// Mixed into the seed for the polish's random stream, so that it is not the loop's.
const POLISH_STREAM: u64 = 0x706f_6c69_7368_0001;

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
        let budget = budget - (budget as f64 * o.polish).floor() as usize;
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
            let grad = PlateauFreeGradient::without_objective()
                .samples(samples)
                .seed(o.seed);
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
        if self.run.as_ref().is_some_and(|run| !run.is_done()) {
            return match &mut self.run {
                Some(run) => run.ask(),
                None => Ok(None),
            };
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
            return Ok(Some(ledger.minimum(self.iterations, 0, self.sigma, stop)));
        }
        let Some(run) = &mut self.run else {
            return Err(Error::NothingAsked);
        };
        let sigma = run.sigma().unwrap_or(self.sigma);
        run.tell(values)?;
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
            && o.polish > 0.0
            && end.stop == Stop::Budget
            && ledger.evaluations < ledger.budget;
        if !polishes {
            return Some(end);
        }
        let mut start = o.clone();
        start.sigma0 = Some(end.sigma);
        start.seed = o.seed ^ POLISH_STREAM;
        let polish = Adaptive::new(&start, &ledger.best.x).counting_from(end.iterations);
        let polish = polish.judged(o, ledger.budget);
        self.polish = Some(Box::new(polish));
        None
    }
}
