//! `Annealer`: the spread sigma as a function of the iteration.

use std::f64::consts::PI;
use std::fmt;
use std::str::FromStr;

use crate::check;
use crate::error::Error;

/// The shape of a schedule.
///
/// Its name, as a command line or a CSV file spells it, is one of `constant`,
/// `warm-linear:<warmup>` (the warm-up fraction written out, `warm-linear:0.5` for the
/// paper's), `exponential`, `cosine`: [`Display`](fmt::Display) writes it, [`FromStr`] reads
/// it (ignoring ASCII case), and with the `serde` feature the variants serialise under the
/// same kebab-case names.
///
/// ```
/// use plateau_free::anneal::Schedule;
/// let paper = Schedule::WarmLinear { warmup: 0.5 };
/// assert_eq!(paper.to_string(), "warm-linear:0.5");
/// assert_eq!("warm-linear:0.5".parse::<Schedule>()?, paper);
/// assert_eq!("Cosine".parse::<Schedule>()?, Schedule::Cosine);
/// assert!("warm-linear:1.5".parse::<Schedule>().is_err());
/// # Ok::<(), plateau_free::Error>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(rename_all = "kebab-case")
)]
pub enum Schedule {
    /// Sigma stays at `sigma0`.
    Constant,
    /// The paper's: `sigma0` for the first `warmup` fraction of the run, then linear to
    /// `sigma_min`, reached at the last iteration.
    WarmLinear {
        /// The fraction of iterations spent at `sigma0`, in `[0, 1)`.
        warmup: f64,
    },
    /// Geometric decay from `sigma0` to `sigma_min` over the run.
    Exponential,
    /// Half a cosine from `sigma0` down to `sigma_min` over the run.
    Cosine,
}

impl Schedule {
    /// Checks the schedule's own parameter (the warm-up fraction must lie in `[0, 1)`).
    ///
    /// ```
    /// use plateau_free::anneal::Schedule;
    /// assert!(Schedule::WarmLinear { warmup: 1.0 }.validate().is_err());
    /// assert!(Schedule::Cosine.validate().is_ok());
    /// ```
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming `warmup` and its value.
    pub fn validate(&self) -> Result<(), Error> {
        match *self {
            Schedule::WarmLinear { warmup } => check::unit_interval("warmup", warmup),
            _ => Ok(()),
        }
    }
}

impl fmt::Display for Schedule {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Schedule::Constant => f.write_str("constant"),
            // `{}` of an f64 is the shortest text that reads back to the same bits.
            Schedule::WarmLinear { warmup } => write!(f, "warm-linear:{warmup}"),
            Schedule::Exponential => f.write_str("exponential"),
            Schedule::Cosine => f.write_str("cosine"),
        }
    }
}

impl FromStr for Schedule {
    type Err = Error;

    /// Reads the spellings that [`Display`](fmt::Display) writes, ignoring ASCII case.
    ///
    /// # Errors
    /// [`Error::UnknownName`] for an unknown name or a warm-up that is not a number;
    /// [`Error::InvalidParameter`] for a warm-up outside `[0, 1)`.
    fn from_str(text: &str) -> Result<Self, Error> {
        let unknown = || Error::UnknownName {
            what: "schedule",
            value: text.to_owned(),
            allowed: "constant, warm-linear:<fraction in [0, 1)>, exponential, cosine",
        };
        let lower = text.trim().to_ascii_lowercase();
        let schedule = match lower.as_str() {
            "constant" => Schedule::Constant,
            "exponential" => Schedule::Exponential,
            "cosine" => Schedule::Cosine,
            other => {
                let warmup = other.strip_prefix("warm-linear:").ok_or_else(unknown)?;
                Schedule::WarmLinear {
                    warmup: warmup.parse().map_err(|_| unknown())?,
                }
            }
        };
        schedule.validate()?;
        Ok(schedule)
    }
}

/// The spread of the smoothing kernel for each iteration of a run of `iterations`
/// iterations. Never below `sigma_min` (nor above `sigma0`); iterations past the end answer
/// the final value.
///
/// ```
/// use plateau_free::Annealer;
/// let a = Annealer::paper(0.5, 400)?;          // warm start for half the run, then linear
/// assert_eq!(a.sigma(0), 0.5);
/// assert_eq!(a.sigma(199), 0.5);
/// assert!((a.sigma(399) - 0.01).abs() < 1e-15);
/// assert!((a.sigma(10_000) - 0.01).abs() < 1e-15);
/// # Ok::<(), plateau_free::Error>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Annealer {
    sigma0: f64,
    sigma_min: f64,
    iterations: usize,
    schedule: Schedule,
}

/// The paper's floor: "sigma_m = 0.01 for all experiments ... to avoid numerical
/// instabilities" (supplemental Sec. 1).
pub const PAPER_SIGMA_MIN: f64 = 0.01;
/// The paper's warm-start fraction: "approx. 50 % of the optimization".
pub const PAPER_WARMUP: f64 = 0.5;

impl Annealer {
    /// A schedule of any shape. If `sigma0 <= sigma_min` the schedule is constant at `sigma0`.
    ///
    /// # Errors
    /// `sigma0` or `sigma_min` not finite and positive, zero iterations, a warm-up fraction
    /// outside `[0, 1)`.
    pub fn new(
        schedule: Schedule,
        sigma0: f64,
        sigma_min: f64,
        iterations: usize,
    ) -> Result<Self, Error> {
        check::positive("sigma0", sigma0)?;
        check::positive("sigma_min", sigma_min)?;
        check::at_least_one("iterations", iterations)?;
        schedule.validate()?;
        Ok(Annealer {
            sigma0,
            sigma_min: sigma_min.min(sigma0),
            iterations,
            schedule,
        })
    }

    /// The paper's schedule: `sigma0` for half the run, then linear to 0.01 at the last
    /// iteration.
    ///
    /// # Errors
    /// As [`Annealer::new`].
    pub fn paper(sigma0: f64, iterations: usize) -> Result<Self, Error> {
        Self::new(
            Schedule::WarmLinear {
                warmup: PAPER_WARMUP,
            },
            sigma0,
            PAPER_SIGMA_MIN,
            iterations,
        )
    }

    /// A constant spread (the "no annealing" ablation).
    ///
    /// # Errors
    /// As [`Annealer::new`].
    pub fn constant(sigma: f64, iterations: usize) -> Result<Self, Error> {
        Self::new(Schedule::Constant, sigma, sigma, iterations)
    }

    /// Geometric decay from `sigma0` to `sigma_min`.
    ///
    /// # Errors
    /// As [`Annealer::new`].
    pub fn exponential(sigma0: f64, sigma_min: f64, iterations: usize) -> Result<Self, Error> {
        Self::new(Schedule::Exponential, sigma0, sigma_min, iterations)
    }

    /// Cosine decay from `sigma0` to `sigma_min`.
    ///
    /// # Errors
    /// As [`Annealer::new`].
    pub fn cosine(sigma0: f64, sigma_min: f64, iterations: usize) -> Result<Self, Error> {
        Self::new(Schedule::Cosine, sigma0, sigma_min, iterations)
    }

    /// The spread at the start.
    pub fn sigma0(&self) -> f64 {
        self.sigma0
    }

    /// The floor.
    pub fn sigma_min(&self) -> f64 {
        self.sigma_min
    }

    /// The length of the run the schedule spans.
    pub fn iterations(&self) -> usize {
        self.iterations
    }

    /// The schedule's shape.
    pub fn schedule(&self) -> Schedule {
        self.schedule
    }

    /// Sigma at `iteration` (counted from 0).
    pub fn sigma(&self, iteration: usize) -> f64 {
        let last = (self.iterations - 1) as f64;
        let t = (iteration as f64).min(last);
        let (s0, s1) = (self.sigma0, self.sigma_min);
        // Progress through the decaying part, in [0, 1].
        let progress = |start: f64| {
            if last <= start {
                1.0
            } else {
                ((t - start) / (last - start)).clamp(0.0, 1.0)
            }
        };
        let sigma = match self.schedule {
            Schedule::Constant => s0,
            Schedule::WarmLinear { warmup } => {
                let start = (warmup * self.iterations as f64).floor();
                if t < start {
                    s0
                } else {
                    s0 + (s1 - s0) * progress(start)
                }
            }
            Schedule::Exponential => s0 * (s1 / s0).powf(progress(0.0)),
            Schedule::Cosine => s1 + (s0 - s1) * 0.5 * (1.0 + (PI * progress(0.0)).cos()),
        };
        sigma.clamp(s1, s0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_schedule_starts_at_sigma0_ends_at_floor_and_never_rises() {
        for schedule in [
            Schedule::WarmLinear { warmup: 0.5 },
            Schedule::Exponential,
            Schedule::Cosine,
        ] {
            let a = Annealer::new(schedule, 0.8, 0.01, 101).unwrap();
            assert_eq!(a.sigma(0), 0.8);
            assert!((a.sigma(100) - 0.01).abs() < 1e-12, "{schedule:?}");
            for t in 0..200 {
                assert!(a.sigma(t + 1) <= a.sigma(t));
                assert!(a.sigma(t) >= 0.01);
            }
        }
    }

    #[test]
    fn paper_schedule_is_linear_after_the_warm_start() {
        let a = Annealer::paper(0.5, 400).unwrap();
        assert_eq!(a.sigma(199), 0.5);
        assert_eq!(a.sigma(200), 0.5);
        let mid = a.sigma(200 + 199 / 2);
        assert!((a.sigma(200) - mid - (mid - a.sigma(399))).abs() < 0.01);
    }

    #[test]
    fn single_iteration_and_tiny_sigma0() {
        // A one-iteration run is all "last iteration": it sits at the floor.
        let a = Annealer::paper(0.5, 1).unwrap();
        assert!((a.sigma(0) - 0.01).abs() < 1e-15);
        let b = Annealer::paper(0.001, 10).unwrap();
        assert_eq!(b.sigma(9), 0.001);
    }

    #[test]
    fn bad_configuration_is_an_error() {
        assert!(Annealer::paper(0.0, 10).is_err());
        assert!(Annealer::paper(f64::NAN, 10).is_err());
        assert!(Annealer::paper(0.5, 0).is_err());
        assert!(Annealer::new(Schedule::WarmLinear { warmup: 1.0 }, 0.5, 0.01, 10).is_err());
        assert!(Annealer::exponential(0.5, -1.0, 10).is_err());
    }
}
