//! `Adam`: the optimiser the paper uses, with optional box bounds.

use crate::check;
use crate::error::Error;

/// Adam (Kingma and Ba, 2015) with bias correction and optional box bounds: after each step
/// every coordinate is projected into `[lower_i, upper_i]`.
///
/// ```
/// use plateau_free::Adam;
/// let mut adam = Adam::new(0.1)?.bounds(vec![0.0], vec![1.0])?;
/// let mut theta = vec![0.05];
/// adam.step(&mut theta, &[1.0])?;   // a step of about lr downhill, then clipped at 0
/// assert_eq!(theta, vec![0.0]);
/// # Ok::<(), plateau_free::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Adam {
    lr: f64,
    beta1: f64,
    beta2: f64,
    epsilon: f64,
    #[cfg_attr(feature = "serde", serde(with = "crate::saved::float_box"))]
    bounds: Option<(Vec<f64>, Vec<f64>)>,
    m: Vec<f64>,
    v: Vec<f64>,
    t: i32,
}

impl Adam {
    /// A read-back optimiser against theta's dimension `n`: its box, and its moments (empty
    /// before the first step, else of length `n`).
    #[cfg(feature = "serde")]
    pub(crate) fn check_dim(&self, n: usize) -> Result<(), Error> {
        if let Some((lower, upper)) = &self.bounds {
            check::len("lower bounds", lower.len(), n)?;
            check::len("upper bounds", upper.len(), n)?;
            check::bounds(lower, upper)?;
        }
        // A failed first step leaves zero moments of length `n` at `t = 0`.
        let moments = if self.t == 0 && self.m.is_empty() {
            0
        } else {
            n
        };
        check::len("Adam's first moment", self.m.len(), moments)?;
        check::len("Adam's second moment", self.v.len(), moments)
    }

    /// Adam with learning rate `lr` and the usual defaults: beta1 0.9, beta2 0.999, epsilon
    /// 1e-8.
    ///
    /// # Errors
    /// `lr` not finite and positive.
    pub fn new(lr: f64) -> Result<Self, Error> {
        check::positive("lr", lr)?;
        Ok(Adam {
            lr,
            beta1: 0.9,
            beta2: 0.999,
            epsilon: 1e-8,
            bounds: None,
            m: Vec::new(),
            v: Vec::new(),
            t: 0,
        })
    }

    /// The decay rates of the first and second moment estimates.
    ///
    /// # Errors
    /// A rate outside `[0, 1)`.
    pub fn betas(mut self, beta1: f64, beta2: f64) -> Result<Self, Error> {
        check::unit_interval("beta1", beta1)?;
        check::unit_interval("beta2", beta2)?;
        self.beta1 = beta1;
        self.beta2 = beta2;
        Ok(self)
    }

    /// The term that keeps the step finite where the second moment is zero.
    ///
    /// # Errors
    /// `epsilon` not finite and positive.
    pub fn epsilon(mut self, epsilon: f64) -> Result<Self, Error> {
        check::positive("epsilon", epsilon)?;
        self.epsilon = epsilon;
        Ok(self)
    }

    /// Box bounds: after every step, coordinate `i` is clamped into `[lower[i], upper[i]]`.
    /// Infinite bounds are allowed (a one-sided box). In an [`crate::Optimizer`] run they are
    /// the run's box: the start must lie inside, and the estimator keeps every evaluated
    /// point inside ([`crate::GradientEstimator::set_bounds`]).
    ///
    /// # Errors
    /// Lengths that differ, a NaN bound, or `lower[i] > upper[i]`.
    pub fn bounds(mut self, lower: Vec<f64>, upper: Vec<f64>) -> Result<Self, Error> {
        check::bounds(&lower, &upper)?;
        self.bounds = Some((lower, upper));
        Ok(self)
    }

    /// The box bounds, if any: `(lower, upper)`.
    ///
    /// ```
    /// use plateau_free::Adam;
    /// let adam = Adam::new(0.1)?.bounds(vec![0.0], vec![1.0])?;
    /// assert_eq!(adam.box_bounds(), Some((&[0.0][..], &[1.0][..])));
    /// assert_eq!(Adam::new(0.1)?.box_bounds(), None);
    /// # Ok::<(), plateau_free::Error>(())
    /// ```
    pub fn box_bounds(&self) -> Option<(&[f64], &[f64])> {
        self.bounds
            .as_ref()
            .map(|(lo, hi)| (lo.as_slice(), hi.as_slice()))
    }

    /// The learning rate.
    pub fn lr(&self) -> f64 {
        self.lr
    }

    /// The number of steps taken since construction or [`Adam::reset`].
    pub fn steps(&self) -> usize {
        self.t as usize
    }

    /// The moment estimates and the step count: what a saved run needs to continue with the
    /// same steps (see [`crate::run::OptimizerState`]).
    ///
    /// ```
    /// use plateau_free::Adam;
    /// let mut adam = Adam::new(0.1)?;
    /// let mut theta = vec![1.0, 2.0];
    /// adam.step(&mut theta, &[1.0, -1.0])?;
    /// let saved = adam.moments();
    /// let mut copy = Adam::new(0.1)?;
    /// copy.set_moments(saved)?;
    /// let (mut a, mut b) = (theta.clone(), theta);
    /// adam.step(&mut a, &[0.5, 0.5])?;
    /// copy.step(&mut b, &[0.5, 0.5])?;
    /// assert_eq!(a, b);
    /// # Ok::<(), plateau_free::Error>(())
    /// ```
    #[must_use]
    pub fn moments(&self) -> AdamMoments {
        if self.t == 0 {
            // Before the first step (or after a refused first step, which sized them) the
            // moments are zero, and an empty state says so.
            return AdamMoments::default();
        }
        AdamMoments {
            m: self.m.clone(),
            v: self.v.clone(),
            steps: self.t as u64,
        }
    }

    /// Replaces the moment estimates and the step count by saved ones.
    ///
    /// # Errors
    /// [`Error::InvalidState`] for moments of different lengths, a non-finite moment, a
    /// negative second-moment root, a step count above `i32::MAX`, or moments without a step
    /// (or steps without moments). The optimiser is unchanged on error.
    pub fn set_moments(&mut self, moments: AdamMoments) -> Result<(), Error> {
        moments.validate()?;
        self.m = moments.m;
        self.v = moments.v;
        self.t = moments.steps as i32;
        Ok(())
    }

    /// Forgets the moment estimates (the next step is a first step again).
    pub fn reset(&mut self) {
        self.m.clear();
        self.v.clear();
        self.t = 0;
    }

    /// One step downhill: `theta -= lr * m_hat / (sqrt(v_hat) + epsilon)`, then the
    /// projection onto the bounds.
    ///
    /// # Errors
    /// `gradient` or the bounds of a different length than `theta`, a non-finite gradient
    /// coordinate, a `theta` whose length changed since the first step, or a step that would
    /// overflow a coordinate ([`Error::StepOverflow`]). On error `theta` and the optimiser's
    /// state are unchanged.
    pub fn step(&mut self, theta: &mut [f64], gradient: &[f64]) -> Result<(), Error> {
        let n = theta.len();
        check::len("gradient", gradient.len(), n)?;
        if let Some((lower, _)) = &self.bounds {
            check::len("bounds", lower.len(), n)?;
        }
        check::gradient(gradient)?;
        if self.t == 0 {
            // Zero moments are the first step's; sized here (and kept on error: they are
            // still zero).
            self.m = vec![0.0; n];
            self.v = vec![0.0; n];
        } else {
            check::len("theta (since the first step)", n, self.m.len())?;
        }
        let t = self.t.saturating_add(1);
        let correct1 = 1.0 - self.beta1.powi(t);
        let correct2_sqrt = (1.0 - self.beta2.powi(t)).sqrt();
        let (sqrt_beta2, sqrt_one_minus_beta2) = (self.beta2.sqrt(), (1.0 - self.beta2).sqrt());
        let (beta1, lr, epsilon) = (self.beta1, self.lr, self.epsilon);
        let bounds = self.bounds.as_ref();
        // Coordinate i's new first moment, second-moment root and parameter.
        let update = |i: usize, m: f64, v: f64, x: f64| {
            let g = gradient[i];
            let m = beta1 * m + (1.0 - beta1) * g;
            // `v` holds the root of the second moment: g^2 overflows for |g| > 1e154, its
            // root never does, and the hypotenuse is only needed when the values are huge.
            let (a, b) = (sqrt_beta2 * v, sqrt_one_minus_beta2 * g.abs());
            let v = if a.max(b) < 1e150 {
                (a * a + b * b).sqrt()
            } else {
                a.hypot(b)
            };
            let mut x = x - lr * (m / correct1) / (v / correct2_sqrt + epsilon);
            if let Some((lower, upper)) = bounds {
                x = x.clamp(lower[i], upper[i]);
            }
            (m, v, x)
        };
        // A step that would carry a coordinate past f64::MAX (a huge lr, or theta already
        // near the end of the range) is refused before anything is written, so that the
        // error leaves theta and the moments as they were.
        let current = self.m.iter().zip(&self.v).zip(theta.iter());
        for (i, ((&m, &v), &x)) in current.enumerate() {
            let (_, _, next) = update(i, m, v, x);
            if !next.is_finite() {
                return Err(Error::StepOverflow {
                    index: i,
                    theta: x,
                    value: next,
                });
            }
        }
        let current = self.m.iter_mut().zip(&mut self.v).zip(theta.iter_mut());
        for (i, ((m, v), x)) in current.enumerate() {
            (*m, *v, *x) = update(i, *m, *v, *x);
        }
        self.t = t;
        Ok(())
    }
}

/// Adam's state between steps: the first moment `m`, the root of the second moment `v` (kept
/// as a root so that huge gradients do not overflow it) and the number of steps taken.
/// Empty vectors and zero steps before the first step.
#[derive(Debug, Clone, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct AdamMoments {
    /// The first moment estimate, one per coordinate.
    pub m: Vec<f64>,
    /// The root of the second moment estimate, one per coordinate (never negative).
    pub v: Vec<f64>,
    /// Steps taken.
    pub steps: u64,
}

impl AdamMoments {
    /// The rules [`Adam::set_moments`] enforces.
    pub(crate) fn validate(&self) -> Result<(), Error> {
        let bad = |field: &'static str, reason: String| Err(Error::InvalidState { field, reason });
        if self.m.len() != self.v.len() {
            return bad(
                "adam.v",
                format!("has length {}, m has {}", self.v.len(), self.m.len()),
            );
        }
        if self.steps > i32::MAX as u64 {
            return bad(
                "adam.steps",
                format!("= {} exceeds {}", self.steps, i32::MAX),
            );
        }
        if (self.steps == 0) != self.m.is_empty() {
            return bad(
                "adam.steps",
                format!("= {} with {} moments", self.steps, self.m.len()),
            );
        }
        if let Some(i) = self.m.iter().position(|x| !x.is_finite()) {
            return bad("adam.m", format!("[{i}] = {:?} is not finite", self.m[i]));
        }
        if let Some(i) = self.v.iter().position(|x| !(x.is_finite() && *x >= 0.0)) {
            return bad(
                "adam.v",
                format!("[{i}] = {:?} is not finite and >= 0", self.v[i]),
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_step_has_length_lr_against_the_gradient_sign() {
        let mut adam = Adam::new(0.01).unwrap();
        let mut theta = vec![1.0, 1.0, 1.0];
        adam.step(&mut theta, &[3.0, -1e-3, 0.0]).unwrap();
        assert!((theta[0] - 0.99).abs() < 1e-9);
        assert!((theta[1] - 1.01).abs() < 1e-6);
        assert_eq!(theta[2], 1.0);
    }

    #[test]
    fn minimises_a_quadratic() {
        let mut adam = Adam::new(0.05).unwrap();
        let mut x = vec![3.0, -2.0];
        for _ in 0..2000 {
            let g = vec![2.0 * (x[0] - 1.0), 20.0 * (x[1] + 0.5)];
            adam.step(&mut x, &g).unwrap();
        }
        assert!(
            (x[0] - 1.0).abs() < 1e-3 && (x[1] + 0.5).abs() < 1e-3,
            "{x:?}"
        );
    }

    #[test]
    fn rejects_bad_input_without_changing_state() {
        let mut adam = Adam::new(0.1).unwrap();
        let mut x = vec![0.0, 0.0];
        assert!(matches!(
            adam.step(&mut x, &[1.0]),
            Err(Error::LengthMismatch { .. })
        ));
        assert!(matches!(
            adam.step(&mut x, &[1.0, f64::NAN]),
            Err(Error::NonFiniteGradient { index: 1, .. })
        ));
        assert_eq!(adam.steps(), 0);
        assert_eq!(x, vec![0.0, 0.0]);
        assert!(Adam::new(0.0).is_err());
        assert!(Adam::new(0.1)
            .unwrap()
            .bounds(vec![1.0], vec![0.0])
            .is_err());
        assert!(Adam::new(0.1)
            .unwrap()
            .bounds(vec![f64::NAN], vec![0.0])
            .is_err());
        assert!(Adam::new(0.1).unwrap().betas(1.0, 0.9).is_err());
    }

    #[test]
    fn huge_gradients_stay_finite() {
        let mut adam = Adam::new(0.1).unwrap();
        let mut x = vec![0.0];
        adam.step(&mut x, &[1e300]).unwrap();
        assert!((x[0] + 0.1).abs() < 1e-9, "{x:?}");
        adam.step(&mut x, &[-1.7e308]).unwrap();
        assert!(x[0].is_finite() && x[0] > -0.1, "{x:?}");
    }
}
