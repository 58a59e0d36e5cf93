//! The points of one ask ([`Ask`]) and the checks every method makes on the values it is
//! told: their count and their finiteness.

use crate::error::Error;
use crate::objective::Points;

/// The points of one ask, and the seed of every point.
#[derive(Debug, Clone, Copy)]
pub struct Ask<'a> {
    points: Points<'a>,
    seeds: &'a [u64],
}

impl<'a> Ask<'a> {
    /// The points, rows of the problem's dimension.
    pub fn points(&self) -> Points<'a> {
        self.points
    }

    /// The seed of every point, for an objective with randomness of its own (common random
    /// numbers): the seeds a [`crate::objective::Seeded`] or [`crate::objective::Batch`] objective would receive.
    pub fn seeds(&self) -> &'a [u64] {
        self.seeds
    }

    /// The number of points (values to tell).
    pub fn len(&self) -> usize {
        self.seeds.len()
    }

    /// Whether there are no points (never the case for an ask that a run hands out).
    pub fn is_empty(&self) -> bool {
        self.seeds.is_empty()
    }

    /// The dimension of every point.
    pub fn dim(&self) -> usize {
        self.points.dim()
    }

    /// The points with their seeds, in order.
    pub fn iter(&self) -> impl ExactSizeIterator<Item = (&'a [f64], u64)> + 'a {
        self.points.iter().zip(self.seeds.iter().copied())
    }
}

impl<'a> Ask<'a> {
    /// An ask of `points` with their `seeds` (one a point), for a method of your own
    /// ([`crate::lifecycle::AskAndTell`]).
    ///
    /// ```
    /// let flat = [1.0, 2.0, 3.0, 4.0];
    /// let ask = plateau_free::Ask::try_new(plateau_free::objective::Points::new(&flat, 2), &[7, 7])?;
    /// assert_eq!((ask.len(), ask.dim()), (2, 2));
    /// # Ok::<(), plateau_free::Error>(())
    /// ```
    ///
    /// # Errors
    /// [`Error::LengthMismatch`] unless there is one seed a point.
    pub fn try_new(points: Points<'a>, seeds: &'a [u64]) -> Result<Ask<'a>, Error> {
        crate::check::len("seeds (one a point)", seeds.len(), points.len())?;
        Ok(Ask { points, seeds })
    }

    /// An ask of `points`, with `seeds` (one a point).
    pub(crate) fn new(points: Points<'a>, seeds: &'a [u64]) -> Ask<'a> {
        Ask { points, seeds }
    }
}

/// The first non-finite value, as the error that names it: `first` is the index of the
/// first value in the run's count of evaluations.
pub(crate) fn non_finite(values: &[f64], points: Points<'_>, first: usize) -> Result<(), Error> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(k) => Err(Error::NonFiniteValue {
            sample: first + k,
            value: values[k],
            point: points.get(k).to_vec(),
        }),
        None => Ok(()),
    }
}

/// The count of told values against the count of asked points.
pub(crate) fn count(expected: usize, got: usize) -> Result<(), Error> {
    if expected == got {
        Ok(())
    } else {
        Err(Error::TellCount { expected, got })
    }
}
