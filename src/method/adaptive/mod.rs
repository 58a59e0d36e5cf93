//! The adaptive search, written once, as a state machine between asks: runs of a Gaussian
//! search distribution (`gaussian/`: its draws and its update), each restart with twice the
//! population, until the budget is spent, the target reached, or (without restarts) a run
//! converges. A restart starts from `x0`, a fresh search of the whole region; after a run
//! that found the best point again it starts from that point, so that the further runs the
//! done rule asks for on ties (`repeats.rs`) check the point where it lies instead of
//! searching for it again ([`crate::Minimizer::restart_from_best`] starts every restart
//! there). [`crate::run::Strategy::Adaptive`] of [`crate::AskTell`], and the polish after
//! the paper's loop (`../polished.rs`).

mod centre;
mod fold;
mod gaussian;
mod repeats;

use std::borrow::Cow;

use nalgebra::DVector;
use rand_xoshiro::Xoshiro256PlusPlus;

use crate::error::Error;
use crate::objective::Points;
use crate::run::{
    Ask, Ledger, Metric, Minimum, Options, Stall, Stop, DECODING_MIN_DIM, FULL_METRIC_MAX_DIM,
};
use gaussian::{floors, rng, Params, SearchGaussian};
use repeats::Repeats;

/// The adaptive search between asks: `Minimizer`'s loop over runs and generations, unrolled.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub(crate) struct Adaptive {
    rng: Xoshiro256PlusPlus,
    sigma0: f64,
    scales: Vec<f64>,
    full: bool,
    /// The low-rank-plus-diagonal metric ([`Metric::LowRank`]).
    #[cfg_attr(feature = "serde", serde(default))]
    low_rank: bool,
    /// The full metric diagonally decoded ([`Metric::Decoded`]).
    #[cfg_attr(feature = "serde", serde(default))]
    decoded: bool,
    lambda: usize,
    /// Where a run starts, in the search's space (the box's points unfolded: `fold.rs`).
    start: Vec<f64>,
    /// The search's start (`x0`) in that space, where restarts go back to; empty in a search
    /// read back from a checkpoint written before it was kept (its restarts stay at `start`).
    #[cfg_attr(feature = "serde", serde(default))]
    origin: Vec<f64>,
    iterations: usize,
    restarts: usize,
    /// The run in progress; `None` when the next ask starts one.
    dist: Option<SearchGaussian>,
    /// The asked generation's offsets (continuous coordinates repaired onto the bounds),
    /// while its values are awaited.
    asked: Option<Vec<DVector<f64>>>,
    #[cfg_attr(feature = "serde", serde(with = "crate::saved::floats"))]
    points: Vec<f64>,
    seeds: Vec<u64>,
    /// The stop rule ([`crate::Minimizer::stop_when_stalled`]), fed each generation's
    /// smallest value.
    #[cfg_attr(feature = "serde", serde(default))]
    stall: Option<Stall>,
    /// The best value seen when the run in progress began (`None` in a search read back from
    /// a checkpoint written before it was kept).
    #[cfg_attr(feature = "serde", serde(default))]
    run_reference: Option<f64>,
    /// The converged runs, for [`crate::Minimizer::patience`].
    #[cfg_attr(feature = "serde", serde(default))]
    repeats: Repeats,
}

impl Adaptive {
    pub(crate) fn new(o: &Options, x0: &[f64]) -> Adaptive {
        let n = x0.len();
        let (sigma0, scales) = start_spread(o, x0);
        let full = match o.metric {
            Metric::Full | Metric::Decoded => true,
            Metric::Diagonal | Metric::LowRank => false,
            Metric::Auto => n <= FULL_METRIC_MAX_DIM,
        };
        Adaptive {
            rng: rng(o.seed),
            sigma0,
            scales,
            full,
            low_rank: o.metric == Metric::LowRank,
            decoded: match o.metric {
                Metric::Decoded => true,
                Metric::Auto => (DECODING_MIN_DIM..=FULL_METRIC_MAX_DIM).contains(&n),
                _ => false,
            },
            lambda: o.population.unwrap_or_else(|| Params::default_lambda(n)),
            start: fold::unfold_discrete(x0, o),
            origin: fold::unfold_discrete(x0, o),
            iterations: 0,
            restarts: 0,
            dist: None,
            asked: None,
            points: Vec::new(),
            seeds: Vec::new(),
            stall: None,
            run_reference: None,
            repeats: Repeats::default(),
        }
    }

    /// The same search judged by the stop rule of `o` (if any), whose window is a fraction
    /// of `budget`, from its first generation.
    /// (The fraction was checked with the options.)
    pub(crate) fn judged(mut self, o: &Options, budget: usize) -> Adaptive {
        self.stall = o.stall.map(|f| Stall::checked(f, budget));
        self
    }

    /// The same search counting its iterations on from `iterations` (the polish continues
    /// the paper's loop's count).
    pub(crate) fn counting_from(mut self, iterations: usize) -> Adaptive {
        self.iterations = iterations;
        self
    }

    /// A read-back search's vectors against the run's dimension `n` (see
    /// `crate::AskTell`'s deserialisation).
    #[cfg(feature = "serde")]
    pub(crate) fn check(&self, n: usize) -> Result<(), Error> {
        use crate::check::len;
        len("adaptive start", self.start.len(), n)?;
        if !self.origin.is_empty() {
            len("adaptive origin", self.origin.len(), n)?;
        }
        len("adaptive scales", self.scales.len(), n)?;
        // A failed ask leaves its points beside the last generation's seeds: whole rows.
        let whole = self.points.len() - self.points.len() % n;
        len("adaptive points", self.points.len(), whole)?;
        if let Some(dist) = &self.dist {
            dist.check(n)?;
        }
        if let Some(stall) = &self.stall {
            stall.check()?;
        }
        self.repeats.check(n)?;
        if let Some(ys) = &self.asked {
            let Some(dist) = &self.dist else {
                return len("adaptive search asked without a distribution", 0, 1);
            };
            len("adaptive asked offsets", ys.len(), self.seeds.len())?;
            len("adaptive asked points", self.points.len(), ys.len() * n)?;
            if ys.len() > dist.p.lambda {
                len("adaptive asked offsets", ys.len(), dist.p.lambda)?;
            }
            for y in ys {
                len("adaptive asked offset", y.len(), n)?;
            }
        }
        Ok(())
    }

    /// The spread of the first generation.
    pub(crate) fn start_sigma(&self) -> f64 {
        self.sigma0
    }

    /// Iterations and restarts so far, and the spread of the next generation.
    pub(crate) fn progress(&self) -> (usize, usize, f64) {
        let sigma = self.dist.as_ref().map_or(self.sigma0, |d| d.sigma);
        (self.iterations, self.restarts, sigma)
    }

    /// Draws the next generation: its points and their seeds.
    pub(crate) fn ask(&mut self, ledger: &Ledger) -> Result<Ask<'_>, Error> {
        let (n, o) = (self.start.len(), &ledger.options);
        if self.asked.is_some() {
            return Err(Error::AskPending);
        }
        if self.dist.is_none() {
            self.run_reference = Some(ledger.best.fun);
            let best = fold::unfold_discrete(&ledger.best.x, o);
            self.repeats.begin(&best);
        }
        let dist = self.dist.get_or_insert_with(|| {
            let mut dist = SearchGaussian::new(
                &self.start,
                self.sigma0,
                &self.scales,
                self.lambda,
                self.full,
            );
            if self.low_rank {
                dist = dist.with_low_rank();
            }
            if self.decoded {
                dist = dist.with_decoding();
            }
            dist.mirrored = o.mirrored;
            dist.flat_growth = o.flat_growth;
            if let Some(steps) = &o.steps {
                dist.floors = floors(steps, self.lambda);
            }
            dist
        });
        let mut ys = dist.sample(&mut self.rng).ys;
        let count = ys.len().min(ledger.left());
        ys.truncate(count);
        self.points.clear();
        for y in ys.iter_mut() {
            let mut x = dist.point(y);
            // Into the box (`fold.rs`): the update learns from the clamped continuous
            // coordinates and from the discrete ones as drawn.
            if let Some(bounds) = &o.bounds {
                let steps = o.steps.as_deref();
                if fold::clamp_continuous(x.as_mut_slice(), bounds, steps) {
                    *y = (&x - &dist.mean) / dist.sigma;
                }
                fold::fold_discrete(x.as_mut_slice(), bounds, steps);
            }
            // Discrete coordinates are rounded for the evaluation only: the update learns
            // from the continuous offset, so that the spread along such a coordinate is
            // the search's, not the rounding's (which is 0 while the draws stay on the
            // mean's tread); only a selected draw that left the mean's tread is learnt from
            // at its grid point (`centre.rs`).
            o.snap(x.as_mut_slice());
            self.points.extend(x.iter());
        }
        if let Some(index) = self.points.iter().position(|v| !v.is_finite()) {
            return Err(Error::NonFinitePoint {
                sample: ledger.evaluations + index / n,
                index: index % n,
                value: self.points[index],
            });
        }
        let seed = o.seed ^ (self.iterations as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        self.seeds.clear();
        self.seeds.resize(count, seed);
        self.asked = Some(ys);
        Ok(Ask::new(Points::new(&self.points, n), &self.seeds))
    }

    /// Takes the asked generation's values: the best point, the budget, the target, the
    /// distribution's update and, when a run ends, the restart. Returns the result once the
    /// whole run has ended.
    pub(crate) fn tell(
        &mut self,
        ledger: &mut Ledger,
        values: &[f64],
    ) -> Result<Option<Minimum>, Error> {
        let (Some(ys), Some(dist)) = (&self.asked, &mut self.dist) else {
            return Err(Error::NothingAsked);
        };
        ledger.take(Points::new(&self.points, self.start.len()), values)?;
        self.iterations += 1;
        let end = |stop, sigma| Some(ledger.minimum(self.iterations, self.restarts, sigma, stop));
        if ledger.target_reached() {
            return Ok(end(Stop::Target, dist.sigma));
        }
        if ledger.evaluations >= ledger.budget || values.len() < dist.p.lambda {
            return Ok(end(Stop::Budget, dist.sigma));
        }
        // A failed point (NaN or an infinity, under FailurePolicy::Continue) ranks below
        // every finite value.
        let ranked = if values.iter().all(|v| v.is_finite()) {
            Cow::Borrowed(values)
        } else {
            Cow::Owned(values.iter().map(|&v| ranked_value(v)).collect())
        };
        if let Some(stall) = &mut self.stall {
            let smallest = ranked.iter().copied().fold(f64::INFINITY, f64::min);
            if stall.observe(values.len(), smallest) {
                return Ok(end(Stop::Stalled, dist.sigma));
            }
        }
        let run_end = if ranked.iter().all(|&v| v == f64::INFINITY) {
            dist.failed_generation()
        } else {
            let ys = centre::centred(ys, dist, &self.points, &ranked, &ledger.options);
            dist.update(&ys, &ranked, ledger.best.fun)
        };
        // A warm-up (diagonal metric: gaussian/'s `Tpa`) that drew nothing better than the
        // best value seen before the run found the spread and nothing else: while sigma was
        // far too wide the mean drifted to points worse than the start (on the texture task at
        // n = 12,288 the run had not come back below the start within 10^4 evaluations:
        // docs/results/large-scale.md). The run goes on from its start point with the spread
        // the warm-up found.
        if dist.warm_up_ended() && self.run_reference.is_some_and(|r| ledger.best.fun >= r) {
            dist.recentre(&self.start);
        }
        let sigma = dist.sigma;
        self.asked = None;
        if let Some(run_end) = run_end {
            let o = &ledger.options;
            if !o.restarts {
                return Ok(end(Stop::Converged, sigma));
            }
            let reference = self.run_reference.unwrap_or(f64::INFINITY);
            if self.repeats.judge(run_end, dist, reference, o.patience) {
                return Ok(end(Stop::Done, sigma));
            }
            self.restarts += 1;
            self.lambda *= 2;
            if o.restart_from_best || self.repeats.found_again() {
                self.start = fold::unfold_discrete(&ledger.best.x, o);
            } else if !self.origin.is_empty() {
                self.start.clone_from(&self.origin);
            }
            self.dist = None;
        }
        Ok(None)
    }
}

/// A told value as the search ranks it: a failed point (NaN or an infinity) below every
/// finite value.
fn ranked_value(v: f64) -> f64 {
    if v.is_finite() {
        v
    } else {
        f64::INFINITY
    }
}

/// The start spread and the covariance's starting scales: [`crate::Minimizer::sigma0_each`]
/// as given; else from the box's finite widths (an open coordinate gets the mean width's
/// spread); else from `x0`.
fn start_spread(o: &Options, x0: &[f64]) -> (f64, Vec<f64>) {
    let n = x0.len();
    if let Some(each) = &o.sigma0_each {
        let mean = each.iter().sum::<f64>() / n as f64;
        return (mean, each.iter().map(|s| s / mean).collect());
    }
    let from_x0 = || {
        let big = x0.iter().fold(1.0f64, |a, v| a.max(v.abs()));
        (o.sigma0.unwrap_or(0.5 * big), vec![1.0; n])
    };
    let Some((lo, hi)) = &o.bounds else {
        return from_x0();
    };
    let widths: Vec<f64> = lo.iter().zip(hi).map(|(l, u)| u - l).collect();
    let finite = widths.iter().filter(|w| w.is_finite());
    let count = finite.clone().count();
    if count == 0 {
        return from_x0();
    }
    let mean = finite.sum::<f64>() / count as f64;
    if mean > 0.0 {
        let scale = |w: &f64| {
            if w.is_finite() {
                (w / mean).max(1e-12)
            } else {
                1.0
            }
        };
        (
            o.sigma0.unwrap_or(0.25 * mean),
            widths.iter().map(scale).collect(),
        )
    } else {
        (o.sigma0.unwrap_or(1.0), vec![1.0; n])
    }
}
