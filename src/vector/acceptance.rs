//! [`Acceptance`]: when the vector method takes a Gauss-Newton step.

/// When a Gauss-Newton step is taken.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Acceptance {
    /// The step's point is evaluated (one evaluation, with the seed every such point gets:
    /// common random numbers) and taken when its sum of squares is not larger than the
    /// current point's; a tie is taken, so a flat objective does not stop the run. A refused
    /// step raises the damping and is tried again, shorter (after
    /// [`crate::LeastSquares::max_rejections`], the Jacobian is estimated again with fresh draws).
    #[default]
    Descent,
    /// Every step is taken (its point still evaluated, for the result): the smoothed model
    /// alone decides, as the scalar method's Adam step does.
    Always,
}
