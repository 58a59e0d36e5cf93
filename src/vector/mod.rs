//! Vector-valued objectives: an objective that returns many numbers (a residual image,
//! per-pixel losses) gives, from the same evaluations, the Gaussian-smoothed Jacobian that
//! the scalar estimator throws away.
//!
//! For `r: R^n -> R^m` and `tau ~ N(0, sigma^2 I)`, Stein's identity gives the Jacobian of
//! the smoothed residuals `R(theta) = E r(theta + tau)` from values of `r` alone:
//!
//! ```text
//! dR_i/dtheta_j = E[ r_i(theta + tau) tau_j ] / sigma^2
//!               = E[ (r_i(theta + tau) - r_i(theta - tau)) tau_j ] / (2 sigma^2).
//! ```
//!
//! With a [`Sparsity`] pattern (output `i` moves only with the parameters of its row), only
//! those entries are estimated, and the variance of an entry depends on the few parameters
//! of its row, not on `n`: a few dozen evaluations give a usable Jacobian for 49,152
//! parameters at once. [`smoothed_jacobian`] is the estimate alone; [`LeastSquares`] takes
//! damped Gauss-Newton steps on the smoothed residuals ([`LeastSquaresAskTell`] as ask and
//! tell).
//!
//! Where it helps: an output moved by few parameters (a texel per pixel is the best case).
//! Where it does not: a pattern that is dense (global lighting couples every pixel to every
//! parameter; then the entries' variance grows with `n`, as the scalar estimator's does), or
//! residuals that are not smooth at the scale of sigma (then the linear model of the
//! smoothed residuals is poor, as for any Gauss-Newton method).

mod acceptance;
mod gauss_newton;
mod jacobian;
mod minimum;
mod solve;
mod sparsity;

pub use acceptance::Acceptance;
pub use gauss_newton::{LeastSquares, LeastSquaresAskTell};
pub use jacobian::{smoothed_jacobian, JacobianEstimate};
pub use minimum::VectorMinimum;
pub use sparsity::Sparsity;
