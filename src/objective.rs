//! The forms an objective can take: a plain closure, a closure that takes a seed (common
//! random numbers), and a batch form that evaluates every point of an estimate in one call.
//!
//! A plain `Fn(&[f64]) -> f64` is an [`Objective`] as it is. Wrap a seeded closure in
//! [`Seeded`] and a batch closure in [`Batch`]; or implement [`Objective`] for your own type
//! (a renderer, a simulator) and override [`Objective::evaluate_batch`] when it can do better
//! than one point at a time.

use std::fmt;

/// A read-only view of `len` points of dimension `dim`, stored row after row.
#[derive(Debug, Clone, Copy)]
pub struct Points<'a> {
    flat: &'a [f64],
    dim: usize,
}

impl<'a> Points<'a> {
    /// A view of `flat` as rows of length `dim`.
    ///
    /// # Panics
    /// If `dim` is zero or does not divide `flat.len()`.
    ///
    /// ```
    /// let flat = [1.0, 2.0, 3.0, 4.0];
    /// let points = plateau_free::objective::Points::new(&flat, 2);
    /// assert_eq!(points.len(), 2);
    /// assert_eq!(points.get(1), &[3.0, 4.0]);
    /// ```
    pub fn new(flat: &'a [f64], dim: usize) -> Self {
        assert!(
            dim > 0 && flat.len() % dim == 0,
            "points of dimension {dim} cannot tile {} values",
            flat.len()
        );
        Points { flat, dim }
    }

    /// The number of points.
    pub fn len(&self) -> usize {
        self.flat.len() / self.dim
    }

    /// Whether there are no points.
    pub fn is_empty(&self) -> bool {
        self.flat.is_empty()
    }

    /// The dimension of every point.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Point `i`.
    pub fn get(&self, i: usize) -> &'a [f64] {
        &self.flat[i * self.dim..(i + 1) * self.dim]
    }

    /// The points in order.
    pub fn iter(&self) -> impl ExactSizeIterator<Item = &'a [f64]> + 'a {
        self.flat.chunks_exact(self.dim)
    }

    /// All coordinates, row after row.
    pub fn as_flat(&self) -> &'a [f64] {
        self.flat
    }
}

/// Something to differentiate: evaluated at points, optionally with a seed for its own
/// randomness.
///
/// `seed` is the same for both members of an antithetic pair and changes between pairs and
/// between estimates; an objective with randomness of its own (a Monte Carlo renderer)
/// should use it, so that the difference within a pair sees the change of theta and not
/// the change of noise (common random numbers).
pub trait Objective {
    /// `f(point)`, with `seed` for any randomness the objective has.
    fn evaluate(&self, point: &[f64], seed: u64) -> f64;

    /// Evaluates every point, writing `out[i] = f(points[i], seeds[i])`. The default calls
    /// [`Objective::evaluate`] in order; override it to hand all points to a batch engine.
    fn evaluate_batch(&self, points: Points<'_>, seeds: &[u64], out: &mut [f64]) {
        for ((point, seed), o) in points.iter().zip(seeds).zip(out.iter_mut()) {
            *o = self.evaluate(point, *seed);
        }
    }
}

impl<F: Fn(&[f64]) -> f64> Objective for F {
    fn evaluate(&self, point: &[f64], _seed: u64) -> f64 {
        self(point)
    }
}

/// An objective that takes a seed: `Seeded(|x: &[f64], seed: u64| render_loss(x, seed))`.
///
/// ```
/// use plateau_free::{Objective, objective::Seeded};
/// let noisy = Seeded(|x: &[f64], seed: u64| x[0] + (seed % 7) as f64);
/// assert_eq!(noisy.evaluate(&[1.0], 9), 3.0);
/// ```
#[derive(Clone, Copy)]
pub struct Seeded<F>(pub F);

impl<F: Fn(&[f64], u64) -> f64> Objective for Seeded<F> {
    fn evaluate(&self, point: &[f64], seed: u64) -> f64 {
        (self.0)(point, seed)
    }
}

/// An objective that evaluates many points in one call (a GPU renderer, a render farm, a
/// remote service): the closure receives all points of an estimate, their seeds, and the
/// output slice to fill.
///
/// ```
/// use plateau_free::{objective::Batch, Objective, objective::Points};
/// let sum_of_squares = Batch(|points: Points<'_>, _seeds: &[u64], out: &mut [f64]| {
///     for (p, o) in points.iter().zip(out.iter_mut()) {
///         *o = p.iter().map(|x| x * x).sum();
///     }
/// });
/// assert_eq!(sum_of_squares.evaluate(&[3.0, 4.0], 0), 25.0);
/// ```
#[derive(Clone, Copy)]
pub struct Batch<F>(pub F);

impl<F: Fn(Points<'_>, &[u64], &mut [f64])> Objective for Batch<F> {
    fn evaluate(&self, point: &[f64], seed: u64) -> f64 {
        let mut out = [0.0];
        (self.0)(Points::new(point, point.len()), &[seed], &mut out);
        out[0]
    }

    fn evaluate_batch(&self, points: Points<'_>, seeds: &[u64], out: &mut [f64]) {
        (self.0)(points, seeds, out)
    }
}

/// `Debug` for the closure wrappers, written once: `Seeded("closure type")`.
macro_rules! debug_by_type_name {
    ($($wrapper:ident),*) => {$(
        impl<F> fmt::Debug for $wrapper<F> {
            /// The closure by its type's name (closures have no `Debug`).
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.debug_tuple(stringify!($wrapper))
                    .field(&std::any::type_name::<F>())
                    .finish()
            }
        }
    )*};
}

debug_by_type_name!(Seeded, Batch);

/// The objective of a run whose points are evaluated elsewhere:
/// [`crate::Minimizer::without_objective`] and
/// [`crate::PlateauFreeGradient::without_objective`] hold it. It is no [`Objective`], so
/// that nothing can evaluate it by mistake.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct NoObjective;
