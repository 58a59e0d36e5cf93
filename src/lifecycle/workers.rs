//! [`Workers`]: an ask's points evaluated on threads, each value written at its point's
//! index, so that any number of workers gives the bits of one.

use std::thread;

use crate::check;
use crate::error::Error;
use crate::objective::{Objective, Points};
use crate::run::Ask;

/// Evaluates an ask's points on `k` threads: the points are cut into `k` contiguous runs,
/// one a thread (the calling thread takes the first), and every value is written at its
/// point's place. The method sees the values in the points' order whatever the threads'
/// timing, so `k` workers give the same bits as one (for an objective whose value depends
/// on its point and seed alone).
///
/// ```
/// use plateau_free::lifecycle::{Driver, Workers};
/// use plateau_free::Minimizer;
///
/// let f = |x: &[f64]| x.iter().map(|v| (v - 0.5).powi(2)).sum::<f64>();
/// let m = Minimizer::new(f).budget(500).seed(2);
/// let one = m.run_with(&[0.0; 4], Driver::new())?;
/// let four = m.run_with(&[0.0; 4], Driver::new().workers(4))?;
/// assert_eq!(one, four);
///
/// // By hand, for the points of any ask.
/// let run = Minimizer::without_objective().budget(100).ask_tell(&[1.0, 2.0])?;
/// # let mut run = run;
/// let ask = run.ask()?.unwrap();
/// let mut values = vec![0.0; ask.len()];
/// Workers::new(3).evaluate(&f, ask, &mut values)?;
/// assert_eq!(values, [0.25 + 2.25]);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Workers {
    threads: usize,
}

impl Default for Workers {
    /// One worker: the calling thread.
    fn default() -> Workers {
        Workers { threads: 1 }
    }
}

impl Workers {
    /// `threads` workers; 0 means one per core the system reports.
    pub fn new(threads: usize) -> Workers {
        let threads = match threads {
            0 => thread::available_parallelism().map_or(1, usize::from),
            k => k,
        };
        Workers { threads }
    }

    /// The number of threads.
    pub fn threads(&self) -> usize {
        self.threads
    }

    /// `out[i] = f(point i, seed i)` for every point of `ask`: one
    /// [`Objective::evaluate_batch`] call per worker, on its run of points.
    ///
    /// # Errors
    /// [`Error::LengthMismatch`] unless `out` has one value a point.
    pub fn evaluate<F>(&self, f: &F, ask: Ask<'_>, out: &mut [f64]) -> Result<(), Error>
    where
        F: Objective + Sync + ?Sized,
    {
        self.each_run(ask, out, 1, |points, seeds, out| {
            f.evaluate_batch(points, seeds, out);
        })
    }

    /// For outputs of `m` values a point (least squares): `f(point, seed, row)` writes
    /// point `i`'s `m` values into `out[i m..(i + 1) m]`.
    ///
    /// # Errors
    /// [`Error::LengthMismatch`] unless `out` has `m` values a point.
    pub fn evaluate_rows<F>(
        &self,
        f: &F,
        ask: Ask<'_>,
        m: usize,
        out: &mut [f64],
    ) -> Result<(), Error>
    where
        F: Fn(&[f64], u64, &mut [f64]) + Sync + ?Sized,
    {
        self.each_run(ask, out, m, |points, seeds, out| {
            for ((x, seed), row) in points.iter().zip(seeds).zip(out.chunks_exact_mut(m)) {
                f(x, *seed, row);
            }
        })
    }

    /// Cuts the points into one contiguous run a thread and calls `run` on each, with its
    /// slice of `out` (`m` values a point).
    fn each_run<R>(&self, ask: Ask<'_>, out: &mut [f64], m: usize, run: R) -> Result<(), Error>
    where
        R: Fn(Points<'_>, &[u64], &mut [f64]) + Sync,
    {
        let (points, seeds, n) = (ask.points(), ask.seeds(), ask.dim());
        let len = seeds.len();
        check::len("outputs (points x values a point)", out.len(), len * m)?;
        let k = self.threads.min(len).max(1);
        if k == 1 || m == 0 {
            run(points, seeds, out);
            return Ok(());
        }
        let chunk = len.div_ceil(k);
        let flat = points.as_flat();
        thread::scope(|scope| {
            let mut parts = flat
                .chunks(chunk * n)
                .zip(seeds.chunks(chunk))
                .zip(out.chunks_mut(chunk * m));
            let first = parts.next();
            for ((xs, ss), os) in parts {
                let run = &run;
                scope.spawn(move || run(Points::new(xs, n), ss, os));
            }
            if let Some(((xs, ss), os)) = first {
                run(Points::new(xs, n), ss, os);
            }
        });
        Ok(())
    }
}
