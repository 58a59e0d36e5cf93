//! Every way an input can be wrong, each carrying the offending value.

use std::fmt;

/// The crate's error type: bad input is reported, never panicked on, and never turned into a
/// silently wrong number.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// The parameter vector has no coordinates.
    #[error("theta is empty: the objective needs at least one parameter")]
    EmptyTheta,

    /// A coordinate of theta is NaN or infinite.
    #[error("theta[{index}] = {value:?} is not finite")]
    NonFiniteTheta {
        /// The coordinate.
        index: usize,
        /// Its value.
        value: f64,
    },

    /// A scalar spread that is not a finite positive number.
    #[error("sigma = {0:?} must be finite and > 0")]
    InvalidSigma(f64),

    /// A per-dimension spread that is not a finite positive number.
    #[error("spreads[{index}] = {value:?} must be finite and > 0")]
    InvalidSpread {
        /// The coordinate.
        index: usize,
        /// Its value.
        value: f64,
    },

    /// Two inputs that must have the same length do not.
    #[error("length mismatch: {what} has length {got}, expected {expected}")]
    LengthMismatch {
        /// Which input has the wrong length.
        what: &'static str,
        /// The length it should have.
        expected: usize,
        /// The length it has.
        got: usize,
    },

    /// The estimator was asked for zero evaluations of `f`.
    #[error("samples = 0 is invalid: must be at least 1 (evaluations of f per estimate)")]
    ZeroSamples,

    /// Antithetic pairs evaluate `f` twice per draw, so the count must be even.
    #[error("antithetic pairs need an even number of samples, got {0}; use an even count or .antithetic(false)")]
    OddSamples(usize),

    /// Orthogonal directions only make sense for samplers that draw a direction.
    #[error("orthogonal directions need Sampling::Radial or Sampling::Gaussian, not {0:?}")]
    OrthogonalUnsupported(crate::Sampling),

    /// A perturbed point overflowed (theta plus its offset is not finite).
    #[error(
        "perturbed point {sample} has coordinate {index} = {value:?} (theta plus offset overflowed)"
    )]
    NonFinitePoint {
        /// Which evaluation of the estimate.
        sample: usize,
        /// The coordinate.
        index: usize,
        /// Its value.
        value: f64,
    },

    /// The objective returned NaN or an infinity.
    #[error(
        "f returned {value:?} at evaluation {sample}, point {}",
        Preview(point)
    )]
    NonFiniteValue {
        /// Which evaluation of the estimate.
        sample: usize,
        /// The value f returned.
        value: f64,
        /// The point at which f was evaluated.
        point: Vec<f64>,
    },

    /// The gradient overflowed: values of f too large for the spread (for example f near
    /// 1e300 with sigma 1e-12). Rescale f or enlarge sigma.
    #[error("gradient coordinate {index} = {value:?} is not finite: f's values are too large for the spread; rescale f")]
    NonFiniteGradient {
        /// The coordinate.
        index: usize,
        /// Its value.
        value: f64,
    },

    /// A configuration value out of its range (annealer, optimiser, baselines, [`crate::Minimizer`]).
    /// The message shows the value as it was given: a count as an integer, a real number as
    /// a real number (see [`ParameterValue`]).
    ///
    /// ```
    /// use plateau_free::{Error, Minimizer, error::ParameterValue};
    /// let e = Minimizer::new(|x: &[f64]| x[0]).budget(0).run(&[1.0]).unwrap_err();
    /// assert_eq!(e.to_string(), "budget = 0 is invalid: must be at least 1 evaluation");
    /// assert!(matches!(e, Error::InvalidParameter { value: ParameterValue::Integer(0), .. }));
    /// let e = plateau_free::Adam::new(-0.5).unwrap_err();
    /// assert_eq!(e.to_string(), "lr = -0.5 is invalid: must be finite and > 0");
    /// ```
    #[error("{name} = {value} is invalid: {reason}")]
    InvalidParameter {
        /// The parameter's name.
        name: &'static str,
        /// Its value.
        value: ParameterValue,
        /// What it must satisfy.
        reason: &'static str,
    },

    /// A name that [`std::str::FromStr`] does not know (a sampler, a schedule): the error
    /// names the value and every accepted spelling.
    #[error("unknown {what} {value:?}: expected one of {allowed}")]
    UnknownName {
        /// What was being parsed.
        what: &'static str,
        /// The text that was given.
        value: String,
        /// The accepted spellings, comma-separated.
        allowed: &'static str,
    },

    /// An Adam step would carry a coordinate of theta past the largest finite number (a
    /// learning rate too large for theta's scale). Nothing was changed.
    #[error("the step would overflow theta[{index}] = {theta:?} to {value:?}; reduce lr")]
    StepOverflow {
        /// The coordinate.
        index: usize,
        /// Its value before the step.
        theta: f64,
        /// The non-finite value the step would give.
        value: f64,
    },

    /// A saved optimiser state that cannot be continued from (see
    /// [`crate::Optimizer::minimize_from`]): a dimension that does not match, a NaN, a
    /// history of the wrong length. Nothing of the state was used.
    #[error("invalid optimizer state: {field} {reason}")]
    InvalidState {
        /// The part of the state at fault.
        field: &'static str,
        /// What is wrong, with the offending value.
        reason: String,
    },

    /// The objective panicked during an estimate and the estimator was set to catch panics
    /// ([`crate::PlateauFreeGradient::catch_panics`]).
    #[error("f panicked during estimate {estimate}: {message}")]
    ObjectivePanicked {
        /// The index of the estimate (its random streams).
        estimate: u64,
        /// The panic's message (cut to 200 characters), or a note that it had none.
        message: String,
    },

    /// An ask-and-tell run was asked for points while the last asked points still wait for
    /// their values ([`crate::AskTell::ask`]).
    #[error("ask called twice: the asked points still wait for their values (tell them first)")]
    AskPending,

    /// Values were told to an ask-and-tell run with no asked points waiting for them
    /// ([`crate::AskTell::tell`]).
    #[error("tell without ask: no asked points wait for values")]
    NothingAsked,

    /// The wrong number of values was told: one value per asked point, in their order.
    #[error("tell got {got} values for {expected} asked points")]
    TellCount {
        /// The number of asked points.
        expected: usize,
        /// The number of values told.
        got: usize,
    },

    /// The result of an ask-and-tell run was taken before the run ended
    /// ([`crate::AskTell::finish`]).
    #[error("the run is not finished ({evaluations} of at most {budget} evaluations told): ask and tell until ask gives None")]
    Unfinished {
        /// Evaluations told so far.
        evaluations: usize,
        /// The run's budget.
        budget: usize,
    },

    /// A start (or a saved state's theta) outside the bounds of the run: with bounds, every
    /// method evaluates `f` only inside the box, and starts there.
    ///
    /// ```
    /// use plateau_free::{Error, Minimizer};
    /// let e = Minimizer::new(|x: &[f64]| x[0]).bounds(vec![0.0], vec![1.0]).run(&[1.5]).unwrap_err();
    /// assert_eq!(e.to_string(), "x0[0] = 1.5 lies outside the bounds [0.0, 1.0]");
    /// ```
    #[error("{what}[{index}] = {value:?} lies outside the bounds [{lower:?}, {upper:?}]")]
    OutsideBounds {
        /// The vector at fault (`x0`, `theta`).
        what: &'static str,
        /// The coordinate.
        index: usize,
        /// Its value.
        value: f64,
        /// The coordinate's lower bound.
        lower: f64,
        /// The coordinate's upper bound.
        upper: f64,
    },

    /// A run with bounds was given a [`crate::GradientEstimator`] that cannot keep its points
    /// inside them (the default [`crate::GradientEstimator::set_bounds`]): the run refuses to
    /// start rather than evaluate `f` outside the box.
    #[error("the gradient estimator {estimator} cannot keep its points inside bounds: implement GradientEstimator::set_bounds for it, or run without bounds")]
    BoundsUnsupported {
        /// The estimator's type name.
        estimator: &'static str,
    },

    /// A lower bound above its upper bound.
    #[error("bounds[{index}]: lower {lower:?} > upper {upper:?} (or not a number)")]
    InvalidBounds {
        /// The coordinate.
        index: usize,
        /// The lower bound.
        lower: f64,
        /// The upper bound.
        upper: f64,
    },

    /// A checkpoint file could not be read, written or understood
    /// ([`crate::lifecycle::Checkpoint`]); the run it belongs to is not touched.
    #[error("checkpoint {path}: {reason}")]
    Checkpoint {
        /// The file.
        path: String,
        /// What went wrong (the system's message, or what is damaged).
        reason: String,
    },

    /// A checkpoint file belongs to another run: resuming from it would not continue this
    /// one ([`crate::lifecycle::Checkpoint`]). `field` is the first setting that differs.
    #[error("checkpoint {path} belongs to another run: {field} is {saved} there, {given} here")]
    CheckpointMismatch {
        /// The file.
        path: String,
        /// The first setting that differs (`x0`, `budget`, `seed`, `strategy`, ...).
        field: String,
        /// Its value in the file.
        saved: String,
        /// Its value in the run given.
        given: String,
    },
}

/// The value of an option in an [`Error::InvalidParameter`], kept as the kind of number the
/// option takes, so that the message shows it as it was written: a count as an integer
/// (`budget = 0`, not `0e0`), a real number in the shortest form that reads back to the same
/// bits (`lr = 0.5`, `sigma0 = 1.0`, `sigma0 = 1e-300`, `NaN`, `inf`).
///
/// ```
/// use plateau_free::error::ParameterValue;
/// assert_eq!(ParameterValue::from(3usize).to_string(), "3");
/// assert_eq!(ParameterValue::from(0.5).to_string(), "0.5");
/// assert_eq!(ParameterValue::from(1.0).to_string(), "1.0");
/// assert_eq!(ParameterValue::from(-2.5e-300).to_string(), "-2.5e-300");
/// assert_eq!(ParameterValue::from(7usize).as_f64(), 7.0);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ParameterValue {
    /// A count: a budget, a population, a number of samples or iterations.
    Integer(u64),
    /// A real number: a learning rate, a spread, a fraction, a target.
    Float(f64),
}

impl ParameterValue {
    /// The value as a real number (a count converted, exactly up to `2^53`).
    #[must_use]
    pub fn as_f64(self) -> f64 {
        match self {
            ParameterValue::Integer(v) => v as f64,
            ParameterValue::Float(v) => v,
        }
    }
}

impl fmt::Display for ParameterValue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ParameterValue::Integer(v) => write!(f, "{v}"),
            // `{:?}` of an f64 is the shortest text that reads back to the same bits, with a
            // decimal point (`1.0`) and an exponent only for very large or small values.
            ParameterValue::Float(v) => write!(f, "{v:?}"),
        }
    }
}

impl From<f64> for ParameterValue {
    fn from(value: f64) -> Self {
        ParameterValue::Float(value)
    }
}

impl From<usize> for ParameterValue {
    fn from(value: usize) -> Self {
        ParameterValue::Integer(value as u64)
    }
}

impl From<u64> for ParameterValue {
    fn from(value: u64) -> Self {
        ParameterValue::Integer(value)
    }
}

/// Shows at most four coordinates, each as written (`{:?}`: the shortest text that reads back
/// to the same bits, as [`ParameterValue`]), and the count: a point may have a million
/// coordinates and a coordinate 300 digits.
struct Preview<'a>(&'a [f64]);

impl fmt::Display for Preview<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        const SHOWN: usize = 4;
        write!(f, "[")?;
        for (i, x) in self.0.iter().take(SHOWN).enumerate() {
            if i > 0 {
                write!(f, ", ")?;
            }
            write!(f, "{x:?}")?;
        }
        if self.0.len() > SHOWN {
            write!(f, ", ... ({} coordinates)", self.0.len())?;
        }
        write!(f, "]")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_points_are_previewed() {
        let e = Error::NonFiniteValue {
            sample: 3,
            value: f64::NAN,
            point: vec![0.5; 100],
        };
        let text = e.to_string();
        assert!(text.contains("evaluation 3"), "{text}");
        assert!(text.contains("(100 coordinates)"), "{text}");
        assert!(text.len() < 200, "{text}");
    }

    #[test]
    fn huge_values_print_short() {
        let e = Error::NonFiniteGradient {
            index: 0,
            value: f64::MAX,
        };
        let text = e.to_string();
        assert!(text.contains("1.7976931348623157e308"), "{text}");
        assert!(text.len() < 150, "{text}");
        let e = Error::NonFiniteValue {
            sample: 0,
            value: f64::INFINITY,
            point: vec![-f64::MAX; 1000],
        };
        assert!(e.to_string().len() < 200, "{e}");
    }
}
