//! [`Trace`]: a run's history (best value, spread, evaluations by iteration) whose memory
//! stays bounded however long the run.

use super::observe::{Observer, Progress};

/// One row of a [`Trace`]: where the run stood after an iteration.
///
/// ```
/// use plateau_free::lifecycle::{Driver, Trace};
/// use plateau_free::Minimizer;
///
/// let mut trace = Trace::default();
/// Minimizer::new(|x: &[f64]| x[0].abs()).budget(50).run_with(&[1.0], Driver::new().observe(&mut trace))?;
/// let rows = trace.rows();
/// // The start alone, then a generation a row.
/// assert_eq!((rows[0].iteration, rows[0].evaluations, rows[0].best), (0, 1, 1.0));
/// assert!(rows[1].evaluations > 1 && rows[1].sigma > 0.0);
/// assert_eq!((trace.stride(), trace.iterations_seen()), (1, rows.len()));
/// # Ok::<(), plateau_free::lifecycle::Failure<plateau_free::Minimum>>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct TraceRow {
    /// Iterations completed.
    pub iteration: usize,
    /// Evaluations told so far (their differences are the evaluations per iteration).
    pub evaluations: usize,
    /// The best value so far.
    #[cfg_attr(feature = "serde", serde(with = "crate::saved::float"))]
    pub best: f64,
    /// The spread.
    #[cfg_attr(feature = "serde", serde(with = "crate::saved::float"))]
    pub sigma: f64,
}

/// A run's history as an [`Observer`]: one [`TraceRow`] per iteration while it has room,
/// then thinned. Once `2 keep` rows are held, every other row is dropped and from then on
/// only every other iteration is recorded (the stride doubles), so a run of any length holds
/// between `keep` and `2 keep` rows spread evenly over the whole run, plus its last row.
///
/// ```
/// use plateau_free::lifecycle::{Driver, Trace};
/// use plateau_free::Minimizer;
///
/// let mut trace = Trace::new(8);
/// let best = Minimizer::new(|x: &[f64]| x[0] * x[0] + x[1] * x[1])
///     .budget(1000)
///     .run_with(&[1.0, 1.0], Driver::new().observe(&mut trace))?;
/// let rows = trace.rows();
/// assert!(rows.len() <= 2 * 8 + 1);
/// assert_eq!(rows[0].iteration, 0);
/// assert_eq!(rows.last().unwrap().iteration, best.iterations);
/// assert!(rows.windows(2).all(|w| w[1].best <= w[0].best));
/// # Ok::<(), plateau_free::lifecycle::Failure<plateau_free::Minimum>>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Trace {
    keep: usize,
    stride: usize,
    seen: usize,
    rows: Vec<TraceRow>,
    /// The latest row, when the stride skipped it.
    last: Option<TraceRow>,
}

impl Trace {
    /// A history of between `keep` and `2 keep` rows (at least 1).
    pub fn new(keep: usize) -> Trace {
        Trace {
            keep: keep.max(1),
            stride: 1,
            seen: 0,
            rows: Vec::new(),
            last: None,
        }
    }

    /// The rows, oldest first, evenly thinned; the latest iteration's row last.
    pub fn rows(&self) -> Vec<TraceRow> {
        let mut rows = self.rows.clone();
        rows.extend(self.last);
        rows
    }

    /// Every how many iterations a row is recorded now (1 until the first thinning).
    pub fn stride(&self) -> usize {
        self.stride
    }

    /// Iterations seen.
    pub fn iterations_seen(&self) -> usize {
        self.seen
    }

    /// Records `row`, the next iteration's, as [`Observer::observe`] does: for a method
    /// wrapped in one of your own that keeps its history in its saved state.
    ///
    /// ```
    /// use plateau_free::lifecycle::{Trace, TraceRow};
    ///
    /// let mut trace = Trace::new(2);
    /// for k in 0..9 {
    ///     trace.record(TraceRow { iteration: k, evaluations: 10 * k, best: 1.0 / (k + 1) as f64, sigma: 0.5 });
    /// }
    /// let kept: Vec<usize> = trace.rows().iter().map(|r| r.iteration).collect();
    /// assert_eq!((kept, trace.stride()), (vec![0, 4, 8], 4));
    /// ```
    pub fn record(&mut self, row: TraceRow) {
        let index = self.seen;
        self.seen += 1;
        if index % self.stride != 0 {
            self.last = Some(row);
            return;
        }
        self.last = None;
        self.rows.push(row);
        if self.rows.len() >= 2 * self.keep {
            // Keep the rows of the iterations the doubled stride records.
            let stride = self.stride;
            let mut i = 0usize;
            self.rows.retain(|_| {
                i += 1;
                (i - 1) % 2 == 0
            });
            self.stride = stride * 2;
            // The newest row sat at an odd place: it stays as the latest.
            self.last = Some(row);
        }
    }
}

impl Default for Trace {
    /// A history of between 10,000 and 20,000 rows.
    fn default() -> Trace {
        Trace::new(10_000)
    }
}

impl Observer for Trace {
    fn observe(&mut self, p: &Progress) {
        self.record(TraceRow {
            iteration: p.iteration,
            evaluations: p.evaluations,
            best: p.best,
            sigma: p.sigma,
        });
    }
}
