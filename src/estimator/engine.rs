//! [`Core`], the estimator without its objective: an estimate's start, its draws and its
//! finish, the same calls for the callback form and for ask and tell.

use std::fmt;

use super::steps::{accumulate, write_points, Spreads, Stream, Uniform};
use super::{Bounds, Buffers, Core, Estimate, OnFailure, Pending, Settings};
use crate::check;
use crate::error::Error;
use crate::objective::Points;
use crate::sampling::Sampling;
use crate::seeding::{stream_seed, RESAMPLE_STREAM};

impl fmt::Debug for Core {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Core")
            .field("settings", &self.settings)
            .field("estimates", &self.estimates)
            .finish_non_exhaustive()
    }
}

impl Default for Core {
    /// The defaults of [`PlateauFreeGradient::new`].
    fn default() -> Self {
        Core {
            settings: Settings {
                samples: 2,
                sampling: Sampling::Radial,
                antithetic: true,
                orthogonal: false,
                seed: 0,
                parallel: false,
                on_failure: OnFailure::Fail,
                catch_panics: false,
            },
            bounds: None,
            estimates: 0,
            buffers: Buffers::default(),
        }
    }
}

impl Core {
    /// The configuration's rules ([`PlateauFreeGradient::validate`]).
    pub(crate) fn validate(&self) -> Result<(), Error> {
        self.settings.validate()?;
        match &self.bounds {
            Some(b) => check::bounds(&b.lower, &b.upper),
            None => Ok(()),
        }
    }

    /// A read-back estimator against theta's dimension `n`: its configuration and box, and,
    /// with an estimate `pending` (between [`Core::start`] and [`Core::finish`]), the sizes
    /// that `start` gave its buffers (without one, the next `start` sizes them).
    #[cfg(feature = "serde")]
    pub(crate) fn check(&self, n: usize, pending: bool) -> Result<(), Error> {
        self.validate()?;
        if let Some(b) = &self.bounds {
            b.check_dim(n)?;
        }
        if !pending {
            return Ok(());
        }
        let (b, draws, samples) = (&self.buffers, self.settings.draws(), self.settings.samples);
        check::len("estimator draws", b.raw.len(), (draws - 1) * n)?;
        check::len("estimator weights", b.weights.len(), draws * n)?;
        check::len("estimator scales", b.scales.len(), draws)?;
        check::len("estimator points", b.points.len(), samples * n)?;
        check::len("estimator seeds", b.seeds.len(), samples)?;
        check::len("estimator values", b.values.len(), samples)?;
        check::len("estimator differences", b.diffs.len(), draws)
    }

    /// The box every evaluated point is clamped onto.
    pub(crate) fn bounds(&self) -> Option<&Bounds> {
        self.bounds.as_ref()
    }

    /// Sets the box every evaluated point is clamped onto (checked).
    pub(crate) fn set_bounds(&mut self, lower: &[f64], upper: &[f64]) -> Result<(), Error> {
        self.bounds = Some(Bounds::new(lower, upper)?);
        Ok(())
    }

    /// Sets the box, unchecked: for the builder, whose box [`Core::validate`] checks.
    pub(crate) fn set_bounds_unchecked(&mut self, bounds: Bounds) {
        self.bounds = Some(bounds);
    }

    /// The index of the next estimate.
    pub(crate) fn position(&self) -> u64 {
        self.estimates
    }

    /// Moves the streams: the next estimate is estimate `position`.
    pub(crate) fn set_position(&mut self, position: u64) {
        self.estimates = position;
    }

    /// Starts an estimate at `theta`: checks what does not depend on the draws and sizes
    /// the buffers. Nothing is counted yet.
    pub(crate) fn start(&mut self, theta: &[f64], theta_checked: bool) -> Result<Pending, Error> {
        if theta.is_empty() {
            return Err(Error::EmptyTheta);
        }
        let settings = self.settings;
        self.validate()?;
        if let Some(bounds) = &self.bounds {
            bounds.check_dim(theta.len())?;
        }
        let (draws, samples, n) = (settings.draws(), settings.samples, theta.len());
        if self.buffers.try_reserve(draws, samples, n).is_err() {
            return Err(Error::InvalidParameter {
                name: "samples",
                value: samples.into(),
                reason: "times the dimension is more memory than can be allocated",
            });
        }
        self.buffers.resize(draws, samples, n);
        Ok(Pending {
            index: self.estimates,
            resampled: 0,
            first: Vec::new(),
            theta_checked,
            n: theta.len(),
        })
    }

    /// Draws the pending attempt's perturbations and writes its points and their seeds
    /// ([`Core::points`], [`Core::seeds`]). The estimate counts as made from here: one whose
    /// `f` fails or panics is still spent, so later estimates draw fresh perturbations.
    pub(super) fn draw<S: Spreads>(
        &mut self,
        theta: &[f64],
        spreads: S,
        pending: &mut Pending,
    ) -> Result<(), Error> {
        let settings = self.settings;
        let n = theta.len();
        let index = pending.index;
        let b = &mut self.buffers;
        let c_n = b.chi_mean(n);
        // Attempt 0 is the estimate as it always was; a redraw takes streams derived from
        // the seed, the index and the attempt: deterministic, and the same on any thread.
        let seed = if pending.resampled == 0 {
            settings.seed
        } else {
            stream_seed(
                settings.seed,
                index,
                RESAMPLE_STREAM ^ pending.resampled as u64,
            )
        };
        let stream = Stream { seed, index };
        // The first draw lives in the memory of the gradient that will be returned: the
        // estimate has to write that memory anyway, and one vector less is touched.
        pending.first = stream.draw(&settings, c_n, n, b);
        if let Err(point_error) = write_points(&settings, theta, spreads, &mut pending.first, b) {
            if !pending.theta_checked && pending.resampled == 0 {
                // Bad input is reported as such and does not consume an estimate.
                check::theta(theta)?;
            }
            self.estimates = index + 1;
            return Err(point_error);
        }
        if let Some(bounds) = &self.bounds {
            // The points only, after the draws: the weights, and so the estimate's formula,
            // are unchanged; the estimate is that of `f` composed with the projection.
            bounds.project(&mut b.points);
        }
        stream.objective_seeds(&settings, &mut b.seeds);
        // Counted before `f` runs: an estimate whose `f` panics is still spent.
        self.estimates = index + 1;
        Ok(())
    }

    /// [`Core::draw`] for one spread `sigma` (checked by the caller) in every coordinate.
    pub(crate) fn draw_uniform(
        &mut self,
        theta: &[f64],
        sigma: f64,
        pending: &mut Pending,
    ) -> Result<(), Error> {
        self.draw(theta, Uniform(sigma), pending)
    }

    /// [`Core::finish`] for one spread `sigma` in every coordinate.
    pub(crate) fn finish_uniform(
        &mut self,
        sigma: f64,
        pending: &mut Pending,
    ) -> Result<Option<Estimate>, Error> {
        self.finish(Uniform(sigma), pending)
    }

    /// The points of the drawn attempt, rows of theta's dimension `n`.
    pub(crate) fn points(&self, n: usize) -> Points<'_> {
        Points::new(&self.buffers.points, n)
    }

    /// The objective's seed of every point of the drawn attempt.
    pub(crate) fn seeds(&self) -> &[u64] {
        &self.buffers.seeds
    }

    /// Where the values of the drawn attempt's points go, in the points' order.
    pub(crate) fn values_mut(&mut self) -> &mut [f64] {
        &mut self.buffers.values
    }

    /// Finishes the attempt from its values: the estimate, or `None` when a non-finite value
    /// calls for a redraw ([`OnFailure::Resample`]; the next [`Core::draw`] makes it).
    ///
    /// # Errors
    /// A non-finite value beyond the policy's redraws ([`Error::NonFiniteValue`]): then the
    /// attempt is untouched and may be finished again with other values. An overflowing
    /// gradient ([`Error::NonFiniteGradient`]): the attempt is used up.
    pub(super) fn finish<S: Spreads>(
        &mut self,
        spreads: S,
        pending: &mut Pending,
    ) -> Result<Option<Estimate>, Error> {
        let settings = self.settings;
        let b = &mut self.buffers;
        let n = pending.n;
        if let Err(e) = check::values(&b.values, &b.points, n) {
            return match settings.on_failure {
                OnFailure::Resample { limit } if pending.resampled < limit => {
                    pending.resampled += 1;
                    Ok(None)
                }
                _ => Err(e),
            };
        }
        let gradient = accumulate(&settings, spreads, std::mem::take(&mut pending.first), b)?;
        let mean_value = mean(&b.values);
        Ok(Some(Estimate {
            gradient,
            evaluations: settings.samples * (pending.resampled + 1),
            mean_value,
            resampled: pending.resampled,
        }))
    }
}

/// The mean of finite values, itself always finite. Summing the shares `v / N` is the
/// usual form (and gives the usual bits); for values near `+-f64::MAX` the sum of the shares
/// can round past the largest finite number, and in units of the largest value it cannot.
pub(crate) fn mean(values: &[f64]) -> f64 {
    let n = values.len() as f64;
    let plain: f64 = values.iter().map(|v| v / n).sum();
    if plain.is_finite() {
        return plain;
    }
    let scale = values.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    values.iter().map(|v| v / scale).sum::<f64>() / n * scale
}
