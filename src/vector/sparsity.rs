//! [`Sparsity`]: which outputs of a vector objective move with which parameters.

use crate::error::Error;

/// Which parameters each output of a vector objective `r: R^n -> R^m` depends on: output `i`
/// depends only on the parameters of its row `S_i`. The smoothed Jacobian is estimated only
/// on these entries, so that the variance of an entry depends on the few parameters that
/// move its output, not on `n`.
///
/// Stored as compressed rows (the parameters of each output, sorted, without repeats), or
/// as the dense pattern (every output on every parameter) without storing it.
///
/// ```
/// use plateau_free::vector::Sparsity;
/// // Output 0 on parameters 0 and 1, output 1 on parameter 1, output 2 on none.
/// let s = Sparsity::from_pairs(3, 2, &[(0, 1), (0, 0), (1, 1), (0, 1)])?;
/// assert_eq!(s.row(0), vec![0, 1]);
/// assert_eq!(s.row(2), Vec::<usize>::new());
/// assert_eq!(s.nnz(), 3);
/// assert_eq!(Sparsity::dense(2, 3)?.nnz(), 6);
/// # Ok::<(), plateau_free::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Sparsity {
    outputs: usize,
    params: usize,
    /// `None`: dense. Else row `i`'s parameters are `cols[starts[i]..starts[i + 1]]`.
    rows: Option<Rows>,
}

#[derive(Debug, Clone, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
struct Rows {
    starts: Vec<usize>,
    cols: Vec<u32>,
}

/// Sizes: both at least one, and a parameter index must fit in `u32` (4 billion
/// parameters; the compressed rows store them so, halving the pattern's memory).
fn check_shape(outputs: usize, params: usize) -> Result<(), Error> {
    crate::check::at_least_one("outputs", outputs)?;
    crate::check::at_least_one("parameters", params)?;
    if params > u32::MAX as usize {
        return Err(Error::InvalidParameter {
            name: "parameters",
            value: params.into(),
            reason: "must be at most 2^32 - 1",
        });
    }
    Ok(())
}

impl Sparsity {
    /// Every output on every parameter (the pattern is not stored).
    ///
    /// # Errors
    /// `outputs` or `params` zero, or more than `2^32 - 1` parameters.
    pub fn dense(outputs: usize, params: usize) -> Result<Self, Error> {
        check_shape(outputs, params)?;
        Ok(Sparsity {
            outputs,
            params,
            rows: None,
        })
    }

    /// From `(output, parameter)` pairs, in any order, repeats ignored.
    ///
    /// # Errors
    /// A zero size, an index out of range, or no pair at all (a pattern with no entry would
    /// estimate nothing).
    pub fn from_pairs(
        outputs: usize,
        params: usize,
        pairs: &[(usize, usize)],
    ) -> Result<Self, Error> {
        check_shape(outputs, params)?;
        let mut counts = vec![0usize; outputs + 1];
        for &(i, j) in pairs {
            check_index("sparsity output", i, outputs)?;
            check_index("sparsity parameter", j, params)?;
            counts[i + 1] += 1;
        }
        for i in 0..outputs {
            counts[i + 1] += counts[i];
        }
        let mut cols = vec![0u32; pairs.len()];
        let mut next = counts.clone();
        for &(i, j) in pairs {
            cols[next[i]] = j as u32;
            next[i] += 1;
        }
        Self::from_unsorted(outputs, params, counts, cols)
    }

    /// From a closure that writes the parameters of output `i` into the vector it is given
    /// (cleared before each call): `outputs` calls, in order.
    ///
    /// ```
    /// use plateau_free::vector::Sparsity;
    /// // A banded pattern: output i on parameters i - 1, i and i + 1.
    /// let s = Sparsity::from_fn(5, 5, |i, row| {
    ///     row.extend(i.saturating_sub(1)..(i + 2).min(5));
    /// })?;
    /// assert_eq!(s.row(0), vec![0, 1]);
    /// assert_eq!(s.row(2), vec![1, 2, 3]);
    /// # Ok::<(), plateau_free::Error>(())
    /// ```
    ///
    /// # Errors
    /// As [`Sparsity::from_pairs`].
    pub fn from_fn<F>(outputs: usize, params: usize, mut row: F) -> Result<Self, Error>
    where
        F: FnMut(usize, &mut Vec<usize>),
    {
        check_shape(outputs, params)?;
        let mut starts = Vec::with_capacity(outputs + 1);
        starts.push(0);
        let mut cols = Vec::new();
        let mut buffer = Vec::new();
        for i in 0..outputs {
            buffer.clear();
            row(i, &mut buffer);
            for &j in &buffer {
                check_index("sparsity parameter", j, params)?;
                cols.push(j as u32);
            }
            starts.push(cols.len());
        }
        Self::from_unsorted(outputs, params, starts, cols)
    }

    /// Sorts and deduplicates every row.
    fn from_unsorted(
        outputs: usize,
        params: usize,
        starts: Vec<usize>,
        mut cols: Vec<u32>,
    ) -> Result<Self, Error> {
        let mut clean_starts = Vec::with_capacity(outputs + 1);
        clean_starts.push(0);
        let mut write = 0;
        for i in 0..outputs {
            let row = &mut cols[starts[i]..starts[i + 1]];
            row.sort_unstable();
            let mut last = None;
            for k in starts[i]..starts[i + 1] {
                let j = cols[k];
                if last != Some(j) {
                    cols[write] = j;
                    write += 1;
                    last = Some(j);
                }
            }
            clean_starts.push(write);
        }
        cols.truncate(write);
        if cols.is_empty() {
            return Err(Error::InvalidParameter {
                name: "sparsity entries",
                value: 0usize.into(),
                reason: "must be at least 1: the pattern names no (output, parameter) pair",
            });
        }
        Ok(Sparsity {
            outputs,
            params,
            rows: Some(Rows {
                starts: clean_starts,
                cols,
            }),
        })
    }

    /// The number of outputs `m`.
    pub fn outputs(&self) -> usize {
        self.outputs
    }

    /// The number of parameters `n`.
    pub fn params(&self) -> usize {
        self.params
    }

    /// The number of entries (estimated Jacobian values).
    pub fn nnz(&self) -> usize {
        match &self.rows {
            None => self.outputs * self.params,
            Some(r) => r.cols.len(),
        }
    }

    /// Whether every output depends on every parameter.
    pub fn is_dense(&self) -> bool {
        self.rows.is_none()
    }

    /// The parameters of output `i`, sorted (empty for `i` out of range).
    pub fn row(&self, i: usize) -> Vec<usize> {
        let mut row = Vec::new();
        if i < self.outputs {
            self.for_row(i, |_, j| row.push(j));
        }
        row
    }

    /// Calls `f(k, j)` for every entry of row `i`: `k` its index in the entries (the
    /// Jacobian's values), `j` its parameter.
    #[inline]
    pub(crate) fn for_row(&self, i: usize, mut f: impl FnMut(usize, usize)) {
        match &self.rows {
            None => {
                let base = i * self.params;
                for j in 0..self.params {
                    f(base + j, j);
                }
            }
            Some(r) => {
                for k in r.starts[i]..r.starts[i + 1] {
                    f(k, r.cols[k] as usize);
                }
            }
        }
    }

    /// The largest number of parameters of one output.
    pub fn max_row(&self) -> usize {
        match &self.rows {
            None => self.params,
            Some(r) => r.starts.windows(2).map(|w| w[1] - w[0]).max().unwrap_or(0),
        }
    }
}

/// An index below its bound.
fn check_index(name: &'static str, index: usize, bound: usize) -> Result<(), Error> {
    if index < bound {
        Ok(())
    } else {
        Err(Error::InvalidParameter {
            name,
            value: index.into(),
            reason: "is out of range (indices count from 0 below the size)",
        })
    }
}
