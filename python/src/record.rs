//! [`Record`]: the per-iteration records of the paper's loop (and its baselines') that
//! `plateau_free.minimize` returns as `history`, kept by `_AskTell`.

use super::*;

/// Per-iteration records of a run: the last `keep_history` iterations (`minimize`'s option,
/// default [`HistoryKeep::DEFAULT_LAST`]), so that a run of any length has bounded memory.
#[derive(Default, Clone, serde::Serialize, serde::Deserialize)]
pub(crate) struct Record {
    pub(crate) sigma: Vec<f64>,
    pub(crate) grad_norm: Vec<f64>,
    pub(crate) value: Vec<f64>,
    pub(crate) nfev: Vec<u64>,
    pub(crate) x: Vec<f64>,
    /// The oldest iterations no longer held (a file without it has dropped none).
    #[serde(default)]
    pub(crate) dropped: usize,
}

impl Record {
    /// Appends one iteration's entry, then drops the oldest beyond the last `keep` once twice
    /// as many are held (O(1) an iteration on average, at most `2 keep` entries held).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn push(
        &mut self,
        sigma: f64,
        gradient: &[f64],
        value: f64,
        nfev: u64,
        theta: Option<&[f64]>,
        keep: usize,
    ) {
        self.sigma.push(sigma);
        self.grad_norm
            .push(gradient.iter().map(|v| v * v).sum::<f64>().sqrt());
        self.value.push(value);
        self.nfev.push(nfev);
        if let Some(theta) = theta {
            self.x.extend_from_slice(theta);
        }
        if self.sigma.len() > keep.saturating_mul(2).max(1) {
            self.trim(keep);
        }
    }

    /// Keeps exactly the last `keep` iterations' entries.
    pub(crate) fn trim(&mut self, keep: usize) {
        let held = self.sigma.len();
        if held <= keep {
            return;
        }
        let cut = held - keep;
        let dim = self.x.len() / held;
        self.sigma.drain(..cut);
        self.grad_norm.drain(..cut);
        self.value.drain(..cut);
        self.nfev.drain(..cut);
        self.x.drain(..cut * dim);
        self.dropped += cut;
    }

    /// The records into `out` (the raw results `plateau_free.minimize` reads), `x` shaped
    /// `(held, *shape)` when recorded.
    pub(crate) fn into_dict(
        self,
        py: Python<'_>,
        out: &Bound<'_, PyDict>,
        shape: &[usize],
        record_x: bool,
    ) -> PyResult<()> {
        let held = self.sigma.len();
        out.set_item("dropped", self.dropped)?;
        out.set_item("sigma", self.sigma.into_pyarray(py))?;
        out.set_item("grad_norm", self.grad_norm.into_pyarray(py))?;
        out.set_item("fun", self.value.into_pyarray(py))?;
        out.set_item("nfev_history", self.nfev.into_pyarray(py))?;
        if record_x {
            let mut full = vec![held];
            full.extend(shape);
            out.set_item("x_history", self.x.into_pyarray(py).reshape(full)?)?;
        }
        Ok(())
    }
}
